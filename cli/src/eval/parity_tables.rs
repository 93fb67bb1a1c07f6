//! The issue-14 tables of a multi-IMU log: steps on every IMU × axis ×
//! sign at several onsets and training starts, biases present from power-up,
//! and the `parity-replay --json` object.

use anyhow::Result;

use hal_sim::array::ArrayKind;

use super::parity_replay::{replay_parity_with, ImuLog, Injection, ParityMethod};

/// One case of the step table: a bias on one IMU channel for a while.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepCase {
    /// Training start, s.
    pub train_start: f64,
    /// The injected step.
    pub injection: Injection,
    /// Isolated to the right sensor within [`STEP_ISOLATE_WITHIN_S`] of onset.
    pub isolated: bool,
    /// Seconds from onset to that isolation.
    pub delay: Option<f64>,
    /// An alarm started outside the fault window (between monitoring start
    /// and `end_s`), or a healthy sensor was isolated.
    pub false_alarm: bool,
}

/// Seconds after onset within which the step must be isolated.
pub const STEP_ISOLATE_WITHIN_S: f64 = 10.0;

/// The log171 step table for one sensor kind and step size: for every
/// training start, every IMU × axis × sign and every onset, a step lasting
/// `duration_s` is replayed; a case passes when the right sensor is
/// isolated within [`STEP_ISOLATE_WITHIN_S`] and nothing alarms outside
/// `[onset, onset + duration_s]` before `end_s` (the crash). Onsets are
/// seconds after the monitoring start of each training start; `method`
/// is [`ParityMethod::Flight`] or [`ParityMethod::FlightAt`].
#[allow(clippy::too_many_arguments)]
pub fn step_table(
    log: &ImuLog,
    kind: ArrayKind,
    size: f64,
    train_starts: &[f64],
    train_s: f64,
    onsets_after_start: &[f64],
    duration_s: f64,
    end_s: f64,
    method: ParityMethod,
) -> Result<Vec<StepCase>> {
    let channel0 = match kind {
        ArrayKind::Gyro => 3,
        ArrayKind::Accel => 0,
    };
    let mut jobs = Vec::new();
    for &ts in train_starts {
        for &after in onsets_after_start {
            for imu in 0..3 {
                for axis in 0..3 {
                    for sign in [1.0, -1.0] {
                        jobs.push((ts, after, imu, axis, sign));
                    }
                }
            }
        }
    }
    use rayon::prelude::*;
    jobs.par_iter()
        .map(|&(ts, after, imu, axis, sign)| {
            let start = ts + train_s + after;
            let injection = Injection {
                imu,
                channel: channel0 + axis,
                size: sign * size,
                start,
                end: start + duration_s,
            };
            let r = replay_parity_with(log, kind, ts, train_s, Some(injection), method)?;
            let sensor = 3 * imu + axis;
            let from = r.monitoring_from.unwrap_or(f64::INFINITY);
            let first = r
                .isolations
                .iter()
                .find(|(_, t)| *t >= start && *t < start + STEP_ISOLATE_WITHIN_S);
            let isolated = first.is_some_and(|(k, _)| *k == sensor);
            let wrong_isolation = r.isolations.iter().any(|(k, t)| *k != sensor && *t < end_s);
            let outside = r
                .alarms
                .iter()
                .any(|a| a.0 >= from && a.0 < end_s && (a.0 < start || a.0 > start + duration_s));
            Ok(StepCase {
                train_start: ts,
                injection,
                isolated,
                delay: first.filter(|_| isolated).map(|(_, t)| t - start),
                false_alarm: wrong_isolation || outside,
            })
        })
        .collect()
}

/// A bias present on one IMU channel from the first row of the log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerUpCase {
    /// Training start, s.
    pub train_start: f64,
    /// The injected bias (start −∞, end +∞).
    pub injection: Injection,
    /// Seconds from monitoring start to the isolation of the right sensor,
    /// when that came within [`STEP_ISOLATE_WITHIN_S`].
    pub delay: Option<f64>,
    /// A healthy sensor was isolated before the crash.
    pub wrong_isolation: bool,
}

/// For every training start, IMU, axis and sign: a bias of `size` on that
/// channel for the whole log. The case passes when the sensor is isolated
/// within [`STEP_ISOLATE_WITHIN_S`] of monitoring start and no healthy
/// sensor is isolated before `end_s`; `method` as in [`step_table`].
pub fn power_up_table(
    log: &ImuLog,
    kind: ArrayKind,
    size: f64,
    train_starts: &[f64],
    train_s: f64,
    end_s: f64,
    method: ParityMethod,
) -> Result<Vec<PowerUpCase>> {
    let channel0 = match kind {
        ArrayKind::Gyro => 3,
        ArrayKind::Accel => 0,
    };
    let mut jobs = Vec::new();
    for &ts in train_starts {
        for imu in 0..3 {
            for axis in 0..3 {
                for sign in [1.0, -1.0] {
                    jobs.push((ts, imu, axis, sign));
                }
            }
        }
    }
    use rayon::prelude::*;
    jobs.par_iter()
        .map(|&(ts, imu, axis, sign)| {
            let injection = Injection {
                imu,
                channel: channel0 + axis,
                size: sign * size,
                start: f64::NEG_INFINITY,
                end: f64::INFINITY,
            };
            let r = replay_parity_with(log, kind, ts, train_s, Some(injection), method)?;
            let sensor = 3 * imu + axis;
            let from = r.monitoring_from.unwrap_or(f64::INFINITY);
            let delay = r
                .isolations
                .iter()
                .find(|(k, t)| *k == sensor && *t < from + STEP_ISOLATE_WITHIN_S)
                .map(|(_, t)| (t - from).max(0.0));
            let wrong_isolation = r.isolations.iter().any(|(k, t)| *k != sensor && *t < end_s);
            Ok(PowerUpCase {
                train_start: ts,
                injection,
                delay,
                wrong_isolation,
            })
        })
        .collect()
}

/// The replay of both sensor kinds as one JSON object (the schema of
/// `imu-fdi-sim parity-replay --json`): `{"gyro": {"monitoring_from_s",
/// "power_up_judged", "alarms": [{"start_s", "end_s", "sensor"}],
/// "isolations": [{"sensor", "t_s"}], "statuses": [{"sensor", "status",
/// "t_s"}], "readmissions": [{"sensor", "t_s"}]}, "accel": {…}}`,
/// sensor = 3 × IMU + axis, times in seconds of the file's clock, `null`
/// where a value does not exist (no monitoring, no suspect).
pub fn replay_json(
    log: &ImuLog,
    train_start: f64,
    train_s: f64,
    method: ParityMethod,
    injection: Option<Injection>,
) -> Result<serde_json::Value> {
    let mut out = serde_json::Map::new();
    for (name, kind) in [("gyro", ArrayKind::Gyro), ("accel", ArrayKind::Accel)] {
        let inj = injection.filter(|i| match kind {
            ArrayKind::Gyro => i.channel >= 3,
            ArrayKind::Accel => i.channel < 3,
        });
        let r = replay_parity_with(log, kind, train_start, train_s, inj, method)?;
        let alarms: Vec<_> = r
            .alarms
            .iter()
            .map(|(a, b, k)| serde_json::json!({"start_s": a, "end_s": b, "sensor": k}))
            .collect();
        let isolations: Vec<_> = r
            .isolations
            .iter()
            .map(|(k, t)| serde_json::json!({"sensor": k, "t_s": t}))
            .collect();
        let readmissions: Vec<_> = r
            .readmissions
            .iter()
            .map(|(k, t)| serde_json::json!({"sensor": k, "t_s": t}))
            .collect();
        let statuses: Vec<_> = r
            .statuses
            .iter()
            .map(|(k, s, t)| {
                serde_json::json!({"sensor": k, "status": format!("{s:?}").to_lowercase(), "t_s": t})
            })
            .collect();
        let not_judging: Vec<_> = r
            .not_judging
            .iter()
            .map(|(a, b, p)| {
                serde_json::json!({"start_s": a, "end_s": b, "phase": format!("{p:?}").to_lowercase()})
            })
            .collect();
        out.insert(
            name.into(),
            serde_json::json!({
                "monitoring_from_s": r.monitoring_from,
                "not_judging": not_judging,
                "power_up_judged": r.power_up_judged,
                "alarms": alarms,
                "isolations": isolations,
                "statuses": statuses,
                "readmissions": readmissions,
            }),
        );
    }
    Ok(serde_json::Value::Object(out))
}

/// The step table as text (what `imu-fdi-sim parity-table` prints): pass
/// counts per IMU × axis, false alarms, and the delays.
pub fn format_step_table(kind: ArrayKind, size: f64, cases: &[StepCase], end_s: f64) -> String {
    use std::fmt::Write;
    let (unit, scale) = match kind {
        ArrayKind::Gyro => ("°/s", 180.0 / std::f64::consts::PI),
        ArrayKind::Accel => ("m/s²", 1.0),
    };
    let cases: Vec<_> = cases
        .iter()
        .filter(|c| c.injection.start + STEP_ISOLATE_WITHIN_S < end_s)
        .collect();
    let pass = |c: &StepCase| c.isolated && !c.false_alarm;
    let ok = cases.iter().filter(|c| pass(c)).count();
    let fa = cases.iter().filter(|c| c.false_alarm).count();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{kind:?} step {:.3} {unit}: {ok}/{} isolated to the right sensor within {STEP_ISOLATE_WITHIN_S} s with no other alarm; {fa} cases with a false alarm",
        size * scale,
        cases.len()
    );
    let _ = writeln!(s, "  {:>5} {:>9} {:>9} {:>9}", "", "x", "y", "z");
    for imu in 0..3 {
        let cells: Vec<String> = (0..3)
            .map(|axis| {
                let sel: Vec<_> = cases
                    .iter()
                    .filter(|c| c.injection.imu == imu && c.injection.channel % 3 == axis)
                    .collect();
                format!("{}/{}", sel.iter().filter(|c| pass(c)).count(), sel.len())
            })
            .collect();
        let _ = writeln!(
            s,
            "  imu{imu} {:>9} {:>9} {:>9}",
            cells[0], cells[1], cells[2]
        );
    }
    let mut d: Vec<f64> = cases.iter().filter_map(|c| c.delay).collect();
    d.sort_by(f64::total_cmp);
    if let (Some(first), Some(last)) = (d.first(), d.last()) {
        let _ = writeln!(
            s,
            "  isolation delay: median {:.1} s, range {first:.1}-{last:.1} s",
            d.get(d.len() / 2).copied().unwrap_or(f64::NAN)
        );
    }
    s
}

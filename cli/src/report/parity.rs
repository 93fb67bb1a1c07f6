//! The redundant-IMU side of the report: three IMUs through the parity
//! monitor (flight method: in-flight calibration, multi-scale GLR tests)
//! and the PX4-like / ArduPilot-like baselines, recorded per step by
//! `eval::parity_replay::replay_parity_observed`.

use anyhow::Result;
use hal_sim::array::ArrayKind;
use imu_fdi::parity::{ParityPhase, Reading, SensorStatus};

use crate::eval::parity_replay::{replay_parity_observed, ImuLog, ParityMethod, ParityStep};

use super::verdict::{State, Verdict, CHANNELS};
use super::{FlightReport, HLine, Marker, Plot, Runs, Series, Strip, Stroke, IMU_COLORS};

/// Text of a sensor status (table and timeline; no Rust debug names).
pub fn status_text(s: SensorStatus) -> &'static str {
    match s {
        SensorStatus::Healthy => "healthy",
        SensorStatus::Clipping => "clipping",
        SensorStatus::Missing => "missing sample",
        SensorStatus::OutOfRange => "out of range",
        SensorStatus::BusError => "bus error",
        SensorStatus::Stuck => "stuck (failed)",
        SensorStatus::Timeout => "timeout (failed)",
        SensorStatus::InvalidOutput => "invalid output (failed)",
        SensorStatus::BusFailure => "bus failure (failed)",
        SensorStatus::Railed => "railed (failed)",
        SensorStatus::ParityIsolated => "isolated by the parity test (failed)",
        SensorStatus::Probation => "on probation after a parity isolation (out of the set)",
    }
}

/// Options of the parity part.
#[derive(Debug, Clone, Copy)]
pub struct ParityOptions {
    /// Log time training starts, s (`None`: the first row).
    pub train_start: Option<f64>,
    /// Training + calibration length, s.
    pub train_s: f64,
}

/// Adds the parity and baseline plots, lanes and verdicts of a three-IMU
/// `log` to `report`; with fewer IMUs, "not judged" rows saying so.
pub fn add(log: &ImuLog, opts: ParityOptions, report: &mut FlightReport) -> Result<()> {
    if log.count != 3 {
        for k in 0..log.count {
            report.verdicts.extend(super::verdict::not_judged(
                k,
                "parity",
                &format!(
                    "the parity monitor needs three IMUs; the log has {}",
                    log.count
                ),
            ));
        }
        return Ok(());
    }
    let train_start = opts
        .train_start
        .unwrap_or_else(|| log.t.first().copied().unwrap_or(0.0));
    for kind in [ArrayKind::Accel, ArrayKind::Gyro] {
        add_kind(log, kind, train_start, opts.train_s, report)?;
    }
    Ok(())
}

fn add_kind(
    log: &ImuLog,
    kind: ArrayKind,
    train_start: f64,
    train_s: f64,
    report: &mut FlightReport,
) -> Result<()> {
    let gyro = kind == ArrayKind::Gyro;
    let (name, unit, scale, ch0) = if gyro {
        ("gyro", "°/s", 180.0 / std::f64::consts::PI, 3)
    } else {
        ("accel", "m/s²", 1.0, 0)
    };
    let axes = ["x", "y", "z"];
    let mut resid: Vec<Series> = (0..9)
        .map(|k| {
            Series::new(
                format!("IMU {} {}", k / 3, axes.get(k % 3).unwrap_or(&"")),
                IMU_COLORS.get(k / 3).copied().unwrap_or("#000"),
                Stroke::Solid,
            )
        })
        .collect();
    let mut ratio = Series::new("GLR score ÷ threshold", "#333333", Stroke::Solid);
    let mut alarm = Runs::default();
    let mut px4 = Runs::default();
    let mut ap = Runs::default();
    let mut lanes: Vec<Runs> = (0..3).map(|_| Runs::default()).collect();
    let mut failed: [Option<(f64, SensorStatus, f64)>; 9] = [None; 9];
    let mut suspected = [0usize; 9];
    let mut markers = Vec::new();
    let mut observe = |s: &ParityStep<'_>| {
        let r = s.report;
        let t = s.t;
        let fused = r.fused;
        for (k, series) in resid.iter_mut().enumerate() {
            let v = match (s.readings.get(k), fused) {
                (Some(Reading::Sample(x)), Some(f)) => f
                    .get(k % 3)
                    .map_or(f64::NAN, |fa| f64::from(*x - *fa) * scale),
                _ => f64::NAN,
            };
            series.push(t, v);
        }
        let monitoring = r.phase == ParityPhase::Monitoring;
        if monitoring && r.decision {
            ratio.push(t, f64::from(r.multiscale.ratio));
        }
        let who = |k: Option<usize>| {
            k.map_or(String::new(), |k| {
                format!(" (IMU {} {})", k / 3, axes.get(k % 3).unwrap_or(&""))
            })
        };
        alarm.see(
            t,
            (monitoring && r.fault).then_some(("parity alarm", "#d62728")),
        );
        if monitoring && r.fault {
            if let Some(c) = r.suspect.and_then(|k| suspected.get_mut(k)) {
                *c += 1;
            }
        }
        let px4_label = s.px4.map(|k| format!("PX4-like: IMU {k} blamed"));
        px4.see(t, px4_label.as_deref().map(|l| (l, "#ff7f0e")));
        ap.see(
            t,
            s.ardupilot
                .then_some(("ArduPilot-like: inconsistent", "#8c564b")),
        );
        for (imu, lane) in lanes.iter_mut().enumerate() {
            let bad: Vec<String> = (0..3)
                .filter_map(|a| {
                    let st = r.status.get(3 * imu + a).copied()?;
                    (st != SensorStatus::Healthy)
                        .then(|| format!("{}: {}", axes.get(a).unwrap_or(&""), status_text(st)))
                })
                .collect();
            let label = bad.join(", ");
            lane.see(t, (!bad.is_empty()).then_some((label.as_str(), "#e377c2")));
        }
        for (k, st) in r.status.iter().enumerate() {
            if st.is_failed() {
                if let Some(f) = failed.get_mut(k) {
                    // The monitor's bias estimate is its suspect's: quote
                    // it only for that sensor.
                    let bias = if r.suspect == Some(k) {
                        f64::from(r.bias_estimate) * scale
                    } else {
                        f64::NAN
                    };
                    f.get_or_insert((t, *st, bias));
                }
            }
        }
        if let Some(k) = r.isolated {
            markers.push(Marker {
                t_s: t,
                label: format!("isolated{}", who(Some(k))),
                color: "#d62728".into(),
            });
        }
    };
    let out = replay_parity_observed(
        log,
        kind,
        train_start,
        train_s,
        None,
        ParityMethod::Flight,
        &mut observe,
    )?;
    report.notes.push(format!(
        "parity monitor ({name}, flight method: in-flight calibration, multi-scale GLR) trained from {train_start:.2} s for {train_s:.0} s; {}; {} alarm(s), {} isolation(s); PX4-like alarms {}, ArduPilot-like alarms {}",
        out.monitoring_from
            .map_or("never monitoring: the log ends before training does".to_string(), |t| format!("monitoring from {t:.2} s")),
        out.alarms.len(),
        out.isolations.len(),
        out.px4.len(),
        out.ardupilot.len()
    ));
    // Verdicts, one per sensor.
    for (k, f) in failed.iter().enumerate() {
        let (state, since_s, why) = match (out.monitoring_from, f) {
            (_, Some((t, st, bias))) => (
                State::Faulty,
                Some(*t),
                if *st == SensorStatus::ParityIsolated && bias.is_finite() {
                    format!("{}; bias estimate {bias:+.3} {unit}", status_text(*st))
                } else {
                    status_text(*st).to_string()
                },
            ),
            (None, None) => (
                State::NotJudged,
                None,
                format!("the log ends before the parity training does ({train_s:.0} s from {train_start:.2} s)"),
            ),
            (Some(t), None) => (
                State::Healthy,
                Some(t),
                match suspected.get(k).copied().unwrap_or(0) {
                    0 => "monitored, never suspected or isolated".to_string(),
                    n => format!("never isolated; suspect of {n} alarm step(s) of the set"),
                },
            ),
        };
        report.verdicts.push(Verdict {
            imu: k / 3,
            channel: CHANNELS.get(ch0 + k % 3).copied().unwrap_or("").into(),
            monitor: "parity".into(),
            state,
            since_s,
            why,
        });
    }
    // Residual per axis: each IMU minus the fused value.
    let mut it = resid.into_iter();
    for a in axes {
        let mut p = Plot::new(
            format!("parity_{name}_{a}_residual"),
            format!("{name} {a}: each IMU minus the least-squares fused value (before in-flight calibration)"),
            unit,
        );
        for _ in 0..3 {
            if let Some(s) = it.next() {
                p.series.push(s);
            }
        }
        p.markers = markers
            .iter()
            .filter(|m| m.label.ends_with(&format!(" {a})")))
            .cloned()
            .collect();
        report.plots.push(p);
    }
    let mut p = Plot::new(
        format!("parity_{name}_test"),
        format!("{name} parity test: largest GLR score ÷ its threshold (alarm above 1), with the baselines' alarms"),
        "ratio",
    );
    p.series.push(ratio);
    p.hlines.push(HLine {
        y: 1.0,
        label: "threshold".into(),
    });
    p.markers = markers;
    p.strips = vec![
        Strip {
            name: "parity".into(),
            intervals: alarm.finish(),
        },
        Strip {
            name: "PX4-like".into(),
            intervals: px4.finish(),
        },
        Strip {
            name: "ArduPilot-like".into(),
            intervals: ap.finish(),
        },
    ];
    report.plots.push(p);
    for (imu, lane) in lanes.into_iter().enumerate() {
        report.timeline.lanes.push(Strip {
            name: format!("parity {name} IMU {imu}"),
            intervals: lane.finish(),
        });
    }
    Ok(())
}

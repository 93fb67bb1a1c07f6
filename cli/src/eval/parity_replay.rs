//! Replays logs of several synchronous IMUs (SPEC §10 columns
//! `imu{k}_{ax,ay,az,gx,gy,gz}`) through the parity monitor and the
//! autopilot baselines, optionally with a bias injected on one IMU channel.

use std::path::Path;

use anyhow::{bail, Context, Result};
use nalgebra::Matrix3;

use imu_fdi::parity::{
    Geometry, ParityConfig, ParityMonitor, ParityPhase, ParityReport, Reading, RestCheck,
    RestConfig, RestState, SensorStatus,
};

use hal_sim::array::ArrayKind;
use hal_sim::baseline::{ArduPilotLike, Px4Like};

const AXES: [&str; 6] = ["ax", "ay", "az", "gx", "gy", "gz"];
/// Most IMUs a replayed log may carry.
pub const MAX_IMUS: usize = 3;

/// The IMU rows of a log.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ImuLog {
    /// Time of each row, s (strictly increasing).
    pub t: Vec<f64>,
    /// Per row, per IMU: `[a_x, a_y, a_z, p, q, r]` (NaN where a cell was empty).
    pub imus: Vec<Vec<[f64; 6]>>,
    /// Number of IMUs found.
    pub count: usize,
    /// Rows skipped because their time did not increase (CSV), or 1 if a
    /// DataFlash log ends partway through a message.
    pub skipped: usize,
    /// What was skipped or could not be read, one line each, naming the
    /// file (for stderr).
    pub warnings: Vec<String>,
}

/// Reads a SPEC §10 CSV with `imu{k}_…` columns (k = 0, 1, …). Errors name
/// the file and line; rows with non-increasing `t` are skipped and counted.
pub fn read_imu_log(path: &Path) -> Result<ImuLog> {
    let (mut rdr, headers) = crate::io::log_import::open_csv(path)?;
    let find = |name: &str| headers.iter().position(|h| h == name);
    let t_col = find("t").with_context(|| format!("{}: no `t` column", path.display()))?;
    let mut cols: Vec<[usize; 6]> = Vec::new();
    for k in 0..MAX_IMUS {
        let idx: Vec<Option<usize>> = AXES.iter().map(|a| find(&format!("imu{k}_{a}"))).collect();
        match idx.iter().copied().collect::<Option<Vec<usize>>>() {
            Some(v) => cols.push([v[0], v[1], v[2], v[3], v[4], v[5]]),
            None if idx.iter().any(Option::is_some) => bail!(
                "{}: imu{k} has only some of imu{k}_ax … imu{k}_gz",
                path.display()
            ),
            None => break,
        }
    }
    if cols.len() < 2 {
        bail!(
            "{}: needs at least two IMUs (imu0_… and imu1_… columns)",
            path.display()
        );
    }
    let mut log = ImuLog {
        count: cols.len(),
        ..ImuLog::default()
    };
    use crate::io::csv_checks::{check_times, parse_cell, ColumnData};
    let names: Vec<Vec<String>> = (0..cols.len())
        .map(|k| AXES.iter().map(|a| format!("imu{k}_{a}")).collect())
        .collect();
    let mut data = ColumnData::new(names.iter().flatten().cloned().collect());
    let mut times = Vec::new();
    let mut first_skipped = None;
    let mut rows = crate::io::log_import::CsvRows::new(&mut rdr, path, headers.len());
    for row in rows.by_ref() {
        let (line, rec) = row?;
        let t = parse_cell(path, line, "t", rec.get(t_col))?;
        if t.is_finite() {
            times.push((line, t));
        }
        if !t.is_finite() || log.t.last().is_some_and(|last| t <= *last) {
            log.skipped += 1;
            first_skipped.get_or_insert(line);
            continue;
        }
        let mut row = Vec::with_capacity(cols.len());
        for (k, c) in cols.iter().enumerate() {
            let mut v = [0.0; 6];
            for (ch, (slot, i)) in v.iter_mut().zip(c.iter()).enumerate() {
                let name = &names[k][ch];
                let x = parse_cell(path, line, name, rec.get(*i))?;
                *slot = data.screen_imu(6 * k + ch, line, x);
            }
            row.push(v);
        }
        log.t.push(t);
        log.imus.push(row);
    }
    log.warnings.extend(rows.notes());
    check_times(path, "t", &times)?;
    if log.t.len() < 10 {
        bail!(
            "{}: fewer than 10 usable rows (a finite, increasing `t`)",
            path.display()
        );
    }
    data.check(path)?;
    log.warnings.extend(data.warning(path));
    if let Some(line) = first_skipped {
        log.warnings.push(format!(
            "{}: read {} rows up to t = {} s; skipped {} rows whose `t` is empty, NaN or does not \
             increase (the first at line {line})",
            path.display(),
            log.t.len(),
            log.t.last().copied().unwrap_or(0.0),
            log.skipped
        ));
    }
    Ok(log)
}

/// A bias added to one IMU channel from a time on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Injection {
    /// IMU index.
    pub imu: usize,
    /// Channel 0–5 `[a_x … r]`.
    pub channel: usize,
    /// Bias (m/s² or rad/s).
    pub size: f64,
    /// Onset, s (log time).
    pub start: f64,
    /// End (exclusive), s; `f64::INFINITY` for a bias that stays.
    pub end: f64,
}

/// What one replay produced for one sensor kind.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParityReplay {
    /// Log time training ended (monitoring began).
    pub monitoring_from: Option<f64>,
    /// Whether a bias present since power-up is judged
    /// ([`ParityConfig::judges_power_up_offsets`]).
    pub power_up_judged: bool,
    /// The rest check (gyros) found two or more gyros beyond the offset
    /// limit at rest: it could not judge, and named none.
    pub rest_common_mode: bool,
    /// Threshold factors `[GLT, PCA, CUSUM]` set by calibration.
    pub threshold_scales: [f64; 3],
    /// Training's correlation factor (block variance ÷ white-noise value).
    pub correlation_factor: f64,
    /// Alarm intervals of the monitor's decision (GLT or CUSUM):
    /// (start, end, suspect sensor at the start).
    pub alarms: Vec<(f64, f64, Option<usize>)>,
    /// Isolations (sensor = 3·imu + axis, time).
    pub isolations: Vec<(usize, f64)>,
    /// Re-admissions after a probation (sensor, time): sensors isolated by
    /// the multi-scale tests, or excluded by a hardware failure that ended;
    /// sensors judged together come back at the same time.
    pub readmissions: Vec<(usize, f64)>,
    /// First time each (sensor, non-healthy status) was seen.
    pub statuses: Vec<(usize, SensorStatus, f64)>,
    /// Spells after monitoring began in which the monitor could not judge
    /// (start, end, phase: `Lost`, `NoRedundancy`, or training again):
    /// "no alarm" does not cover them.
    pub not_judging: Vec<(f64, f64, ParityPhase)>,
    /// Common-mode saturation intervals (start, end, –).
    pub saturation: Vec<(f64, f64, Option<usize>)>,
    /// PX4-like alarm intervals (start, end, IMU blamed).
    pub px4: Vec<(f64, f64, Option<usize>)>,
    /// ArduPilot-like alarm intervals.
    pub ardupilot: Vec<(f64, f64, Option<usize>)>,
}

fn edge(
    list: &mut Vec<(f64, f64, Option<usize>)>,
    on: bool,
    was: &mut bool,
    t: f64,
    who: Option<usize>,
) {
    if on && !*was {
        list.push((t, t, who));
    }
    if on {
        if let Some(last) = list.last_mut() {
            last.1 = t;
        }
    }
    *was = on;
}

/// Replays `log` for gyros or accelerometers (three IMUs, board rotation
/// already applied: aligned triads) from `train_start`, training for
/// `train_s` seconds, with an optional injected bias.
pub fn replay_parity(
    log: &ImuLog,
    kind: ArrayKind,
    train_start: f64,
    train_s: f64,
    injection: Option<Injection>,
) -> Result<ParityReplay> {
    replay_parity_with(
        log,
        kind,
        train_start,
        train_s,
        injection,
        ParityMethod::Flight,
    )
}

/// Which parity tests a replay runs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum ParityMethod {
    /// [`ParityConfig::gyro_flight`]/[`ParityConfig::accel_flight`]: in-flight
    /// relative calibration and multi-scale tests with learned covariances.
    #[default]
    Flight,
    /// [`Flight`](Self::Flight) with the multi-scale tests' per-decision
    /// false-alarm probability replaced (flight default 1e-6): the one
    /// knob that trades sensitivity for false alarms
    /// (`scripts/parity-min-detectable.py`).
    FlightAt(f64),
    /// The simulator's defaults ([`ParityConfig::gyro`]): windowed χ² or
    /// CUSUM on 0.1 s blocks with calibrated thresholds (white-noise model).
    GltCusum,
}

/// [`replay_parity`] with a chosen method.
pub fn replay_parity_with(
    log: &ImuLog,
    kind: ArrayKind,
    train_start: f64,
    train_s: f64,
    injection: Option<Injection>,
    method: ParityMethod,
) -> Result<ParityReplay> {
    replay_parity_observed(
        log,
        kind,
        train_start,
        train_s,
        injection,
        method,
        &mut |_: &ParityStep<'_>| {},
    )
}

/// One step of a parity replay as [`replay_parity_observed`] hands it to
/// its observer (the flight report plots these).
#[derive(Debug, Clone, Copy)]
pub struct ParityStep<'a> {
    /// Log time, s.
    pub t: f64,
    /// The nine readings given to the monitor (sensor = 3·IMU + axis),
    /// injection included.
    pub readings: &'a [Reading<f32>; 9],
    /// The monitor's report of this step.
    pub report: &'a ParityReport<f32, 9>,
    /// PX4-like baseline: the IMU it blames this step.
    pub px4: Option<usize>,
    /// ArduPilot-like baseline: alarm this step.
    pub ardupilot: bool,
}

/// [`replay_parity_with`], calling `observe` after every step from
/// `train_start` on.
pub fn replay_parity_observed(
    log: &ImuLog,
    kind: ArrayKind,
    train_start: f64,
    train_s: f64,
    injection: Option<Injection>,
    method: ParityMethod,
    observe: &mut dyn FnMut(&ParityStep<'_>),
) -> Result<ParityReplay> {
    if log.count != 3 {
        bail!(
            "the parity replay needs three IMUs, the log has {}",
            log.count
        );
    }
    // Configured in samples from the logger's rate, not rows over span: a
    // gap or a clock jump anywhere must not change the replay before it.
    let Some(rate) = super::log_rate::sample_rate_hz(&log.t) else {
        bail!("the log has fewer than two rows with increasing time");
    };
    let (offset, fs) = match kind {
        ArrayKind::Gyro => (3, 2000.0_f64.to_radians()),
        ArrayKind::Accel => (0, 16.0 * imu_fdi::model::G0),
    };
    let cfg = match (kind, method) {
        (ArrayKind::Gyro, ParityMethod::Flight | ParityMethod::FlightAt(_)) => {
            let mut c = ParityConfig::<f32>::gyro_flight(rate, fs as f32);
            c.train_samples = (train_s * rate).round() as u32;
            c
        }
        (ArrayKind::Accel, ParityMethod::Flight | ParityMethod::FlightAt(_)) => {
            let mut c = ParityConfig::<f32>::accel_flight(rate, fs as f32);
            c.train_samples = (train_s * rate).round() as u32;
            c
        }
        (ArrayKind::Gyro, ParityMethod::GltCusum) => {
            let mut c = ParityConfig::<f32>::gyro(rate, fs as f32);
            // Two thirds train, one third calibrates the thresholds.
            c.train_samples = (train_s * rate * 2.0 / 3.0).round() as u32;
            c.calibrate_samples = (train_s * rate / 3.0).round() as u32;
            c
        }
        (ArrayKind::Accel, ParityMethod::GltCusum) => {
            let mut c = ParityConfig::<f32>::accel(rate, fs as f32);
            c.train_samples = (train_s * rate * 2.0 / 3.0).round() as u32;
            c.calibrate_samples = (train_s * rate / 3.0).round() as u32;
            c
        }
    };
    let mut cfg = cfg;
    if let ParityMethod::FlightAt(p) = method {
        cfg.multiscale.false_alarm = p;
    }
    let power_up_judged = cfg.judges_power_up_offsets();
    let geometry = Geometry::<f32, 9>::triads(&[Matrix3::identity(); 3])
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut monitor =
        ParityMonitor::<f32, 9, 40>::new(&geometry, cfg).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    // Gyro biases judged at rest (absolute means while the board is still):
    // the gyro monitor of a real flight, whose offset limit it shares.
    let mut rest = match (kind, method) {
        (ArrayKind::Gyro, ParityMethod::Flight | ParityMethod::FlightAt(_)) => Some(
            RestCheck::<f32, 9>::new(
                &geometry,
                &geometry,
                RestConfig::new(rate, cfg.multiscale.offset_limit),
            )
            .map_err(|e| anyhow::anyhow!("{e:?}"))?,
        ),
        _ => None,
    };
    let mut px4 = Px4Like::<3>::new(kind == ArrayKind::Gyro);
    let mut ap = ArduPilotLike::new(kind == ArrayKind::Gyro);
    let mut out = ParityReplay {
        power_up_judged,
        ..ParityReplay::default()
    };
    let (mut was, mut was_sat, mut was_px4, mut was_ap) = (false, false, false, false);
    let mut was_off = false;
    let mut prev_t = None;
    for (t, row) in log.t.iter().zip(log.imus.iter()) {
        if *t < train_start {
            continue;
        }
        let value = |imu: usize, axis: usize| -> f64 {
            let ch = offset + axis;
            let mut v = row
                .get(imu)
                .and_then(|r| r.get(ch))
                .copied()
                .unwrap_or(f64::NAN);
            if let Some(inj) = injection {
                if inj.imu == imu && inj.channel == ch && *t >= inj.start && *t < inj.end {
                    v += inj.size;
                }
            }
            v
        };
        let readings: [Reading<f32>; 9] = core::array::from_fn(|i| {
            let v = value(i / 3, i % 3);
            if v.is_nan() {
                Reading::Missing
            } else {
                Reading::Sample(v as f32)
            }
        });
        if let Some(rest) = rest.as_mut() {
            let accel: [Reading<f32>; 9] =
                core::array::from_fn(|i| match row.get(i / 3).and_then(|r| r.get(i % 3)) {
                    Some(v) if !v.is_nan() => Reading::Sample(*v as f32),
                    _ => Reading::Missing,
                });
            let verdict = rest.step(&readings, &accel, monitor.space().active());
            if let Some(k) = verdict.isolate.filter(|k| monitor.isolate_external(*k)) {
                out.isolations.push((k, *t));
            }
            if verdict.state == RestState::CommonMode && !out.rest_common_mode {
                out.rest_common_mode = true;
            }
        }
        let r = monitor.step(&readings);
        if out.monitoring_from.is_none() && r.phase == ParityPhase::Monitoring {
            out.monitoring_from = Some(*t);
        }
        for (k, st) in r.status.iter().enumerate() {
            if *st != SensorStatus::Healthy
                && !out.statuses.iter().any(|(j, s, _)| *j == k && s == st)
            {
                out.statuses.push((k, *st, *t));
            }
        }
        if let Some(k) = r.isolated {
            out.isolations.push((k, *t));
        }
        if r.readmitted.is_some() {
            // Sensors judged together (one IMU's axes failed in the same
            // period) come back together: each one on probation until now.
            for (k, st) in r.status.iter().enumerate() {
                if *st == SensorStatus::Probation {
                    out.readmissions.push((k, *t));
                }
            }
        }
        if out.monitoring_from.is_some() {
            edge(&mut out.alarms, r.fault, &mut was, *t, r.suspect);
            let off = r.phase != ParityPhase::Monitoring;
            if off && !was_off {
                out.not_judging.push((*t, *t, r.phase));
            }
            if let Some(last) = out.not_judging.last_mut().filter(|_| off) {
                last.1 = *t;
            }
            was_off = off;
        }
        edge(
            &mut out.saturation,
            r.common_mode_saturation,
            &mut was_sat,
            *t,
            None,
        );
        // Baselines on the IMU vectors.
        let units: [[f64; 3]; 3] = core::array::from_fn(|k| core::array::from_fn(|a| value(k, a)));
        let mean: [f64; 3] =
            core::array::from_fn(|a| units.iter().map(|u| u[a]).sum::<f64>() / 3.0);
        let dev: [[f64; 3]; 3] =
            core::array::from_fn(|k| core::array::from_fn(|a| units[k][a] - mean[a]));
        let diff: Vec<[f64; 3]> = units
            .iter()
            .map(|u| core::array::from_fn(|a| u[a] - units[0][a]))
            .collect();
        let dt = prev_t.map_or(1.0 / rate, |p| t - p);
        prev_t = Some(*t);
        let blame = px4.step(&dev, dt);
        edge(&mut out.px4, blame.is_some(), &mut was_px4, *t, blame);
        let alarm = ap.step(&diff, *t);
        edge(&mut out.ardupilot, alarm, &mut was_ap, *t, None);
        observe(&ParityStep {
            t: *t,
            readings: &readings,
            report: &r,
            px4: blame,
            ardupilot: alarm,
        });
    }
    out.threshold_scales = monitor.threshold_scales().map(f64::from);
    out.correlation_factor = monitor
        .baseline()
        .map_or(1.0, |b| f64::from(b.correlation_factor));
    Ok(out)
}

/// Reads a multi-IMU log by its extension: `.csv` (SPEC §10 columns) or
/// `.bin` (ArduPilot DataFlash). Anything else is an error naming the file.
pub fn read_any_imu_log(path: &Path) -> Result<ImuLog> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("csv") => read_imu_log(path),
        Some("bin") => read_dataflash(path),
        _ => bail!(
            "{}: unknown file type (expected .csv in the SPEC §10 format or an ArduPilot DataFlash .bin)",
            path.display()
        ),
    }
}

pub use super::dataflash_imus::{read_dataflash, read_dataflash_imus};
pub use super::parity_injection::{
    injection_sizes, injection_sweep, InjectionResult, DETECT_WITHIN_S,
};
pub use super::parity_tables::{
    format_step_table, power_up_table, replay_json, step_table, PowerUpCase, StepCase,
    STEP_ISOLATE_WITHIN_S,
};

//! The parity monitor for real flights on the realistic simulated profile
//! ([`hal_sim::realistic`], fitted to log171): fault-free hours for the
//! false-alarm rate, and steps of a given size on every IMU and axis for
//! the detection rate, so the figures a user reads are not white-noise
//! figures (issue 14).

use anyhow::{anyhow, Result};
use nalgebra::Matrix3;
use rayon::prelude::*;

use imu_fdi::parity::{
    Geometry, ParityConfig, ParityMonitor, ParityPhase, RestCheck, RestConfig, RestState,
};

use hal_sim::array::ArrayKind;
use hal_sim::realistic::{ChannelFault, RealisticArray, RealisticProfile};

/// Seconds of flight the monitor trains on.
pub const TRAIN_S: f64 = 30.0;
/// Seconds within which a step must be isolated.
pub const ISOLATE_WITHIN_S: f64 = 10.0;

/// What a fault-free realistic flight produced.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FaultFree {
    /// Monitored hours.
    pub hours: f64,
    /// Alarm events (rising edges of the fault flag).
    pub alarm_events: usize,
    /// Sensors isolated (all healthy here).
    pub isolations: usize,
    /// Isolated sensors re-admitted after their probation.
    pub readmissions: usize,
    /// Seconds the gyro rest check judged the vehicle at rest (the
    /// realistic profile flies throughout: any is a false rest).
    pub at_rest_s: f64,
    /// The alarm events, flight by flight.
    pub events: Vec<AlarmEvent>,
}

/// What the steps of one size produced.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Steps {
    /// Cases run (IMU × axis × sign × seed).
    pub cases: usize,
    /// Isolated to the right sensor within [`ISOLATE_WITHIN_S`], no other
    /// alarm in the flight.
    pub isolated: usize,
    /// Cases with an alarm outside the fault or a healthy sensor isolated.
    pub false_alarms: usize,
    /// Detected: an alarm rose within [`ISOLATE_WITHIN_S`] of onset, no
    /// other alarm in the flight (isolated or not).
    pub detected: usize,
    /// Delays of the isolations, s (sorted).
    pub delays: Vec<f64>,
}

/// The flight configuration of `kind` at `rate`; `false_alarm` replaces
/// the multi-scale tests' per-decision false-alarm probability.
fn config(kind: ArrayKind, rate: f64, false_alarm: Option<f64>) -> ParityConfig<f32> {
    let mut cfg = match kind {
        ArrayKind::Gyro => ParityConfig::gyro_flight(rate, 2000f32.to_radians()),
        ArrayKind::Accel => ParityConfig::accel_flight(rate, 16.0 * imu_fdi::model::G0 as f32),
    };
    if let Some(p) = false_alarm {
        cfg.multiscale.false_alarm = p;
    }
    cfg
}

/// One alarm event of a flight, with what the monitor saw and what the
/// simulation knows.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AlarmEvent {
    /// Seed of the flight.
    pub seed: u64,
    /// Rising edge of the fault flag, s of flight.
    pub t: f64,
    /// Seconds since monitoring began.
    pub since_monitoring: f64,
    /// Largest score ÷ threshold while the alarm held.
    pub ratio: f64,
    /// Window length of that score, s.
    pub window_s: f64,
    /// Sensor whose bias hypothesis explained that window best.
    pub suspect: usize,
    /// Its estimated bias (°/s or m/s²).
    pub bias: f64,
    /// First sensor isolated while the alarm held, if any.
    pub isolated: Option<usize>,
    /// The suspect's simulated relative bias (its bias-instability state and
    /// thermal drift minus the mean of the other two IMUs') at that score,
    /// minus its mean over the 2 minutes before (the calibration's
    /// memory), °/s or m/s²: how far the healthy sensor had really drifted.
    pub true_drift: f64,
}

/// Alarm start times, isolations `(sensor, t)`, monitored seconds, seconds
/// judged at rest, the alarm events and the re-admissions of one flight.
type Flight = (
    Vec<f64>,
    Vec<(usize, f64)>,
    f64,
    f64,
    Vec<AlarmEvent>,
    usize,
);

/// Seconds of simulated truth kept for [`AlarmEvent::true_drift`].
const TRUTH_MEMORY_S: f64 = 120.0;

/// Each sensor's simulated relative bias (its IMU minus the mean of the
/// other two), in °/s or m/s², sensor `3·IMU + axis`.
fn relative_biases(sim: &RealisticArray, kind: ArrayKind) -> [f64; 9] {
    let b = sim.biases();
    let (first, unit) = match kind {
        ArrayKind::Gyro => (3, 1f64.to_radians()),
        ArrayKind::Accel => (0, 1.0),
    };
    core::array::from_fn(|s| {
        let (imu, ch) = (s / 3, first + s % 3);
        let at = |i: usize| b.get(i).and_then(|c| c.get(ch)).copied().unwrap_or(0.0);
        let others = (0..3).filter(|&i| i != imu).map(at).sum::<f64>() / 2.0;
        (at(imu) - others) / unit
    })
}

/// One flight through the monitor: alarm starts after monitoring began,
/// isolations `(sensor, t)`, monitored seconds.
fn run(
    kind: ArrayKind,
    profile: &RealisticProfile,
    seed: u64,
    fault: Option<ChannelFault>,
    false_alarm: Option<f64>,
) -> Result<Flight> {
    let geometry = Geometry::<f32, 9>::triads(&[Matrix3::identity(); 3])
        .map_err(|e| anyhow!("array geometry: {e:?}"))?;
    let mut cfg = config(kind, profile.log_hz, false_alarm);
    cfg.train_samples = (TRAIN_S * profile.log_hz).round() as u32;
    let mut monitor = ParityMonitor::<f32, 9, 40>::new(&geometry, cfg)
        .map_err(|e| anyhow!("parity configuration: {e:?}"))?;
    let mut sim = RealisticArray::new(profile, seed);
    if let Some(f) = fault {
        sim = sim.with_fault(f);
    }
    // The gyros' rest check, as `parity-replay` runs it.
    let mut rest = match kind {
        ArrayKind::Gyro => Some(
            RestCheck::<f32, 9>::new(
                &geometry,
                &geometry,
                RestConfig::new(profile.log_hz, cfg.multiscale.offset_limit),
            )
            .map_err(|e| anyhow!("rest check: {e:?}"))?,
        ),
        ArrayKind::Accel => None,
    };
    let mut at_rest = 0usize;
    let unit = match kind {
        ArrayKind::Gyro => 1f64.to_radians(),
        ArrayKind::Accel => 1.0,
    };
    let block_s = f64::from(cfg.block_len) / profile.log_hz;
    let (mut alarms, mut isolations, mut events) = (Vec::new(), Vec::new(), Vec::new());
    let mut readmissions = 0;
    let mut truth: std::collections::VecDeque<(f64, [f64; 9])> = Default::default();
    let mut open: Option<AlarmEvent> = None;
    let (mut was, mut from, mut last) = (false, None, 0.0);
    while let Some(row) = sim.next() {
        let readings = row.readings(kind).map(|r| r.map(|v| v as f32));
        if let Some(rest) = rest.as_mut() {
            let accel = row.readings(ArrayKind::Accel).map(|r| r.map(|v| v as f32));
            let verdict = rest.step(&readings, &accel, monitor.space().active());
            if verdict.state != RestState::Moving {
                at_rest += 1;
            }
            if let Some(k) = verdict.isolate.filter(|k| monitor.isolate_external(*k)) {
                isolations.push((k, row.t));
            }
        }
        let r = monitor.step(&readings);
        last = row.t;
        truth.push_back((row.t, relative_biases(&sim, kind)));
        while truth
            .front()
            .is_some_and(|(t, _)| *t < row.t - TRUTH_MEMORY_S)
        {
            truth.pop_front();
        }
        if from.is_none() && r.phase == ParityPhase::Monitoring {
            from = Some(row.t);
        }
        if let (Some(f), true, false) = (from, r.fault, was) {
            alarms.push(row.t);
            if let Some(e) = open.take() {
                events.push(e);
            }
            open = Some(AlarmEvent {
                seed,
                t: row.t,
                since_monitoring: row.t - f,
                ..AlarmEvent::default()
            });
        }
        was = r.fault;
        if let Some(k) = r.isolated {
            isolations.push((k, row.t));
        }
        readmissions += usize::from(r.readmitted.is_some());
        if let Some(e) = open.as_mut() {
            let m = r.multiscale;
            if r.fault && f64::from(m.ratio) > e.ratio {
                let k = m.suspect.unwrap_or(0);
                let rel = |x: &[f64; 9]| x.get(k).copied().unwrap_or(0.0);
                let past: Vec<f64> = truth.iter().map(|(_, x)| rel(x)).collect();
                let mean = past.iter().sum::<f64>() / past.len().max(1) as f64;
                e.ratio = f64::from(m.ratio);
                e.window_s = cfg
                    .multiscale
                    .scales
                    .get(m.scale)
                    .map_or(0.0, |&n| f64::from(n) * block_s);
                e.suspect = k;
                e.bias = f64::from(m.bias) / unit;
                e.true_drift = truth.back().map_or(0.0, |(_, x)| rel(x)) - mean;
            }
            if e.isolated.is_none() {
                e.isolated = r.isolated;
            }
            if !r.fault {
                events.extend(open.take());
            }
        }
    }
    events.extend(open);
    let rest_s = at_rest as f64 / profile.log_hz;
    Ok((
        alarms,
        isolations,
        from.map_or(0.0, |f| last - f),
        rest_s,
        events,
        readmissions,
    ))
}

/// `hours` of fault-free realistic flight, split into one-hour flights
/// (seeds `seed..`), run on every core.
pub fn fault_free(kind: ArrayKind, hours: u32, seed: u64) -> Result<FaultFree> {
    fault_free_on(&RealisticProfile::log171(), kind, hours, seed)
}

/// [`fault_free`] on another profile (e.g. `RealisticProfile::log171().integrated()`:
/// the IMUs read as a FIFO driver integrates them, not point-sampled).
pub fn fault_free_on(
    profile: &RealisticProfile,
    kind: ArrayKind,
    hours: u32,
    seed: u64,
) -> Result<FaultFree> {
    fault_free_flights_on(profile, kind, hours, 1, seed, None)
}

/// [`fault_free_on`] with `flights` flights of `flight_hours` hours each
/// (seeds `seed..`): what the monitor learns over more than an hour (e.g.
/// the vibration law's level, docs/parity-real-flights.md) only shows in
/// flights that long. `false_alarm` replaces the multi-scale tests'
/// per-decision false-alarm probability (`None`: the flight default).
pub fn fault_free_flights_on(
    profile: &RealisticProfile,
    kind: ArrayKind,
    flights: u32,
    flight_hours: u32,
    seed: u64,
    false_alarm: Option<f64>,
) -> Result<FaultFree> {
    let profile = profile.with_duration(3600.0 * f64::from(flight_hours) + TRAIN_S);
    let runs: Vec<_> = (0..u64::from(flights))
        .into_par_iter()
        .map(|i| run(kind, &profile, seed + i, None, false_alarm))
        .collect::<Result<_>>()?;
    Ok(runs
        .iter()
        .fold(FaultFree::default(), |mut acc, (a, iso, s, r, ev, back)| {
            acc.hours += s / 3600.0;
            acc.alarm_events += a.len();
            acc.isolations += iso.len();
            acc.readmissions += back;
            acc.at_rest_s += r;
            acc.events.extend_from_slice(ev);
            acc
        }))
}

/// Onset of the steps of [`steps`], s of flight: 30 s into monitoring, in
/// the loiter/acro cycle.
pub const STEP_ONSET_S: f64 = 60.0;

/// Steps of `size` (rad/s or m/s²) lasting 15 s on every IMU × axis × sign
/// of `kind`, `seeds` rounds of them, one realistic flight per case (onset
/// [`STEP_ONSET_S`], flight 100 s), each with its own seed from `seed` on.
pub fn steps(kind: ArrayKind, size: f64, seeds: u64, seed: u64) -> Result<Steps> {
    steps_on(
        &RealisticProfile::log171(),
        kind,
        size,
        seeds,
        seed,
        STEP_ONSET_S,
        None,
    )
}

/// [`steps`] on another profile, with the onset at `onset` s of flight
/// (the flight lasts until 40 s after it). A later onset judges the steps
/// against the covariances learnt in flight rather than those of the
/// first minute after training, which lack the sensors' slow wander
/// (docs/parity-real-flights.md). `false_alarm` as in
/// [`fault_free_flights_on`].
pub fn steps_on(
    profile: &RealisticProfile,
    kind: ArrayKind,
    size: f64,
    seeds: u64,
    seed: u64,
    onset: f64,
    false_alarm: Option<f64>,
) -> Result<Steps> {
    let profile = profile.with_duration(onset + 40.0);
    let channel0 = match kind {
        ArrayKind::Gyro => 3,
        ArrayKind::Accel => 0,
    };
    // Every case flies its own seed: the same flight under every step
    // would count one early false alarm eighteen times.
    let mut jobs = Vec::new();
    for s in 0..seeds {
        for imu in 0..3 {
            for axis in 0..3 {
                for sign in [1.0, -1.0] {
                    let case = jobs.len() as u64;
                    jobs.push((seed + case, imu, axis, sign));
                }
            }
        }
        let _ = s;
    }
    let results: Vec<_> = jobs
        .par_iter()
        .map(|&(sd, imu, axis, sign)| {
            let fault = ChannelFault::bias(imu, channel0 + axis, onset, onset + 15.0, sign * size);
            let (alarms, iso, _, _, _, _) = run(kind, &profile, sd, Some(fault), false_alarm)?;
            let sensor = 3 * imu + axis;
            let hit = iso
                .iter()
                .find(|(k, t)| *k == sensor && *t >= onset && *t < onset + ISOLATE_WITHIN_S)
                .map(|(_, t)| t - onset);
            let wrong = iso.iter().any(|(k, _)| *k != sensor);
            let outside = alarms.iter().any(|t| *t < onset || *t > onset + 15.0);
            let alarmed = alarms
                .iter()
                .any(|t| *t >= onset && *t < onset + ISOLATE_WITHIN_S);
            Ok((hit, alarmed, wrong || outside))
        })
        .collect::<Result<_>>()?;
    let mut out = Steps {
        cases: results.len(),
        ..Steps::default()
    };
    for (hit, alarmed, fa) in results {
        if fa {
            out.false_alarms += 1;
            continue;
        }
        if alarmed || hit.is_some() {
            out.detected += 1;
        }
        if let Some(d) = hit {
            out.isolated += 1;
            out.delays.push(d);
        }
    }
    out.delays.sort_by(f64::total_cmp);
    Ok(out)
}

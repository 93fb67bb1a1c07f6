//! Runs a redundant array through the parity monitor and the autopilot
//! baselines side by side, and scores each (SPEC §9: first correct alarm,
//! false-alarm events, isolation).

use anyhow::{bail, Result};
use nalgebra::{SVector, Vector3};

use imu_fdi::math::Real;
use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, ParityPhase, Reading, SensorStatus};

use hal_sim::array::{ArrayKind, ArraySim, ArraySpec, Layout};
use hal_sim::baseline::{ArduPilotLike, Px4Like};

/// Window capacity (blocks) of the monitors the runner builds.
pub const WINDOW: usize = 32;

/// Score of one detection method on one run.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct MethodOutcome {
    /// Scenario time of the first alarm while a fault is active.
    pub first_alarm: Option<f64>,
    /// Rising edges of the alarm while no fault is active (scenario time ≥ 0).
    pub false_alarm_events: u32,
    /// Unit (sensor, or IMU for triad baselines) blamed at the first alarm.
    pub blamed: Option<usize>,
}

impl MethodOutcome {
    fn record(&mut self, alarm: bool, was: &mut bool, faulty: bool, t: f64, blamed: Option<usize>) {
        if alarm && !*was && !faulty {
            self.false_alarm_events += 1;
        }
        if alarm && faulty && self.first_alarm.is_none() {
            self.first_alarm = Some(t);
            self.blamed = blamed;
        }
        *was = alarm;
    }
}

/// Everything one array run produced.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayRun {
    /// \[PAR\] PCA pattern test.
    pub pca: MethodOutcome,
    /// Windowed χ².
    pub glt: MethodOutcome,
    /// CUSUMs.
    pub cusum: MethodOutcome,
    /// PX4-like baseline.
    pub px4: MethodOutcome,
    /// ArduPilot-like baseline.
    pub ardupilot: MethodOutcome,
    /// First isolation: sensor and scenario time.
    pub isolated: Option<(usize, f64)>,
    /// Sensors isolated or failed by the end, with their status.
    pub failed: Vec<(usize, SensorStatus)>,
    /// Every non-healthy status seen per sensor (first time seen).
    pub statuses_seen: Vec<(usize, SensorStatus, f64)>,
    /// Fault-free monitored time, s.
    pub fault_free_s: f64,
    /// RMS error of the fused output while fault-free (unit).
    pub fused_rms_fault_free: f64,
    /// RMS error of the fused output from 0.5 s after isolation (unit).
    pub fused_rms_after_isolation: Option<f64>,
    /// RMS of (fused − least squares of the truly healthy sensors, `f64`)
    /// while fault-free: the monitor's fusion itself (f32 round-off).
    pub fused_vs_healthy_fault_free: f64,
    /// The same while a fault is active on a sensor the parity test has not
    /// isolated: what the fault does to the output before isolation (and,
    /// for hardware faults, whether the health checks kept it out).
    pub fused_vs_healthy_before_isolation: Option<f64>,
    /// The same once every faulty sensor is isolated (from 0.5 s after the
    /// latest isolation).
    pub fused_vs_healthy_after_isolation: Option<f64>,
    /// Sensors isolated, in order, with scenario time.
    pub isolations: Vec<(usize, f64)>,
    /// Training's correlation factor (1 = white).
    pub correlation_factor: f64,
}

/// Runs `spec` with `seed` through a parity monitor in `T` configured by
/// `cfg` (training length is set from the spec's lead-in) and through both
/// baselines.
pub fn run_array<T: Real, const N: usize>(
    spec: &ArraySpec<N>,
    seed: u64,
    mut cfg: ParityConfig<T>,
) -> Result<ArrayRun> {
    let dirs: [[T; 3]; N] = spec.directions.map(|d| d.map(T::lit));
    let geometry = Geometry::<T, N>::new(&dirs).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let geometry64 =
        Geometry::<f64, N>::new(&spec.directions).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let sim = ArraySim::new(spec, seed);
    cfg.set_lead_in(sim.lead_in_samples());
    let mut monitor =
        ParityMonitor::<T, N, WINDOW>::new(&geometry, cfg).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let gyro = spec.kind == ArrayKind::Gyro;
    let units = match spec.layout {
        Layout::Single => N,
        Layout::Triads => N / 3,
    };
    let mut px4 = Px4Dyn::new(units, gyro);
    let mut ap = ArduPilotLike::new(gyro);
    let dt = 1.0 / spec.rate_hz;
    let onset = spec
        .faults
        .iter()
        .map(|f| f.start)
        .fold(f64::INFINITY, f64::min);

    let mut out = ArrayRun {
        pca: MethodOutcome::default(),
        glt: MethodOutcome::default(),
        cusum: MethodOutcome::default(),
        px4: MethodOutcome::default(),
        ardupilot: MethodOutcome::default(),
        isolated: None,
        failed: Vec::new(),
        statuses_seen: Vec::new(),
        fault_free_s: 0.0,
        fused_rms_fault_free: 0.0,
        fused_rms_after_isolation: None,
        correlation_factor: 1.0,
        fused_vs_healthy_fault_free: 0.0,
        fused_vs_healthy_before_isolation: None,
        fused_vs_healthy_after_isolation: None,
        isolations: Vec::new(),
    };
    let mut rel = [(0.0, 0u64); 3];
    let mut was = [false; 5];
    let (mut ff_sum, mut ff_n) = (0.0, 0u64);
    let (mut iso_sum, mut iso_n) = (0.0, 0u64);
    let mut trained = false;
    for s in sim {
        let readings: [Reading<T>; N] = s.readings.map(|r| r.map(T::lit));
        let report = monitor.step(&readings);
        for (k, st) in report.status.iter().enumerate() {
            if *st != SensorStatus::Healthy
                && !out.statuses_seen.iter().any(|(j, x, _)| *j == k && x == st)
            {
                out.statuses_seen.push((k, *st, s.t));
            }
        }
        if s.training {
            continue;
        }
        if !trained {
            if matches!(
                report.phase,
                ParityPhase::Training | ParityPhase::Calibrating
            ) {
                bail!("{}: training did not finish in the lead-in", spec.name);
            }
            trained = true;
            out.correlation_factor = monitor
                .baseline()
                .map_or(1.0, |b| b.correlation_factor.to_f64());
        }
        let faulty = s.fault_active.iter().any(|a| *a) && s.t >= onset;
        let err = report.fused.map(|f| {
            let d = Vector3::new(f.x.to_f64(), f.y.to_f64(), f.z.to_f64())
                - Vector3::new(s.truth[0], s.truth[1], s.truth[2]);
            d.norm_squared()
        });
        if !faulty {
            out.fault_free_s += dt;
            if let Some(e) = err {
                ff_sum += e;
                ff_n += 1;
            }
        }
        if let Some(k) = report.isolated {
            out.isolated.get_or_insert((k, s.t));
            out.isolations.push((k, s.t));
        }
        let healthy: [bool; N] = core::array::from_fn(|i| {
            !s.fault_active.get(i).copied().unwrap_or(true)
                && matches!(s.readings.get(i), Some(Reading::Sample(x)) if x.is_finite())
        });
        let m64 = SVector::<f64, N>::from_fn(|i, _| match s.readings.get(i) {
            Some(Reading::Sample(x)) if x.is_finite() => *x,
            _ => 0.0,
        });
        if let (Some(f), Some(h)) = (report.fused, least_squares(&geometry64, &m64, &healthy)) {
            let d = (Vector3::new(f.x.to_f64(), f.y.to_f64(), f.z.to_f64()) - h).norm_squared();
            // Slots: fault-free; a fault active on a sensor the parity test
            // has not isolated; every faulty sensor isolated (0.5 s ago).
            let pending = s
                .fault_active
                .iter()
                .enumerate()
                .any(|(k, a)| *a && !out.isolations.iter().any(|(j, _)| *j == k));
            let last = out.isolations.last().map_or(f64::NEG_INFINITY, |(_, t)| *t);
            let slot = if !faulty {
                Some(0)
            } else if pending {
                Some(1)
            } else if s.t >= last + 0.5 {
                Some(2)
            } else {
                None
            };
            if let Some(acc) = slot.and_then(|i| rel.get_mut(i)) {
                acc.0 += d;
                acc.1 += 1;
            }
        }
        if let (Some((_, ti)), Some(e)) = (out.isolated, err) {
            if s.t >= ti + 0.5 {
                iso_sum += e;
                iso_n += 1;
            }
        }
        if report.decision || report.isolated.is_some() {
            let [w0, w1, w2, ..] = &mut was;
            out.pca
                .record(report.flags.pca, w0, faulty, s.t, report.suspect);
            out.glt.record(
                report.flags.glt || report.isolated.is_some(),
                w1,
                faulty,
                s.t,
                report.isolated.or(report.suspect),
            );
            out.cusum.record(
                report.flags.cusum || report.isolated.is_some(),
                w2,
                faulty,
                s.t,
                report.isolated.or(report.suspect),
            );
        }
        // Baselines see the raw samples (a missing one holds the last).
        let m = SVector::<f64, N>::from_fn(|i, _| match s.readings.get(i) {
            Some(Reading::Sample(x)) if x.is_finite() => *x,
            _ => 0.0,
        });
        let (dev, diff) = deviations(&geometry64, spec.layout, &m);
        let px4_alarm = px4.step(&dev, dt);
        let [_, _, _, w3, w4] = &mut was;
        out.px4
            .record(px4_alarm.is_some(), w3, faulty, s.t, px4_alarm);
        let ap_alarm = ap.step(&diff, s.t);
        out.ardupilot.record(ap_alarm, w4, faulty, s.t, None);
    }
    let rms = |(sum, n): (f64, u64)| (n > 0).then(|| (sum / n as f64).sqrt());
    out.fused_vs_healthy_fault_free = rms(rel[0]).unwrap_or(0.0);
    out.fused_vs_healthy_before_isolation = rms(rel[1]);
    out.fused_vs_healthy_after_isolation = rms(rel[2]);
    out.fused_rms_fault_free = (ff_sum / ff_n.max(1) as f64).sqrt();
    out.fused_rms_after_isolation = (iso_n > 0).then(|| (iso_sum / iso_n as f64).sqrt());
    for (k, st) in monitor.space().active().iter().enumerate() {
        if !st {
            out.failed.push((k, SensorStatus::ParityIsolated));
        }
    }
    Ok(out)
}

/// Least squares over the sensors marked, `None` below rank 3.
fn least_squares<const N: usize>(
    g: &Geometry<f64, N>,
    m: &SVector<f64, N>,
    mask: &[bool; N],
) -> Option<Vector3<f64>> {
    let mut gm = nalgebra::Matrix3::<f64>::zeros();
    let mut hm = Vector3::<f64>::zeros();
    for k in (0..N).filter(|k| mask[*k]) {
        let h = g.direction(k)?;
        gm += h * h.transpose();
        hm += h * m[k];
    }
    let inv = gm.try_inverse()?;
    (gm.determinant().abs() > 1e-9).then(|| inv * hm)
}

/// Per-unit deviation from the mean (PX4) and difference from unit 0
/// (ArduPilot), as body-frame vectors for triads or scalar residuals in
/// the first slot for single sensors.
fn deviations<const N: usize>(
    g: &Geometry<f64, N>,
    layout: Layout,
    m: &SVector<f64, N>,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    match layout {
        Layout::Triads => {
            let units: Vec<Vector3<f64>> = (0..N / 3)
                .map(|k| {
                    (0..3)
                        .map(|j| g.direction(3 * k + j).unwrap_or_default() * m[3 * k + j])
                        .sum()
                })
                .collect();
            let mean: Vector3<f64> = units.iter().sum::<Vector3<f64>>() / units.len().max(1) as f64;
            let first = units.first().copied().unwrap_or_default();
            (
                units.iter().map(|u| (u - mean).into()).collect(),
                units.iter().map(|u| (u - first).into()).collect(),
            )
        }
        Layout::Single => {
            let all = [true; N];
            let residual = |mask: &[bool; N], i: usize| {
                let x = least_squares(g, m, mask).unwrap_or_default();
                m[i] - g.direction(i).unwrap_or_default().dot(&x)
            };
            let dev = (0..N).map(|i| [residual(&all, i), 0.0, 0.0]).collect();
            let diff = (0..N)
                .map(|i| {
                    let mut others = all;
                    others[i] = false;
                    [residual(&others, i), 0.0, 0.0]
                })
                .collect();
            (dev, diff)
        }
    }
}

/// [`Px4Like`] for a unit count known only at run time (up to 9).
enum Px4Dyn {
    U2(Px4Like<2>),
    U3(Px4Like<3>),
    U6(Px4Like<6>),
    U9(Px4Like<9>),
}

impl Px4Dyn {
    fn new(units: usize, gyro: bool) -> Self {
        match units {
            2 => Self::U2(Px4Like::new(gyro)),
            3 => Self::U3(Px4Like::new(gyro)),
            6 => Self::U6(Px4Like::new(gyro)),
            _ => Self::U9(Px4Like::new(gyro)),
        }
    }

    fn step(&mut self, dev: &[[f64; 3]], dt: f64) -> Option<usize> {
        fn arr<const U: usize>(dev: &[[f64; 3]]) -> [[f64; 3]; U] {
            core::array::from_fn(|i| dev.get(i).copied().unwrap_or([0.0; 3]))
        }
        match self {
            Self::U2(p) => p.step(&arr(dev), dt),
            Self::U3(p) => p.step(&arr(dev), dt),
            Self::U6(p) => p.step(&arr(dev), dt),
            Self::U9(p) => p.step(&arr(dev), dt),
        }
    }
}

/// Default monitor configuration for an array spec.
pub fn array_config<T: Real, const N: usize>(spec: &ArraySpec<N>) -> ParityConfig<T> {
    let fs = T::lit(spec.errors.full_scale);
    match spec.kind {
        ArrayKind::Gyro => ParityConfig::gyro(spec.rate_hz, fs),
        ArrayKind::Accel => ParityConfig::accel(spec.rate_hz, fs),
    }
}

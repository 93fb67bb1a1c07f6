//! Runs the UKF monitor over a simulated scenario and records a trace.

use imu_fdi::math::Real;
use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::{Phase, UkfMonitor, UkfMonitorConfig, DEFAULT_WINDOW};

use crate::scenario::Scenario;
pub use crate::setup::{monitor_config, RunOptions};
use crate::sim::Simulator;

/// One row of a run trace (one IMU period).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceRow {
    /// Time, s.
    pub t: f64,
    /// Injected additive fault per channel.
    pub fault: [f64; 6],
    /// Which channels have a fault active.
    pub fault_active: [bool; 6],
    /// Monitor verdict per channel: `None` not monitored, else −1/0/+1.
    pub flag: [Option<i8>; 6],
    /// Fault estimate (corrected mapping).
    pub fhat: [f64; 6],
    /// Fault estimate as written in \[UKF\] §4.
    pub fhat_as_written: [f64; 6],
    /// State estimate.
    pub state: [f64; 6],
    /// State σ.
    pub sigma: [f64; 6],
    /// True state.
    pub truth: [f64; 6],
    /// Learned nominal bias.
    pub nominal_bias: [f64; 6],
    /// True sensor bias.
    pub true_bias: [f64; 6],
    /// Monitor phase.
    pub phase: Phase,
    /// t statistics of the six innovation channels.
    pub t_stat: [f64; 6],
    /// Innovations of this step (NaN where none).
    pub innovation: [f64; 6],
    /// Innovation σ of this step (NaN where none).
    pub innovation_sigma: [f64; 6],
    /// Covariance resets so far.
    pub covariance_resets: u32,
    /// Any health flag raised.
    pub health_event: bool,
    /// The health flags of this step.
    pub health: imu_fdi::monitor::Health,
}

/// A recorded run.
#[derive(Debug, Clone)]
pub struct Trace {
    /// The scenario.
    pub scenario: Scenario,
    /// Its seed.
    pub seed: u64,
    /// Rows, one per IMU sample.
    pub rows: Vec<TraceRow>,
    /// Detection latency allowance L = one window + one aiding interval, s.
    pub latency_s: f64,
    /// The t-test critical value used.
    pub t_threshold: f64,
}

/// Latency allowance L for a scenario: one window of the slowest aiding
/// channel plus one of its intervals.
pub fn latency_s(scn: &Scenario) -> f64 {
    let slowest = scn.aiding.vel_rate_hz.min(scn.aiding.att_rate_hz);
    (DEFAULT_WINDOW as f64 + 1.0) / slowest
}

/// Runs scenario `scn` with `seed` through a monitor in precision `T`.
pub fn run<T: Real>(
    scn: &Scenario,
    seed: u64,
    opts: &RunOptions,
) -> Result<Trace, imu_fdi::monitor::ConfigError> {
    let cfg = monitor_config::<T>(scn, opts);
    run_with::<T>(scn, seed, cfg)
}

/// Runs with an explicit monitor configuration.
pub fn run_with<T: Real>(
    scn: &Scenario,
    seed: u64,
    cfg: UkfMonitorConfig<T>,
) -> Result<Trace, imu_fdi::monitor::ConfigError> {
    let mut monitor = UkfMonitor::<T>::new(cfg)?;
    let sim = Simulator::new(scn, seed);
    let mut rows = Vec::with_capacity(sim.len() as usize);
    for s in sim {
        // A lost sample reaches the monitor as NaN, which it must reject.
        let imu = s.imu.unwrap_or([f64::NAN; 6]);
        let u = ImuVec::<T>::from_fn(|i, _| T::lit(imu[i]));
        let z = MeasVec::<T>::from_fn(|i, _| T::lit(s.aiding[i]));
        let m = Measurement {
            z,
            available: s.aiding_available,
        };
        let r = monitor.step(&u, T::lit(s.dt), &m);
        let f =
            |v: &nalgebra::SVector<T, 6>| -> [f64; 6] { core::array::from_fn(|i| v[i].to_f64()) };
        rows.push(TraceRow {
            t: s.t,
            fault: s.fault,
            fault_active: s.fault_active,
            flag: core::array::from_fn(|i| r.status[i].sign()),
            fhat: f(&r.fault_estimate),
            fhat_as_written: f(&r.detail.fault_estimate_as_written),
            state: f(&r.state),
            sigma: f(&r.state_sigma),
            truth: s.truth.state,
            nominal_bias: f(&r.nominal_bias),
            true_bias: s.imu_bias,
            phase: r.phase,
            t_stat: core::array::from_fn(|i| r.detail.t_statistic[i].to_f64()),
            innovation: core::array::from_fn(|i| {
                if r.detail.diag[i].available {
                    r.detail.diag[i].innovation.to_f64()
                } else {
                    f64::NAN
                }
            }),
            innovation_sigma: core::array::from_fn(|i| {
                if r.detail.diag[i].available {
                    r.detail.diag[i].variance.to_f64().sqrt()
                } else {
                    f64::NAN
                }
            }),
            covariance_resets: r.detail.covariance_resets,
            health_event: r.health != imu_fdi::monitor::Health::default(),
            health: r.health,
        });
    }
    Ok(Trace {
        scenario: scn.clone(),
        seed,
        rows,
        latency_s: latency_s(scn),
        t_threshold: monitor.t_threshold().to_f64(),
    })
}

impl Trace {
    /// Writes the trace as CSV (one row per IMU sample) for plotting and
    /// inspection.
    pub fn write_csv(&self, path: &std::path::Path) -> anyhow::Result<()> {
        let mut w = csv::Writer::from_path(path)?;
        let names = imu_fdi::model::CHANNEL_NAMES;
        let mut h = vec!["t".to_string(), "phase".to_string()];
        for prefix in [
            "fault",
            "flag",
            "fhat",
            "fhat_paper",
            "nominal_bias",
            "true_bias",
        ] {
            h.extend(names.iter().map(|c| format!("{prefix}_{c}")));
        }
        for prefix in ["x", "truth", "sigma", "innov", "innov_sigma", "stat"] {
            h.extend(
                ["u", "v", "w", "roll", "pitch", "yaw"]
                    .iter()
                    .map(|c| format!("{prefix}_{c}")),
            );
        }
        w.write_record(&h)?;
        for r in &self.rows {
            let mut row = vec![format!("{:.3}", r.t), format!("{:?}", r.phase)];
            row.extend(r.fault.iter().map(|v| format!("{v:.6e}")));
            row.extend(
                r.flag
                    .iter()
                    .map(|f| f.map_or(String::new(), |v| v.to_string())),
            );
            for arr in [
                &r.fhat,
                &r.fhat_as_written,
                &r.nominal_bias,
                &r.true_bias,
                &r.state,
                &r.truth,
                &r.sigma,
                &r.innovation,
                &r.innovation_sigma,
                &r.t_stat,
            ] {
                row.extend(arr.iter().map(|v| {
                    if v.is_nan() {
                        String::new()
                    } else {
                        format!("{v:.6e}")
                    }
                }));
            }
            w.write_record(&row)?;
        }
        w.flush()?;
        Ok(())
    }
}

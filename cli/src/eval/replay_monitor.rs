//! Either single-IMU monitor behind one `step`, for the replay: the UKF
//! innovation monitor or the OTSUKF monitor, both answering with the core's
//! one report shape (`Report<T, X>`), their details reduced to what the
//! replay writes.

use anyhow::{anyhow, Result};
use imu_fdi::model::{ImuVec, Measurement};
use imu_fdi::monitor::{OtsukfConfig, OtsukfMonitor, Phase, Report, UkfMonitor, UkfMonitorConfig};

/// Which single-IMU monitor a replay runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MonitorKind {
    /// The UKF innovation monitor (windowed t-tests on the innovations).
    #[default]
    Ukf,
    /// The optimal two-stage UKF (OTSUKF): joint state and fault estimation.
    Otsukf,
}

/// The part of either monitor's detail the replay writes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReplayDetail {
    /// Standard deviation of the fault estimate (OTSUKF; UKF monitor with
    /// the tracking estimate, 0 with the window mean).
    pub fault_sigma: Option<ImuVec<f64>>,
    /// The learned innovation inflation per aiding channel (UKF monitor).
    pub innovation_inflation: Option<[f64; 6]>,
    /// Innovation and its variance `S_ii` per aiding channel at the last
    /// update, NaN where the channel was absent (UKF monitor).
    pub innovations: Option<[(f64, f64); 6]>,
    /// The aiding latency the monitor fuses at, s: the configured one or
    /// the online estimate ([`UkfMonitor::aiding_delay_estimate`]; the
    /// OTSUKF's attitude latency, [`OtsukfMonitor::attitude_lag_estimate`],
    /// when configured or estimated).
    pub aiding_delay_s: Option<f64>,
    /// The heading offset of the attitude aiding learnt so far, rad (UKF
    /// monitor; 0 unless estimated;
    /// [`UkfMonitor::heading_offset_estimate`]).
    pub heading_offset_rad: Option<f64>,
    /// The accelerometer/GNSS-velocity test's GNSS lag, s, and learnt
    /// offset per accelerometer axis, m/s² (UKF monitor with the test on;
    /// [`UkfMonitor::velocity_increment_lag`]).
    pub velocity_increment: Option<(f64, [f64; 3])>,
    /// The block tests' largest score/threshold ratio at their last
    /// decision per channel (a_x … a_z from the accelerometer/GNSS-velocity
    /// test, g_x … g_z from the gyro/attitude-aiding test; `None` where the
    /// test is off or the monitor has none; 0 before it judges).
    pub block_ratio: [Option<f64>; 6],
}

/// One monitor of either kind.
#[derive(Debug, Clone)]
pub enum ReplayMonitor {
    /// The UKF innovation monitor.
    Ukf(Box<UkfMonitor<f64>>),
    /// The OTSUKF monitor.
    Otsukf(Box<OtsukfMonitor<f64>>),
}

impl ReplayMonitor {
    /// A monitor of `kind` on `base`: the UKF monitor's configuration, or
    /// the OTSUKF's default around it ([`OtsukfConfig::from_base`]) with
    /// `velocity_lag_s` its compensated velocity-aiding latency.
    pub fn new(
        kind: MonitorKind,
        base: UkfMonitorConfig<f64>,
        velocity_lag_s: f64,
    ) -> Result<Self> {
        let invalid = |e| anyhow!("invalid monitor configuration: {e:?}");
        Ok(match kind {
            MonitorKind::Ukf => Self::Ukf(Box::new(UkfMonitor::new(base).map_err(invalid)?)),
            MonitorKind::Otsukf => Self::Otsukf(Box::new(
                OtsukfMonitor::new({
                    let mut c = OtsukfConfig::from_base(base);
                    c.velocity_lag_s = velocity_lag_s;
                    c
                })
                .map_err(invalid)?,
            )),
        })
    }

    /// One period.
    pub fn step(
        &mut self,
        imu: &ImuVec<f64>,
        dt: f64,
        aiding: &Measurement<f64>,
    ) -> Report<f64, ReplayDetail> {
        match self {
            Self::Ukf(m) => {
                let r = m.step(imu, dt, aiding);
                let (delay, heading) = (m.aiding_delay_estimate(), m.heading_offset_estimate());
                let vi = m.velocity_increment_detail();
                let vel_inc = m.velocity_increment_lag().zip(vi.map(|d| d.offset));
                let ar = m.attitude_rate_detail();
                let block_ratio = core::array::from_fn(|i| {
                    let (d, j) = if i < 3 { (vi, i) } else { (ar, i - 3) };
                    d.and_then(|d| d.ratio.get(j).copied())
                });
                r.map_detail(|d| ReplayDetail {
                    fault_sigma: Some(d.fault_sigma),
                    aiding_delay_s: Some(delay),
                    heading_offset_rad: Some(heading),
                    velocity_increment: vel_inc,
                    block_ratio,
                    innovation_inflation: Some(d.innovation_inflation),
                    innovations: Some(core::array::from_fn(|i| match d.diag.get(i) {
                        Some(c) if c.available => (c.innovation, c.variance),
                        _ => (f64::NAN, f64::NAN),
                    })),
                })
            }
            Self::Otsukf(m) => {
                let r = m.step(imu, dt, aiding);
                // The attitude latency only when configured or estimated:
                // the replay's output is otherwise as before.
                let att_lag = m.attitude_lag_estimate();
                let vi = m.velocity_increment_detail();
                let ar = m.attitude_rate_detail();
                let block_ratio = core::array::from_fn(|i| {
                    let (d, j) = if i < 3 {
                        (vi.map(|v| v.0), i)
                    } else {
                        (ar, i - 3)
                    };
                    d.and_then(|d| d.ratio.get(j).copied())
                });
                r.map_detail(|d| ReplayDetail {
                    fault_sigma: Some(d.fault_sigma),
                    innovation_inflation: Some(d.innovation_inflation),
                    innovations: None,
                    aiding_delay_s: att_lag,
                    heading_offset_rad: None,
                    velocity_increment: vi.map(|(d, lag)| (lag, d.offset)),
                    block_ratio,
                })
            }
        }
    }
}

/// The phase as the replay's CSV and JSON spell it.
pub fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Aligning => "aligning",
        Phase::Converging => "converging",
        Phase::Learning => "learning",
        Phase::Monitoring => "monitoring",
    }
}

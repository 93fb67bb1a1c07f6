//! The periodic monitor task: an IMU driver plus the configured monitors,
//! called once per period with the measured `dt`.

use super::{
    ChannelState, ConfigError, Health, OtsukfMonitor, Phase, UkfMonitor, UkfMonitorConfig,
};
use crate::imu::Imu;
use crate::model::{ImuVec, Measurement};

/// What the task says about one period: small, `Copy`, plain arrays, so it
/// can be logged with defmt or sent over a link as it is.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TaskReport {
    /// Life-cycle phase of the monitor.
    pub phase: Phase,
    /// Verdict per channel `[a_x, a_y, a_z, p, q, r]`.
    pub status: [ChannelState; 6],
    /// Fault estimate per channel (SI units).
    pub fault_estimate: [f32; 6],
    /// The last good IMU sample corrected for nominal bias and flagged faults.
    pub corrected: [f32; 6],
    /// Input and numerical health of this period.
    pub health: Health,
    /// The IMU read failed this period (bus error, no data).
    pub read_failed: bool,
    /// IMU reads that failed since start.
    pub read_failures: u32,
    /// Samples the driver's sequence counter says were skipped since start.
    pub missed_samples: u32,
}

/// What a single-IMU monitor tells the task every period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verdict {
    /// Life-cycle phase.
    pub phase: Phase,
    /// Verdict per channel.
    pub status: [ChannelState; 6],
    /// Fault estimate per channel (SI units).
    pub fault_estimate: ImuVec<f32>,
    /// The sample corrected by the monitor.
    pub corrected_imu: ImuVec<f32>,
    /// Input and numerical health.
    pub health: Health,
}

/// A single-IMU monitor the periodic task can run: the UKF innovation
/// monitor ([`UkfMonitor`]) or the optimal two-stage UKF
/// ([`OtsukfMonitor`]).
pub trait PeriodicMonitor {
    /// One period with the measured `dt` (a NaN sample means "no sample").
    fn step_period(&mut self, imu: &ImuVec<f32>, dt: f32, aiding: &Measurement<f32>) -> Verdict;
}

impl<const W: usize> PeriodicMonitor for UkfMonitor<f32, W> {
    fn step_period(&mut self, imu: &ImuVec<f32>, dt: f32, aiding: &Measurement<f32>) -> Verdict {
        let r = self.step(imu, dt, aiding);
        Verdict {
            phase: r.phase,
            status: r.status,
            fault_estimate: r.fault_estimate,
            corrected_imu: r.corrected_imu,
            health: r.health,
        }
    }
}

impl PeriodicMonitor for OtsukfMonitor<f32> {
    fn step_period(&mut self, imu: &ImuVec<f32>, dt: f32, aiding: &Measurement<f32>) -> Verdict {
        let r = self.step(imu, dt, aiding);
        Verdict {
            phase: r.phase,
            status: r.status,
            fault_estimate: r.fault_estimate,
            corrected_imu: r.corrected_imu,
            health: r.health,
        }
    }
}

/// The monitor task: an IMU driver and one [`PeriodicMonitor`] — by
/// default the UKF innovation monitor; [`MonitorTask::with_monitor`] runs any
/// other (e.g. the two-stage UKF, whose corrected sample removes the
/// estimated fault continuously).
#[derive(Debug)]
pub struct MonitorTask<I, M = UkfMonitor<f32>> {
    imu: I,
    ukf: M,
    pending_dt: f32,
    last_sequence: Option<u32>,
    read_failures: u32,
    missed_samples: u32,
    last_corrected: [f32; 6],
}

/// The task's former name.
#[deprecated(note = "renamed `MonitorTask`: it is the periodic task that drives a monitor")]
pub type Monitor<I, M = UkfMonitor<f32>> = MonitorTask<I, M>;

impl<I: Imu> MonitorTask<I> {
    /// A task reading `imu` and running a UKF monitor configured by `cfg`
    /// (default window). One impl only, so `MonitorTask::new(imu, cfg)`
    /// needs no type annotation; another window or monitor goes through
    /// [`with_monitor`](Self::with_monitor).
    pub fn new(imu: I, cfg: UkfMonitorConfig<f32>) -> Result<Self, ConfigError> {
        Ok(Self::with_monitor(imu, UkfMonitor::new(cfg)?))
    }
}

impl<I: Imu, M: PeriodicMonitor> MonitorTask<I, M> {
    /// A task reading `imu` and running `monitor`.
    pub fn with_monitor(imu: I, monitor: M) -> Self {
        Self {
            imu,
            ukf: monitor,
            pending_dt: 0.0,
            last_sequence: None,
            read_failures: 0,
            missed_samples: 0,
            last_corrected: [0.0; 6],
        }
    }

    /// The monitor (for its filter, configuration, …).
    pub fn monitor(&self) -> &M {
        &self.ukf
    }

    /// Releases the IMU driver.
    pub fn destroy(self) -> I {
        self.imu
    }

    /// One period: `dt` is the measured time since the previous call and
    /// `aiding` whatever arrived in it. A failed read does not stop the
    /// monitor: aiding is still processed, and the elapsed time is carried
    /// to the next good sample so its prediction spans the whole gap (the
    /// monitor treats more than 5 periods as a gap and reports it).
    pub fn step(&mut self, dt: f32, aiding: &Measurement<f32>) -> TaskReport {
        self.pending_dt += if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
        let (sample, read_failed) = match self.imu.read() {
            Ok(s) => {
                if let Some(prev) = self.last_sequence {
                    let gap = s.sequence.wrapping_sub(prev).saturating_sub(1);
                    self.missed_samples = self.missed_samples.saturating_add(gap);
                }
                self.last_sequence = Some(s.sequence);
                (Some(ImuVec::from(s.channels())), false)
            }
            Err(_) => {
                self.read_failures = self.read_failures.saturating_add(1);
                (None, true)
            }
        };
        let report = match sample {
            Some(u) => {
                let dt = self.pending_dt;
                self.pending_dt = 0.0;
                self.ukf.step_period(&u, dt, aiding)
            }
            // No sample: let the monitor process the aiding and report; its
            // prediction is skipped (NaN is rejected as invalid input).
            None => self
                .ukf
                .step_period(&ImuVec::from_element(f32::NAN), dt, aiding),
        };
        if sample.is_some() {
            self.last_corrected = report.corrected_imu.into();
        }
        TaskReport {
            phase: report.phase,
            status: report.status,
            fault_estimate: report.fault_estimate.into(),
            corrected: self.last_corrected,
            health: report.health,
            read_failed,
            read_failures: self.read_failures,
            missed_samples: self.missed_samples,
        }
    }
}

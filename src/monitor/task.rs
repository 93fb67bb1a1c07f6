//! The periodic monitor task: an IMU driver plus the configured monitors,
//! called once per period with the measured `dt`.

use super::{
    ChannelState, ConfigError, Health, OtsukfMonitor, Phase, Report, UkfMonitor, UkfMonitorConfig,
};
use crate::imu::Imu;
use crate::model::{ImuVec, Measurement};

/// Consecutive failed reads after which the task reports
/// [`TaskStatus::ImuUnavailable`]: the monitor's prediction would span a gap
/// (more than 5 nominal periods), so it is not monitoring any more.
pub const MAX_CONSECUTIVE_FAILURES: u32 = 5;

/// Whether the task could run the monitor this period.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TaskStatus {
    /// A sample was read and the monitor stepped.
    #[default]
    Running,
    /// The read failed this period: the monitor was not stepped (its time
    /// and any aiding are carried to the next good sample); the verdict is
    /// the last one.
    ReadFailed,
    /// [`MAX_CONSECUTIVE_FAILURES`] or more reads in a row failed: the
    /// monitor cannot run, every channel is reported
    /// [`ChannelState::NotMonitored`] until a sample is read again.
    ImuUnavailable,
}

/// What the task says about one period: small, `Copy`, plain arrays, so it
/// can be logged with defmt or sent over a link as it is.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TaskReport {
    /// Whether the monitor ran this period.
    pub task_status: TaskStatus,
    /// Life-cycle phase of the monitor.
    pub phase: Phase,
    /// Verdict per channel `[a_x, a_y, a_z, p, q, r]`.
    pub status: [ChannelState; 6],
    /// Fault estimate per channel (SI units).
    pub fault_estimate: [f32; 6],
    /// The last good IMU sample corrected for nominal bias and flagged faults.
    pub corrected: [f32; 6],
    /// Input and numerical health of the last monitor step.
    pub health: Health,
    /// The IMU read failed this period (bus error, no data).
    pub read_failed: bool,
    /// IMU reads that failed since start.
    pub read_failures: u32,
    /// Failed reads in a row up to this period (0 after a good read).
    pub consecutive_failures: u32,
    /// Samples the monitor never saw since start: every failed read, plus
    /// any further gap the driver's sequence counter reveals (a sample is
    /// counted once even when both show it).
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

impl<X> From<&Report<f32, X>> for Verdict {
    /// The common fields of either monitor's report.
    fn from(r: &Report<f32, X>) -> Self {
        Self {
            phase: r.phase,
            status: r.status,
            fault_estimate: r.fault_estimate,
            corrected_imu: r.corrected_imu,
            health: r.health,
        }
    }
}

/// A single-IMU monitor the periodic task can run: the UKF innovation
/// monitor ([`UkfMonitor`]) or the optimal two-stage UKF (OTSUKF,
/// [`OtsukfMonitor`]).
pub trait PeriodicMonitor {
    /// One period with the measured `dt` (a NaN sample means "no sample").
    fn step_period(&mut self, imu: &ImuVec<f32>, dt: f32, aiding: &Measurement<f32>) -> Verdict;
}

impl<const W: usize> PeriodicMonitor for UkfMonitor<f32, W> {
    fn step_period(&mut self, imu: &ImuVec<f32>, dt: f32, aiding: &Measurement<f32>) -> Verdict {
        // By reference: no copy of the report per period (issue 17).
        Verdict::from(self.step_ref(imu, dt, aiding))
    }
}

impl PeriodicMonitor for OtsukfMonitor<f32> {
    fn step_period(&mut self, imu: &ImuVec<f32>, dt: f32, aiding: &Measurement<f32>) -> Verdict {
        Verdict::from(&self.step(imu, dt, aiding))
    }
}

/// The monitor task: an IMU driver and one [`PeriodicMonitor`] — by
/// default the UKF innovation monitor; [`MonitorTask::with_monitor`] runs any
/// other (e.g. the OTSUKF, whose corrected sample removes the
/// estimated fault continuously).
#[derive(Debug)]
pub struct MonitorTask<I, M = UkfMonitor<f32>> {
    imu: I,
    ukf: M,
    /// Measured time since the last good sample (the caller's periods).
    pending_dt: f32,
    /// Aiding that arrived while reads failed, for the next good sample.
    held_aiding: Measurement<f32>,
    last_sequence: Option<u32>,
    last_timestamp_us: Option<u32>,
    read_failures: u32,
    consecutive_failures: u32,
    missed_samples: u32,
    last_corrected: [f32; 6],
    last_verdict: Option<Verdict>,
    /// Board → body rotation applied to every sample (identity: the IMU's
    /// axes are the body's).
    mounting: nalgebra::Matrix3<f32>,
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
            held_aiding: Measurement::none(),
            last_sequence: None,
            last_timestamp_us: None,
            read_failures: 0,
            consecutive_failures: 0,
            missed_samples: 0,
            last_corrected: [0.0; 6],
            last_verdict: None,
            mounting: nalgebra::Matrix3::identity(),
        }
    }

    /// The IMU is mounted rotated on the vehicle: `board_to_body` rotates
    /// the chip's axes into the body frame (FRD), as PX4's `SENS_BOARD_ROT`
    /// and ArduPilot's `AHRS_ORIENTATION` do — e.g.
    /// [`euler_rotation`](crate::parity::euler_rotation)`(π, 0, 0)` for a
    /// board mounted upside down (`ROLL_180`). Applied to the accelerometer
    /// and the gyro of every sample before the monitor sees it, so the
    /// verdict, the fault estimate and the corrected sample are in the body
    /// frame. A matrix that is not a rotation (not orthonormal within 1e-3,
    /// or a reflection) is refused and the mounting left unchanged.
    pub fn with_mounting(
        mut self,
        board_to_body: nalgebra::Matrix3<f32>,
    ) -> Result<Self, ConfigError> {
        let orthonormal = (board_to_body.transpose() * board_to_body
            - nalgebra::Matrix3::identity())
        .iter()
        .all(|e| e.abs() < 1e-3);
        let det = board_to_body.determinant();
        if !(orthonormal && det > 0.999 && det < 1.001) {
            return Err(ConfigError::OutOfRange("mounting"));
        }
        self.mounting = board_to_body;
        Ok(self)
    }

    /// The board → body rotation in use.
    pub fn mounting(&self) -> &nalgebra::Matrix3<f32> {
        &self.mounting
    }

    /// The monitor (for its filter, configuration, …).
    pub fn monitor(&self) -> &M {
        &self.ukf
    }

    /// The IMU driver (e.g. [`Icm42688Fifo::fifo_status`](crate::imu::Icm42688Fifo::fifo_status)).
    pub fn imu(&self) -> &I {
        &self.imu
    }

    /// Releases the IMU driver.
    pub fn destroy(self) -> I {
        self.imu
    }

    /// One period: `dt` is the measured time since the previous call and
    /// `aiding` whatever arrived in it.
    ///
    /// The monitor is stepped once per sample actually read, with the time
    /// since the previous sample read: the difference of the samples' own
    /// time stamps when the driver provides them
    /// ([`ImuSample::timestamp_us`](crate::imu::ImuSample::timestamp_us)),
    /// otherwise the sum of the measured periods since the last good read.
    /// A failed read does not step the monitor (so no time is counted
    /// twice); it is counted in `missed_samples`, its aiding is held for the
    /// next good sample (newest value per channel), and the report carries
    /// the last verdict with [`TaskStatus::ReadFailed`], or
    /// [`TaskStatus::ImuUnavailable`] with no channel monitored once
    /// [`MAX_CONSECUTIVE_FAILURES`] reads in a row have failed.
    pub fn step(&mut self, dt: f32, aiding: &Measurement<f32>) -> TaskReport {
        self.pending_dt += if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
        self.hold_aiding(aiding);
        match self.imu.read() {
            Ok(s) => {
                let failed_before = self.consecutive_failures;
                self.consecutive_failures = 0;
                if let Some(prev) = self.last_sequence {
                    // Samples the sequence says were skipped, beyond the
                    // failed reads already counted.
                    let gap = s.sequence.wrapping_sub(prev).saturating_sub(1);
                    let extra = gap.saturating_sub(failed_before);
                    self.missed_samples = self.missed_samples.saturating_add(extra);
                }
                self.last_sequence = Some(s.sequence);
                let sample_dt = match (s.timestamp_us, self.last_timestamp_us) {
                    (Some(now), Some(prev)) => now.wrapping_sub(prev) as f32 * 1e-6,
                    _ => self.pending_dt,
                };
                self.last_timestamp_us = s.timestamp_us;
                self.pending_dt = 0.0;
                let held = core::mem::replace(&mut self.held_aiding, Measurement::none());
                let a = self.mounting * nalgebra::Vector3::from(s.accel);
                let g = self.mounting * nalgebra::Vector3::from(s.gyro);
                let u = ImuVec::from([a.x, a.y, a.z, g.x, g.y, g.z]);
                let v = self.ukf.step_period(&u, sample_dt, &held);
                self.last_corrected = v.corrected_imu.into();
                self.last_verdict = Some(v);
                self.report(TaskStatus::Running, &v, false)
            }
            Err(_) => {
                self.read_failures = self.read_failures.saturating_add(1);
                self.consecutive_failures = self.consecutive_failures.saturating_add(1);
                self.missed_samples = self.missed_samples.saturating_add(1);
                let status = if self.consecutive_failures >= MAX_CONSECUTIVE_FAILURES {
                    TaskStatus::ImuUnavailable
                } else {
                    TaskStatus::ReadFailed
                };
                let mut v = self.last_verdict.unwrap_or(Verdict {
                    phase: Phase::Aligning,
                    status: [ChannelState::NotMonitored; 6],
                    fault_estimate: ImuVec::zeros(),
                    corrected_imu: ImuVec::zeros(),
                    health: Health::default(),
                });
                if status == TaskStatus::ImuUnavailable {
                    v.status = [ChannelState::NotMonitored; 6];
                }
                self.report(status, &v, true)
            }
        }
    }

    /// Keeps the newest value of every aiding channel that arrived since the
    /// last good sample.
    fn hold_aiding(&mut self, aiding: &Measurement<f32>) {
        for ((h, a), (hz, z)) in self
            .held_aiding
            .available
            .iter_mut()
            .zip(aiding.available.iter())
            .zip(self.held_aiding.z.iter_mut().zip(aiding.z.iter()))
        {
            if *a {
                *h = true;
                *hz = *z;
            }
        }
    }

    fn report(&self, task_status: TaskStatus, v: &Verdict, read_failed: bool) -> TaskReport {
        TaskReport {
            task_status,
            phase: v.phase,
            status: v.status,
            fault_estimate: v.fault_estimate.into(),
            corrected: self.last_corrected,
            health: v.health,
            read_failed,
            read_failures: self.read_failures,
            consecutive_failures: self.consecutive_failures,
            missed_samples: self.missed_samples,
        }
    }
}

use crate::filter::ChannelDiag;
use crate::math::Real;
use crate::model::{ImuVec, StateVec, NU, NZ};

/// Where the monitor is in its life cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Waiting for the first attitude measurement to initialise the state.
    #[default]
    Aligning,
    /// Filter settling after alignment; no statistics.
    Converging,
    /// Estimating the IMU's nominal biases (SPEC §8a); no flags.
    Learning,
    /// Detecting.
    Monitoring,
}

/// Verdict on one IMU channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChannelState {
    /// Not monitored: no aiding observes it now, or not yet monitoring.
    #[default]
    NotMonitored,
    /// Monitored, no fault.
    Healthy,
    /// A fault of positive sign (measured > true).
    FaultPositive,
    /// A fault of negative sign.
    FaultNegative,
}

impl ChannelState {
    /// −1, 0 or +1 for a fault, `None` when not monitored.
    pub fn sign(self) -> Option<i8> {
        match self {
            Self::NotMonitored => None,
            Self::Healthy => Some(0),
            Self::FaultPositive => Some(1),
            Self::FaultNegative => Some(-1),
        }
    }
}

/// Input and numerical health of one step. Every field is a condition the
/// monitor detected and recovered from; none of them is an IMU *fault*.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    /// The IMU sample had NaN/∞ or an out-of-range value; it was not used.
    pub input_invalid: bool,
    /// The IMU has repeated the exact same sample for too long.
    pub frozen: bool,
    /// A channel was near full scale; statistics are paused.
    pub saturated: bool,
    /// `dt` was not positive/finite (step skipped) or beyond 5 periods (gap).
    pub dt_out_of_range: bool,
    /// The attitude is too close to θ = ±90° for the Euler model.
    pub pitch_singular: bool,
    /// The covariance was re-initialised in this step.
    pub covariance_reset: bool,
    /// At least one aiding channel was rejected by the outlier gate.
    pub aiding_rejected: bool,
    /// At least one aiding channel was outside its physical range (or not
    /// finite); it was not used.
    pub aiding_invalid: bool,
    /// After `gate_max_rejections` gate rejections in a row, an aiding
    /// innovation beyond `realign_innovation`: its triad's states were
    /// re-aligned to the aiding (covariance reset) instead of fusing it.
    pub aiding_realigned: bool,
}

/// Everything the monitor says about one period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report<T> {
    /// Life-cycle phase.
    pub phase: Phase,
    /// Per IMU channel `[a_x, a_y, a_z, p, q, r]`.
    pub status: [ChannelState; NU],
    /// Fault estimate (corrected innovation mapping `M⁺ r̄`, SPEC §6).
    pub fault_estimate: ImuVec<T>,
    /// Fault estimate by \[UKF\] §4 as written, for comparison.
    pub fault_estimate_as_written: ImuVec<T>,
    /// Learned nominal bias (subtracted from the IMU before filtering).
    pub nominal_bias: ImuVec<T>,
    /// The IMU sample minus nominal bias and minus the estimate of each
    /// flagged fault: what a flight controller can use instead of the raw one.
    pub corrected_imu: ImuVec<T>,
    /// State estimate `[u, v, w, φ, θ, ψ]`.
    pub state: StateVec<T>,
    /// Its standard deviations.
    pub state_sigma: StateVec<T>,
    /// t statistic per innovation channel (0 where the window is not full).
    pub t_statistic: [T; NZ],
    /// Innovation-level t-test flags (sign of the innovation, not the fault).
    pub innovation_flags: [i8; NZ],
    /// The diagnostic records of the last aiding update.
    pub diag: [ChannelDiag<T>; NZ],
    /// True when aiding was processed in this step.
    pub updated: bool,
    /// Input and numerical health.
    pub health: Health,
    /// Covariance re-initialisations since start.
    pub covariance_resets: u32,
}

impl<T: Real> Default for Report<T> {
    fn default() -> Self {
        Self {
            phase: Phase::Aligning,
            status: [ChannelState::NotMonitored; NU],
            fault_estimate: ImuVec::zeros(),
            fault_estimate_as_written: ImuVec::zeros(),
            nominal_bias: ImuVec::zeros(),
            corrected_imu: ImuVec::zeros(),
            state: StateVec::zeros(),
            state_sigma: StateVec::zeros(),
            t_statistic: [T::zero(); NZ],
            innovation_flags: [0; NZ],
            diag: [ChannelDiag::default(); NZ],
            updated: false,
            health: Health::default(),
            covariance_resets: 0,
        }
    }
}

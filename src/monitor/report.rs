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
    /// An aiding triad repeated its previous values bit for bit (a source
    /// repeating its last output); it was not used. A source that stays
    /// frozen then ages into the aiding-loss handling, as a silent one.
    pub aiding_stale: bool,
    /// After `gate_max_rejections` gate rejections in a row, an aiding
    /// innovation beyond `realign_innovation`: its triad's states were
    /// re-aligned to the aiding (covariance reset) instead of fusing it. The
    /// UKF monitor does the same when aiding returns after a loss (silent
    /// beyond `aiding_timeout_s`) further off than `realign_innovation`.
    pub aiding_realigned: bool,
}

impl Health {
    /// A triad was re-aligned to the aiding (its covariance reset); with
    /// `rejected`, the aiding epoch that showed it was not fused either.
    /// One place for both single-IMU monitors (`monitor::realign`).
    pub(crate) fn mark_realigned(&mut self, rejected: bool) {
        self.aiding_realigned = true;
        self.aiding_rejected |= rejected;
        self.covariance_reset = true;
    }
}

/// Everything a single-IMU monitor says about one period: the fields both
/// monitors share at top level, the monitor-specific ones in `detail`
/// ([`UkfDetail`] for [`UkfMonitor`](super::UkfMonitor), [`OtsukfDetail`]
/// for [`OtsukfMonitor`](super::OtsukfMonitor)). One shape, so a flight
/// controller, a logger or the replay tool handles either monitor with the
/// same code and reads the extension only where it needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report<T, X = UkfDetail<T>> {
    /// Life-cycle phase.
    pub phase: Phase,
    /// Per IMU channel `[a_x, a_y, a_z, p, q, r]`.
    pub status: [ChannelState; NU],
    /// Fault estimate per channel, raw units (m/s², rad/s), nominal bias
    /// removed.
    pub fault_estimate: ImuVec<T>,
    /// Learned nominal bias (SPEC §8a): what the monitor treats as the
    /// IMU's own healthy error, not a fault.
    pub nominal_bias: ImuVec<T>,
    /// The IMU sample with the monitor's correction applied: what a flight
    /// controller can use instead of the raw one.
    pub corrected_imu: ImuVec<T>,
    /// State estimate `[u, v, w, φ, θ, ψ]`.
    pub state: StateVec<T>,
    /// Its standard deviations.
    pub state_sigma: StateVec<T>,
    /// Input and numerical health.
    pub health: Health,
    /// True when aiding was processed in this step.
    pub updated: bool,
    /// The monitor-specific part.
    pub detail: X,
}

/// The UKF innovation monitor's report.
pub type UkfReport<T> = Report<T, UkfDetail<T>>;
/// The optimal two-stage UKF (OTSUKF) monitor's report.
pub type OtsukfReport<T> = Report<T, OtsukfDetail<T>>;

/// What only the UKF innovation monitor reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UkfDetail<T> {
    /// Fault estimate by \[UKF\] §4 as written, for comparison with
    /// [`Report::fault_estimate`] (corrected innovation mapping `M⁺ r̄`,
    /// SPEC §6).
    pub fault_estimate_as_written: ImuVec<T>,
    /// t statistic per innovation channel (0 where the window is not full).
    pub t_statistic: [T; NZ],
    /// Innovation-level t-test flags (sign of the innovation, not the fault).
    pub innovation_flags: [i8; NZ],
    /// The diagnostic records of the last aiding update.
    pub diag: [ChannelDiag<T>; NZ],
    /// Covariance re-initialisations since start.
    pub covariance_resets: u32,
    /// The learned variance inflation of each innovation channel's window
    /// statistic (1 until learning ends, or when disabled; see
    /// `UkfMonitorConfig::max_innovation_inflation`).
    pub innovation_inflation: [T; NZ],
    /// The window-mean estimate `M⁺ r̄` (SPEC §6). It is the report's
    /// [`Report::fault_estimate`] when `UkfMonitorConfig::fault_psd` is
    /// `None`; otherwise that is the tracking estimate and this is kept
    /// for comparison.
    pub fault_estimate_window: ImuVec<T>,
    /// Standard deviation of the tracking fault estimate (0 with the
    /// window-mean estimate).
    pub fault_sigma: ImuVec<T>,
}

/// What only the OTSUKF monitor reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtsukfDetail<T> {
    /// Standard deviation of the fault estimate.
    pub fault_sigma: ImuVec<T>,
    /// Everything the filter attributes to the IMU: `f̂` (nominal bias plus
    /// fault).
    pub total_bias: ImuVec<T>,
    /// The learned inflation of each aiding component's measurement noise
    /// `R` (1 until monitoring starts, and with
    /// `UkfMonitorConfig::max_innovation_inflation` = 1).
    pub innovation_inflation: [T; NZ],
}

impl<T: Real> Default for UkfDetail<T> {
    fn default() -> Self {
        Self {
            fault_estimate_as_written: ImuVec::zeros(),
            t_statistic: [T::zero(); NZ],
            innovation_flags: [0; NZ],
            diag: [ChannelDiag::default(); NZ],
            covariance_resets: 0,
            innovation_inflation: [T::one(); NZ],
            fault_estimate_window: ImuVec::zeros(),
            fault_sigma: ImuVec::zeros(),
        }
    }
}

impl<T: Real> Default for OtsukfDetail<T> {
    fn default() -> Self {
        Self {
            fault_sigma: ImuVec::zeros(),
            total_bias: ImuVec::zeros(),
            innovation_inflation: [T::one(); NZ],
        }
    }
}

impl<T: Real, X: Default> Default for Report<T, X> {
    fn default() -> Self {
        Self {
            phase: Phase::Aligning,
            status: [ChannelState::NotMonitored; NU],
            fault_estimate: ImuVec::zeros(),
            nominal_bias: ImuVec::zeros(),
            corrected_imu: ImuVec::zeros(),
            state: StateVec::zeros(),
            state_sigma: StateVec::zeros(),
            health: Health::default(),
            updated: false,
            detail: X::default(),
        }
    }
}

impl<T, X> Report<T, X> {
    /// The same report with its monitor-specific part mapped by `f`: how a
    /// tool that handles either monitor brings both to one type.
    pub fn map_detail<Y>(self, f: impl FnOnce(X) -> Y) -> Report<T, Y> {
        Report {
            phase: self.phase,
            status: self.status,
            fault_estimate: self.fault_estimate,
            nominal_bias: self.nominal_bias,
            corrected_imu: self.corrected_imu,
            state: self.state,
            state_sigma: self.state_sigma,
            health: self.health,
            updated: self.updated,
            detail: f(self.detail),
        }
    }

    /// True when any channel is reported faulty.
    pub fn any_fault(&self) -> bool {
        self.status
            .iter()
            .any(|s| matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative))
    }
}

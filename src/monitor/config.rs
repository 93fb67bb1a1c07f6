use crate::detect::{Detector, Statistic};
use crate::filter::{SigmaParams, SigmaWeights};
use crate::math::Real;
use crate::model::{AidingKind, ImuNoisePsd, ImuVec, MeasVec, StateVec, G0};
use crate::monitor::{AttitudeRateConfig, ConfigError, VelocityIncrementConfig};

/// Largest nominal bias a learner may assume without a configured turn-on
/// bound, as a multiple of `min_fault`: anything larger is a fault from
/// power-on, not a nominal error.
const MAX_NOMINAL_BIAS_FACTOR: f64 = 20.0;
/// Everything the UKF monitor is tuned by. Units are SI (m/s², rad/s, m/s,
/// rad, s); noise densities are PSDs (see [`ImuNoisePsd`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UkfMonitorConfig<T> {
    /// Aiding model (M1 DVL + compass, or M2 GNSS velocity + attitude).
    pub aiding: AidingKind,
    /// Lever arm IMU → velocity sensor, body axes, m.
    pub lever_arm: [T; 3],
    /// Gravity, m/s².
    pub gravity: T,
    /// Smallest |cos θ| accepted by the model.
    pub cos_pitch_min: T,
    /// Filter process noise. Deliberately larger than the sensor's white
    /// noise: it covers what the 6-state model does not carry (residual
    /// bias, scale-factor and misalignment errors during manoeuvres) and sets
    /// the filter gain so that a fault's innovation settles within a few
    /// aiding epochs — well inside one detection window.
    pub process_noise: ImuNoisePsd<T>,
    /// Aiding noise σ per measurement channel (m/s, rad).
    pub meas_sigma: MeasVec<T>,
    /// Initial state σ after alignment.
    pub initial_sigma: StateVec<T>,
    /// Sigma-point parameters.
    pub sigma: SigmaParams,
    /// Aiding outlier gate in σ (single-epoch spikes are rejected).
    pub gate_sigma: T,
    /// Longest run of consecutive gate rejections of an aiding channel; the
    /// next epoch is fused (a persistent innovation is what an IMU fault
    /// looks like), unless its innovation is beyond `realign_innovation`.
    pub gate_max_rejections: u8,
    /// Largest innovation per aiding channel (m/s, rad) fused after
    /// `gate_max_rejections` rejections: beyond it, the channel's triad
    /// (velocity or attitude) is re-aligned to the aiding with its covariance
    /// reset instead of fusing the outlier.
    pub realign_innovation: MeasVec<T>,
    /// Physical range of an aiding velocity component, m/s: a larger (or
    /// non-finite) value is never fused and raises
    /// [`Health::aiding_invalid`](super::Health::aiding_invalid). Attitude
    /// aiding must be finite and within ±π.
    pub max_aiding_speed: T,
    /// Per-tail significance of the windowed t-test.
    pub alpha: f64,
    /// Windowed outlier removal (SPEC §5): samples beyond this many window σ
    /// are dropped before the test (0 disables; off by default because the
    /// filter's gate already rejects single-epoch aiding spikes).
    pub outlier_k: T,
    /// Raw or pre-whitened innovations in the windows.
    pub statistic: Statistic,
    /// Decision rule.
    pub detector: Detector,
    /// GLR acceptance threshold (χ²₁ scale).
    pub glr_threshold: T,
    /// GLR: a further simultaneous fault is accepted only if its statistic is
    /// at least this fraction of the first one's.
    pub glr_relative: T,
    /// Dead-band of the run-time sign matrix, relative to the row maximum.
    pub sign_deadband: T,
    /// Smallest fault per IMU channel the monitor is specified to detect; used
    /// to scale the threshold method and the run-time sign matrix.
    pub min_fault: ImuVec<T>,
    /// Threshold method: a channel is flagged when its t-test fires and the
    /// window mean mapped through the diagonal of `M` exceeds this fraction
    /// of `min_fault`.
    pub threshold_fraction: T,
    /// Consecutive detections needed to raise or clear a channel flag (AUV
    /// preset 2, aircraft 1; see [`aircraft`](Self::aircraft)).
    pub persistence: u16,
    /// Upper bound of the learned innovation inflation (1 disables it; the
    /// OTSUKF monitor bounds its learned `R` inflation by it too,
    /// `OtsukfConfig::inflation_block`).
    /// During learning the monitor measures, per innovation channel, how
    /// much larger the window t statistic's spread is on this vehicle's
    /// healthy data than the white-noise t distribution says: time
    /// correlation of real aiding errors (GNSS velocity, an autopilot's
    /// attitude, latency) makes the window std underestimate the spread of
    /// the window mean. While monitoring, each channel's t statistic (and
    /// its GLR weight) is divided by that factor's square root, so the
    /// false-alarm rate follows from the data, not from a whiteness
    /// assumption. The factor is ≥ 1 (never more sensitive than the
    /// white-noise test), bounded by this value (a fault present during
    /// learning cannot switch detection off), and learned only in the
    /// learning phase, i.e. frozen while monitoring — unless
    /// [`inflation_memory_s`](Self::inflation_memory_s) is set.
    pub max_innovation_inflation: T,
    /// Memory of the inflation while monitoring, s (0: frozen at the end
    /// of learning). With it (feature `inflation-tracking`) the learning
    /// goes on in flight on quiet epochs with this exponential memory, and
    /// a window more active than what the inflation was learnt at is not
    /// judged by the UKF's own test but learnt (`inflation_cover.rs`):
    /// an inflation learnt on the ground says nothing of flight.
    pub inflation_memory_s: T,
    /// Time from alignment to the start of learning, s.
    pub converge_s: T,
    /// Duration of the learning phase, s.
    pub learn_s: T,
    /// Largest nominal bias the learner may attribute to the IMU per
    /// channel: the sensor's specified turn-on bias (plus whatever drift
    /// the learning may see). A larger bias present from power-up is not
    /// absorbed: the learned bias stops at this bound and the excess stays
    /// in the innovations, where the detector reports it as a fault once
    /// monitoring starts (until then the report's phase says the monitor
    /// cannot judge yet and every channel is `NotMonitored`). `None`:
    /// 20 × `min_fault`, a bound no datasheet needs (the former default).
    pub max_nominal_bias: Option<ImuVec<T>>,
    /// Time constant of the nominal-bias estimator during learning, s.
    pub learn_tau_s: T,
    /// Time constant of drift tracking while monitoring, s.
    pub drift_tau_s: T,
    /// Largest drift-tracking rate per channel (bias-instability spec), unit/s.
    pub drift_rate_limit: ImuVec<T>,
    /// IMU full scale per channel; samples beyond 98 % are "saturated".
    pub full_scale: ImuVec<T>,
    /// Nominal IMU period, s; `dt` beyond 5× is a gap.
    pub imu_period: T,
    /// Known latency of the aiding measurements, s (0 = none): they are
    /// fused against the state estimate of their own time, kept in a short
    /// history of up to [`MAX_DELAY_STEPS`](super::MAX_DELAY_STEPS) IMU periods.
    pub aiding_delay_s: T,
    /// Estimate the aiding latency online (issue 15); `aiding_delay_s` is
    /// then only the lag used until the first estimate (after 6 s of
    /// attitude aiding). The estimate is the lag, within the state history
    /// (≤ 0.22 s with 10 Hz attitude aiding), at which the IMU-propagated
    /// attitude changes best match the aiding's; while it moves during
    /// learning, learning restarts. Read it with
    /// [`UkfMonitor::aiding_delay_estimate`](super::UkfMonitor::aiding_delay_estimate).
    pub estimate_aiding_delay: bool,
    /// Latency of the velocity aiding alone, s, when it differs from the
    /// attitude's (PX4 EKF2's `EKF2_GPS_DELAY` beside `EKF2_EV_DELAY`):
    /// `None` (default) fuses the velocity at the same horizon as the
    /// attitude (`aiding_delay_s` or its estimate). `Some(d)`: each velocity
    /// epoch is brought from its own time to that horizon by the
    /// IMU-propagated change the state history holds between the two,
    /// `z_v + h_v(x[horizon]) − h_v(x[d])`, as the OTSUKF brings a late
    /// velocity to now. At most [`MAX_DELAY_STEPS`](super::MAX_DELAY_STEPS)
    /// IMU periods (the history's length).
    pub velocity_delay_s: Option<T>,
    /// Learn a constant heading offset between the attitude aiding's frame
    /// and the IMU's (issue 15) from the GNSS velocity's horizontal changes
    /// against the IMU-propagated ones, bounded to ±10°, paused while a
    /// fault is flagged, and taken off the yaw aiding. While the offset is
    /// unresolved, manoeuvres do not teach the horizontal accelerometer
    /// biases and learning lasts longer (see `ukf_monitor/heading.rs`,
    /// docs/results.md). Read it with
    /// [`UkfMonitor::heading_offset_estimate`](super::UkfMonitor::heading_offset_estimate).
    /// Epochs the offset not yet resolved may have contaminated beyond half
    /// `min_fault` leave a_x and a_y `NotMonitored`; with that, one decision
    /// (`persistence` 1, the aircraft preset) suffices (3° offset: 0
    /// post-clear events on 85 seeds of episodes, 1 in 2.07 h on 40 more,
    /// 0 in 42 fault-free hours, step delay median 0.94–0.97 s;
    /// docs/results.md).
    pub estimate_heading_offset: bool,
    /// Random-walk spectral density of the fault, per channel
    /// ((m/s²)²/s, (rad/s)²/s), for the tracking fault estimate reported
    /// while monitoring (issue 15; `ukf_monitor/fault_track.rs`): a Kalman
    /// filter on the fault and on the state deviation it has caused, fed by
    /// every innovation, instead of the window mean mapped by `M⁺`
    /// (`None`, SPEC §6). Larger follows faster changes with more noise.
    /// Detection uses the window means either way. Off in the presets: on
    /// the Cortex-M4F it costs ≈ 20,000 instructions per aiding epoch
    /// (docs/performance.md); [`Self::fault_tracking_psd`] is the
    /// OTSUKF's value, on in `replay`'s flight profile.
    pub fault_psd: Option<ImuVec<T>>,
    /// The gyro/attitude-aiding consistency test (issue 15,
    /// `monitor/block_test/attitude_rate/`): the gyro integrated between
    /// attitude epochs against the aiding's rotation, summed over windows
    /// of seconds and tested against the spread this flight has shown at
    /// those lengths, for gyro biases against an aiding whose errors
    /// wander (a real autopilot's attitude). Its flags are added to the
    /// ten-epoch test's on the gyro channels (the OTSUKF monitor's: to its
    /// fault-estimate test's). Off in the presets; on in
    /// `replay`'s flight profile ([`AttitudeRateConfig::flight`]). Needs
    /// the feature `attitude-rate-test`.
    pub attitude_rate: Option<AttitudeRateConfig<T>>,
    /// The accelerometer/GNSS-velocity consistency test (issue 15,
    /// `monitor/block_test/velocity_increment/`): the raw specific force rotated
    /// by the attitude aiding and integrated between GNSS velocity epochs
    /// (at a GNSS lag learnt from the data) against the GNSS velocity
    /// change, as a body-axis bias over windows of seconds, tested like
    /// [`attitude_rate`](Self::attitude_rate). Its flags are added to the
    /// ten-epoch test's (the OTSUKF's fault-estimate test's) on the
    /// accelerometer channels. Off in the presets;
    /// on in `replay`'s flight profile ([`VelocityIncrementConfig::velocity`]).
    /// Needs the feature `velocity-increment-test` and GNSS velocity plus
    /// attitude aiding (M2).
    pub velocity_increment: Option<VelocityIncrementConfig<T>>,
    /// An aiding channel silent for this long is "not monitored", s.
    pub aiding_timeout_s: T,
    /// Identical consecutive IMU samples before the IMU is reported frozen.
    pub frozen_samples: u16,
}

impl<T: Real> UkfMonitorConfig<T> {
    /// Defaults for an AUV with a MEMS IMU (ICM-42688-P class) at 100 Hz, a
    /// 5 Hz DVL (σ 0.01 m/s) and a 10 Hz AHRS/compass (σ 0.02° roll/pitch,
    /// 0.05° heading) — the M1 setting of the built-in scenarios.
    pub fn auv() -> Self {
        let deg = core::f64::consts::PI / 180.0;
        Self {
            aiding: AidingKind::DvlCompass,
            lever_arm: [T::zero(); 3],
            gravity: T::lit(G0),
            cos_pitch_min: T::lit(0.1),
            process_noise: ImuNoisePsd::uniform(T::lit(6.0e-5), T::lit(2.0e-7)),
            meas_sigma: MeasVec::new(
                T::lit(0.01),
                T::lit(0.01),
                T::lit(0.01),
                T::lit(0.02 * deg),
                T::lit(0.02 * deg),
                T::lit(0.05 * deg),
            ),
            initial_sigma: StateVec::new(
                T::lit(0.1),
                T::lit(0.1),
                T::lit(0.1),
                T::lit(1.0 * deg),
                T::lit(1.0 * deg),
                T::lit(2.0 * deg),
            ),
            sigma: SigmaParams::default(),
            gate_sigma: T::lit(8.0),
            gate_max_rejections: 2,
            max_aiding_speed: T::lit(100.0),
            realign_innovation: MeasVec::new(
                T::lit(5.0),
                T::lit(5.0),
                T::lit(5.0),
                T::lit(20.0 * deg),
                T::lit(20.0 * deg),
                T::lit(20.0 * deg),
            ),
            alpha: 1e-6,
            outlier_k: T::zero(),
            statistic: Statistic::Normalized,
            detector: Detector::RuntimeMatrixGlr,
            glr_threshold: T::lit(40.0),
            glr_relative: T::lit(0.02),
            sign_deadband: T::lit(0.3),
            min_fault: ImuVec::new(
                T::lit(0.05),
                T::lit(0.05),
                T::lit(0.05),
                T::lit(0.3 * deg),
                T::lit(0.3 * deg),
                T::lit(0.3 * deg),
            ),
            threshold_fraction: T::lit(1.0),
            persistence: 2,
            max_innovation_inflation: T::one(),
            inflation_memory_s: T::zero(),
            converge_s: T::lit(3.0),
            learn_s: T::lit(7.0),
            max_nominal_bias: None,
            learn_tau_s: T::lit(1.5),
            drift_tau_s: T::lit(200.0),
            drift_rate_limit: ImuVec::new(
                T::lit(2e-4),
                T::lit(2e-4),
                T::lit(2e-4),
                T::lit(2e-5),
                T::lit(2e-5),
                T::lit(2e-5),
            ),
            full_scale: ImuVec::new(
                T::lit(16.0 * G0),
                T::lit(16.0 * G0),
                T::lit(16.0 * G0),
                T::lit(2000.0 * deg),
                T::lit(2000.0 * deg),
                T::lit(2000.0 * deg),
            ),
            imu_period: T::lit(0.01),
            aiding_delay_s: T::zero(),
            estimate_aiding_delay: false,
            velocity_delay_s: None,
            estimate_heading_offset: false,
            fault_psd: None,
            attitude_rate: None,
            velocity_increment: None,
            aiding_timeout_s: T::lit(1.0),
            frozen_samples: 20,
        }
    }

    /// The OTSUKF's fault random walk (`OtsukfConfig::from_base`: 0.05
    /// (m/s²)²/s, (0.5 °/s)²/s), for [`Self::fault_psd`]: the same fault
    /// model for both monitors' estimates.
    pub fn fault_tracking_psd() -> ImuVec<T> {
        let g = core::f64::consts::PI / 180.0 * 0.5;
        ImuVec::new(
            T::lit(0.05),
            T::lit(0.05),
            T::lit(0.05),
            T::lit(g * g),
            T::lit(g * g),
            T::lit(g * g),
        )
    }

    /// Defaults for an aircraft with GNSS NED velocity (σ 0.05 m/s) and GNSS
    /// attitude (σ 0.1°, 0.2° heading), M2; one decision raises a flag
    /// (`persistence` 1).
    pub fn aircraft() -> Self {
        let deg = core::f64::consts::PI / 180.0;
        let mut c = Self::auv();
        c.aiding = AidingKind::GnssAttitude;
        c.meas_sigma = MeasVec::new(
            T::lit(0.05),
            T::lit(0.05),
            T::lit(0.05),
            T::lit(0.1 * deg),
            T::lit(0.1 * deg),
            T::lit(0.2 * deg),
        );
        c.process_noise = ImuNoisePsd::uniform(T::lit(1.0e-3), T::lit(4.0e-6));
        c.min_fault = ImuVec::new(
            T::lit(0.2),
            T::lit(0.2),
            T::lit(0.2),
            T::lit(1.0 * deg),
            T::lit(1.0 * deg),
            T::lit(1.0 * deg),
        );
        // One decision, not two: the false-alarm rate is set by `alpha`
        // (a flag needs some channel's two-sided test to fire, so at most
        // 6·2α per aiding epoch: 0.43 events per hour at 10 Hz and
        // α = 10⁻⁶, on innovations as white as the learnt inflation says), and
        // the windows of consecutive epochs share W − 1 samples, so a second
        // decision adds little independent evidence but one aiding interval
        // of delay (issue 15: aircraft step delay median 1.05 s → 0.95 s,
        // 0 false alarms in 10 fault-free hours either way).
        c.persistence = 1;
        c
    }

    /// Largest nominal bias per channel a monitor's learner may assume:
    /// [`max_nominal_bias`](Self::max_nominal_bias), else
    /// `MAX_NOMINAL_BIAS_FACTOR` (20) × `min_fault`. Beyond it a bias is a
    /// fault present from power-on, not a nominal error (both monitors).
    pub fn nominal_bias_bound(&self) -> ImuVec<T> {
        self.max_nominal_bias
            .unwrap_or_else(|| self.min_fault * T::lit(MAX_NOMINAL_BIAS_FACTOR))
    }

    /// Checks every field: what would make the filter or the tests
    /// meaningless (a NaN statistic) or silent (a test that can never fire).
    /// The error names the first offending field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let pos = |v: T| v.finite() && v > T::zero();
        let non_neg = |v: T| v.finite() && v >= T::zero();
        let positive: [(&'static str, bool); 11] = [
            (
                "process_noise",
                self.process_noise.psd.iter().all(|v| pos(*v)),
            ),
            ("meas_sigma", self.meas_sigma.iter().all(|v| pos(*v))),
            ("initial_sigma", self.initial_sigma.iter().all(|v| pos(*v))),
            ("full_scale", self.full_scale.iter().all(|v| pos(*v))),
            ("imu_period", pos(self.imu_period)),
            ("learn_tau_s", pos(self.learn_tau_s)),
            ("drift_tau_s", pos(self.drift_tau_s)),
            ("aiding_timeout_s", pos(self.aiding_timeout_s)),
            ("gravity", pos(self.gravity)),
            ("max_aiding_speed", pos(self.max_aiding_speed)),
            (
                "realign_innovation",
                self.realign_innovation.iter().all(|v| pos(*v)),
            ),
        ];
        if let Some(&(field, _)) = positive.iter().find(|(_, ok)| !ok) {
            return Err(ConfigError::NonPositive(field));
        }
        let delay_steps = self.aiding_delay_s / self.imu_period;
        if !delay_steps.finite()
            || delay_steps < T::zero()
            || delay_steps > T::lit(super::MAX_DELAY_STEPS as f64)
        {
            return Err(ConfigError::AidingDelay);
        }
        if let Some(d) = self.velocity_delay_s {
            let steps = d / self.imu_period;
            if !steps.finite() || steps < T::zero() || steps > T::lit(super::MAX_DELAY_STEPS as f64)
            {
                return Err(ConfigError::VelocityDelay);
            }
        }
        if !(self.alpha > 0.0 && self.alpha <= 0.5) {
            return Err(ConfigError::TTest);
        }
        // Checked when the filter is built as well; here so that `validate`
        // alone answers for the whole configuration.
        if SigmaWeights::<T, 13>::new(&self.sigma).is_none() {
            return Err(ConfigError::SigmaParams);
        }
        let positive: [(&'static str, bool); 6] = [
            ("gate_sigma", pos(self.gate_sigma)),
            ("glr_threshold", pos(self.glr_threshold)),
            ("min_fault", self.min_fault.iter().all(|v| pos(*v))),
            ("threshold_fraction", pos(self.threshold_fraction)),
            ("persistence", self.persistence > 0),
            ("frozen_samples", self.frozen_samples > 0),
        ];
        if let Some(&(field, _)) = positive.iter().find(|(_, ok)| !ok) {
            return Err(ConfigError::NonPositive(field));
        }
        let in_range: [(&'static str, bool); 12] = [
            ("lever_arm", self.lever_arm.iter().all(|v| v.finite())),
            (
                "cos_pitch_min",
                pos(self.cos_pitch_min) && self.cos_pitch_min < T::one(),
            ),
            ("outlier_k", non_neg(self.outlier_k)),
            (
                "glr_relative",
                non_neg(self.glr_relative) && self.glr_relative <= T::one(),
            ),
            (
                "sign_deadband",
                non_neg(self.sign_deadband) && self.sign_deadband < T::one(),
            ),
            ("converge_s", non_neg(self.converge_s)),
            ("inflation_memory_s", non_neg(self.inflation_memory_s)),
            (
                "max_nominal_bias",
                self.max_nominal_bias
                    .is_none_or(|m| m.iter().all(|v| non_neg(*v))),
            ),
            (
                "max_innovation_inflation",
                self.max_innovation_inflation.finite() && self.max_innovation_inflation >= T::one(),
            ),
            ("learn_s", non_neg(self.learn_s)),
            (
                "fault_psd",
                self.fault_psd.is_none_or(|m| m.iter().all(|v| pos(*v))),
            ),
            (
                "drift_rate_limit",
                self.drift_rate_limit.iter().all(|v| non_neg(*v)),
            ),
        ];
        if let Some(&(field, _)) = in_range.iter().find(|(_, ok)| !ok) {
            return Err(ConfigError::OutOfRange(field));
        }
        if !cfg!(feature = "aiding-estimators") {
            if self.estimate_aiding_delay {
                return Err(ConfigError::NotCompiled("estimate_aiding_delay"));
            }
            if self.estimate_heading_offset {
                return Err(ConfigError::NotCompiled("estimate_heading_offset"));
            }
        }
        if !cfg!(feature = "m2-aiding") && self.aiding == AidingKind::GnssAttitude {
            return Err(ConfigError::NotCompiled("aiding"));
        }
        if !cfg!(feature = "alt-detectors") && self.detector != Detector::RuntimeMatrixGlr {
            return Err(ConfigError::NotCompiled("detector"));
        }
        if !cfg!(feature = "t-statistics") && self.statistic != Statistic::Normalized {
            return Err(ConfigError::NotCompiled("statistic"));
        }
        if !cfg!(feature = "fault-tracking") && self.fault_psd.is_some() {
            return Err(ConfigError::NotCompiled("fault_psd"));
        }
        if let Some(ar) = self.attitude_rate.as_ref() {
            if !cfg!(feature = "attitude-rate-test") {
                return Err(ConfigError::NotCompiled("attitude_rate"));
            }
            ar.check().map_err(ConfigError::OutOfRange)?;
        }
        if let Some(vi) = self.velocity_increment.as_ref() {
            if !cfg!(feature = "velocity-increment-test") {
                return Err(ConfigError::NotCompiled("velocity_increment"));
            }
            // NED GNSS velocity is what it integrates against (M2).
            if vi.check().is_err() || self.aiding != AidingKind::GnssAttitude {
                return Err(ConfigError::OutOfRange("velocity_increment"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn not_compiled_names_its_feature() {
        for (field, feature) in [
            ("aiding", "m2-aiding"),
            ("fault_psd", "fault-tracking"),
            ("estimate_heading_offset", "aiding-estimators"),
            ("detector", "alt-detectors"),
            ("statistic", "t-statistics"),
            ("attitude_rate", "attitude-rate-test"),
            ("velocity_increment", "velocity-increment-test"),
        ] {
            assert_eq!(ConfigError::NotCompiled(field).feature(), Some(feature));
        }
        assert_eq!(ConfigError::TTest.feature(), None);
        let msg = format!("{}", ConfigError::NotCompiled("aiding"));
        assert_eq!(
            msg,
            "aiding: needs the crate's `m2-aiding` feature (on by default)"
        );
    }

    /// M2 aiding, the other decision rules and the t statistics are
    /// accepted exactly when their code is compiled in (`cargo test --lib
    /// --no-default-features` runs the other arm).
    #[test]
    fn options_need_their_features() {
        let check = |c: UkfMonitorConfig<f64>, field: &'static str, on: bool| {
            let want = if on {
                Ok(())
            } else {
                Err(ConfigError::NotCompiled(field))
            };
            assert_eq!(c.validate(), want, "{field}");
        };
        check(
            UkfMonitorConfig::aircraft(),
            "aiding",
            cfg!(feature = "m2-aiding"),
        );
        for d in [
            Detector::Threshold,
            Detector::PaperMatrix,
            Detector::PaperMatrixAsPrinted,
            Detector::RuntimeMatrix,
        ] {
            let mut c = UkfMonitorConfig::auv();
            c.detector = d;
            check(c, "detector", cfg!(feature = "alt-detectors"));
        }
        for st in [Statistic::Raw, Statistic::Whitened] {
            let mut c = UkfMonitorConfig::auv();
            c.statistic = st;
            check(c, "statistic", cfg!(feature = "t-statistics"));
        }
        let mut c = UkfMonitorConfig::auv();
        c.attitude_rate = Some(AttitudeRateConfig::flight());
        check(c, "attitude_rate", cfg!(feature = "attitude-rate-test"));
        if cfg!(feature = "m2-aiding") {
            let mut c = UkfMonitorConfig::aircraft();
            c.velocity_increment = Some(VelocityIncrementConfig::velocity());
            check(
                c,
                "velocity_increment",
                cfg!(feature = "velocity-increment-test"),
            );
        }
        assert_eq!(UkfMonitorConfig::<f64>::auv().validate(), Ok(()));
        // The velocity test integrates against NED GNSS velocity (M2 only).
        let mut c = UkfMonitorConfig::<f64>::auv();
        c.velocity_increment = Some(VelocityIncrementConfig::velocity());
        let want = if cfg!(feature = "velocity-increment-test") {
            ConfigError::OutOfRange("velocity_increment")
        } else {
            ConfigError::NotCompiled("velocity_increment")
        };
        assert_eq!(c.validate(), Err(want));
    }
}

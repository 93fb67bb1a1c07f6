use crate::detect::{Detector, Statistic};
use crate::filter::SigmaParams;
use crate::math::Real;
use crate::model::{AidingKind, ImuNoisePsd, ImuVec, MeasVec, StateVec, G0};

/// A configuration the monitor cannot run with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The sigma-point parameters give no real spread.
    SigmaParams,
    /// α outside (0, 0.5] or a window too short for a t-test.
    TTest,
    /// A noise, σ, rate or time constant is not finite and positive.
    NonPositive,
    /// The aiding latency is negative or longer than the state history.
    AidingDelay,
}

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
    /// Longest run of consecutive gate rejections before fusing again.
    pub gate_max_rejections: u8,
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
    /// Consecutive detections needed to raise or clear a channel flag.
    pub persistence: u16,
    /// Time from alignment to the start of learning, s.
    pub converge_s: T,
    /// Duration of the learning phase, s.
    pub learn_s: T,
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
            converge_s: T::lit(3.0),
            learn_s: T::lit(7.0),
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
            aiding_timeout_s: T::lit(1.0),
            frozen_samples: 20,
        }
    }

    /// Defaults for an aircraft with GNSS NED velocity (σ 0.05 m/s) and GNSS
    /// attitude (σ 0.1°, 0.2° heading), M2.
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
        c
    }

    /// Checks the values that would make the filter or the tests meaningless.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let pos = |v: T| v.finite() && v > T::zero();
        let all_pos = self.process_noise.psd.iter().all(|v| pos(*v))
            && self.meas_sigma.iter().all(|v| pos(*v))
            && self.initial_sigma.iter().all(|v| pos(*v))
            && self.full_scale.iter().all(|v| pos(*v))
            && pos(self.imu_period)
            && pos(self.learn_tau_s)
            && pos(self.drift_tau_s)
            && pos(self.aiding_timeout_s)
            && pos(self.gravity);
        if !all_pos {
            return Err(ConfigError::NonPositive);
        }
        let delay_steps = self.aiding_delay_s / self.imu_period;
        if !delay_steps.finite()
            || delay_steps < T::zero()
            || delay_steps > T::lit(super::MAX_DELAY_STEPS as f64)
        {
            return Err(ConfigError::AidingDelay);
        }
        if !(self.alpha > 0.0 && self.alpha <= 0.5) {
            return Err(ConfigError::TTest);
        }
        Ok(())
    }
}

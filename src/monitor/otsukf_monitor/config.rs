//! Configuration of the two-stage UKF monitor.

use crate::math::Real;
use crate::model::ImuVec;
use crate::monitor::{ConfigError, UkfMonitorConfig};

/// Configuration of [`OtsukfMonitor`](super::OtsukfMonitor).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtsukfConfig<T> {
    /// Vehicle, sensors, aiding, start-up timing and minimum faults, the
    /// bound of the learned `R` inflation (`max_innovation_inflation`) and
    /// the two block tests (`attitude_rate`, `velocity_increment`), and the
    /// attitude aiding's latency: `aiding_delay_s` (fixed) or
    /// `estimate_aiding_delay` (online, up to 32 IMU periods; with the
    /// `aiding-estimators` feature, `attitude_lag.rs`), which here apply to
    /// the attitude only (the velocity's is `velocity_lag_s`); the
    /// innovation monitor's other detector fields are not used.
    pub base: UkfMonitorConfig<T>,
    /// Random-walk power spectral density of the fault model per channel,
    /// ((m/s²)²/s, (rad/s)²/s): `Q^f = psd · dt` per step. It sets how fast a
    /// fault estimate follows a change (and how noisy it is when quiet).
    pub fault_psd: ImuVec<T>,
    /// Initial fault standard deviation per channel (`P^f₀`).
    pub fault_sigma0: ImuVec<T>,
    /// A channel is declared faulty when `|f̂ − b| ≥ k_on·σ_f` and
    /// `|f̂ − b| ≥ min_fault` (`b` the nominal bias learned at start-up)…
    pub k_on: T,
    /// …and cleared when `|f̂ − b| < k_off·σ_f` or `|f̂ − b| < min_fault/2`.
    pub k_off: T,
    /// Adaptive fault noise: when one update moves a channel's fault
    /// estimate by more than `adapt_k` of its standard deviation (the fault
    /// filter is being pulled by a change it was not expecting), that
    /// channel's `Q^f` is multiplied by its `adapt_gain` for `adapt_hold_s`, so a
    /// step is followed in a few aiding periods instead of being smoothed by
    /// a random walk tuned for a quiet bias. A gain of 1 disables it on that
    /// channel.
    pub adapt_k: T,
    /// See [`adapt_k`](Self::adapt_k).
    pub adapt_gain: ImuVec<T>,
    /// See [`adapt_k`](Self::adapt_k).
    pub adapt_hold_s: T,
    /// With `Some(l)`, the adaptation is also held while a monitored
    /// channel's `|f̂ − b| ≥ l·σ_f`, so a fault that keeps changing (a slow
    /// sine) is followed with the faster random walk all the time it is
    /// present, not only after sudden moves. It pays where the aiding is
    /// fast and precise (\[OTS\]'s setting: 100 Hz, 0.01°); with 10 Hz GNSS
    /// the extra fault-estimate noise costs more than the lag it saves
    /// (measured on S2/S3, see the README), hence `None` by default.
    pub adapt_level: Option<T>,
    /// Epochs per block of the learned measurement-noise inflation (bounded
    /// by `base.max_innovation_inflation`; 1 there disables it): during
    /// learning each aiding component's `R` is scaled by what the spread of
    /// its innovation, averaged over blocks of this many consecutive
    /// epochs, proves beyond the filter's prediction, so time correlation
    /// over a block counts too (`inflation.rs`).
    pub inflation_block: u16,
    /// Latency of the velocity aiding, s: each velocity sample describes the
    /// vehicle this long before it arrives, and is brought to now by the
    /// IMU-propagated velocity change over the lag before it is fused
    /// (`velocity_lag.rs`). 0: fused on arrival. At most 64 IMU periods.
    pub velocity_lag_s: T,
}

impl<T: Real> OtsukfConfig<T> {
    /// Defaults around an innovation-monitor configuration: fault random walk
    /// of 0.05 (m/s²)²/s and (0.5 °/s)²/s — a step is followed within about a
    /// second at 10 Hz aiding — initial fault σ of 1 m/s² and 1 °/s, and a
    /// 4σ / 2σ hysteresis (4σ: the 0.3 m/s² step of S2 is flagged while
    /// S2, S3 and 24 fault-free hours raise no false flag). The `Q^f`
    /// adaptation (×10 for 0.3 s after a 3σ move) is on for the
    /// accelerometers only: with 10 Hz GNSS or 5 Hz DVL/compass aiding it
    /// measured no gain on the gyro channels of S2 and S3 and 2 % more
    /// fault-free noise (README, two-stage UKF).
    pub fn from_base(base: UkfMonitorConfig<T>) -> Self {
        let deg = core::f64::consts::PI / 180.0;
        let ga = T::lit(0.05);
        let gg = T::lit((0.5 * deg) * (0.5 * deg));
        Self {
            base,
            fault_psd: ImuVec::new(ga, ga, ga, gg, gg, gg),
            fault_sigma0: ImuVec::new(
                T::one(),
                T::one(),
                T::one(),
                T::lit(deg),
                T::lit(deg),
                T::lit(deg),
            ),
            k_on: T::lit(4.0),
            k_off: T::lit(2.0),
            adapt_k: T::lit(3.0),
            adapt_gain: ImuVec::new(
                T::lit(10.0),
                T::lit(10.0),
                T::lit(10.0),
                T::one(),
                T::one(),
                T::one(),
            ),
            adapt_hold_s: T::lit(0.3),
            adapt_level: None,
            inflation_block: 10,
            velocity_lag_s: T::zero(),
        }
    }

    /// The velocity aiding's latency in whole IMU periods.
    pub(super) fn lag_steps(&self) -> usize {
        let n = (self.velocity_lag_s / self.base.imu_period).to_f64();
        if n.is_finite() && n > 0.0 {
            (n + 0.5) as usize
        } else {
            0
        }
    }

    /// The attitude aiding's configured latency (`base.aiding_delay_s`) in
    /// whole IMU periods: the lag compensated until an estimate exists.
    #[cfg(feature = "aiding-estimators")]
    pub(super) fn attitude_lag_steps(&self) -> usize {
        let n = (self.base.aiding_delay_s / self.base.imu_period).to_f64();
        if n.is_finite() && n > 0.0 {
            (n + 0.5) as usize
        } else {
            0
        }
    }

    /// Checks every field, the base configuration's included; the error
    /// names the first offending field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.base.validate()?;
        let pos = |v: T| v.finite() && v > T::zero();
        let positive: [(&'static str, bool); 6] = [
            ("fault_psd", self.fault_psd.iter().all(|v| pos(*v))),
            ("fault_sigma0", self.fault_sigma0.iter().all(|v| pos(*v))),
            ("k_on", pos(self.k_on)),
            ("k_off", pos(self.k_off)),
            ("adapt_k", pos(self.adapt_k)),
            ("adapt_level", self.adapt_level.is_none_or(pos)),
        ];
        if let Some(&(field, _)) = positive.iter().find(|(_, ok)| !ok) {
            return Err(ConfigError::NonPositive(field));
        }
        let in_range: [(&'static str, bool); 4] = [
            // Hysteresis: the clear threshold may not exceed the set one.
            ("k_off", self.k_off <= self.k_on),
            (
                "adapt_gain",
                self.adapt_gain.iter().all(|g| g.finite() && *g >= T::one()),
            ),
            (
                "adapt_hold_s",
                self.adapt_hold_s.finite() && self.adapt_hold_s >= T::zero(),
            ),
            (
                "velocity_lag_s",
                self.velocity_lag_s.finite()
                    && self.velocity_lag_s >= T::zero()
                    && self.lag_steps() <= super::LAG_RING,
            ),
        ];
        if let Some(&(field, _)) = in_range.iter().find(|(_, ok)| !ok) {
            return Err(ConfigError::OutOfRange(field));
        }
        // The attitude latency (`attitude_lag.rs`) is compiled with the
        // aiding estimators; without them it would be silently ignored.
        if !cfg!(feature = "aiding-estimators") && self.base.aiding_delay_s != T::zero() {
            return Err(ConfigError::NotCompiled("aiding_delay_s"));
        }
        Ok(())
    }
}

//! Complete validation of a [`ParityConfig`], and the text of a
//! [`ConfigError`]. Kept apart from the monitor so that the checks read as
//! one list.

use core::fmt;

use super::{ConfigError, ParityConfig};
use crate::math::Real;

impl<T: Real> ParityConfig<T> {
    /// Checks every field: what would make the statistics NaN (no samples
    /// per block or no training) or the tests silent (a margin, bias or
    /// limit of zero). The monitor's capacity `W` is checked by
    /// [`ParityMonitor::new`](super::ParityMonitor::new), which calls this.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.window_blocks == 0 {
            return Err(ConfigError::Window);
        }
        if !(self.false_alarm > 0.0 && self.false_alarm < 0.5)
            || self.cusum_arl0.is_nan()
            || self.cusum_arl0 <= 1.0
        {
            return Err(ConfigError::Probability);
        }
        let pos = |v: T| v.finite() && v > T::zero();
        let non_neg = |v: T| v.finite() && v >= T::zero();
        let h = &self.health;
        let checks: [(&'static str, bool); 14] = [
            ("block_len", self.block_len > 0),
            ("train_samples", self.train_samples > 0),
            ("threshold_margin", pos(self.threshold_margin)),
            ("cusum_bias", pos(self.cusum_bias)),
            ("ridge", non_neg(self.ridge)),
            ("drift_blocks", non_neg(self.drift_blocks)),
            ("isolate_after", self.isolate_after > 0),
            ("health.full_scale", pos(h.full_scale)),
            (
                "health.clip_fraction",
                pos(h.clip_fraction) && h.clip_fraction <= T::one(),
            ),
            ("health.stuck_samples", h.stuck_samples > 0),
            ("health.timeout_samples", h.timeout_samples > 0),
            ("health.out_of_range_limit", h.out_of_range_limit > 0),
            ("health.bus_error_limit", h.bus_error_limit > 0),
            ("health.rail_samples", h.rail_samples > 0),
        ];
        match checks.iter().find(|(_, ok)| !ok) {
            Some(&(field, _)) => Err(ConfigError::Field(field)),
            None => Ok(()),
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadDirection(i) => {
                write!(f, "geometry: direction of sensor {i} is zero or not finite")
            }
            Self::TriadCount => {
                f.write_str("geometry: N is not three times the number of rotations")
            }
            Self::TooFewSensors => {
                f.write_str("geometry: fewer than four active sensors, no parity space")
            }
            Self::RankDeficient => f.write_str("geometry: the active directions do not span 3-D"),
            Self::Window => {
                f.write_str("window_blocks: zero, or longer than the monitor's capacity W")
            }
            Self::Probability => f.write_str(
                "false_alarm / cusum_arl0: probability outside (0, 0.5) or run length ≤ 1",
            ),
            Self::Multiscale => {
                f.write_str("multiscale: a field out of range (see MultiscaleConfig::check)")
            }
            Self::Field(field) => write!(f, "{field}: zero, negative, NaN or out of range"),
        }
    }
}

impl core::error::Error for ConfigError {}

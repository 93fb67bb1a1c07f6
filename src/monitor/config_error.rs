//! The UKF monitor's configuration errors.

use core::fmt;

/// A configuration the monitor cannot run with. Its `Display` names the
/// field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The sigma-point parameters (`sigma`) give no real spread.
    SigmaParams,
    /// `alpha` outside (0, 0.5] or a window too short for a t-test.
    TTest,
    /// This field (a noise, σ, rate, time constant, threshold or count) is
    /// zero, negative or not finite.
    NonPositive(&'static str),
    /// This field is not finite or outside its range (a fraction beyond 1, a
    /// negative time, a hysteresis threshold above the one it pairs with).
    OutOfRange(&'static str),
    /// `aiding_delay_s` is negative or longer than the state history.
    AidingDelay,
    /// `velocity_delay_s` is negative or longer than the state history.
    VelocityDelay,
    /// This option needs a cargo feature the crate was built without
    /// (`estimate_aiding_delay` and `estimate_heading_offset`:
    /// `aiding-estimators`; `fault_psd`: `fault-tracking`; M2 `aiding`:
    /// `m2-aiding`; a `detector` other than GLR: `alt-detectors`; a
    /// `statistic` other than `Normalized`: `t-statistics`;
    /// `attitude_rate`: `attitude-rate-test`; `velocity_increment`:
    /// `velocity-increment-test`).
    NotCompiled(&'static str),
}

impl ConfigError {
    /// The configuration field at fault.
    pub fn field(&self) -> &'static str {
        match self {
            Self::SigmaParams => "sigma",
            Self::TTest => "alpha",
            Self::NonPositive(f) | Self::OutOfRange(f) | Self::NotCompiled(f) => f,
            Self::AidingDelay => "aiding_delay_s",
            Self::VelocityDelay => "velocity_delay_s",
        }
    }

    /// The cargo feature a [`NotCompiled`](Self::NotCompiled) field needs
    /// (`None` for the other errors).
    pub fn feature(&self) -> Option<&'static str> {
        match self {
            Self::NotCompiled("fault_psd") => Some("fault-tracking"),
            Self::NotCompiled("aiding") => Some("m2-aiding"),
            Self::NotCompiled("detector") => Some("alt-detectors"),
            Self::NotCompiled("statistic") => Some("t-statistics"),
            Self::NotCompiled("attitude_rate") => Some("attitude-rate-test"),
            Self::NotCompiled("velocity_increment") => Some("velocity-increment-test"),
            Self::NotCompiled(_) => Some("aiding-estimators"),
            _ => None,
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let field = self.field();
        match self {
            Self::SigmaParams => {
                write!(f, "{field}: the sigma-point parameters give no real spread")
            }
            Self::TTest => write!(
                f,
                "{field}: outside (0, 0.5], or the window is too short for a t-test"
            ),
            Self::NonPositive(_) => write!(f, "{field}: must be finite and positive"),
            Self::OutOfRange(_) => write!(f, "{field}: not finite or outside its range"),
            Self::AidingDelay | Self::VelocityDelay => write!(
                f,
                "{field}: negative, or longer than the state history (MAX_DELAY_STEPS IMU periods)"
            ),
            Self::NotCompiled(_) => write!(
                f,
                "{field}: needs the crate's `{}` feature (on by default)",
                self.feature().unwrap_or_default()
            ),
        }
    }
}

impl core::error::Error for ConfigError {}

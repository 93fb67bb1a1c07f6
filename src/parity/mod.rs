//! Redundant single-axis sensors (\[PAR\], SPEC §7): parity space computed on
//! the target from any rank-3 geometry, the paper's PCA pattern test, a
//! windowed χ² (GLT) test and per-sensor CUSUMs, isolation by fault
//! direction, reconfiguration, hardware health checks and the fused output.
//!
//! ```
//! use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, Reading};
//!
//! let geometry = Geometry::<f32, 6>::cone6();
//! let cfg = ParityConfig::gyro(100.0, 34.9);
//! let mut monitor = ParityMonitor::<f32, 6, 16>::new(&geometry, cfg).unwrap();
//! let rate = nalgebra::Vector3::new(0.1_f32, -0.2, 0.05);
//! let readings = core::array::from_fn(|i| {
//!     Reading::Sample(geometry.direction(i).unwrap().dot(&rate))
//! });
//! let report = monitor.step(&readings);
//! assert!((report.fused.unwrap() - rate).norm() < 1e-6);
//! ```

mod config;
mod geometry;
mod health;
mod monitor;
mod multiscale;
mod rest;
mod space;
mod training;
mod validate;

pub use config::{ParityConfig, ParityDetector};
pub use geometry::{euler_rotation, yaw_rotation, Geometry};
pub use health::{HealthConfig, Reading, SensorHealth, SensorStatus};
pub use monitor::{
    reconfig_steps, DetectorFlags, ParityMonitor, ParityPhase, ParityReport, MAX_ISOLATIONS,
};
pub use multiscale::{
    BlockStage, MultiscaleConfig, MultiscaleDecision, REGRESSORS, SCALES, STAGES,
};
pub use rest::{RestCheck, RestConfig, RestReport, RestState, MIN_REST_BLOCKS};
pub use space::ParitySpace;
pub use training::{Baseline, Trainer};

/// A redundant-array configuration that cannot work. Its `Display` names
/// the field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// Sensor direction zero or not finite (sensor index).
    BadDirection(usize),
    /// Triad geometry: `N` is not three times the number of rotations.
    TriadCount,
    /// Fewer than four active sensors: no parity space.
    TooFewSensors,
    /// The active sensing directions do not span 3-D (rank < 3).
    RankDeficient,
    /// Window of zero blocks or longer than the monitor's capacity `W`.
    Window,
    /// False-alarm probability outside (0, 0.5) or run length ≤ 1.
    Probability,
    /// A field of [`MultiscaleConfig`] out of range (see its `check`).
    Multiscale,
    /// This field is zero, negative, not finite or out of range (see
    /// [`ParityConfig::validate`]).
    Field(&'static str),
}

//! The vehicle model shared by the UKF monitor and the two-stage filter
//! (SPEC §3): body-frame ground velocity and ZYX Euler attitude driven by the
//! IMU, and the two aiding measurement models.
//!
//! State `x = [u, v, w, φ, θ, ψ]` (m/s, rad); input `u_m = [a_x, a_y, a_z, p, q, r]`
//! (specific force m/s², body rate rad/s, FRD body axes, NED navigation frame).

mod dynamics;
mod measurement;
mod noise;

pub use dynamics::{AttitudeTrig, ModelError, VehicleModel};
pub use measurement::{AidingKind, Measurement, MeasurementModel, LEVER_ARM_NONE};
pub use noise::{
    discrete_process_noise, discrete_process_noise_from, discrete_process_noise_structured,
    ImuNoisePsd,
};

use nalgebra::{SMatrix, SVector};

/// Number of states.
pub const NX: usize = 6;
/// Number of IMU channels (and of fault channels).
pub const NU: usize = 6;
/// Number of aiding measurement channels.
pub const NZ: usize = 6;

/// State vector `[u, v, w, φ, θ, ψ]`.
pub type StateVec<T> = SVector<T, NX>;
/// IMU sample or fault vector in channel order `[a_x, a_y, a_z, p, q, r]`.
pub type ImuVec<T> = SVector<T, NU>;
/// Aiding measurement vector (see [`MeasurementModel`]).
pub type MeasVec<T> = SVector<T, NZ>;
/// A 6×6 matrix (covariances, Jacobians).
pub type Mat6<T> = SMatrix<T, 6, 6>;

/// Index of the roll angle φ in the state and measurement vectors.
pub const ROLL: usize = 3;
/// Index of the pitch angle θ.
pub const PITCH: usize = 4;
/// Index of the yaw angle ψ.
pub const YAW: usize = 5;
/// Which state components are angles (circular mean, wrapped differences).
pub const STATE_ANGLES: [bool; NX] = [false, false, false, true, true, true];
/// Standard gravity, m/s².
pub const G0: f64 = 9.806_65;
/// IMU channel names in channel order, for reports.
pub const CHANNEL_NAMES: [&str; NU] = ["ax", "ay", "az", "gx", "gy", "gz"];

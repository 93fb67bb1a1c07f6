//! # imu-fdi
//!
//! `no_std`, allocation-free fault detection, isolation and estimation for
//! inertial measurement units, for flight controllers and underwater vehicles.
//!
//! Every IMU period the monitor says whether each channel
//! `[a_x, a_y, a_z, p, q, r]` is faulty, with which sign, how large the fault
//! is and what the corrected reading is. This release implements the UKF
//! innovation monitor ([`monitor::UkfMonitor`]): a 6-state unscented Kalman
//! filter on the vehicle's body velocity and attitude, fed by the IMU and
//! aided by DVL + compass (AUV) or GNSS velocity + attitude (aircraft), with
//! windowed t-tests on the innovations, decoupling-matrix and GLR isolation,
//! and fault estimation.
//!
//! ```
//! use imu_fdi::model::{ImuVec, Measurement, MeasVec};
//! use imu_fdi::monitor::{UkfMonitor, UkfMonitorConfig, Phase};
//!
//! let mut monitor = UkfMonitor::<f32>::new(UkfMonitorConfig::auv()).unwrap();
//! // A level AUV at rest: specific force (0, 0, −g), no rotation.
//! let imu = ImuVec::new(0.0, 0.0, -9.806_65, 0.0, 0.0, 0.0);
//! let aiding = Measurement { z: MeasVec::zeros(), available: [true; 6] };
//! let report = monitor.step(&imu, 0.01, &aiding);
//! assert_eq!(report.phase, Phase::Converging);
//! ```
//!
//! For two or more redundant IMUs (or any array of single-axis sensors),
//! [`parity::ParityMonitor`] tests the parity space of the array: motion-free
//! residuals, the \[PAR\] PCA pattern, χ² and CUSUM tests, isolation of the
//! faulty sensor, reconfiguration, hardware health checks and the fused
//! rate or specific force.
//!
//! Crate layout: [`math`] (scalar trait, trig, Cholesky), [`model`] (vehicle
//! dynamics, measurement models, process noise), [`filter`] (UKF),
//! [`detect`] (windows, t-test, decoupling, GLR, estimators), [`stats`]
//! (Student-t, normal, χ² quantiles, CUSUM thresholds), [`monitor`] (the
//! composed periodic monitors), [`parity`] (redundant sensors).
//!
//! Safety: `unsafe_code` is denied crate-wide; the one exception is the
//! two-instruction naked function behind [`math::sqrt_f32`] that issues the
//! Cortex-M4F's `vsqrt` (only compiled for hard-float ARM targets).
#![cfg_attr(not(test), no_std)]

pub mod detect;
pub mod filter;
pub mod imu;
pub mod math;
pub mod model;
pub mod monitor;
pub mod parity;
pub mod stats;

/// The vector types of the monitors' signatures: an IMU sample
/// `[a_x, a_y, a_z, p, q, r]`, an aiding measurement and its availability,
/// the state, and the 6×6 matrices.
pub use model::{ImuVec, Mat6, MeasVec, Measurement, StateVec};
/// The `nalgebra` the API is written in (`no_std`, `libm`): use it for the
/// vectors and matrices of the signatures without a version to match.
pub use nalgebra;
/// `Vector3` (gyro rates, lever arms, fused outputs) and `Matrix3` (array
/// rotations) of the signatures.
pub use nalgebra::{Matrix3, Vector3};

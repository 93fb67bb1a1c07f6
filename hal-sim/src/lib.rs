//! # hal-sim
//!
//! The simulated hardware for `imu-fdi`: deterministic vehicle trajectories
//! with exact IMU truth ([`trajectory`]), a datasheet-class IMU error model
//! ([`imu_model`]), aiding sensors at their own rates, an emulated
//! ICM-42688-P ([`emulated_icm42688`]), redundant arrays ([`array`](mod@array)), fault
//! injection ([`fault`]), scenarios as data ([`scenario`]) and a three-IMU
//! flight that looks like a real one (vibration, each IMU's signal chain,
//! the logger's decimation; fitted to ArduPilot log171: [`realistic`]), all
//! `no_std` so the same models run inside firmware (the `imu-fdi-qemu`
//! images). With the default `std` feature it adds the scenario runner and
//! SPEC §9 metrics (`runner`, `metrics`), which the core crate's scenario
//! tests use; the host tools (the `imu-fdi-sim` CLI, log import and replay,
//! parity replay, campaigns, plots) are the `imu-fdi-cli` crate.
#![cfg_attr(not(feature = "std"), no_std)]

pub mod array;
pub mod baseline;
pub mod emulated_icm42688;
pub mod fault;
pub mod imu_model;
pub mod ots;
pub mod realistic;
pub mod scenario;
pub mod setup;
pub mod sim;
pub mod target_checks;
pub mod trajectory;

#[cfg(feature = "std")]
pub mod episodes;
#[cfg(feature = "std")]
pub mod metrics;
#[cfg(feature = "std")]
pub mod recovery;
#[cfg(feature = "std")]
pub mod runner;

pub use fault::{FaultKind, FaultRow, FaultSizes};
pub use imu_model::{ImuErrors, SimImu, TriadErrors};
pub use scenario::{AidingSpec, Scenario};
pub use sim::{SimSample, Simulator};
pub use trajectory::{Profile, Trajectory, Truth};

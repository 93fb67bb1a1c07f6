//! # hal-sim
//!
//! The simulated hardware for `imu-fdi`: deterministic vehicle trajectories
//! with exact IMU truth ([`trajectory`]), a datasheet-class IMU error model
//! ([`imu_model`]), aiding sensors at their own rates, fault injection
//! ([`fault`]) and scenarios as data ([`scenario`]), a three-IMU flight
//! that looks like a real one (vibration, each IMU's signal chain, the
//! logger's decimation; fitted to ArduPilot log171: [`realistic`]), all
//! `no_std` so the same models can run inside firmware. With the default `std` feature it adds the
//! scenario runner and SPEC §9 metrics ([`runner`], [`metrics`]), the SPEC §10
//! replay format ([`replay`]) and the `imu-fdi-sim` CLI.
#![cfg_attr(not(feature = "std"), no_std)]

pub mod array;
pub mod baseline;
pub mod emulated_icm42688;
pub mod fault;
pub mod imu_model;
pub mod ots;
#[cfg(all(target_os = "none", feature = "sil"))]
pub mod qemu;
pub mod realistic;
pub mod scenario;
pub mod setup;
pub mod sim;
pub mod target_checks;
pub mod trajectory;

#[cfg(feature = "std")]
pub mod array_run;
#[cfg(feature = "std")]
pub mod array_sweep;
#[cfg(feature = "std")]
pub mod campaign;
#[cfg(feature = "std")]
pub mod inject;
#[cfg(feature = "std")]
pub mod log_import;
#[cfg(feature = "std")]
pub mod metrics;
#[cfg(feature = "std")]
pub mod parity_campaign;
#[cfg(feature = "std")]
pub mod parity_replay;
#[cfg(feature = "std")]
pub mod plot;
#[cfg(feature = "std")]
pub mod replay;
#[cfg(feature = "std")]
pub mod runner;
#[cfg(feature = "std")]
pub mod scenario_file;
#[cfg(feature = "std")]
pub mod stats_ci;

pub use fault::{FaultKind, FaultRow, FaultSizes};
pub use imu_model::{ImuErrors, SimImu, TriadErrors};
pub use scenario::{AidingSpec, Scenario};
pub use sim::{SimSample, Simulator};
pub use trajectory::{Profile, Trajectory, Truth};

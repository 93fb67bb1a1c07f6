//! Running the monitors over data and scoring them: SPEC §10 replays of
//! single-IMU logs, parity replays of multi-IMU logs, redundant-array runs
//! and sweeps, Monte-Carlo campaigns with confidence intervals, and fault
//! injection on recorded data. (The scenario runner and the SPEC §9 metrics
//! are `hal_sim::runner` and `hal_sim::metrics`: the core crate's tests use
//! them without these host dependencies.)

pub mod array_run;
pub mod array_sweep;
pub mod attitude_lag;
pub mod campaign;
mod dataflash_imus;
pub mod gnss_lag;
pub mod inject;
pub mod log_rate;
pub mod parity_campaign;
pub mod parity_injection;
pub mod parity_replay;
pub mod parity_tables;
pub mod replay;
pub mod replay_monitor;
mod replay_options;
mod replay_read;
mod replay_sim;
mod replay_summary;
pub mod stats_ci;

//! Files in and out: flight logs (PX4 ULog, ArduPilot DataFlash, CSV
//! extracts) converted to the SPEC §10 replay CSV, and scenarios as TOML.

pub mod csv_checks;
pub mod csv_extract;
pub mod dataflash_scan;
pub mod guard;
pub mod log_import;
pub mod scenario_file;

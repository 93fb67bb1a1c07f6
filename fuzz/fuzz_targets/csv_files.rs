//! The CSV readers of the CLI on arbitrary bytes: the SPEC §10 IMU-log
//! reader (parity replay) and the CSV-extract importer. Never a panic; an
//! error is one line naming the file.
#![no_main]

use imu_fdi_cli::eval::parity_replay::read_imu_log;
use imu_fdi_cli::io::csv_extract::csv_extracts_to_replay_csv;
use imu_fdi_fuzz::{check_error, scratch};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let input = scratch("csv");
    let out = scratch("out.csv");
    std::fs::write(&input, data).unwrap();
    if let Err(e) = read_imu_log(&input) {
        check_error(&e, &input);
    }
    if let Err(e) = csv_extracts_to_replay_csv(&input, None, None, &out) {
        check_error(&e, &input);
    }
});

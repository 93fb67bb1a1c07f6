//! The ArduPilot DataFlash readers on arbitrary bytes: the framing scan,
//! the replay importer and the parity reader. Never a panic; an error is
//! one line naming the file.
#![no_main]

use imu_fdi_cli::eval::parity_replay::read_dataflash_imus;
use imu_fdi_cli::io::dataflash_scan::scan;
use imu_fdi_cli::io::log_import::dataflash_to_replay_csv;
use imu_fdi_fuzz::{check_error, scratch};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let s = scan(data);
    assert!(s.garbage_bytes <= data.len() && s.truncated_at.is_none_or(|a| a <= data.len()));
    let input = scratch("bin");
    let out = scratch("bin.csv");
    std::fs::write(&input, data).unwrap();
    if let Err(e) = dataflash_to_replay_csv(&input, &out) {
        check_error(&e, &input);
    }
    if let Err(e) = read_dataflash_imus(&input) {
        check_error(&e, &input);
    }
});

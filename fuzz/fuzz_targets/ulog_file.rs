//! The PX4 ULog importer on arbitrary bytes: never a panic or an abort
//! (px4-ulog's own panics are caught), an error is one line naming the file.
#![no_main]

use imu_fdi_cli::io::log_import::ulog_to_replay_csv;
use imu_fdi_fuzz::{check_error, scratch};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let input = scratch("ulg");
    let out = scratch("ulg.csv");
    std::fs::write(&input, data).unwrap();
    if let Err(e) = ulog_to_replay_csv(&input, &out) {
        check_error(&e, &input);
    }
});

//! Scenario files on arbitrary text: parsing and validation never panic
//! or abort (no allocation sized by a duration or rate from the file), an
//! error is one line naming the file; a scenario that validates can be
//! simulated for its first samples.
#![no_main]

use imu_fdi_cli::io::scenario_file::read_scenario;
use imu_fdi_fuzz::{check_error, scratch};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let input = scratch("toml");
    std::fs::write(&input, data).unwrap();
    match read_scenario(&input) {
        Ok(scn) => {
            for s in hal_sim::Simulator::new(&scn, 1).take(200) {
                assert!(s.t.is_finite() && s.dt.is_finite(), "{s:?}");
            }
        }
        Err(e) => check_error(&e, &input),
    }
});

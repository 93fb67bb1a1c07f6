//! Power-up bias table on log171 (diagnostic).
use std::path::Path;

use hal_sim::array::ArrayKind;
use imu_fdi_cli::eval::parity_replay::{power_up_table, read_imu_log};

fn main() -> anyhow::Result<()> {
    let log = read_imu_log(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    )))?;
    for (kind, size) in [
        (ArrayKind::Gyro, 2.0_f64.to_radians()),
        (ArrayKind::Accel, 0.5),
    ] {
        let cases = power_up_table(
            &log,
            kind,
            size,
            &[60.0, 70.0, 80.0, 90.0, 100.0],
            30.0,
            239.0,
        )?;
        let ok = cases
            .iter()
            .filter(|c| c.delay.is_some() && !c.wrong_isolation)
            .count();
        let wrong = cases.iter().filter(|c| c.wrong_isolation).count();
        println!(
            "{kind:?}: {ok}/{} isolated within 10 s, {wrong} with a healthy sensor named",
            cases.len()
        );
    }
    Ok(())
}

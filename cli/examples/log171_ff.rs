//! Fault-free log171 replays for several training starts (diagnostic).
use std::path::Path;

use hal_sim::array::ArrayKind;
use imu_fdi_cli::eval::parity_replay::{read_imu_log, replay_parity};

fn main() -> anyhow::Result<()> {
    let log = read_imu_log(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    )))?;
    for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
        for ts in [60.0, 65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0, 100.0] {
            let r = replay_parity(&log, kind, ts, 30.0, None)?;
            let al: Vec<String> = r
                .alarms
                .iter()
                .map(|a| format!("{:.1}-{:.1}:{:?}", a.0, a.1, a.2))
                .collect();
            let iso: Vec<String> = r
                .isolations
                .iter()
                .filter(|a| a.1 < 239.0)
                .map(|a| format!("{}@{:.1}", a.0, a.1))
                .collect();
            println!(
                "{kind:?} ts {ts}: from {:?} alarms {al:?} iso {iso:?}",
                r.monitoring_from
            );
        }
    }
    Ok(())
}

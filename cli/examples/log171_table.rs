//! Prints the log171 step table (issue 14) for one kind and size, per
//! IMU × axis: `cargo run --release -p imu-fdi-cli --example log171_table -- gyro 1.0`.
use std::path::Path;

use hal_sim::array::ArrayKind;
use imu_fdi_cli::eval::parity_replay::{read_imu_log, step_table};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let kind = match args.get(1).map(String::as_str) {
        Some("accel") => ArrayKind::Accel,
        _ => ArrayKind::Gyro,
    };
    let size: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let size_si = if kind == ArrayKind::Gyro {
        size.to_radians()
    } else {
        size
    };
    let log = read_imu_log(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    )))?;
    let starts = [60.0, 70.0, 80.0, 90.0, 100.0];
    let onsets = [5.0, 25.0, 45.0, 65.0, 85.0, 105.0];
    let cases = step_table(&log, kind, size_si, &starts, 30.0, &onsets, 15.0, 239.0)?;
    let cases: Vec<_> = cases
        .into_iter()
        .filter(|c| c.injection.start + 10.0 < 239.0)
        .collect();
    let ok = cases
        .iter()
        .filter(|c| c.isolated && !c.false_alarm)
        .count();
    let fa = cases.iter().filter(|c| c.false_alarm).count();
    println!(
        "{kind:?} {size}: {ok}/{} pass, {fa} with a false alarm",
        cases.len()
    );
    for imu in 0..3 {
        let row: Vec<String> = (0..3)
            .map(|axis| {
                let sel: Vec<_> = cases
                    .iter()
                    .filter(|c| c.injection.imu == imu && c.injection.channel % 3 == axis)
                    .collect();
                let ok = sel.iter().filter(|c| c.isolated && !c.false_alarm).count();
                format!("{ok}/{}", sel.len())
            })
            .collect();
        println!("  imu{imu} x y z: {}", row.join(" "));
    }
    Ok(())
}

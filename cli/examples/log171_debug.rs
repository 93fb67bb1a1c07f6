//! Per-decision trace of the multi-scale tests on log171 (diagnostic):
//! `log171_debug KIND TRAIN_START IMU AXIS SIZE ONSET`.
use std::path::Path;

use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, Reading};
use imu_fdi_cli::eval::parity_replay::read_imu_log;
use nalgebra::Matrix3;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let gyro = a.get(1).map(String::as_str) != Some("accel");
    let p = |i: usize, d: f64| a.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(d);
    let (ts, imu, axis, size, onset) = (
        p(2, 80.0),
        p(3, 1.0) as usize,
        p(4, 0.0) as usize,
        p(5, 1.0),
        p(6, 135.0),
    );
    let size = if gyro { size.to_radians() } else { size };
    let log = read_imu_log(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    )))?;
    let rate = 49.0;
    let mut cfg = if gyro {
        ParityConfig::<f32>::gyro_flight(rate, 34.9)
    } else {
        ParityConfig::<f32>::accel_flight(rate, 156.9)
    };
    cfg.train_samples = (30.0 * rate) as u32;
    let g = Geometry::<f32, 9>::triads(&[Matrix3::identity(); 3])
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut m = ParityMonitor::<f32, 9, 40>::new(&g, cfg).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let off = if gyro { 3 } else { 0 };
    for (t, row) in log.t.iter().zip(log.imus.iter()) {
        if *t < ts || *t > 239.0 {
            continue;
        }
        let r: [Reading<f32>; 9] = core::array::from_fn(|i| {
            let mut v = row[i / 3][off + i % 3];
            if i / 3 == imu && i % 3 == axis && *t >= onset && *t < onset + 15.0 {
                v += size;
            }
            Reading::Sample(v as f32)
        });
        let rep = m.step(&r);
        if rep.decision && *t > onset - 3.0 && *t < onset + 16.0 {
            let d = rep.multiscale;
            println!("{t:.2} ratio {:.2} scale {} suspect {:?} bias {:.3} margin {:.1} learn {} iso {:?}", d.ratio, d.scale, d.suspect, if gyro { f64::from(d.bias).to_degrees() } else { f64::from(d.bias) }, d.margin, d.learning, rep.isolated);
        }
    }
    Ok(())
}

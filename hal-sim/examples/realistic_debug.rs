//! Trace of one realistic fault-free flight (diagnostic).
use hal_sim::array::ArrayKind;
use hal_sim::realistic::{RealisticArray, RealisticProfile};
use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor};
use nalgebra::Matrix3;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let gyro = a.get(1).map(String::as_str) != Some("accel");
    let secs: f64 = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(600.0);
    let profile = RealisticProfile::log171().with_duration(secs);
    let kind = if gyro {
        ArrayKind::Gyro
    } else {
        ArrayKind::Accel
    };
    let mut cfg = if gyro {
        ParityConfig::<f32>::gyro_flight(profile.log_hz, 34.9)
    } else {
        ParityConfig::<f32>::accel_flight(profile.log_hz, 156.9)
    };
    cfg.train_samples = (30.0 * profile.log_hz) as u32;
    let g = Geometry::<f32, 9>::triads(&[Matrix3::identity(); 3])
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut m = ParityMonitor::<f32, 9, 40>::new(&g, cfg).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut was = false;
    for row in RealisticArray::new(&profile, 1000) {
        let r = m.step(&row.readings(kind).map(|x| x.map(|v| v as f32)));
        if r.fault != was || r.isolated.is_some() {
            let d = r.multiscale;
            println!(
                "{:.1} fault {} ratio {:.2} scale {} suspect {:?} bias {:.3} margin {:.1} iso {:?}",
                row.t,
                r.fault,
                d.ratio,
                d.scale,
                d.suspect,
                if gyro {
                    f64::from(d.bias).to_degrees()
                } else {
                    f64::from(d.bias)
                },
                d.margin,
                r.isolated
            );
        }
        was = r.fault;
    }
    Ok(())
}

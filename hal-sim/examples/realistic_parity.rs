//! Realistic-profile figures of the parity monitor for real flights.
use hal_sim::array::ArrayKind;
use hal_sim::parity_campaign::{fault_free, steps};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let hours: u32 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(2);
    for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
        let ff = fault_free(kind, hours, 1000)?;
        println!(
            "{kind:?}: {:.2} h fault-free: {} alarm events, {} isolations",
            ff.hours, ff.alarm_events, ff.isolations
        );
        let sizes: &[f64] = match kind {
            ArrayKind::Gyro => &[0.5, 1.0, 2.0, 3.0],
            ArrayKind::Accel => &[0.1, 0.2, 0.3, 0.5],
        };
        for &s in sizes {
            let si = if kind == ArrayKind::Gyro {
                s.to_radians()
            } else {
                s
            };
            let r = steps(kind, si, 2, 1)?;
            let med = r
                .delays
                .get(r.delays.len() / 2)
                .copied()
                .unwrap_or(f64::NAN);
            println!(
                "  step {s}: {}/{} isolated, {} false alarms, median {med:.1} s",
                r.isolated, r.cases, r.false_alarms
            );
        }
    }
    Ok(())
}

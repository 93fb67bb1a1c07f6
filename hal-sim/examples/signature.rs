//! Prints the closed-loop signature matrix M of the S1 run at a few times,
//! scaled to innovation σ per minimum fault (what the detectors compare).
use hal_sim::{
    runner::{monitor_config, RunOptions},
    Scenario, Simulator,
};
use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::UkfMonitor;

fn main() {
    let scn = Scenario::auv_fault_free(40.0);
    let cfg = monitor_config::<f64>(&scn, &RunOptions::default());
    let mut m = UkfMonitor::<f64>::new(cfg).unwrap();
    for s in Simulator::new(&scn, 1) {
        let u = ImuVec::from(s.imu.unwrap());
        let r = m.step(
            &u,
            s.dt,
            &Measurement {
                z: MeasVec::from(s.aiding),
                available: s.aiding_available,
            },
        );
        if (s.t - 30.0).abs() < 1e-9 || (s.t - 35.0).abs() < 1e-9 {
            let sig = m.signature();
            println!(
                "t = {} s: M·min_fault / innovation σ (rows u v w φ θ ψ; cols ax ay az p q r)",
                s.t
            );
            for i in 0..6 {
                let sd = r.diag[i].variance.sqrt();
                let row: Vec<String> = (0..6)
                    .map(|j| {
                        format!(
                            "{:8.2}",
                            sig[(i, j)] * cfg.min_fault[j] / if sd > 0.0 { sd } else { f64::NAN }
                        )
                    })
                    .collect();
                println!("  {}", row.join(" "));
            }
        }
    }
}

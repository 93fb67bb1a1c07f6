//! The fault estimators on constant faults held long enough for the filter
//! to reach steady state: the corrected mapping `M⁺ r̄` (and the tracking
//! estimate, `UkfMonitorConfig::fault_psd`) are unbiased, [UKF] §4 as
//! written over-estimates by ≈ T/(K·dt).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use hal_sim::fault::{FaultKind, FaultRow};
use hal_sim::runner::{monitor_config, run, run_with, RunOptions};
use hal_sim::Scenario;
use imu_fdi::monitor::UkfMonitorConfig;

fn step_on(channel: usize, size: f64) -> Scenario {
    let mut s = Scenario::auv_fault_free(40.0);
    s.sizes.accel[0] = size;
    s.sizes.gyro[0] = size;
    s.faults.clear();
    s.faults
        .push(FaultRow {
            channel,
            start: 15.0,
            end: 40.0,
            kind: FaultKind::E1,
            sign: 1.0,
        })
        .unwrap();
    s
}

#[test]
fn corrected_estimator_is_unbiased_and_the_papers_over_estimates() {
    let sizes = [
        0.3,
        0.3,
        0.3,
        1.5f64.to_radians(),
        1.5f64.to_radians(),
        1.5f64.to_radians(),
    ];
    println!("ch  fault     corrected/f  paper/f  tracking/f");
    for (ch, f) in sizes.iter().enumerate() {
        let mut corr = Vec::new();
        let mut paper = Vec::new();
        let mut track = Vec::new();
        for seed in 1..4 {
            let scn = step_on(ch, *f);
            let mut cfg = monitor_config::<f32>(&scn, &RunOptions::default());
            cfg.fault_psd = Some(UkfMonitorConfig::fault_tracking_psd());
            let t = run_with::<f32>(&scn, seed, cfg).unwrap();
            let rows: Vec<_> = t.rows.iter().filter(|r| r.t >= 25.0).collect();
            track.push(rows.iter().map(|r| r.fhat[ch]).sum::<f64>() / rows.len() as f64 / f);
            let t = run::<f32>(&step_on(ch, *f), seed, &RunOptions::default()).unwrap();
            let rows: Vec<_> = t.rows.iter().filter(|r| r.t >= 25.0).collect();
            corr.push(rows.iter().map(|r| r.fhat[ch]).sum::<f64>() / rows.len() as f64 / f);
            paper.push(
                rows.iter().map(|r| r.fhat_as_written[ch]).sum::<f64>() / rows.len() as f64 / f,
            );
        }
        let c = corr.iter().sum::<f64>() / 3.0;
        let p = paper.iter().sum::<f64>() / 3.0;
        let k = track.iter().sum::<f64>() / 3.0;
        println!("{ch}   {f:.4}    {c:.3}        {p:.1}     {k:.3}");
        assert!(
            (k - 1.0).abs() < 0.05,
            "channel {ch}: tracking estimator ratio {k}"
        );
        assert!(
            (c - 1.0).abs() < 0.1,
            "channel {ch}: corrected estimator ratio {c}"
        );
        assert!(p > 5.0, "channel {ch}: as-written ratio {p} (expected ≫ 1)");
    }
}

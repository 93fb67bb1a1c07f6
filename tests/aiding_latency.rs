//! A known aiding latency (SPEC §3.1): with both DVL and compass 0.1 s late,
//! fusing them against the state of their own time keeps the monitor quiet
//! and the estimate accurate; ignoring the latency does neither.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use hal_sim::metrics::{evaluate, RunMetrics};
use hal_sim::runner::{monitor_config, run_with, RunOptions};
use hal_sim::Scenario;

fn run(delay_in_monitor: f32, scn: &Scenario) -> RunMetrics {
    let mut cfg = monitor_config::<f32>(scn, &RunOptions::default());
    cfg.aiding_delay_s = delay_in_monitor;
    let mut m = RunMetrics::default();
    for seed in 1..3 {
        m.merge(&evaluate(&run_with::<f32>(scn, seed, cfg).unwrap()));
    }
    m
}

#[test]
fn compensating_a_known_aiding_latency() {
    let mut scn = Scenario::auv_fault_free(600.0);
    scn.aiding.delay_s = 0.1;
    let compensated = run(0.1, &scn);
    let ignored = run(0.0, &scn);
    let deg = |v: f64| v.to_degrees();
    println!(
        "0.1 s aiding latency, 2 × 10 min AUV: compensated: FA events {}, yaw RMSE {:.4}°, roll RMSE {:.4}°; ignored: FA events {}, yaw RMSE {:.4}°, roll RMSE {:.4}°",
        compensated.false_alarm_events,
        deg(compensated.state_rmse[5]),
        deg(compensated.state_rmse[3]),
        ignored.false_alarm_events,
        deg(ignored.state_rmse[5]),
        deg(ignored.state_rmse[3]),
    );
    assert_eq!(compensated.false_alarm_events, 0);
    assert_eq!(compensated.covariance_resets, 0);
    assert!(compensated.state_rmse[5] < 0.1 * ignored.state_rmse[5]);
    assert!(
        ignored.false_alarm_events > 0,
        "the latency should matter in this setting"
    );
}

#[test]
fn a_latency_beyond_the_history_is_a_configuration_error() {
    let scn = Scenario::auv_fault_free(1.0);
    let mut cfg = monitor_config::<f32>(&scn, &RunOptions::default());
    cfg.aiding_delay_s = 1.0;
    assert_eq!(
        imu_fdi::monitor::UkfMonitor::<f32>::new(cfg).err(),
        Some(imu_fdi::monitor::ConfigError::AidingDelay)
    );
}

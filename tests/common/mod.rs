//! Shared helpers for the scenario tests.
#![allow(dead_code)]

use hal_sim::metrics::{evaluate, RunMetrics};
use hal_sim::runner::{run, RunOptions};
use hal_sim::Scenario;
use imu_fdi::detect::Detector;

/// Runs `seeds` seeds of a scenario in `f32` and merges the metrics.
pub fn campaign(scn: &Scenario, seeds: std::ops::Range<u64>, detector: Detector) -> RunMetrics {
    let opts = RunOptions {
        detector,
        ..RunOptions::default()
    };
    let mut total = RunMetrics::default();
    for seed in seeds {
        let trace = run::<f32>(scn, seed, &opts).unwrap();
        total.merge(&evaluate(&trace));
    }
    total
}

/// THEN: every fault detected on the right channel with the right sign,
/// ≥ 99 % detection after L, ≤ 1 % wrong-channel flags, zero false alarms.
pub fn assert_paper_targets(name: &str, m: &RunMetrics) {
    print!("{name}\n{}", m.table());
    for (c, ch) in m.channels.iter().zip(imu_fdi::model::CHANNEL_NAMES) {
        assert_eq!(c.detected, c.faults, "{name} {ch}: missed faults");
        let rate = c.detection_rate().unwrap();
        assert!(rate >= 0.99, "{name} {ch}: detection rate {rate}");
        let wrong = c.wrong_channel_rate().unwrap();
        assert!(wrong <= 0.01, "{name} {ch}: wrong-channel rate {wrong}");
        assert!(
            c.delay_max <= m.latency_s,
            "{name} {ch}: delay {} > L",
            c.delay_max
        );
    }
    assert_eq!(m.total_false_alarms(), 0, "{name}: false alarms");
    assert_eq!(m.false_alarm_events, 0);
    assert_eq!(m.covariance_resets, 0);
}

//! S5 (SPEC §8): hardware faults on the UKF monitor's IMU — how each is
//! seen (health check or channel flag), and that a dropout does not make
//! the other channels flag afterwards (the filter dead-reckons through it).

use hal_sim::metrics::{evaluate, hardware_detections};
use hal_sim::runner::{run, RunOptions};
use hal_sim::Scenario;

#[test]
fn s5_hardware_faults_are_seen_and_a_dropout_is_ridden_through() {
    let scn = Scenario::s5();
    let seeds = 1..=6u64;
    let n = seeds.clone().count();
    let mut seen = [0usize; 6];
    let mut delay_max = [0.0f64; 6];
    let mut dropout_by_health = 0;
    let mut dropout_other = 0;
    for seed in seeds {
        let t = run::<f32>(&scn, seed, &RunOptions::default()).expect("valid configuration");
        let m = evaluate(&t);
        assert_eq!(
            m.false_alarm_events, 0,
            "seed {seed}: false alarms outside the faults"
        );
        let ds = hardware_detections(&t);
        assert_eq!(ds.len(), 6);
        for (i, d) in ds.iter().enumerate() {
            if let Some(s) = d.first_seen() {
                seen[i] += 1;
                delay_max[i] = delay_max[i].max(s);
            }
        }
        let drop = &ds[1];
        assert_eq!(drop.kind, "Dropout");
        if drop
            .first_health
            .as_ref()
            .is_some_and(|(s, n)| *s == 0.0 && n.contains("input_invalid"))
        {
            dropout_by_health += 1;
        }
        dropout_other += drop.other_channel_samples;
    }
    // Stuck gyro (r, while the vehicle turns): flagged on its channel.
    assert_eq!(seen[0], n, "stuck");
    assert!(delay_max[0] < 3.5, "stuck: {}", delay_max[0]);
    // Dropout: the sample is rejected at once...
    assert_eq!(dropout_by_health, n);
    // ...and riding through it costs at most a few flagged samples (before
    // the dead-reckoning fix: 630 on seed 1).
    assert!(
        dropout_other <= 30 * n,
        "dropout: {dropout_other} other-channel flag samples"
    );
    // Clipping at 0.2 m/s² during manoeuvres, spike bursts: seen.
    assert!(seen[2] + 1 >= n, "clip: {}/{n}", seen[2]);
    assert_eq!(seen[3], n, "spikes");
    assert!(delay_max[3] < 0.5, "spikes: {}", delay_max[3]);
}

//! Issue 15's aircraft Monte-Carlo: GIVEN the aircraft profile with nominal
//! MEMS errors (SPEC §8a) and, per run, a step (0.3 m/s², 1.5 °/s) and a
//! ramp (0.1 m/s³, 0.5 °/s²) on every channel in random order and sign,
//! WHEN the UKF monitor runs, THEN every episode is flagged on its channel,
//! steps within about a second, and no flag is raised once a fault has
//! cleared and 5 s have passed; fault-free hours raise none either. The
//! same with the aiding 0.2 s late and the latency estimated online, and
//! with a 3° heading offset learnt (first onset at 60 s: learning lasts
//! longer there); and with the replay flight profile's block tests on,
//! with clean, late and heading-offset aiding.
//! CI runs 2 seeds; the ignored tests run 20 (+ 20 held out) and 10 h
//! (`cargo test --release --test aircraft_episodes -- --ignored --nocapture`,
//! about a minute; the figures are in docs/results.md).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code: a panic is a failed assertion

use hal_sim::episodes::{episode_scenario, score, EpisodePlan, EpisodeTotals};
use hal_sim::metrics::{evaluate, RunMetrics};
use hal_sim::runner::{monitor_config, run_with, RunOptions};
use hal_sim::Scenario;
use imu_fdi::monitor::UkfMonitorConfig;

/// How the monitor is set up beyond the sensors' specifications.
#[derive(Clone, Copy)]
enum Setup {
    /// As an integrator would from the datasheets (latency 0, not estimated).
    Specs,
    /// Plus the online aiding-delay estimate.
    EstimateDelay,
    /// Plus the heading-offset estimate.
    EstimateHeading,
    /// Plus the gyro/attitude-aiding consistency test (replay's flight
    /// settings).
    AttitudeRate,
    /// Plus the accelerometer/GNSS-velocity consistency test as well
    /// (replay's flight settings; GNSS aiding only).
    BlockTests,
    /// Both block tests and the online aiding-delay estimate.
    BlockTestsEstimateDelay,
    /// Both block tests and the heading-offset estimate.
    BlockTestsEstimateHeading,
}

fn config(scn: &Scenario, setup: Setup) -> UkfMonitorConfig<f32> {
    let mut c = monitor_config::<f32>(scn, &RunOptions::default());
    c.estimate_aiding_delay =
        matches!(setup, Setup::EstimateDelay | Setup::BlockTestsEstimateDelay);
    c.estimate_heading_offset = matches!(
        setup,
        Setup::EstimateHeading | Setup::BlockTestsEstimateHeading
    );
    let block_tests = matches!(
        setup,
        Setup::BlockTests | Setup::BlockTestsEstimateDelay | Setup::BlockTestsEstimateHeading
    );
    if block_tests || matches!(setup, Setup::AttitudeRate) {
        c.attitude_rate = Some(imu_fdi::monitor::AttitudeRateConfig::flight());
    }
    if block_tests && c.aiding == imu_fdi::model::AidingKind::GnssAttitude {
        c.velocity_increment = Some(imu_fdi::monitor::VelocityIncrementConfig::velocity());
    }
    c
}

fn episodes_with(base: &Scenario, seeds: std::ops::Range<u64>, setup: Setup) -> EpisodeTotals {
    let plan = EpisodePlan::default();
    let mut all = Vec::new();
    for seed in seeds {
        let scn = episode_scenario(base, seed, &plan);
        let trace = run_with::<f32>(&scn, seed, config(&scn, setup)).unwrap();
        all.extend(score(&trace, &plan));
    }
    EpisodeTotals::of(&all)
}

fn episodes(base: &Scenario, seeds: std::ops::Range<u64>) -> EpisodeTotals {
    episodes_with(base, seeds, Setup::Specs)
}

fn fault_free_with(base: &Scenario, seeds: std::ops::Range<u64>, setup: Setup) -> RunMetrics {
    let mut m = RunMetrics::default();
    for seed in seeds {
        m.merge(&evaluate(
            &run_with::<f32>(base, seed, config(base, setup)).unwrap(),
        ));
    }
    m
}

fn fault_free(base: &Scenario, seeds: std::ops::Range<u64>) -> RunMetrics {
    fault_free_with(base, seeds, Setup::Specs)
}

/// The targets: ≥ 99 % detected, step delay median ≤ 1 s (1.05 s
/// with the former two-decision persistence on the aircraft, 0.95 s with
/// one; docs/results.md), no post-clear false alarm.
fn assert_targets(name: &str, t: &EpisodeTotals) {
    println!("{name}: {}", t.line());
    assert!(
        t.detected as f64 >= 0.99 * t.episodes as f64,
        "{name}: {} of {} episodes detected",
        t.detected,
        t.episodes
    );
    assert!(t.step_delay_median_s <= 1.0, "{name}: step delay median");
    assert_eq!(t.post_clear_events, 0, "{name}: post-clear false alarms");
}

#[test]
fn aircraft_steps_and_ramps_two_seeds() {
    let t = episodes(&Scenario::aircraft_fault_free(0.0), 1..3);
    assert_eq!(t.episodes, 24);
    assert_targets("aircraft, 2 seeds", &t);
}

#[test]
fn auv_steps_and_ramps_two_seeds() {
    let t = episodes(&Scenario::auv_fault_free(0.0), 1..3);
    assert_targets("AUV, 2 seeds", &t);
    assert_eq!(t.detected, t.episodes);
}

#[test]
#[ignore = "20 + 20 seeds: run with --release -- --ignored"]
fn aircraft_steps_and_ramps_twenty_seeds_and_held_out() {
    let base = Scenario::aircraft_fault_free(0.0);
    assert_targets("aircraft, seeds 100-119", &episodes(&base, 100..120));
    assert_targets(
        "aircraft, held-out seeds 500-519",
        &episodes(&base, 500..520),
    );
    let auv = Scenario::auv_fault_free(0.0);
    let t = episodes(&auv, 100..120);
    assert_targets("AUV, seeds 100-119", &t);
    assert_eq!(t.detected, t.episodes);
}

#[test]
#[ignore = "10 simulated hours: run with --release -- --ignored"]
fn aircraft_ten_fault_free_hours() {
    let m = fault_free(&Scenario::aircraft_fault_free(3600.0), 200..211);
    println!(
        "aircraft, 11 fault-free flights of 1 h (seeds 200-210): {} false-alarm events in {:.2} h, {} covariance resets",
        m.false_alarm_events,
        m.free_time_s / 3600.0,
        m.covariance_resets
    );
    assert!(m.free_time_s > 10.0 * 3600.0);
    assert_eq!(m.false_alarm_events, 0);
}

/// GIVEN the aircraft, WHEN the gyro/attitude-aiding consistency test
/// (replay's flight settings) runs besides the innovation windows, THEN
/// the episode figures and the fault-free hours are as measured
/// (docs/results.md): what enabling it in the aircraft preset would cost;
/// the same on held-out seeds and on the AUV (compass attitude, M1).
#[test]
#[ignore = "20 seeds of episodes and 10 h: run with --release -- --ignored"]
fn aircraft_attitude_rate_test() {
    let base = Scenario::aircraft_fault_free(0.0);
    let t = episodes_with(&base, 100..120, Setup::AttitudeRate);
    assert_targets("aircraft + attitude-rate test, seeds 100-119", &t);
    assert_eq!(t.detected, t.episodes);
    let t = episodes_with(&base, 500..520, Setup::AttitudeRate);
    assert_targets("aircraft + attitude-rate test, held-out seeds 500-519", &t);
    let auv = Scenario::auv_fault_free(0.0);
    let t = episodes_with(&auv, 100..120, Setup::AttitudeRate);
    assert_targets("AUV + attitude-rate test, seeds 100-119", &t);
    assert_eq!(t.detected, t.episodes);
    let m = fault_free_with(
        &Scenario::aircraft_fault_free(3600.0),
        200..211,
        Setup::AttitudeRate,
    );
    println!(
        "aircraft + attitude-rate test, 11 fault-free flights of 1 h (seeds 200-210): {} false-alarm events in {:.2} h",
        m.false_alarm_events,
        m.free_time_s / 3600.0
    );
    assert!(m.free_time_s > 10.0 * 3600.0);
    assert_eq!(m.false_alarm_events, 0);
}

/// GIVEN the aircraft episodes WHEN the accelerometer/GNSS-velocity test
/// runs beside the gyro/attitude-aiding test (replay's flight profile)
/// THEN the episode targets hold on the design and held-out seeds (no
/// post-clear event), but the 10 fault-free hours raise 34 events, not 0:
/// the test is calibrated to its design rate (10 per hour, as the gyro
/// test's) and the simulated aiding is so clean (10-s window σ ≈ 0.01 m/s²)
/// that the accelerometers' scale-factor and misalignment errors under
/// load factor show (docs/results.md). Off in the presets for that reason.
#[test]
#[ignore = "40 seeds of episodes and 10 h: run with --release -- --ignored"]
fn aircraft_velocity_increment_test() {
    let base = Scenario::aircraft_fault_free(0.0);
    for (seeds, name) in [
        (100..120, "seeds 100-119"),
        (500..520, "held-out seeds 500-519"),
    ] {
        let t = episodes_with(&base, seeds, Setup::BlockTests);
        assert_targets(&format!("aircraft + both block tests, {name}"), &t);
        assert_eq!(t.detected, t.episodes);
    }
    // Design seeds, then seeds no change was looked at on.
    for (first, name) in [(200, "design"), (700, "held-out")] {
        let m = fault_free_with(
            &Scenario::aircraft_fault_free(3600.0),
            first..first + 11,
            Setup::BlockTests,
        );
        println!(
            "aircraft + both block tests, 11 fault-free flights of 1 h ({name}, seeds {first}-{}): {} false-alarm events in {:.2} h",
            first + 10,
            m.false_alarm_events,
            m.free_time_s / 3600.0
        );
        assert!(m.free_time_s > 10.0 * 3600.0);
        // The smallest fault reported (`min_fault`) keeps the scale-factor
        // and misalignment errors a clean aiding resolves unreported: 34
        // events on the design seeds without it.
        assert_eq!(m.false_alarm_events, 0, "{name}");
    }
}

/// GIVEN aiding 0.2 s late or a 3° heading offset (each learnt by the
/// monitor's estimator), WHEN both block tests run as well (replay's flight
/// settings: the velocity test learns its own GNSS lag and integrates the
/// attitude with the learnt offset taken off), THEN the targets
/// hold: every episode detected (first onset 60 s with the offset, as in
/// `aircraft_heading_offset`: learning lasts longer there), step delay
/// median ≤ 1.2 s late (as without the tests) and ≤ 1 s with the offset,
/// ≤ 1 false-alarm event per fault-free hour and after faults clear.
#[test]
#[ignore = "40 seeds of episodes and 20 h: run with --release -- --ignored"]
fn aircraft_block_tests_with_late_or_offset_aiding() {
    let mut late = Scenario::aircraft_fault_free(0.0);
    late.aiding.delay_s = 0.2;
    let mut offset = Scenario::aircraft_fault_free(0.0);
    offset.aiding.heading_offset_rad = 3f64.to_radians();
    let t = episodes_with(&late, 100..120, Setup::BlockTestsEstimateDelay);
    assert_targets_late("aircraft + both block tests, 0.2 s late, seeds 100-119", &t);
    let t = heading_episodes_with(&offset, 100..120, Setup::BlockTestsEstimateHeading);
    assert_targets(
        "aircraft + both block tests, 3° heading offset, first onset 60 s, seeds 100-119",
        &t,
    );
    for (name, scn, setup) in [
        ("0.2 s late", &late, Setup::BlockTestsEstimateDelay),
        (
            "3° heading offset",
            &offset,
            Setup::BlockTestsEstimateHeading,
        ),
    ] {
        let mut hour = scn.clone();
        hour.duration_s = 3600.0;
        let m = fault_free_with(&hour, 700..711, setup);
        let h = m.free_time_s / 3600.0;
        println!(
            "aircraft + both block tests, {name}, 11 fault-free flights of 1 h (seeds 700-710): {} false-alarm events in {h:.2} h",
            m.false_alarm_events
        );
        assert!(h > 10.0, "{name}");
        assert!(m.false_alarm_events as f64 <= h, "{name}");
    }
}

/// GIVEN aiding 0.2 s late, not stated to the monitor, WHEN it estimates
/// the latency online, THEN the episode targets hold; without the estimate
/// the same runs raise post-clear false alarms (so the latency matters here).
#[test]
fn aircraft_late_aiding_estimated_two_seeds() {
    let mut late = Scenario::aircraft_fault_free(0.0);
    late.aiding.delay_s = 0.2;
    let t = episodes_with(&late, 1..3, Setup::EstimateDelay);
    assert_targets_late("aircraft, aiding 0.2 s late, estimated, 2 seeds", &t);
    let ignored = episodes(&late, 1..3);
    println!(
        "aircraft, aiding 0.2 s late, ignored, 2 seeds: {}",
        ignored.line()
    );
    assert!(ignored.post_clear_events > 0);
}

/// GIVEN a vehicle whose aiding is 0.2 s late, WHEN the monitor estimates the
/// latency, THEN it finds 0.2 s ± 0.03 s within two minutes (aircraft and AUV).
#[test]
fn the_online_delay_estimate_finds_the_latency() {
    use hal_sim::Simulator;
    use imu_fdi::model::{ImuVec, MeasVec, Measurement};
    for base in [
        Scenario::aircraft_fault_free(120.0),
        Scenario::auv_fault_free(120.0),
    ] {
        for seed in 1..3 {
            let mut scn = base.clone();
            scn.aiding.delay_s = 0.2;
            let mut m =
                imu_fdi::monitor::UkfMonitor::<f32>::new(config(&scn, Setup::EstimateDelay))
                    .unwrap();
            for s in Simulator::new(&scn, seed) {
                let imu = s.imu.unwrap();
                let u = ImuVec::<f32>::from_fn(|i, _| imu[i] as f32);
                let z = MeasVec::<f32>::from_fn(|i, _| s.aiding[i] as f32);
                m.step(
                    &u,
                    s.dt as f32,
                    &Measurement {
                        z,
                        available: s.aiding_available,
                    },
                );
            }
            let d = m.aiding_delay_estimate();
            println!("{:?} seed {seed}: latency estimate {d:.2} s", scn.profile);
            assert!((d - 0.2).abs() <= 0.03, "estimate {d}");
        }
    }
}

/// The targets with late aiding: the step delay median includes the 0.2 s
/// the aiding arrives late, so it is asserted ≤ 1.2 s (measured 1.15–1.16 s
/// on 40 seeds).
fn assert_targets_late(name: &str, t: &EpisodeTotals) {
    println!("{name}: {}", t.line());
    assert!(
        t.detected as f64 >= 0.99 * t.episodes as f64,
        "{name}: {} of {} episodes detected",
        t.detected,
        t.episodes
    );
    assert!(t.step_delay_median_s <= 1.2, "{name}: step delay median");
    assert_eq!(t.post_clear_events, 0, "{name}: post-clear false alarms");
}

/// Aiding 0.2 s late with the latency estimated: 20 + 20 held-out seeds of
/// episodes and 10 fault-free hours; the estimate on aiding that is not late
/// (it must not cost anything there); the AUV.
#[test]
#[ignore = "40 seeds of episodes and 10 h: run with --release -- --ignored"]
fn late_aiding_estimated_twenty_seeds_and_ten_hours() {
    let mut late = Scenario::aircraft_fault_free(0.0);
    late.aiding.delay_s = 0.2;
    for (name, seeds) in [
        ("seeds 100-119", 100..120),
        ("held-out seeds 500-519", 500..520),
    ] {
        let t = episodes_with(&late, seeds, Setup::EstimateDelay);
        assert_targets_late(&format!("aircraft, 0.2 s late, estimated, {name}"), &t);
    }
    let mut hour = late.clone();
    hour.duration_s = 3600.0;
    let m = fault_free_with(&hour, 200..211, Setup::EstimateDelay);
    println!(
        "aircraft, 0.2 s late, estimated, 11 fault-free flights of 1 h (seeds 200-210): {} false-alarm events in {:.2} h",
        m.false_alarm_events,
        m.free_time_s / 3600.0
    );
    assert!(m.false_alarm_events as f64 <= m.free_time_s / 3600.0);
    let on_time = Scenario::aircraft_fault_free(0.0);
    let t = episodes_with(&on_time, 100..120, Setup::EstimateDelay);
    assert_targets("aircraft, aiding on time, estimated, seeds 100-119", &t);
    // The AUV with late aiding (seeds 700-719 not looked at while
    // designing; 500-519 looked at while diagnosing seeds 510 and 515).
    let mut auv = Scenario::auv_fault_free(0.0);
    auv.aiding.delay_s = 0.2;
    for (name, seeds) in [
        ("seeds 100-119", 100..120),
        ("seeds 500-519", 500..520),
        ("held-out seeds 700-719", 700..720),
    ] {
        let t = episodes_with(&auv, seeds, Setup::EstimateDelay);
        println!("AUV, 0.2 s late, estimated, {name}: {}", t.line());
        assert_eq!(t.detected, t.episodes, "{name}");
        assert!(
            t.post_clear_events as f64 <= t.post_clear_s / 3600.0,
            "{name}: post-clear false alarms"
        );
    }
    let mut hour = auv;
    hour.duration_s = 3600.0;
    let m = fault_free_with(&hour, 200..205, Setup::EstimateDelay);
    println!(
        "AUV, 0.2 s late, estimated, 5 fault-free hours (seeds 200-204): {} false-alarm events in {:.2} h",
        m.false_alarm_events,
        m.free_time_s / 3600.0
    );
    assert!(m.false_alarm_events as f64 <= m.free_time_s / 3600.0);
}

/// GIVEN an AUV whose aiding is 0.2 s late, WHEN the monitor estimates the
/// latency, THEN every episode is flagged and none after the faults clear.
/// Seeds 103 and 119 are the two that failed before the estimator put the
/// learnt gyro bias back into the propagated attitude changes: 31 and 13
/// post-clear events (the estimate was 0.16 s and 0.07 s when monitoring
/// started and crept to 0.20 s over 5 min, pulled towards the lag in use).
#[test]
fn auv_late_aiding_estimated_two_seeds() {
    let mut auv = Scenario::auv_fault_free(0.0);
    auv.aiding.delay_s = 0.2;
    for seed in [103, 119] {
        let t = episodes_with(&auv, seed..seed + 1, Setup::EstimateDelay);
        println!("AUV, 0.2 s late, estimated, seed {seed}: {}", t.line());
        assert_eq!(t.detected, t.episodes, "seed {seed}");
        assert_eq!(t.post_clear_events, 0, "seed {seed}");
    }
}

/// GIVEN a 3° heading offset learnt online, WHEN the estimator applies an
/// offset step, THEN the filter's heading turns with the corrected yaw
/// aiding and the step raises no yaw-rate (r) flag. Before the filter was
/// turned with it, each step was a yaw-aiding jump the filter followed over
/// seconds: r flagged at 32 s (seed 301) and 28 s (seed 302); the first
/// minutes hold the steps (the estimate moves by ≥ 1° in them).
#[test]
fn heading_offset_steps_raise_no_yaw_rate_flag() {
    use hal_sim::Simulator;
    use imu_fdi::model::{ImuVec, MeasVec, Measurement};
    use imu_fdi::monitor::ChannelState;
    let mut scn = Scenario::aircraft_fault_free(120.0);
    scn.aiding.heading_offset_rad = 3f64.to_radians();
    for seed in 301..303 {
        let mut m =
            imu_fdi::monitor::UkfMonitor::<f32>::new(config(&scn, Setup::EstimateHeading)).unwrap();
        let mut r_flags = 0;
        let mut prev = false;
        for s in Simulator::new(&scn, seed) {
            let imu = s.imu.unwrap();
            let u = ImuVec::<f32>::from_fn(|i, _| imu[i] as f32);
            let z = MeasVec::<f32>::from_fn(|i, _| s.aiding[i] as f32);
            let rep = m.step(
                &u,
                s.dt as f32,
                &Measurement {
                    z,
                    available: s.aiding_available,
                },
            );
            let now = matches!(
                rep.status[5],
                ChannelState::FaultPositive | ChannelState::FaultNegative
            );
            r_flags += usize::from(now && !prev);
            prev = now;
        }
        let est = m.heading_offset_estimate().to_degrees();
        println!("seed {seed}: heading offset estimate {est:.2}°, {r_flags} r flag events");
        assert!(est >= 1.0, "estimate {est}");
        assert_eq!(r_flags, 0);
    }
}

/// GIVEN a 3° heading offset learnt online and a run whose first seconds
/// are a turn, WHEN the monitor learns its nominal biases, THEN it does not
/// learn the horizontal accelerometers' from the turn (the unresolved offset
/// is in those innovations) beyond the half `min_fault` (0.1 m/s² here) the
/// contamination rule allows (`heading.rs`), and raises no false alarm in
/// 5 min. Before that rule, seed 304 learnt a_x 0.23 m/s² off and raised
/// 16 events in 5 min, seed 308 0.13 m/s² off and 34; measured now 0.003
/// and 0.063 m/s², 0 events (`aircraft_heading_offset` runs 30 h).
#[test]
fn heading_offset_turns_are_not_learnt_as_accelerometer_bias() {
    let mut scn = Scenario::aircraft_fault_free(300.0);
    scn.aiding.heading_offset_rad = 3f64.to_radians();
    for seed in [304, 308] {
        let trace = run_with::<f32>(&scn, seed, config(&scn, Setup::EstimateHeading)).unwrap();
        let m = evaluate(&trace);
        let last = trace.rows.last().unwrap();
        let err = (last.nominal_bias[0] - last.true_bias[0]).abs();
        println!(
            "seed {seed}: {} false-alarm events in {:.0} s, a_x nominal bias error {err:.3} m/s²",
            m.false_alarm_events, m.free_time_s
        );
        assert_eq!(m.false_alarm_events, 0);
        let allowed = 0.5 * config(&scn, Setup::EstimateHeading).min_fault[0] as f64;
        assert!(err < allowed, "a_x bias error {err}");
    }
}

/// Episodes for the heading-offset estimate: the first onset at 60 s. With
/// the estimate on, the learning phase counts only epochs an unresolved
/// offset cannot have contaminated, so it ends later (measured: monitoring
/// from 12.5–53 s on seeds 500–519) and a fault starting before that is a
/// power-up fault, absorbed up to `max_nominal_bias` (docs/results.md).
fn heading_plan() -> EpisodePlan {
    EpisodePlan {
        first_onset_s: 60.0,
        ..EpisodePlan::default()
    }
}

fn heading_episodes(base: &Scenario, seeds: std::ops::Range<u64>) -> EpisodeTotals {
    heading_episodes_with(base, seeds, Setup::EstimateHeading)
}

fn heading_episodes_with(
    base: &Scenario,
    seeds: std::ops::Range<u64>,
    setup: Setup,
) -> EpisodeTotals {
    let plan = heading_plan();
    let mut all = Vec::new();
    for seed in seeds {
        let scn = episode_scenario(base, seed, &plan);
        let trace = run_with::<f32>(&scn, seed, config(&scn, setup)).unwrap();
        all.extend(score(&trace, &plan));
    }
    EpisodeTotals::of(&all)
}

/// A 3° heading offset between the attitude aiding and the IMU frame,
/// learnt from the GNSS velocity (`estimate_heading_offset`), with the
/// aircraft preset's one-decision persistence: fault-free hours and the
/// time after faults clear meet the issue's ≤ 1 false-alarm event per hour,
/// every episode set ≥ 99 % detected with a step delay median ≤ 1 s
/// (docs/results.md). Seeds 200–201 and 100–104 were looked at while
/// designing, 300–309, 410–419 and 500–519 (and 520–559, not run here)
/// while diagnosing; 400–409 and 600–619 only as totals, 700–719, 420–429
/// and 800–819 not at all.
#[test]
#[ignore = "42 h and 105 seeds of episodes: run with --release -- --ignored"]
fn aircraft_heading_offset() {
    let mut offset = Scenario::aircraft_fault_free(0.0);
    offset.aiding.heading_offset_rad = 3f64.to_radians();
    let mut hour = offset.clone();
    hour.duration_s = 3600.0;
    let ignored = fault_free(&hour, 200..202);
    println!(
        "aircraft, 3° heading offset, ignored, seeds 200-201: {} false-alarm events in {:.2} fault-free h",
        ignored.false_alarm_events,
        ignored.free_time_s / 3600.0
    );
    assert!(ignored.false_alarm_events > 100);
    for (name, seeds) in [
        ("seeds 200-201", 200..202),
        ("seeds 300-309", 300..310),
        ("held-out seeds 400-409", 400..410),
        ("seeds 410-419", 410..420),
        ("held-out seeds 420-429", 420..430),
    ] {
        let m = fault_free_with(&hour, seeds, Setup::EstimateHeading);
        let h = m.free_time_s / 3600.0;
        println!(
            "aircraft, 3° heading offset, estimated, {name}: {} false-alarm events in {h:.2} fault-free h",
            m.false_alarm_events
        );
        assert!(m.false_alarm_events as f64 <= h, "{name}");
    }
    for (name, seeds) in [
        ("seeds 100-104", 100..105),
        ("seeds 500-519", 500..520),
        ("held-out seeds 600-619", 600..620),
        ("held-out seeds 700-719", 700..720),
        ("held-out seeds 800-819", 800..820),
    ] {
        let t = heading_episodes(&offset, seeds);
        println!(
            "aircraft, 3° heading offset, estimated, first onset 60 s, {name}: {}",
            t.line()
        );
        assert!(t.detected as f64 >= 0.99 * t.episodes as f64, "{name}");
        assert!(t.step_delay_median_s <= 1.0, "{name}: step delay median");
        // The issue's ≤ 1 event per hour (measured 0 on each; 20 in 1.03 h
        // on 500-519 with persistence 2 before the bias was solved for
        // with the angle).
        assert!(
            t.post_clear_events as f64 <= t.post_clear_s / 3600.0,
            "{name}"
        );
    }
    // Learning the offset costs no detection where there is none.
    let t = heading_episodes(&Scenario::aircraft_fault_free(0.0), 100..105);
    println!(
        "aircraft, no offset, estimated, first onset 60 s, seeds 100-104: {}",
        t.line()
    );
    assert_eq!(t.detected, t.episodes);
    assert_eq!(t.post_clear_events, 0);
}

/// Seeds from `IMU_FDI_SEEDS` (`first..end`, default `900..920`): the
/// campaign on any seeds a user picks, so the figures are not those of the
/// seeds the tuning saw.
fn seeds_from_env() -> std::ops::Range<u64> {
    let text = std::env::var("IMU_FDI_SEEDS").unwrap_or_else(|_| "900..920".into());
    let (a, b) = text
        .split_once("..")
        .expect("IMU_FDI_SEEDS is first..end, e.g. 900..920");
    let (a, b): (u64, u64) = (a.trim().parse().unwrap(), b.trim().parse().unwrap());
    assert!(a < b, "IMU_FDI_SEEDS: empty range {text}");
    a..b
}

/// GIVEN seeds of the user's choosing (`IMU_FDI_SEEDS=first..end`), WHEN
/// the aircraft and AUV campaigns run on them (episodes on every seed, one
/// fault-free aircraft hour per seed), THEN the targets hold:
/// `IMU_FDI_SEEDS=900..920 cargo test --release --test aircraft_episodes
/// any_seeds -- --ignored --nocapture`.
#[test]
#[ignore = "seeds from IMU_FDI_SEEDS: run with --release -- --ignored"]
fn any_seeds() {
    let seeds = seeds_from_env();
    let name = format!("seeds {}-{}", seeds.start, seeds.end - 1);
    assert_targets(
        &format!("aircraft, {name}"),
        &episodes(&Scenario::aircraft_fault_free(0.0), seeds.clone()),
    );
    let t = episodes(&Scenario::auv_fault_free(0.0), seeds.clone());
    assert_targets(&format!("AUV, {name}"), &t);
    assert_eq!(t.detected, t.episodes);
    let m = fault_free(&Scenario::aircraft_fault_free(3600.0), seeds);
    println!(
        "aircraft, fault-free, {name}: {} false-alarm events in {:.2} h",
        m.false_alarm_events,
        m.free_time_s / 3600.0
    );
    assert_eq!(m.false_alarm_events, 0);
}

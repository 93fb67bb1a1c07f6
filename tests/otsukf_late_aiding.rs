//! Held-out check of the OTSUKF monitor's attitude latency (issue 15,
//! `otsukf_monitor/attitude_lag.rs`): GIVEN the simulated aircraft with all
//! aiding 0.2 s late (the GNSS velocity's lag known to the monitor,
//! `velocity_lag_s`, as the replay fits it on the learning span), WHEN the
//! OTSUKF runs with both block tests (replay's flight settings) and its
//! attitude latency ignored or estimated online, THEN the estimate finds
//! the latency and the fault-free false-alarm events and the episodes'
//! post-clear events are printed for both.
//! `cargo test --release --test otsukf_late_aiding -- --ignored --nocapture`.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code: a panic is a failed assertion

use hal_sim::episodes::{episode_scenario, score, EpisodePlan, EpisodeTotals};
use hal_sim::metrics::{evaluate, RunMetrics};
use hal_sim::runner::{latency_s, monitor_config, RunOptions, Trace, TraceRow};
use hal_sim::{Scenario, Simulator};
use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::{OtsukfConfig, OtsukfMonitor};

/// Replay's flight settings on the scenario: both block tests, the GNSS
/// velocity's lag known, the attitude latency estimated or not.
fn config(scn: &Scenario, estimate: bool) -> OtsukfConfig<f32> {
    let mut b = monitor_config::<f32>(scn, &RunOptions::default());
    b.attitude_rate = Some(imu_fdi::monitor::AttitudeRateConfig::flight());
    b.velocity_increment = Some(imu_fdi::monitor::VelocityIncrementConfig::velocity());
    b.estimate_aiding_delay = estimate;
    let mut c = OtsukfConfig::from_base(b);
    c.velocity_lag_s = scn.aiding.delay_s as f32;
    c
}

/// The OTSUKF's run as a trace the episode and false-alarm scoring take;
/// the latency estimate at the end.
fn run(scn: &Scenario, seed: u64, estimate: bool) -> (Trace, f32) {
    let mut m = OtsukfMonitor::<f32>::new(config(scn, estimate)).unwrap();
    let mut rows = Vec::new();
    for s in Simulator::new(scn, seed) {
        let imu = s.imu.unwrap_or([f64::NAN; 6]);
        let u = ImuVec::<f32>::from_fn(|i, _| imu[i] as f32);
        let z = MeasVec::<f32>::from_fn(|i, _| s.aiding[i] as f32);
        let r = m.step(
            &u,
            s.dt as f32,
            &Measurement {
                z,
                available: s.aiding_available,
            },
        );
        let f = |v: &nalgebra::SVector<f32, 6>| -> [f64; 6] {
            core::array::from_fn(|i| f64::from(v[i]))
        };
        rows.push(TraceRow {
            t: s.t,
            fault: s.fault,
            fault_active: s.fault_active,
            flag: core::array::from_fn(|i| r.status[i].sign()),
            fhat: f(&r.fault_estimate),
            fhat_as_written: f(&r.fault_estimate),
            state: f(&r.state),
            sigma: f(&r.state_sigma),
            truth: s.truth.state,
            nominal_bias: f(&r.nominal_bias),
            true_bias: s.imu_bias,
            phase: r.phase,
            t_stat: [f64::NAN; 6],
            innovation: [f64::NAN; 6],
            innovation_sigma: [f64::NAN; 6],
            covariance_resets: 0,
            health_event: r.health != imu_fdi::monitor::Health::default(),
            health: r.health,
        });
    }
    let trace = Trace {
        scenario: scn.clone(),
        seed,
        rows,
        latency_s: latency_s(scn),
        t_threshold: f64::NAN,
    };
    (trace, m.attitude_lag_estimate().unwrap_or(0.0))
}

#[test]
#[ignore = "minutes of simulated flights: run with --release -- --ignored"]
fn otsukf_aircraft_with_late_aiding() {
    let seeds: u64 = std::env::var("SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(4);
    let mut late = Scenario::aircraft_fault_free(0.0);
    late.aiding.delay_s = 0.2;
    let plan = EpisodePlan::default();
    for estimate in [false, true] {
        let mut all = Vec::new();
        let mut est = Vec::new();
        for seed in 100..100 + seeds {
            let scn = episode_scenario(&late, seed, &plan);
            let (trace, d) = run(&scn, seed, estimate);
            est.push(d);
            all.extend(score(&trace, &plan));
        }
        let t = EpisodeTotals::of(&all);
        println!("otsukf aircraft 0.2 s late, attitude latency estimated: {estimate}, seeds 100-{}: {}; estimates {est:.2?}", 99 + seeds, t.line());
        let mut hour = late.clone();
        hour.duration_s = 3600.0;
        let mut m = RunMetrics::default();
        let mut est = Vec::new();
        for seed in 700..700 + seeds {
            let (trace, d) = run(&hour, seed, estimate);
            est.push(d);
            m.merge(&evaluate(&trace));
        }
        println!(
            "otsukf aircraft 0.2 s late, attitude latency estimated: {estimate}, fault-free 1 h seeds 700-{}: {} false-alarm events in {:.2} h; estimates {est:.2?}",
            699 + seeds,
            m.false_alarm_events,
            m.free_time_s / 3600.0
        );
        if estimate {
            for d in est {
                assert!((d - 0.2).abs() <= 0.03, "estimate {d}");
            }
        }
    }
}

//! A gyro bias beyond the sensor's specified turn-on bias, present from
//! power-up (issue 15): with `max_nominal_bias` set to the datasheet bound
//! the learner stops there, and the excess is reported as a fault of the
//! right sign within a bounded time of monitoring start; before that the
//! report says "cannot judge" (phase not `Monitoring`, channels
//! `NotMonitored`), never "healthy". Without the bound (the former default,
//! 20 × `min_fault`) the same bias is absorbed as nominal and never
//! reported.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code: a panic is a failed assertion

use hal_sim::fault::{FaultKind, FaultRow};
use hal_sim::runner::{monitor_config, run_with, RunOptions};
use hal_sim::Scenario;
use imu_fdi::model::ImuVec;
use imu_fdi::monitor::Phase;

/// Seconds from monitoring start to the first positive flag on `p`, or
/// `None`; also asserts that nothing is reported healthy before
/// monitoring.
fn delay(bounded: bool, seed: u64) -> Option<f64> {
    let mut scn = Scenario::aircraft_fault_free(60.0);
    // E1 on p: the S1/S2 gyro step, 1.5 °/s, from power-up to the end.
    scn.faults
        .push(FaultRow {
            channel: 3,
            start: 0.0,
            end: 1e9,
            kind: FaultKind::E1,
            sign: 1.0,
        })
        .unwrap();
    let mut cfg = monitor_config::<f32>(&scn, &RunOptions::default());
    if bounded {
        // The simulated MEMS spec: turn-on bias σ 20 mg, 0.2 °/s, at most
        // 2.5 σ (hal_sim::imu_model).
        let (a, g) = (
            2.5 * scn.imu_errors.accel.turn_on_bias,
            2.5 * scn.imu_errors.gyro.turn_on_bias,
        );
        cfg.max_nominal_bias = Some(ImuVec::new(a, a, a, g, g, g).map(|v| v as f32));
    }
    let trace = run_with::<f32>(&scn, seed, cfg).unwrap();
    let mut start = None;
    for r in &trace.rows {
        if r.phase != Phase::Monitoring {
            assert!(
                r.flag.iter().all(Option::is_none),
                "judged before monitoring"
            );
            continue;
        }
        let t0 = *start.get_or_insert(r.t);
        if r.flag[3] == Some(1) {
            return Some(r.t - t0);
        }
    }
    None
}

#[test]
fn a_bias_beyond_the_turn_on_spec_is_reported_after_learning() {
    let bounded: Vec<_> = (1..=5).map(|s| delay(true, s)).collect();
    let unbounded: Vec<_> = (1..=5).map(|s| delay(false, s)).collect();
    println!("1.5 °/s p bias from power-up, 5 seeds: delay after monitoring start with the turn-on bound {bounded:.2?}; without {unbounded:.2?}");
    for d in &bounded {
        assert!(d.is_some_and(|d| d <= 5.0), "{bounded:?}");
    }
    assert!(unbounded.iter().all(Option::is_none), "{unbounded:?}");
}

//! Scenario tests, read like the papers' tables: GIVEN a vehicle, nominal
//! MEMS sensor errors (SPEC §8a) and a fault table, WHEN the monitor runs,
//! THEN detection, false-alarm and wrong-channel figures meet the targets.
//! CI runs 3 seeds; the ignored tests run 20 (`cargo test --release -- --ignored`).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

mod common;

use common::{assert_paper_targets, campaign};
use hal_sim::Scenario;
use imu_fdi::detect::Detector;

#[test]
fn s1_threshold_method_three_seeds() {
    let m = campaign(&Scenario::s1(), 1..4, Detector::Threshold);
    assert_paper_targets("S1 threshold", &m);
}

#[test]
fn s2_runtime_matrix_glr_three_seeds() {
    let m = campaign(&Scenario::s2(), 1..4, Detector::RuntimeMatrixGlr);
    assert_paper_targets("S2 run-time matrix + GLR", &m);
}

#[test]
#[ignore = "20 seeds per scenario: run with --release -- --ignored"]
fn s1_threshold_method_twenty_seeds() {
    let m = campaign(&Scenario::s1(), 100..120, Detector::Threshold);
    assert_paper_targets("S1 threshold, 20 seeds", &m);
}

#[test]
#[ignore = "20 seeds per scenario: run with --release -- --ignored"]
fn s2_runtime_matrix_glr_twenty_seeds() {
    let m = campaign(&Scenario::s2(), 100..120, Detector::RuntimeMatrixGlr);
    assert_paper_targets("S2 run-time matrix + GLR, 20 seeds", &m);
}

/// The paper's fixed matrix on S2 is reported, not required to pass. Its
/// known limitation (SPEC §5): C⁻¹·flag is whole only when the flag pattern
/// is a column of C, and at this operating point the gyro faults' patterns
/// are not — so it must do measurably worse than the GLR default there.
#[test]
fn s2_paper_fixed_matrix_is_reported_beside_the_default() {
    let paper = campaign(&Scenario::s2(), 1..4, Detector::PaperMatrix);
    let glr = campaign(&Scenario::s2(), 1..4, Detector::RuntimeMatrixGlr);
    print!("S2 paper matrix\n{}", paper.table());
    let gyro_detected = |m: &hal_sim::metrics::RunMetrics| {
        m.channels[3..].iter().map(|c| c.detected).sum::<usize>()
    };
    assert_eq!(gyro_detected(&glr), 9);
    assert!(
        gyro_detected(&paper) < gyro_detected(&glr),
        "paper matrix unexpectedly isolates every gyro fault"
    );
    // As printed (a_x sign wrong) it reports a_x faults with the wrong sign.
    let printed = campaign(&Scenario::s2(), 1..2, Detector::PaperMatrixAsPrinted);
    assert_eq!(
        printed.channels[0].hits, 0,
        "as-printed matrix should never give a_x the right sign"
    );
}

#[test]
fn fault_free_hour_auv_has_zero_false_alarms() {
    let m = campaign(
        &Scenario::auv_fault_free(3600.0),
        7..8,
        Detector::RuntimeMatrixGlr,
    );
    print!("AUV fault-free hour\n{}", m.table());
    assert!(m.free_time_s > 3580.0);
    assert_eq!(m.false_alarm_events, 0);
    assert_eq!(m.covariance_resets, 0);
    // Navigation stays sane: velocity within 2 cm/s, attitude within 0.05°.
    assert!(
        m.state_rmse[..3].iter().all(|v| *v < 0.02),
        "{:?}",
        m.state_rmse
    );
    assert!(
        m.state_rmse[3..].iter().all(|v| v.to_degrees() < 0.05),
        "{:?}",
        m.state_rmse
    );
}

#[test]
fn fault_free_hour_aircraft_has_zero_false_alarms() {
    let m = campaign(
        &Scenario::aircraft_fault_free(3600.0),
        7..8,
        Detector::RuntimeMatrixGlr,
    );
    print!("Aircraft fault-free hour\n{}", m.table());
    assert!(m.free_time_s > 3580.0);
    assert_eq!(m.false_alarm_events, 0);
    assert_eq!(m.covariance_resets, 0);
}

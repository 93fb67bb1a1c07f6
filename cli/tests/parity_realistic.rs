//! The multi-scale parity monitor on the realistic simulated profile
//! (`hal_sim::realistic`, fitted to log171), fault-free: the hour of
//! flight with the most gyro false alarms of the ten that
//! `imu-fdi-sim parity-realistic --hours 10` flies (seed 1004), and the
//! accelerometer hour whose healthy a_z offset the power-up test took for
//! a fault (seed 1002).

use hal_sim::array::ArrayKind;
use hal_sim::realistic::RealisticProfile;
use imu_fdi_cli::eval::parity_campaign::fault_free_on;

#[test]
fn folded_rotor_lines_do_not_raise_gyro_alarms() {
    // In this hour IMU0's x gyro line folds through 0 Hz six times for a
    // second or two (block means swing by up to 10 °/s while the spread
    // within each block collapses). Each swing held the 2.5-s window above
    // threshold for one or two decisions, and raised an alarm when one
    // decision sufficed (6 events); with the alarm confirmed by three
    // consecutive decisions, one long fold remained; with the covariances
    // learning a block only once every window containing it was judged
    // (and learning up to 0.95 of the threshold), none.
    let r = fault_free_on(&RealisticProfile::log171(), ArrayKind::Gyro, 1, 1004).unwrap();
    assert!(r.hours > 0.99, "{}", r.hours);
    assert_eq!(r.alarm_events, 0);
    assert_eq!(r.isolations, 0);
}

#[test]
fn a_healthy_rectified_accel_z_is_not_taken_for_a_power_up_fault() {
    // In this hour IMU2's a_z sits about 1.0–1.1 m/s² from the others'
    // mean (vibration rectification, opposite on IMU0 and IMU2). The
    // power-up offset test with a 1.0 m/s² limit raised an alarm 21 s after
    // training and isolated that healthy a_z; `accel_flight` has no such
    // test now (its offset limit is infinite), and nothing else alarms.
    let r = fault_free_on(&RealisticProfile::log171(), ArrayKind::Accel, 1, 1002).unwrap();
    assert!(r.hours > 0.99, "{}", r.hours);
    assert_eq!(r.alarm_events, 0);
    assert_eq!(r.isolations, 0);
}

#[test]
fn a_held_out_accel_alarm_names_the_sensor_that_really_drifted() {
    // Seed 30022 (never tuned on): 55 s into monitoring, IMU2's a_z is
    // isolated with an estimated bias of +0.38 m/s². The simulation says
    // its bias (Gauss–Markov instability, 0.131 m/s², 30 s, fitted to
    // log171) had really moved +0.32 m/s² from its mean over the 2 minutes
    // before: a healthy sensor drifting by the size of the steps the
    // monitor detects (issue 14, case "the sensor really drifted").
    let r = fault_free_on(&RealisticProfile::log171(), ArrayKind::Accel, 1, 30022).unwrap();
    assert_eq!(r.events.len(), 1, "{:?}", r.events);
    let e = r.events[0];
    assert_eq!((e.suspect, e.isolated), (8, Some(8)));
    assert!(e.since_monitoring < 60.0, "{}", e.since_monitoring);
    assert!(e.bias > 0.3 && e.true_drift > 0.25, "{e:?}");
}

#[test]
fn a_held_out_gyro_alarm_is_a_fold_not_a_drift() {
    // Seed 30016 (never tuned on): 44 min in, IMU0's x gyro is isolated
    // with an estimated bias of −4.1 °/s while its simulated bias moved by
    // less than 0.01 °/s: the rotor line that its 1 kHz sampling folds
    // through 0 Hz (vibration, a second or two), not a drift. Since the
    // re-admission of isolated sensors it comes back and the next fold,
    // 53 min in, isolates it again (+2.8 °/s, drift 0.03 °/s): before, it
    // stayed out for the rest of the flight and that was one event.
    let r = fault_free_on(&RealisticProfile::log171(), ArrayKind::Gyro, 1, 30016).unwrap();
    assert_eq!(r.events.len(), 2, "{:?}", r.events);
    let e = r.events[0];
    assert_eq!((e.suspect, e.isolated), (0, Some(0)));
    assert!(e.bias < -3.0 && e.true_drift.abs() < 0.05, "{e:?}");
    let e2 = r.events[1];
    assert_eq!((e2.suspect, e2.isolated), (0, Some(0)));
    assert!(
        e2.t > e.t + 20.0 && e2.bias.abs() > 2.0 && e2.true_drift.abs() < 0.05,
        "{e2:?}"
    );
}

//! Real data, GIVEN ArduPilot log171 (three synchronous IMUs at 49 Hz, a
//! Pixhawk in Loiter then Acro, crash at ≈ 239 s; CC BY-SA 3.0, see
//! tests/data/LICENSE-ap_log171.md), WHEN the parity monitor trains in
//! flight (80–110 s: 20 s training, 10 s calibration) and runs to the end,
//! THEN normal flight raises no alarm, the crash is flagged in the window
//! the external DroneKit-LA analyser reports (239.825–241.335 s), and
//! injected biases are found at these sizes.

use std::path::Path;

use hal_sim::array::ArrayKind;
use imu_fdi_cli::eval::parity_replay::{read_imu_log, replay_parity, ImuLog, Injection};

/// DroneKit-LA: "IMU vs IMU2 gyro differ, max 11.7 deg/s", this interval.
const ANALYSER: (f64, f64) = (239.825, 241.335);
/// The crash begins (SOURCES.md: ≈ 239 s; the first saturated sample is at 239.16 s).
const CRASH: f64 = 239.0;

fn log() -> ImuLog {
    read_imu_log(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    )))
    .unwrap()
}

#[test]
fn normal_flight_is_quiet_and_the_crash_is_flagged_in_the_analysers_window() {
    let log = log();
    for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
        let r = replay_parity(&log, kind, 80.0, 30.0, None).unwrap();
        let from = r.monitoring_from.unwrap();
        assert!((109.0..111.0).contains(&from), "{kind:?}: {from}");
        // 129 s of Loiter and Acro without a single alarm or isolation.
        assert!(
            r.alarms.iter().all(|a| a.0 >= CRASH),
            "{kind:?}: {:?}",
            r.alarms
        );
        assert!(
            r.isolations.iter().all(|a| a.1 >= CRASH),
            "{kind:?}: {:?}",
            r.isolations
        );
        // The crash: first alarm after it began and no later than the end of
        // the analyser's interval.
        let first = r.alarms.first().map(|a| a.0).unwrap();
        assert!((CRASH..=ANALYSER.1).contains(&first), "{kind:?}: {first}");
        // The baselines stay silent through normal flight too.
        assert!(r.px4.iter().chain(r.ardupilot.iter()).all(|a| a.0 >= CRASH));
    }
    let gyro = replay_parity(&log, ArrayKind::Gyro, 80.0, 30.0, None).unwrap();
    // A gyro alarm inside the analyser's own interval (measured: 240.49–240.67 s)...
    assert!(
        gyro.alarms
            .iter()
            .any(|a| a.0 <= ANALYSER.1 && a.1 >= ANALYSER.0),
        "{:?}",
        gyro.alarms
    );
    // ...saturated gyros (beyond ±2,000 °/s) are marked, not used.
    assert!(gyro.statuses.iter().any(|(_, s, t)| {
        matches!(
            s,
            imu_fdi::parity::SensorStatus::OutOfRange | imu_fdi::parity::SensorStatus::Clipping
        ) && (CRASH..ANALYSER.1).contains(t)
    }));
    // Neither autopilot baseline flags the gyros at all (ArduPilot-like needs
    // 10 s of disagreement; PX4-like accumulates past 7 °/s).
    assert!(gyro.px4.is_empty() && gyro.ardupilot.is_empty());
}

/// Smallest bias (from the grid) flagged within 15 s and isolated to the right sensor.
fn smallest(
    log: &ImuLog,
    kind: ArrayKind,
    imu: usize,
    channel: usize,
    sizes: &[f64],
) -> Option<(f64, f64)> {
    sizes.iter().find_map(|&size| {
        let inj = Injection {
            imu,
            channel,
            size,
            start: 130.0,
        };
        let r = replay_parity(log, kind, 80.0, 30.0, Some(inj)).unwrap();
        let alarm = r.alarms.iter().find(|a| a.0 >= 130.0 && a.0 < 145.0)?;
        let sensor = 3 * imu + channel % 3;
        r.isolations
            .iter()
            .any(|(k, t)| *k == sensor && *t < 145.0)
            .then_some((size, alarm.0 - 130.0))
    })
}

#[test]
fn injected_biases_in_flight_are_found_at_these_sizes() {
    let log = log();
    let deg = [1.0, 2.0, 3.0, 5.0, 7.0, 10.0].map(|d: f64| d.to_radians());
    // IMU 1 yaw gyro: 5 °/s, in about a second (PX4-like needs 15 °/s,
    // ArduPilot-like 10 °/s and 10 s: `cargo sim parity-replay … --inject-at 130,180`).
    let (size, delay) = smallest(&log, ArrayKind::Gyro, 1, 5, &deg).unwrap();
    assert_eq!(size, 5.0_f64.to_radians());
    assert!(delay < 1.5, "{delay}");
    // IMU 2 lateral accelerometer: 0.5 m/s² (PX4-like 1.5, ArduPilot-like 1.0).
    let (size, delay) = smallest(&log, ArrayKind::Accel, 2, 1, &[0.2, 0.3, 0.5, 0.7, 1.0]).unwrap();
    assert_eq!(size, 0.5);
    assert!(delay < 1.5, "{delay}");
}

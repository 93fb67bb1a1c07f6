//! Real data, GIVEN ArduPilot log171 (three synchronous IMUs at 49 Hz; CC
//! BY-SA 3.0, tests/data/LICENSE-ap_log171.md) damaged as a board damages
//! it — one IMU's output frozen (a FIFO or driver that repeats its last
//! sample) or absent (an I²C hang) for a spell in flight — WHEN the parity
//! monitor for real flights replays it (training at 80 s), THEN the IMU's
//! three axes fail their hardware check, are excluded, judged against the
//! other two IMUs once their output is good again, and re-admitted together
//! after the probation (the longest window filled, then twice it quiet),
//! with no alarm and no isolation before the crash; an IMU that stays
//! frozen stays out, reported failed (issue 14, "never stuck": such a
//! spell used to cost the board that IMU until reset).
#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code

use std::path::Path;

use hal_sim::array::ArrayKind;
use imu_fdi::parity::SensorStatus;
use imu_fdi_cli::eval::parity_replay::{read_imu_log, replay_parity, ImuLog};

/// The crash begins (SOURCES.md: ≈ 239 s).
const CRASH: f64 = 239.0;

fn log() -> ImuLog {
    read_imu_log(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    )))
    .unwrap()
}

/// `log` with IMU `imu` frozen at its first row in `[start, end)`
/// (`absent`: its cells empty instead, read as missing samples).
fn damaged(log: &ImuLog, imu: usize, start: f64, end: f64, absent: bool) -> ImuLog {
    let mut out = log.clone();
    let mut held = None;
    for (t, row) in out.t.iter().zip(out.imus.iter_mut()) {
        if (start..end).contains(t) {
            let cells = &mut row[imu];
            *cells = if absent {
                [f64::NAN; 6]
            } else {
                *held.get_or_insert(*cells)
            };
        }
    }
    out
}

#[test]
fn an_imu_frozen_or_silent_for_a_spell_is_readmitted_once_its_output_is_back() {
    let log = log();
    // (IMU, start, end, absent, expected status), spells not tuned on:
    // 15 s frozen in the Loiter phase, 3 s silent in Acro.
    for (imu, start, end, absent, failure) in [
        (1, 160.0, 175.0, false, SensorStatus::Stuck),
        (2, 190.0, 193.0, true, SensorStatus::Timeout),
    ] {
        let bad = damaged(&log, imu, start, end, absent);
        for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
            let r = replay_parity(&bad, kind, 80.0, 30.0, None).unwrap();
            let what = format!("IMU{imu} {kind:?} {start}–{end} s");
            for axis in 0..3 {
                let k = 3 * imu + axis;
                let (_, _, t_fail) = *r
                    .statuses
                    .iter()
                    .find(|(j, s, _)| *j == k && *s == failure)
                    .unwrap_or_else(|| panic!("{what}: {:?}", r.statuses));
                assert!((start..start + 1.5).contains(&t_fail), "{what}: {t_fail}");
                let (_, t_back) = *r
                    .readmissions
                    .iter()
                    .find(|(j, _)| *j == k)
                    .unwrap_or_else(|| panic!("{what}: never re-admitted"));
                // The 10-s window filled and 20 s quiet after the output
                // came back (measured: 29.5 s frozen, ≈ 31 s silent).
                assert!(
                    (end + 28.0..end + 36.0).contains(&t_back),
                    "{what}: {t_back}"
                );
            }
            assert!(
                r.alarms.iter().all(|a| a.0 >= CRASH),
                "{what}: {:?}",
                r.alarms
            );
            assert!(
                r.isolations.iter().all(|a| a.1 >= CRASH),
                "{what}: {:?}",
                r.isolations
            );
        }
    }
}

#[test]
fn an_imu_that_stays_frozen_stays_out() {
    let bad = damaged(&log(), 0, 150.0, 300.0, false);
    let r = replay_parity(&bad, ArrayKind::Gyro, 80.0, 30.0, None).unwrap();
    assert!(r.readmissions.is_empty(), "{:?}", r.readmissions);
    for k in 0..3 {
        assert!(r
            .statuses
            .iter()
            .any(|(j, s, _)| *j == k && *s == SensorStatus::Stuck));
        // Never reported as anything but stuck (not on probation).
        assert!(
            r.statuses
                .iter()
                .all(|(j, s, _)| *j != k || *s == SensorStatus::Stuck),
            "{:?}",
            r.statuses
        );
    }
}

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
use imu_fdi_cli::eval::parity_replay::{
    read_imu_log, replay_parity, ImuLog, Injection, ParityReplay,
};

/// The crash begins (SOURCES.md: ≈ 239 s).
const CRASH: f64 = 239.0;

/// No alarm and no isolation before the crash.
fn nothing_before_the_crash(r: &ParityReplay, what: &str) {
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
            nothing_before_the_crash(&r, &what);
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

/// `log` with every IMU's row held at its first in `[start, end)`: the
/// logger or the driver repeating a sample, all IMUs at once.
fn all_held(log: &ImuLog, start: f64, end: f64) -> ImuLog {
    (0..3).fold(log.clone(), |l, imu| damaged(&l, imu, start, end, false))
}

/// A 10 °/s step on IMU `imu`'s z gyro from `start` to the crash: the
/// monitor must still isolate it (it is judging, and with every IMU).
fn gz_step(imu: usize, start: f64) -> Option<Injection> {
    Some(Injection {
        imu,
        channel: 5,
        size: 10f64.to_radians(),
        start,
        end: CRASH,
    })
}

/// GIVEN every IMU frozen together for 2 s, in flight (training at 80 s)
/// or while training (at 100 s), THEN no sensor is latched out — a
/// common-mode event, reported `Stuck` while it lasts — nothing alarms
/// before the crash, and a later step is still isolated to its IMU
/// (before: all nine sensors latched, the monitor `Lost` for the rest of
/// the flight, or never monitoring when it happened in training).
#[test]
fn every_imu_frozen_at_once_is_a_common_mode_event() {
    let log = log();
    for (start, train) in [(150.0, 80.0), (120.0, 100.0)] {
        let bad = all_held(&log, start, start + 2.0);
        for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
            let what = format!("{kind:?} held {start} s, training {train} s");
            let r = replay_parity(&bad, kind, train, 30.0, None).unwrap();
            assert!(r.monitoring_from.is_some(), "{what}: never monitoring");
            // Reported while frozen (1 s of repeats at 49 Hz), on every IMU.
            for k in 0..9 {
                assert!(
                    r.statuses.iter().any(|(j, s, t)| *j == k
                        && *s == SensorStatus::Stuck
                        && (start..start + 2.0).contains(t)),
                    "{what}: {:?}",
                    r.statuses
                );
            }
            nothing_before_the_crash(&r, &what);
        }
        let r = replay_parity(&bad, ArrayKind::Gyro, train, 30.0, gz_step(2, 190.0)).unwrap();
        let first = r.isolations.first().copied();
        assert!(
            first.is_some_and(|(k, t)| k == 8 && (190.0..200.0).contains(&t)),
            "held {start} s: step on IMU2 g_z at 190 s: {:?}",
            r.isolations
        );
    }
}

/// GIVEN IMU1 frozen for 5 s while the monitor trains (from 100 s), THEN
/// once its output is back it rejoins and training starts over with all
/// three IMUs, so a step on IMU1 later is isolated to it (before: trained
/// and monitored with two IMUs, which detect but cannot isolate, and
/// IMU1 out for the rest of the flight).
#[test]
fn an_imu_frozen_while_training_rejoins_and_training_starts_over() {
    let bad = damaged(&log(), 1, 120.0, 125.0, false);
    let r = replay_parity(&bad, ArrayKind::Gyro, 100.0, 30.0, gz_step(1, 190.0)).unwrap();
    let from = r.monitoring_from.unwrap();
    // Training restarted at the first good sample (≥ 125 s) for 30 s.
    assert!((150.0..165.0).contains(&from), "monitoring from {from}");
    assert!(
        r.statuses
            .iter()
            .any(|(j, s, t)| *j == 3 && *s == SensorStatus::Stuck && (120.0..122.0).contains(t)),
        "{:?}",
        r.statuses
    );
    let first = r.isolations.first().copied();
    assert!(
        first.is_some_and(|(k, t)| k == 5 && (190.0..200.0).contains(&t)),
        "step on IMU1 g_z at 190 s: {:?}",
        r.isolations
    );
    assert!(r.alarms.iter().all(|a| a.0 >= 190.0), "{:?}", r.alarms);
}

/// `log` with the rows in `[start, end)` removed (a logging dropout) and,
/// when `jump` is not zero, every later time stamp moved by `jump` s (a
/// logger clock that jumps).
fn gap(log: &ImuLog, start: f64, end: f64, jump: f64) -> ImuLog {
    let mut out = log.clone();
    let keep: Vec<bool> = log.t.iter().map(|t| !(start..end).contains(t)).collect();
    let mut k = keep.iter();
    out.t.retain(|_| *k.next().unwrap());
    let mut k = keep.iter();
    out.imus.retain(|_| *k.next().unwrap());
    for t in out.t.iter_mut().filter(|t| **t >= end) {
        *t += jump;
    }
    out
}

#[test]
fn a_dropout_or_a_clock_jump_changes_nothing_before_it() {
    // The replay's sample rate used to be rows over span: a 30-s dropout
    // made it 41 Hz, a 1,000-s clock jump 8 Hz, and training, blocks and
    // windows — configured in samples from it — then ended elsewhere
    // before the damage (monitoring from 105.6 s instead of 110.2 s; with
    // the jump, alarms and isolations of healthy sensors at 92–106 s).
    let log = log();
    let step = gz_step(1, 125.0);
    for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
        let base = replay_parity(&log, kind, 80.0, 30.0, step).unwrap();
        for (what, bad) in [
            ("dropout 150–180 s", gap(&log, 150.0, 180.0, 0.0)),
            ("clock +1000 s at 150 s", gap(&log, 150.0, 150.0, 1000.0)),
        ] {
            let r = replay_parity(&bad, kind, 80.0, 30.0, step).unwrap();
            let what = format!("{kind:?}, {what}");
            assert_eq!(r.monitoring_from, base.monitoring_from, "{what}");
            let before = |r: &ParityReplay| -> (Vec<(usize, f64)>, usize) {
                let iso = r.isolations.iter().copied().filter(|i| i.1 < 150.0);
                (
                    iso.collect(),
                    r.alarms.iter().filter(|a| a.0 < 150.0).count(),
                )
            };
            assert_eq!(before(&r), before(&base), "{what}");
        }
        if kind == ArrayKind::Gyro {
            // The step itself is isolated to IMU1 z within 10 s.
            let (k, t) = base.isolations[0];
            assert!(k == 5 && t < 135.0, "{:?}", base.isolations);
        }
    }
}

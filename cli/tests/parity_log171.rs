//! Real data, GIVEN ArduPilot log171 (three synchronous IMUs at 49 Hz, a
//! Pixhawk in Loiter then Acro, crash at ≈ 239 s; CC BY-SA 3.0, see
//! tests/data/LICENSE-ap_log171.md), WHEN the parity monitor for real
//! flights (`ParityConfig::gyro_flight`/`accel_flight`: in-flight relative
//! calibration, multi-scale tests with covariances learned from the data)
//! trains for 30 s from any start between 60 and 100 s and runs to the end,
//! THEN the gyros raise no alarm in normal flight, the crash is flagged in
//! the window the external DroneKit-LA analyser reports, and injected steps
//! are isolated at the rates measured below (the issue-14 table: every IMU ×
//! axis × sign, six onsets after monitoring start, five training starts,
//! 15-s steps, isolated to the right sensor within 10 s and nothing else
//! alarming before the crash). The figures are asserted as measured, so a
//! change that loses detections or adds false alarms fails here.

use std::path::Path;

use hal_sim::array::ArrayKind;
use imu_fdi_cli::eval::parity_replay::{
    power_up_table, read_imu_log, replay_parity, replay_parity_with, step_table, ImuLog, Injection,
    ParityMethod, PowerUpCase, StepCase,
};

/// DroneKit-LA: "IMU vs IMU2 gyro differ, max 11.7 deg/s", this interval.
const ANALYSER: (f64, f64) = (239.825, 241.335);
/// The crash begins (SOURCES.md: ≈ 239 s; the first saturated sample is at 239.16 s).
const CRASH: f64 = 239.0;
const TRAIN_STARTS: [f64; 5] = [60.0, 70.0, 80.0, 90.0, 100.0];
/// Onsets, seconds after monitoring start.
const ONSETS: [f64; 6] = [5.0, 25.0, 45.0, 65.0, 85.0, 105.0];

fn log() -> ImuLog {
    read_imu_log(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    )))
    .unwrap()
}

#[test]
fn gyros_are_quiet_in_normal_flight_from_any_training_start_and_flag_the_crash() {
    let log = log();
    for ts in [60.0, 65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0, 100.0] {
        let r = replay_parity(&log, ArrayKind::Gyro, ts, 30.0, None).unwrap();
        let from = r.monitoring_from.unwrap();
        assert!((ts + 29.0..ts + 33.0).contains(&from), "{ts}: {from}");
        assert!(
            r.alarms.iter().all(|a| a.0 >= CRASH),
            "{ts}: {:?}",
            r.alarms
        );
        assert!(
            r.isolations.iter().all(|a| a.1 >= CRASH),
            "{ts}: {:?}",
            r.isolations
        );
    }
    let gyro = replay_parity(&log, ArrayKind::Gyro, 80.0, 30.0, None).unwrap();
    // The crash: an alarm inside the analyser's interval (measured 240.0–240.5 s)…
    assert!(
        gyro.alarms
            .iter()
            .any(|a| a.0 >= CRASH && a.0 <= ANALYSER.1 && a.1 >= ANALYSER.0),
        "{:?}",
        gyro.alarms
    );
    // …and saturated gyros (beyond ±2,000 °/s) are marked, not used.
    assert!(gyro.statuses.iter().any(|(_, s, t)| {
        matches!(
            s,
            imu_fdi::parity::SensorStatus::OutOfRange | imu_fdi::parity::SensorStatus::Clipping
        ) && (CRASH..ANALYSER.1).contains(t)
    }));
}

#[test]
fn accelerometer_false_alarms_in_normal_flight_stay_as_measured() {
    // On this 2015 board the a_z of the three IMUs part by up to 2 m/s² for
    // seconds under vibration; the rectification regressors remove most of
    // it but not all, and the vibration-scaled residuals (multiscale::scale)
    // do not count a loud block as much as a calm one. Measured over nine
    // training starts (60, 65, …, 100 s): no alarm before the crash, no
    // sensor isolated (before the scaling: one 0.3-s alarm).
    let log = log();
    let (mut events, mut isolations) = (0, 0);
    for ts in [60.0, 65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0, 100.0] {
        let r = replay_parity(&log, ArrayKind::Accel, ts, 30.0, None).unwrap();
        events += r.alarms.iter().filter(|a| a.0 < CRASH).count();
        isolations += r.isolations.iter().filter(|a| a.1 < CRASH).count();
    }
    assert!(events == 0, "{events}");
    assert!(isolations == 0, "{isolations}");
}

#[test]
fn the_simulators_glt_cusum_method_still_replays() {
    // The white-noise method (SPEC §7 defaults) trained at 80 s, as before
    // the real-flight tests existed: quiet in normal flight.
    let log = log();
    for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
        let r = replay_parity_with(&log, kind, 80.0, 30.0, None, ParityMethod::GltCusum).unwrap();
        assert!(r.alarms.iter().all(|a| a.0 >= CRASH), "{kind:?}");
    }
}

fn passes(cases: &[StepCase], pred: impl Fn(&StepCase) -> bool) -> (usize, usize) {
    let sel: Vec<_> = cases
        .iter()
        .filter(|c| c.injection.start + 10.0 < CRASH && pred(c))
        .collect();
    let ok = sel.iter().filter(|c| c.isolated && !c.false_alarm).count();
    (ok, sel.len())
}

#[test]
fn injected_gyro_steps_are_isolated_at_the_measured_rates() {
    let log = log();
    let cases = step_table(
        &log,
        ArrayKind::Gyro,
        1.0_f64.to_radians(),
        &TRAIN_STARTS,
        30.0,
        &ONSETS,
        15.0,
        CRASH,
        ParityMethod::Flight,
    )
    .unwrap();
    let axis = |a: usize| move |c: &StepCase| c.injection.channel == 3 + a;
    // 1 °/s, measured: z 167/174, y 137/174, x 31/174, 3 cases with a
    // false alarm (with the rate as rows over span, which the log's arming
    // gap biased to 49.06 Hz: y 136, x 33, 4 cases). IMU0's x gyro reads 12 °/s of aliased vibration per
    // sample, so a step on IMU1 or IMU2 x is nearly the opposite step on
    // the other one (whitened cosine −0.95): x steps are isolated only since
    // the 5- and 10-s windows attribute alarms on their unclipped means
    // (before: x 5, y 135, 5 false-alarm cases; IMU0 x still 0/58). (Before
    // the covariances learned a block only after every window containing
    // it was judged, and learning stopped at half the threshold: z 150,
    // y 124, x 8, 8 false-alarm cases.)
    let (z, n) = passes(&cases, axis(2));
    assert!(z >= 166 && n == 174, "{z}/{n}");
    let (y, _) = passes(&cases, axis(1));
    assert!(y >= 135, "{y}");
    let (x, _) = passes(&cases, axis(0));
    assert!(x >= 30, "{x}");
    let fa = cases.iter().filter(|c| c.false_alarm).count();
    assert!(fa <= 3, "{fa}");
    // Every IMU is covered: z steps on each IMU isolated in ≥ 52 of 58
    // cases (measured 53, 56, 58).
    for imu in 0..3 {
        let (ok, _) = passes(&cases, |c| {
            c.injection.imu == imu && c.injection.channel == 5
        });
        assert!(ok >= 52, "imu {imu}: {ok}");
    }
    // Delays: every isolation within the 10 s, median a few seconds.
    let mut d: Vec<f64> = cases.iter().filter_map(|c| c.delay).collect();
    d.sort_by(f64::total_cmp);
    assert!(d.last().is_some_and(|x| *x < 10.0));
}

#[test]
fn injected_accelerometer_steps_are_isolated_at_the_measured_rates() {
    let log = log();
    let cases = step_table(
        &log,
        ArrayKind::Accel,
        0.3,
        &TRAIN_STARTS,
        30.0,
        &ONSETS,
        15.0,
        CRASH,
        ParityMethod::Flight,
    )
    .unwrap();
    // 0.3 m/s², measured: x 153/174, y 166/174, z 96/174 (the a_z
    // vibration events above), 5 cases with a false alarm (with the rate as
    // rows over span, 49.06 Hz: x 156, y 164, z 101, 3; before the
    // unclipped attribution: y 162, z 96, 4). (Before the covariances'
    // delayed learning and `learn_below` 0.95: x 141, y 159, z 91, 5 cases
    // with a false alarm.)
    let axis = |a: usize| move |c: &StepCase| c.injection.channel == a;
    let (x, _) = passes(&cases, axis(0));
    let (y, _) = passes(&cases, axis(1));
    let (z, _) = passes(&cases, axis(2));
    assert!(x >= 152 && y >= 165 && z >= 95, "{x} {y} {z}");
    let fa = cases.iter().filter(|c| c.false_alarm).count();
    assert!(fa <= 5, "{fa}");
    for imu in 0..3 {
        let (ok, _) = passes(&cases, |c| {
            c.injection.imu == imu && c.injection.channel < 2
        });
        // Measured 103, 108, 108 (105, 107, 108 at 49.06 Hz).
        assert!(ok >= 102, "imu {imu}: {ok}");
    }
}

#[test]
fn a_gyro_bias_present_from_power_up_is_reported_without_naming_a_healthy_sensor() {
    let log = log();
    let cases = power_up_table(
        &log,
        ArrayKind::Gyro,
        2.0_f64.to_radians(),
        &TRAIN_STARTS,
        30.0,
        CRASH,
        ParityMethod::Flight,
    )
    .unwrap();
    // Measured: 78 of 90 isolated within 10 s of monitoring start, never a
    // healthy sensor. Trained from 60 or 70 s the board is at rest until
    // takeoff (≈ 83 s): the rest check (absolute gyro means) isolates all
    // 36, before monitoring starts; from 80 s on (≤ 3 s of rest) the
    // offset check (relative bias above 1.2 °/s) gives 42 of 54.
    let ok = cases.iter().filter(|c| c.delay.is_some()).count();
    assert!(ok >= 76, "{ok}");
    assert!(cases.iter().all(|c| !c.wrong_isolation));
    let at_rest = |c: &&PowerUpCase| c.train_start < 75.0;
    let rest_ok = cases
        .iter()
        .filter(at_rest)
        .filter(|c| c.delay == Some(0.0))
        .count();
    assert_eq!(rest_ok, 36);
    // Training starts the rest check was not designed on, all within the
    // rest before takeoff: measured 90 of 90 (56 without the rest check).
    let held_out = power_up_table(
        &log,
        ArrayKind::Gyro,
        2.0_f64.to_radians(),
        &[62.0, 65.0, 67.0, 73.0, 76.0],
        30.0,
        CRASH,
        ParityMethod::Flight,
    )
    .unwrap();
    assert!(held_out
        .iter()
        .all(|c| c.delay.is_some() && !c.wrong_isolation));
}

/// Re-admission (docs/recovery.md, "Parity monitor"): GIVEN a 1-s +3 m/s²
/// glitch on IMU0 a_x at 140 s (a shock that passes the hardware checks),
/// WHEN it is isolated, THEN the sensor is judged by the full set's frozen
/// tests and re-admitted after its probation, with no alarm between the
/// re-admission and the crash, which is still alarmed. The same for a
/// 20 °/s 1-s glitch on IMU1 g_x at 150 s (a case not diagnosed on).
#[test]
fn a_short_glitch_is_isolated_then_readmitted_and_the_crash_still_alarmed() {
    let log = log();
    for (kind, imu, channel, size, start, sensor) in [
        (ArrayKind::Accel, 0, 0, 3.0, 140.0, 0),
        (ArrayKind::Gyro, 1, 3, 20f64.to_radians(), 150.0, 3),
    ] {
        let inj = Injection {
            imu,
            channel,
            size,
            start,
            end: start + 1.0,
        };
        let r = replay_parity(&log, kind, 80.0, 30.0, Some(inj)).unwrap();
        let (k, t_iso) = r.isolations.first().copied().unwrap();
        assert_eq!(k, sensor, "{:?}", r.isolations);
        assert!((start..start + 3.0).contains(&t_iso), "{t_iso}");
        let (k, t_back) = r.readmissions.first().copied().unwrap();
        assert_eq!(k, sensor);
        // At least the longest window filled plus the probation after the
        // isolation: 40 + 80 blocks of 12 samples at 49 Hz = 29.4 s, from
        // the blocks just before the isolation
        // (measured: 170.70 s and 180.62 s).
        assert!(
            (t_iso + 28.0..t_iso + 40.0).contains(&t_back),
            "{t_iso} {t_back}"
        );
        assert!(r.statuses.iter().any(|(j, s, t)| *j == sensor
            && *s == imu_fdi::parity::SensorStatus::Probation
            && *t > t_iso
            && *t < t_back));
        // No alarm from the glitch's end to the crash, one at the crash.
        assert!(
            r.alarms.iter().all(|a| a.0 < start + 3.0 || a.0 >= CRASH),
            "{:?}",
            r.alarms
        );
        assert!(r.alarms.iter().any(|a| a.0 >= CRASH), "{:?}", r.alarms);
        assert_eq!(
            r.isolations.iter().filter(|(_, t)| *t < CRASH).count(),
            1,
            "{:?}",
            r.isolations
        );
    }
}

/// A persistent 2 °/s bias on IMU1 g_x from 140 s to the end is isolated
/// and never re-admitted while it lasts.
#[test]
fn a_persistent_bias_is_never_readmitted() {
    let log = log();
    for (imu, axis, sign) in [(1, 0, 1.0), (0, 2, -1.0), (2, 1, 1.0)] {
        let inj = Injection {
            imu,
            channel: 3 + axis,
            size: sign * 2f64.to_radians(),
            start: 140.0,
            end: f64::INFINITY,
        };
        let r = replay_parity(&log, ArrayKind::Gyro, 80.0, 30.0, Some(inj)).unwrap();
        let sensor = 3 * imu + axis;
        assert!(
            r.isolations.iter().any(|(k, t)| *k == sensor && *t < 160.0),
            "{:?}",
            r.isolations
        );
        assert!(
            r.readmissions.iter().all(|(k, _)| *k != sensor),
            "{:?}",
            r.readmissions
        );
    }
}

/// An intermittent sensor (docs/recovery.md): 1-s +5 m/s² glitches on
/// IMU0 a_x at 115, 150 and 205 s (and at 115, 175 and 225 s). Each is
/// isolated; the first re-admission follows the 20-s probation, the second
/// the doubled 40-s one, and the third isolation (`MAX_ISOLATIONS`) stays
/// for good: the alarms are bounded to three. Before the re-admitted
/// tests took the calibration of one to two longest windows before the
/// isolation, the 205-s glitch was not even alarmed (the glitch at 150 s
/// had been learned into the calibration before its alarm).
#[test]
fn an_intermittent_sensor_gets_longer_probations_then_stays_out() {
    for glitches in [[115.0, 150.0, 205.0], [115.0, 175.0, 225.0]] {
        let mut log = log();
        for (t, row) in log.t.iter().zip(log.imus.iter_mut()) {
            if glitches.iter().any(|s| (*s..*s + 1.0).contains(t)) {
                if let Some(v) = row.get_mut(0).and_then(|imu| imu.get_mut(0)) {
                    *v += 5.0;
                }
            }
        }
        let r = replay_parity(&log, ArrayKind::Accel, 80.0, 30.0, None).unwrap();
        let iso: Vec<f64> = r
            .isolations
            .iter()
            .filter(|(k, t)| *k == 0 && *t < CRASH)
            .map(|(_, t)| *t)
            .collect();
        let back: Vec<f64> = r
            .readmissions
            .iter()
            .filter(|(k, _)| *k == 0)
            .map(|(_, t)| *t)
            .collect();
        assert_eq!(
            iso.len(),
            imu_fdi::parity::MAX_ISOLATIONS as usize,
            "{iso:?}"
        );
        assert!(glitches
            .iter()
            .zip(iso.iter())
            .all(|(g, i)| (*g..*g + 3.0).contains(i)));
        assert_eq!(back.len(), 2, "{back:?} {iso:?}");
        // Probation 80 then 160 blocks of 0.245 s after the 40-block fill.
        assert!(
            back[0] - iso[0] >= 28.0 && back[0] - iso[0] < 40.0,
            "{back:?} {iso:?}"
        );
        assert!(
            back[1] - iso[1] >= 48.0 && back[1] - iso[1] < 60.0,
            "{back:?} {iso:?}"
        );
        assert!(iso[1] > back[0] && iso[2] > back[1]);
        // No other sensor isolated before the crash.
        assert!(r.isolations.iter().all(|(k, t)| *k == 0 || *t >= CRASH));
    }
}

/// Issue 14, found with the 99-Hz copy (docs/recovery.md): GIVEN log171
/// with a row interpolated halfway between each two (as
/// `scripts/parity-log-damage.py` "upsample2" builds it), training from
/// 100 s and a 0.5 m/s² step on IMU0 a_x from 135 s, WHEN the stepped
/// sensor has been isolated, THEN a one-sample +3.9 m/s² spike on IMU2 a_z
/// at 144.47 s, whose within-block energy lies far beyond the range the
/// reduced set's frozen calibration learned, isolates no healthy sensor
/// before the crash (before the gross test left such blocks out: IMU2 a_z,
/// sensor 8, isolated at 145.0 s), and the crash is still alarmed.
#[test]
fn a_spike_beyond_the_learned_vibration_isolates_no_healthy_sensor() {
    let log = log();
    let mut up = ImuLog {
        count: log.count,
        ..ImuLog::default()
    };
    for (i, (t, row)) in log.t.iter().zip(log.imus.iter()).enumerate() {
        up.t.push(*t);
        up.imus.push(row.clone());
        if let (Some(t1), Some(next)) = (log.t.get(i + 1), log.imus.get(i + 1)) {
            if t1 - t < 0.05 {
                up.t.push((t + t1) / 2.0);
                up.imus.push(
                    row.iter()
                        .zip(next.iter())
                        .map(|(a, b)| std::array::from_fn(|c| (a[c] + b[c]) / 2.0))
                        .collect(),
                );
            }
        }
    }
    let inj = Injection {
        imu: 0,
        channel: 0,
        size: 0.5,
        start: 135.0,
        end: f64::INFINITY,
    };
    let r = replay_parity(&up, ArrayKind::Accel, 100.0, 30.0, Some(inj)).unwrap();
    // The step: isolated (measured 137.67 s).
    assert!(
        r.isolations
            .iter()
            .any(|(k, t)| *k == 0 && (135.0..145.0).contains(t)),
        "{:?}",
        r.isolations
    );
    assert!(
        r.isolations.iter().all(|(k, t)| *k == 0 || *t >= CRASH),
        "{:?}",
        r.isolations
    );
    assert!(r.alarms.iter().any(|a| a.0 >= CRASH), "{:?}", r.alarms);
}

/// The per-decision false-alarm probability is the monitor's one
/// sensitivity knob (`parity-table --false-alarm`): 1e-8, where the
/// realistic profile's fault-free hours are clean
/// (`scripts/parity-min-detectable.py`), costs log171 accelerometer cases.
#[test]
fn a_tighter_false_alarm_probability_isolates_fewer_steps() {
    let log = log();
    let table = |method| {
        let cases = step_table(
            &log,
            ArrayKind::Accel,
            0.5,
            &[80.0],
            30.0,
            &ONSETS,
            15.0,
            CRASH,
            method,
        )
        .unwrap();
        let ok = cases
            .iter()
            .filter(|c| c.isolated && !c.false_alarm)
            .count();
        let fa = cases.iter().filter(|c| c.false_alarm).count();
        (ok, fa, cases.len())
    };
    // Measured: 106/108 and 86/108, no false-alarm case either way.
    let (ok, fa, n) = table(ParityMethod::Flight);
    assert_eq!(n, 108);
    assert!(ok >= 104 && fa == 0, "{ok} {fa}");
    let (tight, tight_fa, _) = table(ParityMethod::FlightAt(1e-8));
    assert!(
        (80..=92).contains(&tight) && tight_fa == 0,
        "{tight} {tight_fa}"
    );
}

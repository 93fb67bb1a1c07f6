//! Real data, GIVEN ArduPilot log171 (the extracts in tests/data, CC BY-SA
//! 3.0, see tests/data/LICENSE-ap_log171.md) replayed 80–235 s as
//! `scripts/single-imu-log171.sh` does, WHEN one large short glitch (an E1
//! step) is injected on one IMU channel, THEN the single-IMU monitor flags
//! it, is back to nominal within 5 s of the glitch's end (issue 15: the
//! simulated campaign's settle time) and raises no other flag on that IMU
//! (no cascade). `scripts/single-imu-glitches.sh` runs the whole matrix
//! (docs/recovery.md). Before the re-alignment on an ended fault, IMU0 gz
//! +20 °/s for 3 s at 200 s stayed flagged to 211.5 s (UKF) and 210.8 s
//! (OTSUKF); IMU0 gx +20 °/s for 5 s at 120 s to 135.3 s (OTSUKF). Before
//! the end-of-fault rule held a flag to the estimate it was raised with,
//! IMU0 a_x +5 m/s² for 1 s at 160 s stayed flagged (UKF) to 168.1 s and
//! again 169.1–171.1 s.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code

mod common;
use common::{bin, data, step_faults, tmp};

const CHANNELS: [&str; 6] = ["ax", "ay", "az", "gx", "gy", "gz"];

/// The flag events `(channel, on, off)` of IMU0 with monitor `mon`, and
/// with `glitch` `(channel, size, start, end)` a positive step on that
/// channel (0–2 accelerometer, m/s²; 3–5 gyro, °/s) of IMU0 over
/// `start`–`end` s.
fn events(mon: &str, glitch: Option<(usize, f64, f64, f64)>) -> Vec<(String, f64, f64)> {
    signed_events(mon, glitch)
        .into_iter()
        .map(|(c, on, off, _)| (c, on, off))
        .collect()
}

/// [`events`] with each event's flag sign (+1/−1, of its first row) and
/// its largest fault estimate in magnitude (`fhat_*`, signed).
fn signed_events(
    mon: &str,
    glitch: Option<(usize, f64, f64, f64)>,
) -> Vec<(String, f64, f64, (i32, f64))> {
    let tag = format!("{mon}-{glitch:?}");
    let csv = tmp(&format!("{}.csv", tag.replace([' ', '(', ')', ','], "_")));
    let mut cmd = bin();
    cmd.arg("replay")
        .arg(data("ap_log171_3imu.csv"))
        .arg("--gnss")
        .arg(data("ap_log171_gps_vel_ned.csv"))
        .arg("--att")
        .arg(data("ap_log171_attitude_quat.csv"))
        .args(["--from", "80", "--to", "235", "--monitor", mon, "--out"])
        .arg(&csv);
    if let Some((channel, size, start, end)) = glitch {
        let (acc, gyro) = if channel < 3 {
            (size, 0.0)
        } else {
            (0.0, size)
        };
        let name = csv.with_extension("toml");
        let name = name.file_name().unwrap().to_str().unwrap();
        let toml = step_faults(name, channel, start, end, acc, gyro);
        cmd.arg("--faults").arg(&toml).args(["--inject-imu", "0"]);
    }
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let cols: Vec<usize> = CHANNELS.iter().map(|c| col(&format!("flag_{c}"))).collect();
    let fhat: Vec<usize> = CHANNELS.iter().map(|c| col(&format!("fhat_{c}"))).collect();
    let t_col = col("t");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let mut events = Vec::new();
    for ((c, j), k) in CHANNELS.iter().zip(cols).zip(fhat) {
        let mut on = None;
        let mut last = 0.0;
        let (mut sign, mut size) = (0, 0.0_f64);
        for r in &rows {
            let t: f64 = r[t_col].parse().unwrap();
            last = t;
            let flagged = !matches!(r[j], "" | "0");
            if flagged {
                let f: f64 = r[k].parse().unwrap_or(0.0);
                if f.abs() > size.abs() {
                    size = f;
                }
            }
            match (flagged, on) {
                (true, None) => {
                    on = Some(t);
                    sign = r[j].parse().unwrap_or(0);
                }
                (false, Some(t0)) => {
                    events.push((c.to_string(), t0, t, (sign, size)));
                    on = None;
                    size = 0.0;
                }
                _ => {}
            }
        }
        if let Some(t0) = on {
            events.push((c.to_string(), t0, last, (sign, size)));
        }
    }
    events
}

/// One event on the glitched gyro channel (20 °/s), raised during the
/// glitch and over within `back_max` s of its end; nothing else on the IMU
/// that the fault-free replay does not show.
fn assert_recovers(mon: &str, axis: usize, start: f64, dur: f64, back_max: f64) {
    assert_glitch_recovers(mon, (3 + axis, 20.0), start, dur, 0.0, back_max);
}

/// One event on the glitched channel (`glitch`: channel 0–5 and size, m/s²
/// or °/s), raised before `late` s after the glitch's end and over within
/// `back_max` s of it; nothing else on the IMU that the fault-free replay
/// does not show.
fn assert_glitch_recovers(
    mon: &str,
    glitch: (usize, f64),
    start: f64,
    dur: f64,
    late: f64,
    back_max: f64,
) {
    let end = start + dur;
    // The fault-free replay's events (the OTSUKF's a_y at 145.5–148.3 s)
    // are not the glitch's.
    let free = events(mon, None);
    let mut ev = events(mon, Some((glitch.0, glitch.1, start, end)));
    ev.retain(|e| e.2 > start && !free.iter().any(|f| f.0 == e.0 && f.1 < e.2 && e.1 < f.2));
    let ch = CHANNELS[glitch.0];
    assert_eq!(ev.len(), 1, "{mon} {ch}: {ev:?}");
    let (c, on, off) = &ev[0];
    assert_eq!(c, ch, "{mon}: {ev:?}");
    assert!(*on < end + late, "{mon} {ch}: raised at {on}");
    let back = off - end;
    assert!(
        back <= back_max,
        "{mon} {ch}: back {back:.1} s after the glitch ({ev:?})"
    );
}

/// The case, IMU0 gz +20 °/s for 3 s at 200 s: measured back 2.7 s
/// (UKF, 201.1–205.7 s) and 2.6 s (OTSUKF, 201.1–205.6 s) after the end,
/// against 8.5 s and 7.8 s before.
#[test]
fn gz_20_deg_s_3_s_back_within_5_s_both_monitors() {
    assert_recovers("ukf", 2, 200.0, 3.0, 3.5);
    assert_recovers("otsukf", 2, 200.0, 3.0, 3.5);
}

/// IMU0 gx +20 °/s for 5 s at 120 s, the OTSUKF's slowest case the lead
/// measured (flagged to 135.3 s before): back 2.4 s after the end.
#[test]
fn otsukf_gx_20_deg_s_5_s_back_within_5_s() {
    assert_recovers("otsukf", 0, 120.0, 5.0, 3.5);
}

/// IMU0 a_x +5 m/s² for 1 s at 160 s (UKF): the velocity test's 2-s window
/// raises the flag 1.1 s after the glitch at 2.17 m/s²; its 5-s and 10-s
/// windows then carry it at their falling means (0.84, 0.41 m/s²), which
/// the 2-s window cannot contradict. Held to the size it was raised with,
/// the flag ends 4.4 s after the glitch (was two events to 10.1 s).
#[test]
fn ukf_ax_5_m_s2_1_s_back_within_5_s() {
    assert_glitch_recovers("ukf", (0, 5.0), 160.0, 1.0, 1.5, 5.0);
}

/// IMU0 g_y +50 °/s for 5 s at 200 s (UKF): the pitch error the glitch
/// integrated leaks gravity into the filter's velocity, and the UKF's own
/// test flagged a_z at 2.1 m/s² from 205.7 s to 208.7 s while the
/// accelerometer/GNSS-velocity test saw ≤ 0.2 of its threshold. From the
/// gyro flag on, the accelerometers are judged by that test alone until
/// the velocity and attitude are re-aligned (`velocity_tainted`): g_y
/// alone, 204.4–206.4 s.
#[test]
fn ukf_gy_50_deg_s_5_s_does_not_cascade_onto_a_z() {
    assert_glitch_recovers("ukf", (4, 50.0), 200.0, 5.0, 0.0, 2.5);
}

/// IMU0 g_z +50 °/s for 1 s at 120 s, in a 23° roll: the yaw error the
/// glitch integrates couples into the filters' pitch, and their own tests
/// flagged g_y too (UKF 121.0–121.6 s, OTSUKF 120.9–124.1 s, estimates
/// −4 °/s) while the gyro/attitude test saw 0.16–0.23 of its threshold on
/// g_y and 4.8 on g_z. A flag the block test contradicts while it sees a
/// fault on another gyro is withheld (`withhold_coupled_flags`): only g_z
/// is flagged (the UKF's flag split by the manoeuvre at 122 s, which it
/// does not judge), and over within 3.5 s of the glitch's end.
#[test]
fn gz_50_deg_s_1_s_does_not_cascade_onto_g_y_both_monitors() {
    for mon in ["ukf", "otsukf"] {
        let free = events(mon, None);
        let mut ev = events(mon, Some((5, 50.0, 120.0, 121.0)));
        ev.retain(|e| e.2 > 120.0 && !free.iter().any(|f| f.0 == e.0 && f.1 < e.2 && e.1 < f.2));
        assert!(!ev.is_empty(), "{mon}: not flagged");
        assert!(ev.iter().all(|e| e.0 == "gz"), "{mon}: {ev:?}");
        assert!(ev.iter().all(|e| e.2 <= 124.5), "{mon}: {ev:?}");
    }
}

/// IMU0 a_x +5 m/s² for 3 s at 160 s (UKF, issue 15): the velocity test
/// makes no decision before the aiding's jump rule re-aligns the velocity
/// at 161.1 s, and the statistics are then held; the glitch went
/// unattributed (every channel `NotMonitored` to 165.9 s) while the
/// re-aligned velocity diverged again. The regression of the velocity
/// innovations on the accelerometer signature since the re-alignment
/// (`regrowth.rs`) flags a_x, positive, during the glitch (measured
/// 162.5–165.1 s, raised at 3.6 m/s², largest estimate 4.1), and nothing
/// else.
#[test]
fn ukf_ax_5_m_s2_3_s_re_aligned_by_the_jump_rule_is_attributed() {
    let free = events("ukf", None);
    let mut ev = signed_events("ukf", Some((0, 5.0, 160.0, 163.0)));
    ev.retain(|e| e.2 > 160.0 && !free.iter().any(|f| f.0 == e.0 && f.1 < e.2 && e.1 < f.2));
    assert_eq!(ev.len(), 1, "{ev:?}");
    let (c, on, off, (sign, size)) = &ev[0];
    assert_eq!(c, "ax", "{ev:?}");
    assert_eq!(*sign, 1, "{ev:?}");
    assert!(*on < 163.0, "raised at {on}");
    assert!(
        *off - 163.0 <= 5.0,
        "back {:.1} s after the glitch",
        off - 163.0
    );
    assert!((2.5..=7.5).contains(size), "estimate {size}");
}

//! Real data damaged as a board damages it, GIVEN ArduPilot log171's
//! extracts (tests/data, CC BY-SA 3.0, tests/data/LICENSE-ap_log171.md)
//! with the IMU rows of a spell in flight cut (a dropout: the next row
//! carries the time) or held at the spell's first row (a frozen output),
//! WHEN `imu-fdi-sim replay` runs each IMU through its single-IMU monitor,
//! THEN the monitor holds its statistics and re-aligns after the gap
//! (`ukf_monitor/imu_gap.rs`, `otsukf_monitor/imu_gap.rs`) and flags no
//! channel the undamaged flight does not: before, a 2-s cut at 150 s
//! flagged a_x, g_y and g_z of every IMU for 3–6 s (UKF monitor; 9 extra
//! events, OTSUKF 7), a 2-s freeze a_z and g_y.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code

mod common;
use common::{bin, data, tmp};

/// The IMU extract with `damage` applied to the rows in `[start, end)`.
fn damaged(tag: &str, start: f64, end: f64, cut: bool) -> std::path::PathBuf {
    let text = std::fs::read_to_string(data("ap_log171_3imu.csv")).unwrap();
    let mut out = String::new();
    let mut held: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap_or(-1.0);
        if i > 0 && (start..end).contains(&t) {
            if cut {
                continue;
            }
            let cells = held.get_or_insert_with(|| line.split_once(',').unwrap().1.to_string());
            out.push_str(&format!("{},{cells}\n", line.split(',').next().unwrap()));
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    let path = tmp(&format!("{tag}.csv"));
    std::fs::write(&path, out).unwrap();
    path
}

/// Flag events per channel of every IMU, replaying `imu` 80–235 s.
fn events(imu: &std::path::Path, monitor: &str) -> Vec<u64> {
    let out = bin()
        .arg("replay")
        .arg(imu)
        .arg("--gnss")
        .arg(data("ap_log171_gps_vel_ned.csv"))
        .arg("--att")
        .arg(data("ap_log171_attitude_quat.csv"))
        .args([
            "--from",
            "80",
            "--to",
            "235",
            "--json",
            "--monitor",
            monitor,
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    s["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["flag_events"].as_u64().unwrap())
        .collect()
}

#[test]
fn an_imu_dropout_or_freeze_in_flight_flags_nothing_new() {
    // Spells not tuned on: 2 s cut at 120 s, 5 s cut at 180 s, 2 s frozen
    // at 150 s (the sweep in docs/recovery.md covers 24 more).
    let spells = [
        damaged("cut120", 120.0, 122.0, true),
        damaged("cut180", 180.0, 185.0, true),
        damaged("frozen150", 150.0, 152.0, false),
    ];
    for monitor in ["ukf", "otsukf"] {
        let clean = events(&data("ap_log171_3imu.csv"), monitor);
        for path in &spells {
            let got = events(path, monitor);
            let extra: Vec<_> = got
                .iter()
                .zip(clean.iter())
                .enumerate()
                .filter(|(_, (g, c))| g > c)
                .collect();
            assert!(extra.is_empty(), "{monitor} {path:?}: {extra:?}");
        }
    }
}

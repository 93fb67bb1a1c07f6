//! The CLI on real flight logs, driven as a user would: PX4 ULog and
//! ArduPilot DataFlash conversion and replay, fault tables and instances
//! named in errors (split from `cli.rs`).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code

mod common;

use common::{bin, channel, json, tmp};

#[test]
fn px4_ulog_converts_and_replays_from_the_cli() {
    let ulg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/px4_fmuv3_outdoor_flight.ulg"
    );
    let out = tmp("fmuv3.csv");
    let o = bin()
        .args(["convert", ulg, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("341 rows of 1 IMU(s)") && s.contains("175 rows with GNSS velocity"),
        "{s}"
    );
    let header = std::fs::read_to_string(&out).unwrap();
    assert!(header.starts_with("t,imu0_ax,imu0_ay,imu0_az,imu0_gx,imu0_gy,imu0_gz,gnss_vn"));
    let o = bin().args(["replay", ulg]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("replayed 341 rows") && s.contains("aiding GnssAttitude"),
        "{s}"
    );
    // Not a ULog: named, no panic.
    let o = bin()
        .args(["convert", "flight.txt", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("flight.txt: unknown file type"));
    let fake = tmp("fake.ulg");
    std::fs::write(&fake, b"ULog? no").unwrap();
    let o = bin()
        .arg("convert")
        .arg(&fake)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("fake.ulg"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn dataflash_log_replays_every_imu_and_attributes_common_mode_flags() {
    let bin_log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_head.bin"
    );
    // Learning before the GPS fix (45 s) cannot learn the accelerometer
    // offsets: when GPS velocity arrives, a_z is flagged on all three IMUs at
    // once, which the replay attributes to the aiding/model, not to an IMU.
    let summary = tmp("ap-head.json");
    let o = bin()
        .args(["replay", bin_log, "--learn", "10", "--summary"])
        .arg(&summary)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("3526 rows of 3 IMU(s)") && out.contains("191 with GNSS velocity"),
        "{out}"
    );
    let s = json(&summary);
    assert_eq!(s["imus"], 3);
    assert_eq!(s["profile"], "Flight");
    for name in ["az", "imu1_az", "imu2_az"] {
        let c = channel(&s, name);
        let flagged = c["flagged_samples"].as_u64().unwrap();
        assert!(flagged > 1000, "{c}");
        // All of them common mode but for instants where one IMU's test
        // did not judge (motion beyond what its inflation was learnt at)
        // or judged again later than the others after the log's 2-s IMU
        // gap at arming (72.6 s: every monitor holds its statistics and
        // re-aligns, `imu_gap.rs`; measured 60 samples, IMU0 back at 79.5 s
        // unflagged for 1.2 s): at most 2 s of samples at 49 Hz.
        let common = c["common_mode_samples"].as_u64().unwrap();
        assert!(common <= flagged && flagged - common <= 98, "{c}");
    }
    // Learning with GPS, then faults injected on IMU 1: found on IMU 1 only.
    let faults = tmp("ap-head-faults.toml");
    std::fs::write(
        &faults,
        "[sizes]\naccel = [1.0, 0.0, 0.0]\ngyro = [0.17453292519943295, 0.0, 0.0]\n\
         f_unit = [1.0, 0.017453292519943295]\n\
         [[faults]]\nchannel = 5\nstart = 15.0\nend = 20.0\nkind = \"E1\"\nsign = 1.0\n\
         [[faults]]\nchannel = 1\nstart = 28.0\nend = 34.0\nkind = \"E1\"\nsign = -1.0\n",
    )
    .unwrap();
    // The learned inflation followed in flight does not judge the first
    // seconds after take-off (72.6 s; more active than anything learnt on
    // the ground: `inflation_cover.rs`), where the a_y step lies: it finds
    // the g_z step on the ground and nothing else.
    let replay_head = |memory: &str| {
        let o = bin()
            .args(["replay", bin_log, "--from", "48", "--learn", "10"])
            .arg("--faults")
            .arg(&faults)
            .args(["--fault-offset", "50", "--inject-imu", "1"])
            .args(["--inflation-memory", memory, "--summary"])
            .arg(&summary)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        json(&summary)
    };
    let s = replay_head("120");
    let gz = channel(&s, "imu1_gz");
    let t = gz["first_correct_s"].as_f64().unwrap();
    assert!((65.0..68.5).contains(&t), "{gz}");
    for c in s["channels"].as_array().unwrap() {
        if c["channel"] != "imu1_gz" {
            assert_eq!(c["flagged_samples"], 0, "{c}");
        }
    }
    // Frozen at the end of learning, it judges them.
    let s = replay_head("0");
    let gz = channel(&s, "imu1_gz");
    let t = gz["first_correct_s"].as_f64().unwrap();
    assert!(
        (65.0..68.5).contains(&t),
        "10 °/s step at 65 s found at {t}: {gz}"
    );
    let ay = channel(&s, "imu1_ay");
    let t = ay["first_correct_s"].as_f64().unwrap();
    assert!(
        (78.0..80.5).contains(&t),
        "−1 m/s² step at 78 s found at {t}: {ay}"
    );
    // 193 of 298 with the learned innovation inflation (233 with
    // `--max-inflation 1`): detected 0.8 s later.
    assert!(ay["correct_samples"].as_u64().unwrap() > 180, "{ay}");
    for c in s["channels"].as_array().unwrap() {
        let name = c["channel"].as_str().unwrap();
        if !name.starts_with("imu") || name.starts_with("imu2_g") {
            assert_eq!(c["flagged_samples"], 0, "clean IMU flagged: {c}");
        }
    }
}

#[test]
fn replay_rejects_bad_fault_tables_and_instances_by_name() {
    let ulg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/px4_fmuv3_outdoor_flight.ulg"
    );
    let bad = tmp("bad-faults.toml");
    std::fs::write(
        &bad,
        "[[faults]]\nchannel = 9\nstart = 1.0\nend = 2.0\nkind = \"Stuck\"\nsign = 1.0\n",
    )
    .unwrap();
    let o = bin()
        .args(["replay", ulg, "--faults"])
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("bad-faults.toml") && e.contains("channel must be 0–5"),
        "{e}"
    );
    let steps = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/faults/steps.toml"
    );
    let o = bin()
        .args(["replay", ulg, "--faults", steps, "--inject-imu", "2"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("cannot inject on IMU 2: the file has 1 IMU(s)"),
        "{e}"
    );
}

#[test]
fn csv_extract_without_aiding_is_converted_then_refused_by_name() {
    let mut x = String::from(
        "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),\
         Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)\n",
    );
    for k in 0..50 {
        x += &format!("{},0.1,0.2,0.3,0,0,1\n", 0.01 * k as f64);
    }
    let xio = tmp("handheld.csv");
    std::fs::write(&xio, x).unwrap();
    let o = bin().arg("replay").arg(&xio).output().unwrap();
    assert!(!o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        out.contains("converted") && out.contains("50 rows of 1 IMU(s)"),
        "{out}"
    );
    assert!(
        err.contains("handheld.csv") && err.contains("no aiding"),
        "{err}"
    );
    // A .ulg does not take the extract's aiding files.
    let ulg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/px4_fmuv3_outdoor_flight.ulg"
    );
    let o = bin()
        .args(["convert", ulg, "--gnss", "g.csv", "--out"])
        .arg(tmp("x.csv"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--gnss and --att go with a CSV extract"));
}

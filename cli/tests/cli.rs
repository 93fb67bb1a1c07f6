//! The CLI driven as a user would: spawned process, files in a temp dir.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code

mod common;

use common::{bin, bin_cmd_output, tmp};

#[test]
fn simulate_then_replay_round_trip_detects_s2_faults() {
    let input = tmp("s2.csv");
    let out = tmp("s2-out.csv");
    let summary = tmp("s2-summary.json");
    let o = bin()
        .args(["simulate", "s2", "--seed", "3", "--out"])
        .arg(&input)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = bin()
        .arg("replay")
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .arg("--summary")
        .arg(&summary)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("replayed 6500 rows"), "{stdout}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    assert_eq!(s["aiding"], "DvlCompass");
    for ch in s["channels"].as_array().unwrap() {
        let faults = ch["fault_samples"].as_u64().unwrap();
        let correct = ch["correct_samples"].as_u64().unwrap();
        assert!(faults > 0 && correct as f64 > 0.6 * faults as f64, "{ch}");
        assert_eq!(ch["false_alarm_samples"], 0, "{ch}");
    }
    let text = std::fs::read_to_string(&out).unwrap();
    let header = text.lines().next().unwrap();
    assert!(header.starts_with("t,x_u,x_v,x_w,x_roll,x_pitch,x_yaw,phase,flag_ax"));
    assert_eq!(text.lines().count(), 6501);
}

#[test]
fn replay_reports_missing_columns_with_the_file_name() {
    let input = tmp("bad-columns.csv");
    std::fs::write(&input, "t,imu0_ax,imu0_ay\n0.0,1,2\n").unwrap();
    let o = bin().arg("replay").arg(&input).output().unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad-columns.csv") && err.contains("imu0_az"),
        "{err}"
    );
}

#[test]
fn replay_skips_non_monotonic_and_rejects_nan_rows() {
    let input = tmp("jumbled.csv");
    let mut s = String::from("t,imu0_ax,imu0_ay,imu0_az,imu0_gx,imu0_gy,imu0_gz,dvl_u,dvl_v,dvl_w,att_roll,att_pitch,att_yaw\n");
    for k in 0..50 {
        s.push_str(&format!(
            "{},0,0,-9.80665,0,0,0,0,0,0,0,0,0\n",
            k as f64 * 0.01
        ));
    }
    s.push_str("0.2,0,0,-9.8,0,0,0,,,,,,\n"); // time goes backwards
    s.push_str("0.6,NaN,0,-9.8,0,0,0,,,,,,\n"); // NaN sample
    std::fs::write(&input, s).unwrap();
    let o = bin().arg("replay").arg(&input).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("replayed 52 rows (1 skipped, 1 IMU rows rejected)"),
        "{out}"
    );
}

#[test]
fn unknown_scenario_is_a_clear_error() {
    let o = bin().args(["scenario", "s9"]).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown scenario 's9'"));
}

#[test]
fn closed_stdout_ends_quietly_instead_of_panicking() {
    use std::process::Stdio;
    let mut child = bin()
        .args(["scenario", "s1", "--seeds", "3"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // like `| head -0`
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.status.success());
}

#[test]
fn otsukf_prints_the_rmse_table_beside_the_paper() {
    let o = bin()
        .args(["otsukf", "s3-paper", "--seeds", "1", "--augmented"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("two-stage") && text.contains("augmented") && text.contains("paper"));
    // The paper's f_ax RMSE is printed beside ours, and there are no false flags.
    let fax = text.lines().find(|l| l.starts_with("f_ax")).unwrap();
    let cols: Vec<f64> = fax
        .split_whitespace()
        .skip(1)
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(cols.len(), 3);
    assert_eq!(cols[2], 0.1087);
    assert!(cols[0] > 0.0 && cols[0] < 0.2, "{fax}");
    assert!(text.contains("in the last 2 s): 0"));
    let bad = bin()
        .args(["otsukf", "s3", "--seeds", "0"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--seeds must be at least 1"));
    for (args, why) in [
        (&["--shape", "F9"][..], "expected F1, F2 or F3"),
        (&["--adapt-gain", "0.5"][..], "at least 1"),
        (&["--adapt-gain", "2,2"][..], "one value or six"),
        (&["--qf-scale", "1,-1"][..], "two positive numbers"),
    ] {
        let bad = bin()
            .args(["otsukf", "s3", "--seeds", "1"])
            .args(args)
            .output()
            .unwrap();
        assert!(!bad.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&bad.stderr);
        assert!(err.contains(why), "{args:?}: {err}");
    }
    // Without faults the RMSE rows are empty and the noise rows are not:
    // the adapted paper-setting estimate stays near its fixed-Q^f noise
    // (0.019 over seeds 100–119).
    let text = bin_cmd_output(&["otsukf", "s3-paper", "--seeds", "1", "--fault-free"]);
    let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("f_p")).collect();
    assert_eq!(rows.len(), 2, "{text}");
    assert!(rows[0].contains("NaN"), "{text}");
    let noise: f64 = rows[1].split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(noise > 0.01 && noise < 0.025, "{text}");
}

#[test]
fn parity_s4_prints_per_seed_detections_and_isolations() {
    let o = bin().args(["parity", "--seeds", "3"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("isolated to sensor 5 in 3/3 runs; false-alarm events before onset: 0"),
        "{s}"
    );
    let o = bin().args(["parity", "--seeds", "0"]).output().unwrap();
    assert!(!o.status.success());
}

#[test]
fn parity_sweep_prints_one_row_per_method_and_writes_json() {
    let json = tmp("sweep.json");
    let o = bin()
        .args([
            "parity-sweep",
            "--array",
            "cone6",
            "--kind",
            "accel",
            "--runs",
            "3",
            "--json",
        ])
        .arg(&json)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    for m in [
        "paper PCA",
        "chi2/GLT",
        "CUSUM",
        "PX4-like",
        "ArduPilot-like",
    ] {
        assert!(s.contains(m), "{m}: {s}");
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["methods"].as_array().unwrap().len(), 5);
}

#[test]
fn parity_replay_reads_the_real_log_and_rejects_bad_files() {
    let log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    );
    let o = bin().args(["parity-replay", log]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("9521 rows, 3 IMUs"), "{s}");
    // The DataFlash excerpt directly.
    let df = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_head.bin"
    );
    let o = bin_cmd_output(&[
        "parity-replay",
        df,
        "--train-start",
        "62",
        "--train-s",
        "20",
    ]);
    assert!(o.contains("3526 rows, 3 IMUs, t = 11.46..84.84 s"), "{o}");
    // The crash (≈ 239 s) is the first alarm, nothing in normal flight:
    // the gyros' first alarm starts within DroneKit-LA's interval
    // (239.825–241.335 s; measured 240.19 s at the log's gap-free rate,
    // 239.71 s with rows over span).
    let first: f64 = s
        .split("parity alarms: ")
        .nth(1)
        .and_then(|r| r.split('-').next())
        .and_then(|x| x.trim().parse().ok())
        .unwrap_or(f64::NAN);
    assert!((239.825..=241.335).contains(&first), "{first}: {s}");
    // --json: one object, the issue-14 schema, times in the file's seconds.
    let log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    );
    let o = bin()
        .args(["parity-replay", log, "--json"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for kind in ["gyro", "accel"] {
        let k = &v[kind];
        let from = k["monitoring_from_s"].as_f64().unwrap();
        assert!((109.0..111.0).contains(&from), "{from}");
        for a in k["alarms"].as_array().unwrap() {
            assert!(a["start_s"].as_f64().unwrap() >= 239.0, "{a}");
            assert!(a["end_s"].as_f64().unwrap() >= a["start_s"].as_f64().unwrap());
            assert!(a["sensor"].as_u64().unwrap() < 9);
        }
        for i in k["isolations"].as_array().unwrap() {
            assert!(i["sensor"].as_u64().unwrap() < 9 && i["t_s"].as_f64().unwrap() >= 239.0);
        }
    }
    // An injected 2 °/s step on IMU 1's z gyro at 150 s is isolated to sensor 5.
    let o = bin()
        .args(["parity-replay", log, "--json", "--inject", "1,5,2,150"])
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let first = &v["gyro"]["isolations"][0];
    assert_eq!(first["sensor"].as_u64(), Some(5), "{v}");
    let t = first["t_s"].as_f64().unwrap();
    assert!((150.0..160.0).contains(&t), "{t}");

    // One IMU only: a clear error naming the file.
    let one = tmp("one-imu.csv");
    std::fs::write(
        &one,
        "t,imu0_ax,imu0_ay,imu0_az,imu0_gx,imu0_gy,imu0_gz\n0,0,0,-9.8,0,0,0\n",
    )
    .unwrap();
    let o = bin().arg("parity-replay").arg(&one).output().unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("one-imu.csv") && e.contains("at least two IMUs"),
        "{e}"
    );

    // A bad number: file and line.
    let bad = tmp("bad-cell.csv");
    let mut text = String::from("t,imu0_ax,imu0_ay,imu0_az,imu0_gx,imu0_gy,imu0_gz,imu1_ax,imu1_ay,imu1_az,imu1_gx,imu1_gy,imu1_gz\n");
    text.push_str("0,0,0,-9.8,0,0,0,0,0,-9.8,0,0,0\n");
    text.push_str("0.01,0,zero,-9.8,0,0,0,0,0,-9.8,0,0,0\n");
    std::fs::write(&bad, text).unwrap();
    let o = bin().arg("parity-replay").arg(&bad).output().unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("bad-cell.csv: line 3") && e.contains("'zero' is not a number"),
        "{e}"
    );
}

#[test]
fn campaign_shards_merge_to_the_same_table_and_bad_input_is_named() {
    let (full, a, b) = (tmp("full.csv"), tmp("shard1.csv"), tmp("shard2.csv"));
    let (fj, mj) = (tmp("full.json"), tmp("merged.json"));
    let run = |args: &[&str], extra: &[&std::path::Path]| {
        let mut c = bin();
        c.args(args);
        for p in extra {
            c.arg(p);
        }
        let o = c.output().unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).to_string()
    };
    let s = run(
        &["campaign", "s2", "--runs", "12", "--seed", "5", "--json"],
        &[&fj],
    );
    assert!(s.contains("12 runs (indices 0..=11)"), "{s}");
    assert!(s.contains("detection rate (runs)"), "{s}");
    run(
        &["campaign", "s2", "--runs", "12", "--seed", "5", "--csv"],
        &[&full],
    );
    run(
        &[
            "campaign", "s2", "--runs", "12", "--seed", "5", "--shard", "1/2", "--csv",
        ],
        &[&a],
    );
    run(
        &[
            "campaign", "s2", "--runs", "12", "--seed", "5", "--shard", "2/2", "--csv",
        ],
        &[&b],
    );
    let m = run(&["merge", "--json"], &[&mj, &a, &b]);
    assert!(m.contains("merged 2 files: 12 runs"), "{m}");
    // The merged shards summarise exactly as the full campaign.
    let summary = |p: &std::path::PathBuf| -> serde_json::Value {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
        v["summary"].clone()
    };
    assert_eq!(summary(&fj), summary(&mj));
    assert_eq!(summary(&fj)["runs"], 12);

    // Bad shard, duplicate shard, broken row: clear messages, no panic.
    let o = bin()
        .args(["campaign", "s2", "--runs", "4", "--shard", "3/2"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("need 1 <= i <= n"));
    let o = bin().arg("merge").arg(&a).arg(&a).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("appears in more than one shard"));
    let broken = tmp("broken.csv");
    let text = std::fs::read_to_string(&a)
        .unwrap()
        .replacen(",1,", ",x,", 1);
    std::fs::write(&broken, text).unwrap();
    let o = bin().arg("merge").arg(&broken).output().unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("broken.csv: line"), "{e}");
}

#[test]
fn plot_writes_png_and_svg_for_a_ukf_scenario_and_for_s4() {
    let dir = tmp("plots");
    let o = bin()
        .args(["plot", "s2", "--seed", "2", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("wrote 8 files"), "{s}");
    for tag in ["faults_flags", "estimates", "innovations", "statistic"] {
        for ext in ["png", "svg"] {
            let f = dir.join(format!("s2_seed2_{tag}.{ext}"));
            let bytes = std::fs::read(&f).unwrap();
            assert!(bytes.len() > 10_000, "{}", f.display());
            if ext == "png" {
                assert_eq!(&bytes[1..4], b"PNG");
            } else {
                assert!(String::from_utf8_lossy(&bytes).contains("<svg"));
            }
        }
    }
    let o = bin()
        .args(["plot", "s4", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("s4_seed1_parity.png").exists());
    let o = bin()
        .args(["plot", "nope", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown scenario 'nope'"));
}

#[test]
fn parity_realistic_rejects_flights_of_no_hours() {
    let o = bin()
        .args(["parity-realistic", "--hours", "1", "--rounds", "0"])
        .args(["--flight-hours", "0"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("--flight-hours") && e.lines().count() == 1,
        "{e}"
    );
}

#[test]
fn parity_realistic_rejects_a_false_alarm_or_size_out_of_range() {
    for (opt, bad) in [
        ("--false-alarm", "0"),
        ("--false-alarm", "0.7"),
        ("--false-alarm", "NaN"),
        ("--sizes", "1,-2"),
        ("--sizes", "inf"),
    ] {
        let o = bin()
            .args(["parity-realistic", "--hours", "0", "--rounds", "1"])
            .args([opt, bad])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{opt} {bad}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(opt) && e.lines().count() == 1, "{e}");
    }
}

#[test]
fn parity_realistic_rejects_a_step_onset_inside_training() {
    for bad in ["10", "NaN", "1e9"] {
        let o = bin()
            .args(["parity-realistic", "--hours", "0", "--rounds", "1"])
            .args(["--step-onset", bad])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{bad}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("--step-onset") && e.lines().count() == 1, "{e}");
    }
}

#[test]
fn parity_table_and_replay_reject_a_false_alarm_out_of_range() {
    let log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_3imu.csv"
    );
    for args in [
        vec!["parity-table", log, "--size", "1", "--false-alarm", "0.5"],
        vec!["parity-replay", log, "--false-alarm=-1"],
        vec![
            "parity-replay",
            log,
            "--method",
            "glt-cusum",
            "--false-alarm",
            "1e-8",
        ],
    ] {
        let o = bin().args(&args).output().unwrap();
        assert!(!o.status.success(), "{args:?}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("--false-alarm") && e.lines().count() == 1, "{e}");
    }
}

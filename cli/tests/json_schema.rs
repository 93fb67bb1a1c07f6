//! `--json` on every subcommand follows one convention (docs/cli-json.md):
//! one JSON object on stdout, snake_case keys, and every non-integer
//! number under a key (or, for `{value, low, high}` intervals and arrays,
//! its parent's key) that names its unit or says it is dimensionless.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// Unit suffixes (SI with `_` for `/` and powers as digits) and the
/// dimensionless ones.
const SUFFIXES: [&str; 17] = [
    "_s",
    "_hz",
    "_h",
    "_per_hour",
    "_m_s",
    "_m_s2",
    "_m_s3",
    "_m2_s3",
    "_rad",
    "_rad_s",
    "_rad_s2",
    "_deg",
    "_deg_s",
    "_bytes",
    "_fraction",
    "_factor",
    "_ratio",
];

fn data(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(name)
        .display()
        .to_string()
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-fdi-json-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Runs the binary; its stdout must be exactly one JSON object.
fn json(args: &[&str]) -> Value {
    let o = Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = String::from_utf8(o.stdout).unwrap();
    assert_eq!(out.lines().count(), 1, "{args:?}: not one line:\n{out}");
    let v: Value =
        serde_json::from_str(&out).unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}):\n{out}"));
    assert!(v.is_object(), "{args:?}: not an object");
    let mut problems = Vec::new();
    check(&v, "", "", &mut problems);
    assert!(problems.is_empty(), "{args:?}: {problems:#?}");
    v
}

fn snake(k: &str) -> bool {
    let mut c = k.chars();
    c.next().is_some_and(|f| f.is_ascii_lowercase())
        && k.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && !k.contains("__")
        && !k.ends_with('_')
}

fn has_unit(k: &str) -> bool {
    SUFFIXES.iter().any(|s| k.ends_with(s))
}

/// Walks `v` (reached under `key`, whose parent key is `parent`).
fn check(v: &Value, key: &str, parent: &str, problems: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                if !snake(k) {
                    problems.push(format!("key `{k}` is not snake_case"));
                }
                check(x, k, key, problems);
            }
        }
        Value::Array(a) => {
            for x in a {
                check(x, key, parent, problems);
            }
        }
        Value::Number(n) if n.is_f64() && !has_unit(key) && !has_unit(parent) => {
            problems.push(format!(
                "`{key}` (in `{parent}`) holds {n} with no unit in its name"
            ));
        }
        _ => {}
    }
}

fn keys(v: &Value) -> Vec<&str> {
    v.as_object().unwrap().keys().map(String::as_str).collect()
}

#[test]
fn the_checker_catches_bad_names() {
    let mut p = Vec::new();
    let bad: Value = serde_json::json!({"delay": 1.5, "camelCase": 1, "ok_s": 2.5,
        "iv_m_s2": {"value": 0.5}, "n": 3});
    check(&bad, "", "", &mut p);
    assert_eq!(p.len(), 2, "{p:?}");
}

#[test]
fn simulations_and_tables() {
    let v = json(&["parity", "--seeds", "1", "--json"]);
    assert_eq!(v["runs"].as_array().unwrap().len(), 1);
    assert_eq!(v["isolated_right"], 1);
    assert!(v["runs"][0]["isolated_at_s"].as_f64().unwrap() > 6.0);
    let csv = tmp("c.csv");
    let v = json(&[
        "campaign",
        "s2",
        "--runs",
        "4",
        "--csv",
        csv.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(v["summary"]["runs"], 4);
    let d = v["summary"]["detection_fraction"]["value"]
        .as_f64()
        .unwrap();
    assert!((0.0..=1.0).contains(&d));
    let m = json(&["merge", csv.to_str().unwrap(), "--json"]);
    assert_eq!(
        m["summary"], v["summary"],
        "merge of one shard = the campaign"
    );
    let v = json(&["scenario", "s2", "--seeds", "1", "--json"]);
    let ch = v["metrics"]["channels"].as_array().unwrap();
    assert_eq!(ch.len(), 6);
    assert!(ch[0].get("rmse_m_s2").is_some() && ch[3].get("rmse_rad_s").is_some());
    let v = json(&["demo", "--seeds", "1", "--json"]);
    assert_eq!(v["runs"].as_array().unwrap().len(), 3);
    let v = json(&["sweep", "s2", "--factors", "1", "--seeds", "1", "--json"]);
    assert_eq!(v["factors"][0]["accel_a_m_s2"], 0.3);
    let v = json(&["detections", "s2", "--json"]);
    let f = v["faults"].as_array().unwrap();
    assert!(!f.is_empty());
    for x in f {
        assert_eq!(
            keys(x),
            ["channel", "delay_s", "detected_s", "end_s", "start_s"]
        );
    }
    let v = json(&["parity-sweep", "--runs", "2", "--hours", "1", "--json"]);
    assert!(v["methods"][0]["sizes"][0].get("size_rad_s").is_some());
    let sim = tmp("sim.csv");
    let v = json(&["simulate", "s2", "--out", sim.to_str().unwrap(), "--json"]);
    assert_eq!(v["rows"], 6500);
    let dir = tmp("plots");
    let v = json(&["plot", "s2", "--out", dir.to_str().unwrap(), "--json"]);
    assert_eq!(v["files"].as_array().unwrap().len(), 8);
    let v = json(&["gallery", "--out", dir.to_str().unwrap(), "--json"]);
    assert!(v["files"].as_array().unwrap().len() >= 10);
}

#[test]
fn logs() {
    let out = tmp("x.csv");
    let v = json(&[
        "convert",
        &data("px4_fmuv3_outdoor_flight.ulg"),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(v["imus"], 1);
    assert!(v["imu_rate_hz"].as_f64().unwrap() > 0.0);
    let log = data("ap_log171_3imu.csv");
    let v = json(&["parity-replay", &log, "--json"]);
    assert_eq!(keys(&v), ["accel", "gyro"]);
    for k in ["monitoring_from_s", "alarms", "isolations"] {
        assert!(v["gyro"].get(k).is_some(), "{k}");
    }
    // The gyros' flight default tests power-up offsets, the accelerometers'
    // cannot (rectification): said, not left as a silent "healthy".
    assert_eq!(v["gyro"]["power_up_judged"], true);
    assert_eq!(v["accel"]["power_up_judged"], false);
    let v = json(&[
        "parity-table",
        &log,
        "--size",
        "5",
        "--train-starts",
        "80",
        "--onsets",
        "5",
        "--json",
    ]);
    assert_eq!(v["cases"].as_array().unwrap().len(), 18);
    assert_eq!(v["cases"][0]["injection"]["size_deg_s"], 5.0);
    // Both single-IMU monitors on a real log, one output shape.
    for monitor in ["ukf", "otsukf"] {
        let v = json(&[
            "replay",
            &data("px4_fmuv3_outdoor_flight.ulg"),
            "--monitor",
            monitor,
            "--json",
        ]);
        assert_eq!(v["monitor"], monitor);
        assert_eq!(v["channels"].as_array().unwrap().len(), 6);
        assert_eq!(v["meas_sigma_velocity_m_s"].as_array().unwrap().len(), 3);
    }
    let v = json(&["otsukf", "--seeds", "1", "--json"]);
    assert!(v["rmse"]["otsukf"]["f_p_deg_s"].as_f64().unwrap() > 0.0);
    let html = tmp("r.html");
    let v = json(&["report", &log, "--out", html.to_str().unwrap(), "--json"]);
    assert_eq!(v["verdicts"].as_array().unwrap().len(), 36);
}

/// `parity-realistic` flies a simulated hour (15 s in release): run with
/// `cargo test --release -- --ignored`.
#[test]
#[ignore]
fn parity_realistic() {
    let v = json(&[
        "parity-realistic",
        "--hours",
        "1",
        "--rounds",
        "1",
        "--kind",
        "gyro",
        "--json",
    ]);
    assert_eq!(v["kinds"][0]["steps"].as_array().unwrap().len(), 4);
    assert!(v["kinds"][0]["false_alarm"].is_null());
    let v = json(&[
        "parity-realistic",
        "--hours",
        "0",
        "--rounds",
        "1",
        "--kind",
        "accel",
        "--false-alarm",
        "1e-8",
        "--sizes",
        "1.5",
        "--json",
    ]);
    assert_eq!(v["kinds"][0]["false_alarm"].as_f64(), Some(1e-8));
    let steps = v["kinds"][0]["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 1);
    assert_eq!(steps[0]["size_m_s2"].as_f64(), Some(1.5));
}

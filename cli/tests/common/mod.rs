//! Helpers shared by the CLI tests: the binary, its output, temp files
//! and the replay JSON.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
// Each test crate uses its own subset of these.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

/// The `imu-fdi-sim` binary built for these tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
}

/// Runs the binary with `args`, asserts success, returns stdout.
pub fn bin_cmd_output(args: &[&str]) -> String {
    let o = bin().args(args).output().unwrap();
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// A file of the repository's `tests/data` (the shipped log extracts).
pub fn data(name: &str) -> PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(name)
}

/// A path in this test process's own temp dir.
pub fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-fdi-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A JSON file, parsed.
pub fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The replay JSON's entry for channel `name`.
pub fn channel<'a>(s: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    s["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["channel"] == name)
        .unwrap()
}

/// A fault table (`replay --faults`) with one step (`E1`, sign +1) on
/// `channel` (0–5: a_x … g_z) over `[start, end)` s: `accel_m_s2` on an
/// accelerometer, `gyro_deg_s` on a gyro. Written to `tmp(name)`.
pub fn step_faults(
    name: &str,
    channel: usize,
    start: f64,
    end: f64,
    accel_m_s2: f64,
    gyro_deg_s: f64,
) -> PathBuf {
    let path = tmp(name);
    std::fs::write(
        &path,
        format!(
            "[sizes]\naccel = [{accel_m_s2:?}, 0.0, 0.0]\ngyro = [{:?}, 0.0, 0.0]\n\
             f_unit = [1.0, 0.017453292519943295]\n\
             [[faults]]\nchannel = {channel}\nstart = {start:?}\nend = {end:?}\n\
             kind = \"E1\"\nsign = 1.0\n",
            gyro_deg_s.to_radians()
        ),
    )
    .unwrap();
    path
}

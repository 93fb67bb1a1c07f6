//! ArduPilot DataFlash `.bin` input, cross-checked against an independent
//! decoder: `tests/data/ap_log171_head.bin` (the first 900 kB of log171,
//! CC BY-SA 3.0) read with `ardupilot-binlog` must give the same IMU
//! samples as `tests/data/ap_log171_3imu.csv`, which was decoded with
//! pymavlink (SOURCES.md) and rounded to 1e-4 rad/s and 1e-3 m/s².

use std::path::Path;

use imu_fdi_cli::eval::parity_replay::{read_any_imu_log, read_dataflash, read_imu_log};

fn data(name: &str) -> std::path::PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data")).join(name)
}

#[test]
fn dataflash_imus_match_the_pymavlink_extract() {
    let bin = read_dataflash(&data("ap_log171_head.bin")).unwrap();
    let csv = read_imu_log(&data("ap_log171_3imu.csv")).unwrap();
    assert_eq!(bin.count, 3);
    // 11.46 s (first sample) to the truncation of the excerpt.
    assert!((bin.t[0] - 11.46).abs() < 1e-9, "{}", bin.t[0]);
    assert!(bin.t.len() > 3000, "{}", bin.t.len());
    let mut compared = 0;
    for (t, row) in csv.t.iter().zip(csv.imus.iter()) {
        let ms = |x: f64| (x * 1000.0).round() as i64;
        let Ok(i) = bin.t.binary_search_by_key(&ms(*t), |x| ms(*x)) else {
            // CSV times are rounded to the ms like TimeMS: every one must match.
            assert!(*t > *bin.t.last().unwrap(), "row {t} missing from the .bin");
            continue;
        };
        for (a, b) in row.iter().zip(bin.imus[i].iter()) {
            for ch in 0..6 {
                // Half the CSV rounding step, plus the float32 representation
                // error the CSV went through before rounding (double rounding).
                let tol = if ch < 3 { 0.5e-3 + 2e-6 } else { 0.5e-4 + 2e-7 };
                assert!(
                    (a[ch] - b[ch]).abs() <= tol,
                    "t {t} ch {ch}: csv {} bin {}",
                    a[ch],
                    b[ch]
                );
            }
        }
        compared += 1;
    }
    assert!(compared > 1000, "{compared}");
}

#[test]
fn unknown_and_wrong_files_get_clear_errors() {
    let e = read_any_imu_log(Path::new("flight.ulg")).unwrap_err();
    assert!(
        format!("{e:#}").contains("flight.ulg: unknown file type"),
        "{e:#}"
    );
    let dir = std::env::temp_dir().join(format!("imu-fdi-df-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fake = dir.join("notes.bin");
    std::fs::write(&fake, b"this is not a dataflash log at all").unwrap();
    let e = read_any_imu_log(&fake).unwrap_err();
    let msg = format!("{e:#}");
    assert!(msg.contains("notes.bin"), "{msg}");
}

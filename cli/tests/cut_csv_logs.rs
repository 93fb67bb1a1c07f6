//! A CSV log cut mid-write (the logger lost power, the file was copied while
//! open) ends in a row with fewer cells than the header: the readers drop
//! that row with a warning naming the file and line, as the binary log
//! readers stop at a cut record, and replay everything before it. A short
//! row anywhere else is still an error naming the file and the line.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code

use std::path::{Path, PathBuf};

use imu_fdi_cli::eval::parity_replay::read_imu_log;

fn log171() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/ap_log171_3imu.csv"),
    )
    .unwrap()
}

fn write(tag: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-fdi-cut-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("{tag}.csv"));
    std::fs::write(&p, text).unwrap();
    p
}

/// The first `rows` data rows of log171, and then the start of the next
/// row cut after `cells` of its cells (no newline: the write stopped there).
fn cut_after(rows: usize, cells: usize) -> (String, usize) {
    let text = log171();
    let mut lines = text.lines();
    let mut out = String::new();
    for _ in 0..=rows {
        out.push_str(lines.next().unwrap());
        out.push('\n');
    }
    let next: Vec<&str> = lines.next().unwrap().split(',').collect();
    out.push_str(&next[..cells].join(","));
    (out, rows + 2)
}

#[test]
fn a_log_cut_mid_row_is_read_up_to_the_cut_with_a_warning() {
    let (text, cut_line) = cut_after(3000, 8);
    let p = write("cut", &text);
    let log = read_imu_log(&p).expect("a cut log is read");
    assert_eq!(log.t.len(), 3000, "every complete row is kept");
    assert_eq!(log.skipped, 0);
    let warning = log
        .warnings
        .iter()
        .find(|w| w.contains("ends mid-row"))
        .expect("the cut is reported");
    assert!(warning.contains("cut.csv"), "{warning}");
    assert!(warning.contains(&format!("line {cut_line}")), "{warning}");
    assert!(warning.contains("8 of 19 cells"), "{warning}");
}

#[test]
fn a_short_row_inside_the_log_is_an_error_naming_file_and_line() {
    let (head, short_line) = cut_after(3000, 8);
    let tail: String = log171()
        .lines()
        .skip(3002)
        .take(100)
        .map(|l| format!("\n{l}"))
        .collect();
    let p = write("short", &format!("{head}{tail}\n"));
    let err = format!("{:#}", read_imu_log(&p).expect_err("a short row mid-file"));
    assert!(err.contains("short.csv"), "{err}");
    assert!(err.contains(&format!("line {short_line}")), "{err}");
    assert!(err.contains("8 cells, the header has 19"), "{err}");
}

#[test]
fn the_binary_replays_a_cut_log_and_warns_on_stderr() {
    let (text, cut_line) = cut_after(4000, 5);
    let p = write("cut_bin", &text);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
        .args(["parity-replay", p.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("cut_bin.csv: the last row (line {cut_line})")),
        "{stderr}"
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json["gyro"]["monitoring_from_s"].as_f64().is_some());
}

/// log171 with cell `col` of data row `row` replaced by `cell`.
fn with_cell(row: usize, col: usize, cell: &str) -> String {
    log171()
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == row + 1 {
                let mut c: Vec<&str> = l.split(',').collect();
                c[col] = cell;
                c.join(",")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_corrupt_imu_cell_is_a_missing_sample_with_a_warning() {
    // An `inf` or a huge value in one cell (a flipped bit, a logger's
    // overflow) used to refuse the whole file; the binary logs' readers
    // dropped such samples. Both CSV readers now read it as missing.
    let good = read_imu_log(&write("good", &log171())).unwrap();
    for (tag, cell) in [("inf", "inf"), ("huge", "-3.4e38")] {
        // Data row 4360 is line 4362, t ≈ 150 s; column 8 is imu1_ay.
        let p = write(tag, &with_cell(4360, 8, cell));
        let log = read_imu_log(&p).unwrap();
        assert_eq!(log.t, good.t, "{tag}");
        assert!(log.imus[4360][1][1].is_nan(), "{tag}");
        assert_eq!(log.imus[4361], good.imus[4361], "{tag}");
        let w = log.warnings.join(" ");
        assert!(
            w.contains("read 1 IMU cells") && w.contains("line 4362, column 'imu1_ay'"),
            "{w}"
        );
        // Through the binary, both replays run and warn once.
        let aid = |f: &str| {
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../tests/data")
                .join(f)
                .to_string_lossy()
                .into_owned()
        };
        let (gnss, att) = (
            aid("ap_log171_gps_vel_ned.csv"),
            aid("ap_log171_attitude_quat.csv"),
        );
        let p = p.to_str().unwrap();
        for args in [
            vec!["parity-replay", p, "--json"],
            vec!["replay", p, "--gnss", &gnss, "--att", &att, "--json"],
        ] {
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
                .args(&args)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(out.status.success(), "{args:?}: {err}");
            assert_eq!(err.matches("line 4362").count(), 1, "{args:?}: {err}");
            if args[0] == "parity-replay" {
                // No alarm before the crash (239 s), as undamaged.
                let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
                for kind in ["gyro", "accel"] {
                    let early = v[kind]["alarms"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .filter(|a| a["start_s"].as_f64().unwrap() < 239.0)
                        .count();
                    assert_eq!(early, 0, "{tag} {kind}");
                }
            }
        }
    }
    // Every cell of a column beyond the limit: a unit mix-up, refused.
    let text: String = log171()
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut c: Vec<String> = l.split(',').map(String::from).collect();
            if i > 0 {
                c[3] = format!("{}", c[3].parse::<f64>().unwrap() * 1000.0);
            }
            c.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let e = read_imu_log(&write("mm", &text)).unwrap_err().to_string();
    assert!(
        e.contains("column 'imu0_az'") && e.contains("unit mix-up"),
        "{e}"
    );
}

#[test]
fn rows_written_twice_are_read_once() {
    // Every row doubled (a logger or an export writing each row twice):
    // half the rows "did not increase in time", and both readers refused
    // the file as unsorted. Identical rows are now skipped, with a warning.
    let text = log171();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let doubled: String = std::iter::once(header.to_string())
        .chain(lines.flat_map(|l| [l.to_string(), l.to_string()]))
        .collect::<Vec<_>>()
        .join("\n");
    let good = read_imu_log(&write("once", &text)).unwrap();
    let log = read_imu_log(&write("twice", &doubled)).unwrap();
    assert_eq!((log.t.clone(), log.imus.clone()), (good.t, good.imus));
    let w = log.warnings.join(" ");
    assert!(
        w.contains("skipped 9521 rows identical") && w.contains("line 3"),
        "{w}"
    );
    // The GNSS velocity file doubled, through the single-IMU replay.
    let gnss = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/ap_log171_gps_vel_ned.csv"),
    )
    .unwrap();
    let mut g = gnss.lines();
    let gh = g.next().unwrap().to_string();
    let gnss2: String = std::iter::once(gh)
        .chain(g.flat_map(|l| [l.to_string(), l.to_string()]))
        .collect::<Vec<_>>()
        .join("\n");
    let gp = write("gnss_twice", &gnss2);
    let imu = write("imu_once", &text);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
        .args([
            "replay",
            imu.to_str().unwrap(),
            "--gnss",
            gp.to_str().unwrap(),
        ])
        .args(["--from", "100", "--to", "140", "--json"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("rows identical to the row before"), "{err}");
}

//! Seeded mutations of every shipped input file (DataFlash .bin, PX4 .ulg,
//! SPEC §10 CSV, scenario TOML), run through the readers of
//! `imu_fdi_cli::io` in-process: no reader may panic, and every error must
//! name the file. A handful of them also go through the binary: non-zero
//! exit, one `error: …` line on stderr, no panic or Debug output.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::Command;

use imu_fdi_cli::eval::parity_replay::{read_dataflash_imus, read_imu_log};
use imu_fdi_cli::io::log_import::{dataflash_to_replay_csv, ulog_to_replay_csv};
use imu_fdi_cli::io::scenario_file::read_scenario;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(name)
}

/// Mutations per file are multiplied by `IMU_FDI_MUTATIONS` (default 1)
/// for longer runs by hand.
fn scaled(n: usize) -> usize {
    n * std::env::var("IMU_FDI_MUTATIONS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(1)
        .max(1)
}

fn tmp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("imu-fdi-malformed-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// xorshift64*: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// An offset, half the time within the first `head` bytes (headers, format
/// definitions: where parsers read lengths).
fn offset(rng: &mut Rng, len: usize, head: usize) -> usize {
    if rng.below(2) == 0 {
        rng.below(head.min(len))
    } else {
        rng.below(len)
    }
}

/// `n` byte-level mutations of `bytes`: truncations (evenly spaced and
/// random), byte flips, garbage inserted, ranges zeroed or duplicated.
fn byte_mutations(bytes: &[u8], n: usize, seed: u64, head: usize) -> Vec<(String, Vec<u8>)> {
    let mut rng = Rng(seed);
    let len = bytes.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (what, m) = match i % 5 {
            0 => {
                let at = if i % 2 == 0 {
                    (i * len) / n
                } else {
                    offset(&mut rng, len, head)
                };
                (format!("truncated at {at}"), bytes[..at].to_vec())
            }
            1 => {
                let mut m = bytes.to_vec();
                let k = 1 + rng.below(8);
                let mut at = Vec::new();
                for _ in 0..k {
                    let p = offset(&mut rng, len, head);
                    m[p] = rng.next() as u8;
                    at.push(p);
                }
                (format!("bytes set at {at:?}"), m)
            }
            2 => {
                let p = offset(&mut rng, len, head);
                let k = 1 + rng.below(64);
                let garbage: Vec<u8> = (0..k).map(|_| rng.next() as u8).collect();
                let mut m = bytes[..p].to_vec();
                m.extend(&garbage);
                m.extend(&bytes[p..]);
                (format!("{k} garbage bytes inserted at {p}"), m)
            }
            3 => {
                let p = offset(&mut rng, len, head);
                let k = (1 + rng.below(256)).min(len - p);
                let mut m = bytes.to_vec();
                let fill = [0x00, 0xFF][rng.below(2)];
                m[p..p + k].fill(fill);
                (format!("{k} bytes at {p} set to {fill:#x}"), m)
            }
            _ => {
                let p = offset(&mut rng, len, head);
                let k = (1 + rng.below(512)).min(len - p);
                let q = offset(&mut rng, len, head);
                let mut m = bytes[..q].to_vec();
                m.extend(&bytes[p..p + k]);
                m.extend(&bytes[q..]);
                (format!("{k} bytes from {p} copied to {q}"), m)
            }
        };
        out.push((what, m));
    }
    out
}

/// `n` mutations of a ULog's message framing (16-byte file header, then
/// `u16 size, u8 type, payload`): a message's size or type replaced, or
/// its payload's first bytes set to 0xFF (lengths and counts inside
/// definitions).
fn ulog_framing_mutations(bytes: &[u8], n: usize, seed: u64) -> Vec<(String, Vec<u8>)> {
    let mut rng = Rng(seed);
    let mut starts = Vec::new();
    let mut pos = 16;
    while pos + 3 <= bytes.len() {
        starts.push(pos);
        pos += 3 + usize::from(u16::from_le_bytes([bytes[pos], bytes[pos + 1]]));
    }
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Half of them among the first 64 messages (formats, parameters).
        let k = if i % 2 == 0 {
            rng.below(starts.len().min(64))
        } else {
            rng.below(starts.len())
        };
        let at = starts[k];
        let mut m = bytes.to_vec();
        let what = match rng.below(3) {
            0 => {
                let old = u16::from_le_bytes([m[at], m[at + 1]]);
                let size = match rng.below(4) {
                    0 => 0,
                    1 => u16::MAX,
                    2 => old.saturating_sub(1 + rng.below(8) as u16),
                    _ => rng.next() as u16,
                };
                m[at..at + 2].copy_from_slice(&size.to_le_bytes());
                format!("message {k} at {at}: size {old} -> {size}")
            }
            1 => {
                let t = b"FIAMDLPRCOQSBZ"[rng.below(14)];
                m[at + 2] = t;
                format!("message {k} at {at}: type -> '{}'", t as char)
            }
            _ => {
                let len = (1 + rng.below(8)).min(m.len() - at - 3);
                m[at + 3..at + 3 + len].fill(0xFF);
                format!("message {k} at {at}: {len} payload bytes -> 0xff")
            }
        };
        out.push((what, m));
    }
    out
}

const BAD_NUMBERS: [&str; 10] = [
    "NaN", "1e308", "-1e38", "", "inf", "-inf", "abc", "1e12", "1e15", "-0",
];

/// `n` text mutations of a CSV: cells replaced by bad numbers, a whole
/// column replaced, the header damaged, lines dropped or swapped, times in
/// other units, plus byte-level damage.
fn csv_mutations(text: &str, n: usize, seed: u64) -> Vec<(String, Vec<u8>)> {
    let mut rng = Rng(seed);
    let lines: Vec<&str> = text.lines().collect();
    let cols = lines[0].split(',').count();
    let rebuild = |rows: Vec<Vec<String>>| -> Vec<u8> {
        rows.iter()
            .map(|r| r.join(","))
            .collect::<Vec<_>>()
            .join("\n")
            .into_bytes()
    };
    let table: Vec<Vec<String>> = lines
        .iter()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let bytes = byte_mutations(text.as_bytes(), n, seed ^ 0xC5C5, 256);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut t = table.clone();
        let bad = BAD_NUMBERS[rng.below(BAD_NUMBERS.len())];
        let what = match i % 8 {
            0 | 1 => {
                let k = 1 + rng.below(5);
                let mut at = Vec::new();
                for _ in 0..k {
                    let (r, c) = (1 + rng.below(t.len() - 1), rng.below(cols));
                    t[r][c] = bad.to_string();
                    at.push((r + 1, c));
                }
                format!("cells (line, col) {at:?} = '{bad}'")
            }
            2 => {
                let c = rng.below(cols);
                for r in t.iter_mut().skip(1) {
                    r[c] = bad.to_string();
                }
                format!("column {c} all '{bad}'")
            }
            3 => {
                let c = rng.below(cols);
                for r in &mut t {
                    r.remove(c);
                }
                format!("column {c} removed")
            }
            4 => {
                let c = rng.below(cols);
                t[0][c] = "renamed".into();
                format!("header of column {c} renamed")
            }
            5 => {
                let scale = [1e3, 1e6, 1e9, 1e-9, -1.0][rng.below(5)];
                for r in t.iter_mut().skip(1) {
                    if let Ok(x) = r[0].parse::<f64>() {
                        r[0] = format!("{}", x * scale);
                    }
                }
                format!("times × {scale}")
            }
            6 => {
                let (a, b) = (1 + rng.below(t.len() - 1), 1 + rng.below(t.len() - 1));
                t.swap(a, b);
                let d = 1 + rng.below(t.len() - 1);
                t.remove(d);
                format!("lines {a} and {b} swapped, line {d} removed")
            }
            _ => {
                out.push(bytes[i].clone());
                continue;
            }
        };
        out.push((what, rebuild(t)));
    }
    out
}

/// `n` mutations of a scenario TOML: one number replaced by a bad value,
/// plus byte-level damage.
fn toml_mutations(text: &str, n: usize, seed: u64) -> Vec<(String, Vec<u8>)> {
    let mut rng = Rng(seed);
    let lines: Vec<&str> = text.lines().collect();
    let numeric: Vec<usize> = (0..lines.len())
        .filter(|&i| {
            let l = lines[i].trim().trim_end_matches(',');
            let v = l.split_once('=').map_or(l, |(_, v)| v.trim());
            v.parse::<f64>().is_ok()
        })
        .collect();
    let bad = [
        "1e12",
        "inf",
        "-inf",
        "nan",
        "1e308",
        "-1e38",
        "0.0",
        "-1.0",
        "1e15",
        "\"x\"",
        "",
        "1e6",
        "99999999999999999999",
    ];
    let bytes = byte_mutations(text.as_bytes(), n, seed ^ 0x7077, 512);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        if i % 4 == 3 {
            out.push(bytes[i].clone());
            continue;
        }
        let line = numeric[rng.below(numeric.len())];
        let v = bad[rng.below(bad.len())];
        let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
        l[line] = match lines[line].split_once('=') {
            Some((k, _)) => format!("{k}= {v}"),
            None => format!("    {v},"),
        };
        out.push((
            format!("line {} = {v}", line + 1),
            l.join("\n").into_bytes(),
        ));
    }
    out
}

/// Runs `read` on every mutation written to `dir/name`; returns (oks,
/// errors) and fails listing every panic or error that does not name the
/// file.
fn run_all(
    dir: &Path,
    name: &str,
    mutations: &[(String, Vec<u8>)],
    read: &dyn Fn(&Path) -> anyhow::Result<()>,
) -> (usize, usize) {
    let path = dir.join(name);
    let (mut ok, mut err, mut caught) = (0, 0, 0);
    let mut failures = Vec::new();
    for (what, bytes) in mutations {
        std::fs::write(&path, bytes).unwrap();
        match catch_unwind(AssertUnwindSafe(|| read(&path))) {
            Ok(Ok(())) => ok += 1,
            Ok(Err(e)) => {
                err += 1;
                let msg = format!("{e:#}");
                caught += usize::from(msg.contains("the parser failed"));
                if !msg.contains(name) || msg.contains('\n') {
                    failures.push(format!(
                        "{what}: error is not one line naming {name}: {msg}"
                    ));
                }
            }
            Err(_) => failures.push(format!("{what}: PANIC")),
        }
    }
    assert!(
        failures.is_empty(),
        "{name}: {} of {} mutations failed:\n{}",
        failures.len(),
        mutations.len(),
        failures.join("\n")
    );
    eprintln!(
        "{name}: {} mutations, {ok} read, {err} refused with an error naming the file \
         ({caught} of them a parser panic caught by the reader), 0 panics escaped",
        mutations.len()
    );
    (ok, err)
}

#[test]
fn mutated_dataflash_logs_never_panic_and_errors_name_the_file() {
    let dir = tmp_dir("bin");
    let bytes = std::fs::read(data("ap_log171_head.bin")).unwrap();
    // The first 150 kB keep the mutations fast (enough for >10 rows).
    let bytes = &bytes[..150_000];
    let muts = byte_mutations(bytes, scaled(300), 0xB1, 8_000);
    let out = dir.join("out.csv");
    run_all(&dir, "mutant.bin", &muts, &|p| {
        read_dataflash_imus(p)?;
        Ok(())
    });
    // The full conversion (IMU + GPS + ATT) on a subset.
    run_all(&dir, "mutant.bin", &muts[..60], &|p| {
        dataflash_to_replay_csv(p, &out)?;
        Ok(())
    });
}

#[test]
fn mutated_ulogs_never_panic_and_errors_name_the_file() {
    let dir = tmp_dir("ulg");
    let bytes = std::fs::read(data("px4_fmuv3_outdoor_flight.ulg")).unwrap();
    let out = dir.join("out.csv");
    let read = |p: &Path| -> anyhow::Result<()> {
        ulog_to_replay_csv(p, &out)?;
        Ok(())
    };
    let muts = byte_mutations(&bytes, scaled(300), 0x01C, 16_000);
    run_all(&dir, "mutant.ulg", &muts, &read);
    let muts = ulog_framing_mutations(&bytes, scaled(200), 0x0F1);
    run_all(&dir, "mutant.ulg", &muts, &read);
}

#[test]
fn mutated_csvs_never_panic_and_errors_name_the_file() {
    let dir = tmp_dir("csv");
    let text = std::fs::read_to_string(data("ap_log171_3imu.csv")).unwrap();
    let head: String = text.lines().take(200).collect::<Vec<_>>().join("\n");
    let muts = csv_mutations(&head, scaled(400), 0xC5);
    run_all(&dir, "mutant.csv", &muts, &|p| {
        read_imu_log(p)?;
        Ok(())
    });
}

#[test]
fn mutated_scenarios_never_panic_and_errors_name_the_file() {
    let dir = tmp_dir("toml");
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/s3.toml"))
            .unwrap();
    let muts = toml_mutations(&text, scaled(400), 0x70);
    let (ok, _) = run_all(&dir, "mutant.toml", &muts, &|p| {
        let scn = read_scenario(p)?;
        // What was accepted is bounded: a run of it cannot exhaust memory.
        assert!(scn.duration_s.is_finite() && scn.duration_s <= 1e6);
        assert!(scn.imu_rate_hz.is_finite() && scn.imu_rate_hz <= 1e5);
        Ok(())
    });
    assert!(ok > 0, "some harmless mutations must still load");
}

/// The binary on a few bad files: non-zero exit, one `error:` line.
#[test]
fn the_binary_explains_bad_files_in_one_line() {
    let dir = tmp_dir("bin-run");
    let exe = env!("CARGO_BIN_EXE_imu-fdi-sim");
    let ulg = std::fs::read(data("px4_fmuv3_outdoor_flight.ulg")).unwrap();
    let bin = std::fs::read(data("ap_log171_head.bin")).unwrap();
    let csv = std::fs::read_to_string(data("ap_log171_3imu.csv")).unwrap();
    let head: Vec<&str> = csv.lines().take(200).collect();
    let scn =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/s2.toml"))
            .unwrap();
    let ns_times: String = head
        .iter()
        .enumerate()
        .map(|(i, l)| match (i, l.split_once(',')) {
            (0, _) | (_, None) => l.to_string(),
            (_, Some((t, rest))) => format!("{:.0},{rest}", t.parse::<f64>().unwrap() * 1e9),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let nan_column: String = head
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let mut c: Vec<&str> = l.split(',').collect();
            if i > 0 {
                c[8] = "NaN";
            }
            c.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let missing_column: String = head
        .iter()
        .map(|l| {
            let mut c: Vec<&str> = l.split(',').collect();
            c.remove(9);
            c.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        ("cut.ulg", ulg[..300].to_vec(), vec!["convert"]),
        ("junk.ulg", vec![0x55; 4000], vec!["convert"]),
        ("cut.bin", bin[..400].to_vec(), vec!["convert"]),
        ("junk.bin", vec![0xA3; 5000], vec!["parity-replay"]),
        ("ns.csv", ns_times.into_bytes(), vec!["parity-replay"]),
        ("nan.csv", nan_column.into_bytes(), vec!["parity-replay"]),
        (
            "missing.csv",
            missing_column.into_bytes(),
            vec!["parity-replay"],
        ),
        (
            "inf.toml",
            scn.replace("duration_s = 65.0", "duration_s = inf")
                .into_bytes(),
            vec!["scenario"],
        ),
        (
            "fast.toml",
            scn.replace("imu_rate_hz = 100.0", "imu_rate_hz = 1e15")
                .into_bytes(),
            vec!["scenario"],
        ),
    ];
    // A SPEC §10 replay file in nanoseconds, and a PX4-style extract whose
    // gyro_y column is empty.
    let mut replay_ns = String::from(
        "t,imu0_ax,imu0_ay,imu0_az,imu0_gx,imu0_gy,imu0_gz,dvl_u,dvl_v,dvl_w,att_roll,att_pitch,att_yaw\n",
    );
    let mut extract = String::from(
        "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n",
    );
    for k in 0..60u64 {
        replay_ns += &format!("{},0,0,-9.8,0,0,0,0,0,0,0,0,0\n", k * 10_000_000);
        extract += &format!("{},0.1,,0.3,1,2,-9.8\n", 10.0 + 0.01 * k as f64);
    }
    let mut cases = cases;
    cases.push(("ns-replay.csv", replay_ns.into_bytes(), vec!["replay"]));
    cases.push(("extract.csv", extract.into_bytes(), vec!["convert"]));
    // A framing mutation on which px4-ulog itself panics (caught by the
    // reader): the user still sees one line.
    let probe = dir.join("probe.ulg");
    let panicking = ulog_framing_mutations(&ulg, 200, 0x0F1)
        .into_iter()
        .find(|(_, m)| {
            std::fs::write(&probe, m).unwrap();
            ulog_to_replay_csv(&probe, &dir.join("probe.csv"))
                .is_err_and(|e| format!("{e:#}").contains("the parser failed"))
        })
        .expect("a framing mutation on which px4-ulog panics");
    cases.push(("panics.ulg", panicking.1, vec!["convert"]));
    for (name, bytes, args) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let mut cmd = Command::new(exe);
        cmd.args(&args).arg(&path);
        if args == ["convert"] {
            cmd.arg("--out").arg(dir.join("out.csv"));
        }
        let o = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name}: exit 0\n{err}");
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{name}: not one line:\n{err}");
        assert!(
            lines[0].starts_with("error: ") && lines[0].contains(name),
            "{name}: {err}"
        );
        for bad in ["panicked", "{ ", "Some(", "RUST_BACKTRACE"] {
            assert!(!err.contains(bad), "{name}: '{bad}' in {err}");
        }
    }
}

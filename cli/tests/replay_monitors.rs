//! `replay --monitor ukf|otsukf`: both single-IMU monitors on the same files,
//! one output format, and the fault estimate on replay against the 12-state
//! augmented UKF on the same data (issue 15).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code

use std::path::PathBuf;
use std::process::Command;

use hal_sim::ots::run_augmented;
use hal_sim::runner::{monitor_config, RunOptions};
use hal_sim::Scenario;
use imu_fdi::monitor::{OtsukfConfig, UkfMonitorConfig};
use imu_fdi_cli::eval::replay::{replay, write_simulated, ReplayOptions};
use imu_fdi_cli::eval::replay_monitor::MonitorKind;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-fdi-replay-mon-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Fault-estimate RMSE per channel (m/s², °/s) of `kind` replayed on S3
/// seed `seed` written as a SPEC §10 CSV.
fn replay_rmse(csv: &std::path::Path, kind: MonitorKind) -> [f64; 6] {
    replay_rmse_with(csv, kind, true)
}

/// [`replay_rmse`], the UKF monitor with its tracking estimate (`track`)
/// or SPEC §6's window mean `M⁺ r̄` (`fault_psd: None`).
fn replay_rmse_with(csv: &std::path::Path, kind: MonitorKind, track: bool) -> [f64; 6] {
    replay_rmse_on(&Scenario::s3(), csv, kind, track)
}

/// [`replay_rmse_with`] on scenario `s3` (any scenario).
fn replay_rmse_on(
    s3: &Scenario,
    csv: &std::path::Path,
    kind: MonitorKind,
    track: bool,
) -> [f64; 6] {
    let opts = ReplayOptions {
        monitor: kind,
        ..ReplayOptions::default()
    };
    let sum = replay(
        csv,
        None,
        None,
        |_| {
            let mut c = monitor_config(s3, &RunOptions::default());
            if track {
                c.fault_psd = Some(UkfMonitorConfig::fault_tracking_psd());
            }
            c
        },
        &opts,
    )
    .unwrap();
    assert_eq!(sum.profile, "Sim");
    core::array::from_fn(|c| {
        let ch = &sum.channels[c];
        assert_eq!(ch.false_alarm_samples, Some(0), "{kind:?}: {ch:?}");
        let r = ch.fault_rmse_si.unwrap();
        if c >= 3 {
            r.to_degrees()
        } else {
            r
        }
    })
}

/// Both monitors replayed from a CSV estimate S3's faults within 20 % of
/// the 12-state augmented UKF run on the same samples with the same model,
/// noise and fault random walk (`OtsukfConfig::from_base` of the replay's
/// configuration), channel by channel, summed over three seeds: the OTSUKF,
/// and the UKF innovation monitor with its tracking estimate
/// (`fault_track.rs`, same fault random walk). SPEC §6's window mean
/// `M⁺ r̄`, which the UKF monitor reported before, does not (1.3–1.9×).
#[test]
fn both_monitors_replay_estimates_faults_within_20_percent_of_the_augmented_ukf() {
    let s3 = Scenario::s3();
    let mut base = monitor_config::<f64>(&s3, &RunOptions::default());
    base.imu_period = 1.0 / s3.imu_rate_hz;
    let aug_cfg = OtsukfConfig::from_base(base);
    let (mut ots, mut ukf, mut aug) = ([0.0; 6], [0.0; 6], [0.0; 6]);
    let mut win = [0.0; 6];
    let seeds = [1u64, 2, 3];
    for seed in seeds {
        let csv = tmp(&format!("s3-{seed}.csv"));
        write_simulated(&s3, seed, &csv).unwrap();
        let o = replay_rmse(&csv, MonitorKind::Otsukf);
        let u = replay_rmse(&csv, MonitorKind::Ukf);
        let w = replay_rmse_with(&csv, MonitorKind::Ukf, false);
        let a = run_augmented(&s3, seed, &aug_cfg).unwrap().rmse();
        for c in 0..6 {
            ots[c] += o[c] * o[c] / seeds.len() as f64;
            ukf[c] += u[c] * u[c] / seeds.len() as f64;
            win[c] += w[c] * w[c] / seeds.len() as f64;
            aug[c] += a[6 + c] * a[6 + c] / seeds.len() as f64;
        }
    }
    let (ots, ukf, aug) = (ots.map(f64::sqrt), ukf.map(f64::sqrt), aug.map(f64::sqrt));
    let win = win.map(f64::sqrt);
    println!(
        "S3 seeds {seeds:?}, fault RMSE (m/s², °/s):\n  otsukf replay {ots:.4?}\n  ukf replay    {ukf:.4?}\n  ukf window    {win:.4?}\n  augmented UKF {aug:.4?}\n  otsukf/aug {:.3?}\n  ukf/aug    {:.3?}\n  window/aug {:.3?}",
        core::array::from_fn::<f64, 6, _>(|c| ots[c] / aug[c]),
        core::array::from_fn::<f64, 6, _>(|c| ukf[c] / aug[c]),
        core::array::from_fn::<f64, 6, _>(|c| win[c] / aug[c]),
    );
    for c in 0..6 {
        assert!(
            ots[c] <= 1.2 * aug[c],
            "channel {c}: OTSUKF {} vs augmented {}",
            ots[c],
            aug[c]
        );
        // Measured 0.94–1.06×.
        assert!(
            ukf[c] <= 1.2 * aug[c],
            "channel {c}: UKF monitor {} vs augmented {}",
            ukf[c],
            aug[c]
        );
        // The window mean: 1.30–1.86× (measured).
        assert!(
            win[c] > 1.25 * aug[c],
            "channel {c}: window mean {} vs augmented {}",
            win[c],
            aug[c]
        );
    }
}

/// The same real log (ArduPilot log171's head, a DataFlash .bin) through
/// both monitors from the command line with `--json`: stdout is one JSON
/// object of the same shape, and the 10 °/s gz and −1 m/s² ay steps
/// injected on IMU 1 are found on IMU 1 by both; the OTSUKF flags nothing
/// else.
#[test]
fn both_monitors_replay_a_dataflash_log_with_one_json_shape() {
    let bin_log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/ap_log171_head.bin"
    );
    let faults = tmp("ap-head-faults.toml");
    std::fs::write(
        &faults,
        "[sizes]\naccel = [1.0, 0.0, 0.0]\ngyro = [0.17453292519943295, 0.0, 0.0]\n\
         f_unit = [1.0, 0.017453292519943295]\n\
         [[faults]]\nchannel = 5\nstart = 15.0\nend = 20.0\nkind = \"E1\"\nsign = 1.0\n\
         [[faults]]\nchannel = 1\nstart = 28.0\nend = 34.0\nkind = \"E1\"\nsign = -1.0\n",
    )
    .unwrap();
    let mut keys = Vec::new();
    for monitor in ["ukf", "otsukf"] {
        let out = tmp(&format!("ap-head-{monitor}.csv"));
        let o = Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
            .args(["replay", bin_log, "--from", "48", "--learn", "10"])
            .arg("--faults")
            .arg(&faults)
            .args(["--fault-offset", "50", "--inject-imu", "1"])
            .args(["--monitor", monitor, "--json", "--out"])
            .arg(&out)
            // The a_y step 5 s after take-off is judged with the inflation
            // frozen at the end of learning; followed in flight it is not
            // judged (more active than anything learnt on the ground:
            // `real_log_cli.rs`).
            .args(["--inflation-memory", "0"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        // Diagnostics on stderr, exactly one JSON object on stdout.
        assert!(String::from_utf8_lossy(&o.stderr).contains("replayed"));
        let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(s["monitor"], monitor);
        keys.push(s.as_object().unwrap().keys().cloned().collect::<Vec<_>>());
        let ch = |name: &str| {
            s["channels"]
                .as_array()
                .unwrap()
                .iter()
                .find(|c| c["channel"] == name)
                .unwrap()
                .clone()
        };
        let gz = ch("imu1_gz");
        let t = gz["first_correct_s"].as_f64().unwrap();
        assert!(
            (65.0..68.5).contains(&t),
            "{monitor}: gz step at 65 s found at {t}"
        );
        let ay = ch("imu1_ay");
        let t = ay["first_correct_s"].as_f64().unwrap();
        assert!(
            (78.0..80.5).contains(&t),
            "{monitor}: ay step at 78 s found at {t}"
        );
        for c in s["channels"].as_array().unwrap() {
            let name = c["channel"].as_str().unwrap();
            // The UKF monitor flags IMU 2's a_z on this log (335 samples
            // measured): the false alarm issue 15 is about; the OTSUKF none.
            let known = monitor == "ukf" && name == "imu2_az";
            if !name.starts_with("imu1_") && !known {
                assert_eq!(
                    c["flagged_samples"], 0,
                    "{monitor}: clean channel flagged: {c}"
                );
            }
        }
        // One per-row layout: phase, flags, estimates, σ, block-test
        // ratios per IMU.
        let header = std::fs::read_to_string(&out).unwrap();
        let header = header.lines().next().unwrap();
        assert!(
            header.contains(",imu1_phase,imu1_flag_ax,")
                && header.contains(",imu1_fhat_gz,imu1_fsig_ax,")
                && header.contains(",imu1_fsig_gz,imu1_ratio_ax,")
                && header.ends_with(",imu2_ratio_gz"),
            "{header}"
        );
    }
    assert_eq!(keys[0], keys[1], "the two monitors' JSON differ in shape");
}

/// The learned innovation inflation on a real flight. log171 80–235 s
/// (the CSV extracts), the UKF monitor's own test alone (block tests off):
/// with the inflation off (`--max-inflation 1`) it raises 17/12/17 flag
/// events per IMU, learned (the flight default) none. On log171's head
/// (DataFlash, fault-free from 48 s) the velocity channels' factors come
/// out above 1 (time-correlated GPS and attitude errors), the attitude
/// channels' at 1. (The head's former case, 2 IMU2 a_z events with the
/// inflation off, was its 2-s IMU gap at arming, 72.6 s: 0 since the
/// monitors hold and re-align after a gap, `imu_gap.rs`.)
#[test]
fn learned_inflation_removes_the_false_alarms_of_a_real_flight() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/");
    let run = |args: &[&str]| -> serde_json::Value {
        let o = Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
            .arg("replay")
            .args(args)
            .arg("--json")
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let per_imu = |s: &serde_json::Value| -> Vec<u64> {
        s["channels"]
            .as_array()
            .unwrap()
            .chunks(6)
            .map(|c| c.iter().map(|c| c["flag_events"].as_u64().unwrap()).sum())
            .collect()
    };
    let (imu, gnss, att) = (
        format!("{dir}ap_log171_3imu.csv"),
        format!("{dir}ap_log171_gps_vel_ned.csv"),
        format!("{dir}ap_log171_attitude_quat.csv"),
    );
    let flight = [
        imu.as_str(),
        "--gnss",
        &gnss,
        "--att",
        &att,
        "--from",
        "80",
        "--to",
        "235",
        "--attitude-rate",
        "off",
        "--velocity-increment",
        "off",
    ];
    let off = run(&[&flight[..], &["--max-inflation", "1"]].concat());
    assert!(
        per_imu(&off).iter().all(|e| *e >= 10),
        "{:?}",
        per_imu(&off)
    );
    assert_eq!(per_imu(&run(&flight)), [0, 0, 0]);
    let head = format!("{dir}ap_log171_head.bin");
    let on = run(&[&head, "--from", "48", "--learn", "10"]);
    assert_eq!(per_imu(&on), [0, 0, 0]);
    for imu in on["innovation_inflation_factor"].as_array().unwrap() {
        let f: Vec<f64> = imu
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert!(f[..3].iter().any(|v| *v > 2.0), "{f:?}");
        assert!(f[3..].iter().all(|v| *v == 1.0), "{f:?}");
        assert!(f.iter().all(|v| (1.0..=25.0).contains(v)), "{f:?}");
    }
}

/// Held out (not looked at while building the tracking estimate): S1 and
/// S2 on the AUV (DVL 5 Hz, compass 10 Hz), seeds 11–13. The UKF monitor's
/// tracking estimate is within 10 % of the augmented UKF on every channel
/// (measured 0.98–1.02×, S2 a_y 0.73×); the window mean is 0.69–3.1×.
/// Before the tracker also read the innovations the filter's own gate
/// rejects, S1's 1.5 °/s pitch-rate step gave 1.24×.
#[test]
fn ukf_tracking_estimate_on_the_auv_scenarios() {
    for scn in [Scenario::s1(), Scenario::s2()] {
        let mut base = monitor_config::<f64>(&scn, &RunOptions::default());
        base.imu_period = 1.0 / scn.imu_rate_hz;
        let aug_cfg = OtsukfConfig::from_base(base);
        let (mut ukf, mut win, mut aug) = ([0.0; 6], [0.0; 6], [0.0; 6]);
        let seeds = [11u64, 12, 13];
        for seed in seeds {
            let csv = tmp(&format!("{}-{seed}.csv", scn.name));
            write_simulated(&scn, seed, &csv).unwrap();
            let u = replay_rmse_on(&scn, &csv, MonitorKind::Ukf, true);
            let w = replay_rmse_on(&scn, &csv, MonitorKind::Ukf, false);
            let a = run_augmented(&scn, seed, &aug_cfg).unwrap().rmse();
            for c in 0..6 {
                ukf[c] += u[c] * u[c] / seeds.len() as f64;
                win[c] += w[c] * w[c] / seeds.len() as f64;
                aug[c] += a[6 + c] * a[6 + c] / seeds.len() as f64;
            }
        }
        let (ukf, win, aug) = (ukf.map(f64::sqrt), win.map(f64::sqrt), aug.map(f64::sqrt));
        let ratio = |v: &[f64; 6]| core::array::from_fn::<f64, 6, _>(|c| v[c] / aug[c]);
        println!(
            "{} seeds {seeds:?}: fault RMSE / augmented UKF: tracking {:.3?}, window mean {:.3?}",
            scn.name,
            ratio(&ukf),
            ratio(&win)
        );
        for (c, r) in ratio(&ukf).iter().enumerate() {
            assert!(
                *r <= 1.1,
                "{} channel {c}: tracking / augmented {r}",
                scn.name
            );
        }
    }
}

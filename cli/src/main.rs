//! `imu-fdi-sim`: run scenarios, replay logs and print SPEC §9 figures.
//!
//! This file parses the command line and dispatches; each subcommand is a
//! module of `cmd/` with its arguments and its `run`.

use anyhow::Result;
use clap::{Parser, Subcommand};

/// `println!` that ends the program quietly when stdout is closed (e.g.
/// piped into `head`) instead of panicking on the broken pipe, and prints
/// above a running progress spinner.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let r = crate::cmd::progress::suspend(|| writeln!(std::io::stdout().lock(), $($arg)*));
        if let Err(e) = r {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
        }
    }};
}

/// `print!` counterpart of [`out!`].
macro_rules! out_nl {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let r = crate::cmd::progress::suspend(|| write!(std::io::stdout().lock(), $($arg)*));
        if let Err(e) = r {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
        }
    }};
}

mod cmd;

#[derive(Parser)]
#[command(
    name = "imu-fdi-sim",
    version,
    about = "Simulate, replay and score the imu-fdi monitors"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// S4 (parity paper): 0.5 °/s bias on sensor 5 of a manoeuvring cone6 gyro
    /// array; parity monitor (PCA, χ², CUSUM) beside the PX4-like and
    /// ArduPilot-like baselines, over several seeds.
    Parity(cmd::parity::Args),
    /// Monte-Carlo campaign: N seeded runs of a scenario, each with one random
    /// fault (onset, channel, shape, sign, size), in parallel over all cores;
    /// prints detection rate, false alarms per hour, delay, isolation
    /// accuracy and RMSE with 95 % intervals.
    Campaign(cmd::campaign::Args),
    /// The papers' figures of one run as PNG and SVG: injected fault vs flag,
    /// estimate vs truth, innovations ±3σ, statistic vs threshold (UKF
    /// scenarios), or the parity pattern and χ² (s4).
    Plot(cmd::plot::Args),
    /// The README gallery: S1–S4 figures (seed 1) as PNG and SVG.
    Gallery(cmd::gallery::Args),
    /// Converts a flight log to the SPEC §10 replay CSV: a PX4 ULog (.ulg:
    /// primary IMU from sensor_combined, GNSS velocity with a 3-D fix,
    /// attitude quaternion -> Euler) or an ArduPilot DataFlash log (.bin:
    /// IMU/IMU2/IMU3, GPS velocity with a 3-D fix, ATT). `replay` accepts
    /// both directly through the same conversion.
    ///
    /// A CSV extract not in SPEC §10 form (`../shared/data`: imu0_gyro_x_rad_s…,
    /// gyro_x_rad_s…, or x-io's g and deg/s) is mapped too, with its GNSS
    /// velocity (`--gnss`, fix ≥ 3 only) and attitude (`--att`, quaternion or
    /// degrees) files.
    Convert(cmd::convert::Args),
    /// Merges the per-run CSVs of campaign shards into one table.
    Merge(cmd::merge::Args),
    /// Replays a log of three synchronous IMUs (SPEC §10 `imu{k}_…` columns,
    /// e.g. tests/data/ap_log171_3imu.csv, or an ArduPilot DataFlash .bin
    /// with IMU/IMU2/IMU3) through the parity monitor and the
    /// baselines: alarms, isolations, statuses; optionally the smallest
    /// injected bias each method detects per channel.
    ParityReplay(cmd::parity_replay::Args),
    /// The step table of a multi-IMU log: every IMU × axis × sign, several
    /// onsets and training starts; a case passes when the right sensor is
    /// isolated within 10 s and nothing else alarms (`--power-up`: a bias
    /// present from the first row).
    ParityTable(cmd::parity_table::Args),
    /// The parity monitor for real flights on the realistic simulated
    /// profile (fitted to log171): false-alarm events over fault-free hours
    /// and isolated steps per size.
    ParityRealistic(cmd::parity_realistic::Args),
    /// Smallest bias each method detects in >= 99 % of runs at zero false
    /// alarms over fault-free hours, with its delay (redundant arrays).
    ParitySweep(cmd::parity_sweep::Args),
    /// The optimal two-stage UKF (OTSUKF) on S3 (s3: realistic sensors; s3-paper: the
    /// paper's noise, aiding at the IMU rate): SPEC §9 RMSE over seeds, beside
    /// the 12-state augmented UKF and the paper's numbers.
    Otsukf(cmd::otsukf::Args),
    /// Run a scenario over seeds and print the per-channel table: a built-in
    /// (s1, s2, s3, s3-paper, s5, auv-hour, aircraft-hour; s4 runs the parity
    /// monitor on the cone of six gyros) or a .toml scenario file.
    Scenario(cmd::scenario::Args),
    /// S1 (threshold method) and S2 (run-time matrix + GLR, and the paper's fixed matrix) in one go.
    Demo(cmd::demo::Args),
    /// Scale the fault sizes a, b, c of a scenario and print detection per channel for each scale.
    Sweep(cmd::sweep::Args),
    /// First detection of every fault row of one seed, in the same format as the QEMU image prints (for diffing host vs target).
    Detections(cmd::detections::Args),
    /// Write a simulated run in the SPEC §10 replay format (with truth columns).
    Simulate(cmd::simulate::Args),
    /// Replay a SPEC §10 CSV, a ULog or a DataFlash log through a single-IMU
    /// monitor (`--monitor ukf`: UKF innovation monitor, default detector
    /// run-time matrix + GLR; `--monitor otsukf`: the OTSUKF), one output
    /// format for both.
    Replay(Box<cmd::replay::Args>),
    /// A flight report: any log (.ulg, .bin, SPEC §10 CSV; one or three
    /// IMUs) replayed into one self-contained HTML page that opens offline:
    /// verdict per IMU channel, fault estimates with flags, innovations
    /// ±3σ, parity residuals and tests with the PX4-like and ArduPilot-like
    /// baselines, status timeline; zoom and pan over the whole log.
    Report(cmd::report::Args),
}

/// Errors reach the user as one line on stderr (`error: what: why`, the
/// whole context chain, no Rust debug formatting or backtrace) with exit
/// status 1.
fn main() -> std::process::ExitCode {
    match run(Cli::parse().cmd) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cmd: Cmd) -> Result<()> {
    match cmd {
        Cmd::Parity(a) => cmd::parity::run(a),
        Cmd::Campaign(a) => cmd::campaign::run(a),
        Cmd::Plot(a) => cmd::plot::run(a),
        Cmd::Gallery(a) => cmd::gallery::run(a),
        Cmd::Convert(a) => cmd::convert::run(a),
        Cmd::Merge(a) => cmd::merge::run(a),
        Cmd::ParityReplay(a) => cmd::parity_replay::run(a),
        Cmd::ParityTable(a) => cmd::parity_table::run(a),
        Cmd::ParityRealistic(a) => cmd::parity_realistic::run(a),
        Cmd::ParitySweep(a) => cmd::parity_sweep::run(a),
        Cmd::Otsukf(a) => cmd::otsukf::run(a),
        Cmd::Scenario(a) => cmd::scenario::run(a),
        Cmd::Demo(a) => cmd::demo::run(a),
        Cmd::Sweep(a) => cmd::sweep::run(a),
        Cmd::Detections(a) => cmd::detections::run(a),
        Cmd::Simulate(a) => cmd::simulate::run(a),
        Cmd::Replay(a) => cmd::replay::run(*a),
        Cmd::Report(a) => cmd::report::run(a),
    }
}

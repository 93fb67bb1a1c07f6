//! `imu-fdi-sim`: run scenarios, replay logs and print SPEC §9 figures.

use std::path::PathBuf;

use anyhow::{anyhow, Result};
use clap::{Parser, Subcommand, ValueEnum};
use hal_sim::metrics::{evaluate, RunMetrics};
use hal_sim::runner::{monitor_config, run, RunOptions};
use hal_sim::Scenario;
use imu_fdi::detect::{Detector, Statistic};
use imu_fdi::model::AidingKind;
use imu_fdi::monitor::UkfMonitorConfig;

/// `println!` that ends the program quietly when stdout is closed (e.g.
/// piped into `head`) instead of panicking on the broken pipe.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout().lock(), $($arg)*) {
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
        if let Err(e) = write!(std::io::stdout().lock(), $($arg)*) {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
        }
    }};
}

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

/// Replay tuning profile.
#[derive(Clone, Copy, ValueEnum)]
enum ProfileArg {
    Sim,
    Flight,
    Auto,
}

impl From<ProfileArg> for hal_sim::replay::Profile {
    fn from(p: ProfileArg) -> Self {
        match p {
            ProfileArg::Sim => Self::Sim,
            ProfileArg::Flight => Self::Flight,
            ProfileArg::Auto => Self::Auto,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum DetectorArg {
    /// \[UKF\] §3.1 threshold method.
    Threshold,
    /// Paper's fixed sign matrix (erratum applied).
    Paper,
    /// Paper's matrix exactly as printed.
    PaperAsPrinted,
    /// Run-time sign matrix C⁻¹·flag.
    Runtime,
    /// Run-time signature matrix with GLR isolation (default).
    RuntimeGlr,
}

impl From<DetectorArg> for Detector {
    fn from(d: DetectorArg) -> Self {
        match d {
            DetectorArg::Threshold => Detector::Threshold,
            DetectorArg::Paper => Detector::PaperMatrix,
            DetectorArg::PaperAsPrinted => Detector::PaperMatrixAsPrinted,
            DetectorArg::Runtime => Detector::RuntimeMatrix,
            DetectorArg::RuntimeGlr => Detector::RuntimeMatrixGlr,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum StatisticArg {
    /// The paper's t-test on raw innovations.
    Raw,
    /// t-test on innovations whitened by the filter's S.
    Whitened,
    /// Known-variance normalised-innovation test.
    Normalized,
}

#[derive(clap::Args, Clone)]
struct DetectOpts {
    /// Decision rule (default: the scenario's: threshold for S1, runtime-glr otherwise).
    #[arg(long, value_enum)]
    detector: Option<DetectorArg>,
    /// Samples in the t-test windows.
    #[arg(long, value_enum, default_value = "normalized")]
    statistic: StatisticArg,
    /// Per-tail significance of the t-test.
    #[arg(long, default_value_t = 1e-6)]
    alpha: f64,
}

#[derive(Clone, Copy, ValueEnum)]
enum ArrayArg {
    /// Six single-axis sensors on the parity paper's cone.
    Cone6,
    /// Two IMUs, the second yawed 180° (detect only: axes parallel).
    Triads2,
    /// Three IMUs yawed 0°, 90°, 180° (per-axis 2-of-3 isolation).
    Triads3,
}

#[derive(Clone, Copy, ValueEnum)]
enum KindArg {
    Gyro,
    Accel,
}

#[derive(Subcommand)]
enum Cmd {
    /// S4 (parity paper): 0.5 °/s bias on sensor 5 of a manoeuvring cone6 gyro
    /// array; parity monitor (PCA, χ², CUSUM) beside the PX4-like and
    /// ArduPilot-like baselines, over several seeds.
    Parity {
        #[arg(long, default_value_t = 1)]
        first_seed: u64,
        #[arg(long, default_value_t = 20)]
        seeds: u64,
    },
    /// Monte-Carlo campaign: N seeded runs of a scenario, each with one random
    /// fault (onset, channel, shape, sign, size), in parallel over all cores;
    /// prints detection rate, false alarms per hour, delay, isolation
    /// accuracy and RMSE with 95 % intervals.
    Campaign {
        /// Built-in scenario whose vehicle, sensors and aiding are used.
        #[arg(default_value = "s2")]
        name: String,
        #[arg(long, default_value_t = 1000)]
        runs: u64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Only this machine's share: i/n takes runs k with k mod n = i - 1.
        #[arg(long)]
        shard: Option<hal_sim::campaign::Shard>,
        /// Per-run rows (CSV), the input of `merge`.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Summary (JSON).
        #[arg(long)]
        json: Option<PathBuf>,
        #[command(flatten)]
        detect: DetectOpts,
    },
    /// The papers' figures of one run as PNG and SVG: injected fault vs flag,
    /// estimate vs truth, innovations ±3σ, statistic vs threshold (UKF
    /// scenarios), or the parity pattern and χ² (s4).
    Plot {
        name: String,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[arg(long, default_value = "plots")]
        out: PathBuf,
        #[command(flatten)]
        detect: DetectOpts,
    },
    /// The README gallery: S1–S4 figures (seed 1) as PNG and SVG.
    Gallery {
        #[arg(long, default_value = "docs/gallery")]
        out: PathBuf,
    },
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
    Convert {
        input: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// GNSS velocity CSV of a CSV extract (time_s, vel_n_m_s, …).
        #[arg(long)]
        gnss: Option<PathBuf>,
        /// Attitude CSV of a CSV extract (time_s, q_w… or roll_deg…).
        #[arg(long)]
        att: Option<PathBuf>,
    },
    /// Merges the per-run CSVs of campaign shards into one table.
    Merge {
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        #[arg(long)]
        csv: Option<PathBuf>,
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Replays a log of three synchronous IMUs (SPEC §10 `imu{k}_…` columns,
    /// e.g. tests/data/ap_log171_3imu.csv, or an ArduPilot DataFlash .bin
    /// with IMU/IMU2/IMU3) through the parity monitor and the
    /// baselines: alarms, isolations, statuses; optionally the smallest
    /// injected bias each method detects per channel.
    ParityReplay {
        input: PathBuf,
        /// Log time training starts (in flight: vibration must be in it).
        #[arg(long, default_value_t = 80.0)]
        train_start: f64,
        /// Training + calibration length, s.
        #[arg(long, default_value_t = 30.0)]
        train_s: f64,
        /// Inject biases on every channel at these onsets (comma-separated,
        /// s) and report the smallest detected per method.
        #[arg(long, value_delimiter = ',')]
        inject_at: Vec<f64>,
    },
    /// Smallest bias each method detects in >= 99 % of runs at zero false
    /// alarms over fault-free hours, with its delay (redundant arrays).
    ParitySweep {
        #[arg(long, value_enum, default_value = "triads3")]
        array: ArrayArg,
        #[arg(long, value_enum, default_value = "gyro")]
        kind: KindArg,
        /// Runs per bias size.
        #[arg(long, default_value_t = 100)]
        runs: u32,
        /// Fault-free simulated hours for the false-alarm count.
        #[arg(long, default_value_t = 1)]
        hours: u32,
        #[arg(long, default_value_t = 1)]
        first_seed: u64,
        /// Also write the full per-size results as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// The optimal two-stage UKF on S3 (s3: realistic sensors; s3-paper: the
    /// paper's noise, aiding at the IMU rate): SPEC §9 RMSE over seeds, beside
    /// the 12-state augmented UKF and the paper's numbers.
    Otsukf {
        /// Scenario: s3 or s3-paper.
        #[arg(default_value = "s3")]
        name: String,
        /// First seed (held-out seeds start at 100).
        #[arg(long, default_value_t = 100)]
        first_seed: u64,
        /// Number of seeds.
        #[arg(long, default_value_t = 20)]
        seeds: u64,
        /// Also run the 12-state augmented UKF on the same seeds.
        #[arg(long)]
        augmented: bool,
        /// Run the two-stage monitor in f32 (default f64).
        #[arg(long)]
        f32: bool,
        /// Q^f multiplier while a fault is tracked (1 = no adaptation: the
        /// augmented UKF's fixed Q^f, for a like-for-like comparison): one
        /// value for every channel or six (a_x a_y a_z p q r).
        #[arg(long, value_delimiter = ',')]
        adapt_gain: Option<Vec<f64>>,
        /// Standardised move of one update that starts the adaptation.
        #[arg(long)]
        adapt_k: Option<f64>,
        /// How long the adaptation holds, s.
        #[arg(long)]
        adapt_hold: Option<f64>,
        /// The adaptation also holds while |f̂ − b| ≥ this many σ_f
        /// (0: only sudden moves start it).
        #[arg(long)]
        adapt_level: Option<f64>,
        /// Multiplier of the accelerometer and gyro fault random walk Q^f
        /// (both filters), e.g. `1,3`.
        #[arg(
            long,
            value_delimiter = ',',
            value_name = "ACCEL,GYRO",
            allow_negative_numbers = true
        )]
        qf_scale: Option<Vec<f64>>,
        /// Run the scenario with its fault table removed: the fault rows
        /// are then empty and the last row gives the estimates' noise.
        #[arg(long)]
        fault_free: bool,
        /// Keep only the fault rows of one shape (F1 step, F2 ramp, F3 sine).
        #[arg(long)]
        shape: Option<String>,
    },
    /// Run a scenario over seeds and print the per-channel table: a built-in
    /// (s1, s2, s3, s3-paper, s5, auv-hour, aircraft-hour; s4 runs the parity
    /// monitor on the cone of six gyros) or a .toml scenario file.
    Scenario {
        /// Scenario name.
        name: String,
        /// First seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Number of seeds.
        #[arg(long, default_value_t = 5)]
        seeds: u64,
        #[command(flatten)]
        detect: DetectOpts,
        /// Also write the metrics as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Write the first seed's per-sample trace as CSV here.
        #[arg(long)]
        trace: Option<PathBuf>,
    },
    /// S1 (threshold method) and S2 (run-time matrix + GLR, and the paper's fixed matrix) in one go.
    Demo {
        /// Number of seeds per scenario.
        #[arg(long, default_value_t = 5)]
        seeds: u64,
    },
    /// Scale the fault sizes a, b, c of a scenario and print detection per channel for each scale.
    Sweep {
        /// Scenario name.
        name: String,
        /// Scale factors applied to every fault size.
        #[arg(long, value_delimiter = ',', default_value = "0.25,0.5,1,2,4")]
        factors: Vec<f64>,
        /// Number of seeds per factor.
        #[arg(long, default_value_t = 5)]
        seeds: u64,
        #[command(flatten)]
        detect: DetectOpts,
    },
    /// First detection of every fault row of one seed, in the same format as the QEMU image prints (for diffing host vs target).
    Detections {
        /// Scenario name.
        name: String,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Feed the monitor as the firmware does: the ICM-42688-P driver
        /// reading the emulated chip, into the periodic Monitor task.
        #[arg(long)]
        via_chip: bool,
    },
    /// Write a simulated run in the SPEC §10 replay format (with truth columns).
    Simulate {
        /// Scenario name.
        name: String,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output CSV.
        #[arg(long)]
        out: PathBuf,
    },
    /// Replay a SPEC §10 CSV through the monitor (default detector: run-time matrix + GLR).
    Replay {
        /// Input CSV.
        input: PathBuf,
        /// Per-row output CSV.
        #[arg(long)]
        out: Option<PathBuf>,
        /// JSON summary.
        #[arg(long)]
        summary: Option<PathBuf>,
        /// With truth columns: seconds after a fault during which flags are not false alarms (2·L).
        #[arg(long, default_value_t = 4.4)]
        grace: f64,
        /// With a CSV extract: its GNSS velocity file (see `convert`).
        #[arg(long)]
        gnss: Option<PathBuf>,
        /// With a CSV extract: its attitude file (see `convert`).
        #[arg(long)]
        att: Option<PathBuf>,
        /// Ignore rows before this time, s (start the monitor in flight).
        #[arg(long)]
        from: Option<f64>,
        /// Ignore rows after this time, s.
        #[arg(long)]
        to: Option<f64>,
        /// Fault table (TOML: `[sizes]` and `[[faults]]`, or a scenario file) to
        /// inject on top of the recorded IMU.
        #[arg(long)]
        faults: Option<PathBuf>,
        /// Added to the fault table's times (a scenario's table starts near 0 s).
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        fault_offset: f64,
        /// IMU instance the faults go on.
        #[arg(long, default_value_t = 0)]
        inject_imu: usize,
        /// Seed of injected noise (NoiseIncrease).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Tuning: sim (the S2/S3 scenarios'), flight (real logs: wide aiding
        /// noise, IMU noise measured on the log), auto (sim if the file has
        /// truth columns, else flight).
        #[arg(long, value_enum, default_value_t = ProfileArg::Auto)]
        profile: ProfileArg,
        /// Learning phase, s (flight default 20).
        #[arg(long)]
        learn: Option<f64>,
        /// Flight profile: aiding velocity σ, m/s.
        #[arg(long, default_value_t = 0.3)]
        vel_sigma: f64,
        /// Flight profile: attitude σ in degrees, one value or roll,pitch,yaw
        /// (an autopilot's own estimate is not independent of the IMU: keep it wide).
        #[arg(long, value_delimiter = ',', default_value = "1,1,10")]
        att_sigma_deg: Vec<f64>,
        #[command(flatten)]
        detect: DetectOpts,
    },
}

fn default_detector(name: &str) -> Detector {
    if name.eq_ignore_ascii_case("s1") {
        Detector::Threshold
    } else {
        Detector::RuntimeMatrixGlr
    }
}

fn options(name: &str, d: &DetectOpts) -> RunOptions {
    RunOptions {
        detector: d
            .detector
            .map_or_else(|| default_detector(name), Detector::from),
        statistic: match d.statistic {
            StatisticArg::Raw => Statistic::Raw,
            StatisticArg::Whitened => Statistic::Whitened,
            StatisticArg::Normalized => Statistic::Normalized,
        },
        alpha: d.alpha,
    }
}

fn campaign(scn: &Scenario, first: u64, seeds: u64, opts: &RunOptions) -> Result<RunMetrics> {
    let mut total = RunMetrics::default();
    for seed in first..first + seeds {
        let trace =
            run::<f32>(scn, seed, opts).map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
        total.merge(&evaluate(&trace));
    }
    Ok(total)
}

/// True when `path` reads as a CSV whose header has the SPEC §10 `t`
/// column (or cannot be read: `replay` then reports it); false for a CSV
/// extract that `convert` maps.
fn has_time_column(path: &std::path::Path) -> bool {
    hal_sim::log_import::open_csv(path).map_or(true, |(_, h)| h.iter().any(|c| c == "t"))
}

/// The S5 table: how each hardware fault row was seen over the seeds.
fn print_hardware(scn: &Scenario, first: u64, seeds: u64, opts: &RunOptions) -> Result<()> {
    let mut per_row: Vec<Vec<hal_sim::metrics::HardwareDetection>> = Vec::new();
    for seed in first..first + seeds {
        let t = run::<f32>(scn, seed, opts).map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
        for (i, d) in hal_sim::metrics::hardware_detections(&t)
            .into_iter()
            .enumerate()
        {
            if per_row.len() <= i {
                per_row.push(Vec::new());
            }
            if let Some(v) = per_row.get_mut(i) {
                v.push(d);
            }
        }
    }
    out!("hardware faults over {seeds} seeds (seen = a health flag, or a flag on the faulty channel, from onset to end + L):");
    out!("  fault                  ch  interval s     seen  delay mean/max s  by health  other-channel flag samples");
    for ds in &per_row {
        let Some(d0) = ds.first() else { continue };
        let delays: Vec<f64> = ds.iter().filter_map(|d| d.first_seen()).collect();
        let by_health = ds.iter().filter(|d| d.first_health.is_some()).count();
        let other: usize = ds.iter().map(|d| d.other_channel_samples).sum();
        let (mean, max) = if delays.is_empty() {
            ("-".to_string(), "-".to_string())
        } else {
            (
                format!("{:.2}", delays.iter().sum::<f64>() / delays.len() as f64),
                format!("{:.2}", delays.iter().copied().fold(0.0, f64::max)),
            )
        };
        out!(
            "  {:<22} {:<3} {:>5.1}-{:<5.1}  {:>3}/{:<3}  {:>6}/{:<6}     {:>3}/{:<3}  {}",
            d0.kind,
            d0.channel,
            d0.start,
            d0.end,
            delays.len(),
            ds.len(),
            mean,
            max,
            by_health,
            ds.len(),
            other
        );
    }
    Ok(())
}

fn scenario(name: &str) -> Result<Scenario> {
    hal_sim::scenario_file::load_scenario(name)
}

fn print_run(
    title: &str,
    scn: &Scenario,
    first: u64,
    seeds: u64,
    opts: &RunOptions,
) -> Result<RunMetrics> {
    let m = campaign(scn, first, seeds, opts)?;
    out!(
        "== {title}: {} seeds {}..{}, detector {:?}, statistic {:?}, α = {:e} (f32 monitor)",
        scn.name,
        first,
        first + seeds - 1,
        opts.detector,
        opts.statistic,
        opts.alpha
    );
    out_nl!("{}", m.table());
    out!();
    Ok(m)
}

fn parity_sweep<const N: usize>(
    spec: &hal_sim::array::ArraySpec<N>,
    runs: u32,
    hours: u32,
    first_seed: u64,
    json: Option<PathBuf>,
) -> Result<()> {
    use hal_sim::array_sweep::{default_sizes, format_sweep, sweep};
    if runs == 0 {
        return Err(anyhow!("--runs must be at least 1"));
    }
    let started = std::time::Instant::now();
    let sizes = default_sizes(spec.kind);
    let result = sweep(spec, &sizes, runs, hours, first_seed)?;
    out!(
        "{} {:?} array, {} sizes x {runs} runs, {hours} fault-free h ({:.1} s):",
        spec.name,
        spec.kind,
        sizes.len(),
        started.elapsed().as_secs_f64()
    );
    out_nl!("{}", format_sweep(spec.kind, &result, runs, hours));
    if let Some(p) = json {
        std::fs::write(&p, serde_json::to_string_pretty(&result)?)?;
        out!("wrote {}", p.display());
    }
    Ok(())
}

fn parity_replay_cmd(
    input: &std::path::Path,
    train_start: f64,
    train_s: f64,
    inject_at: &[f64],
) -> Result<()> {
    use hal_sim::array::ArrayKind;
    use hal_sim::parity_replay::{
        injection_sizes, injection_sweep, read_any_imu_log, replay_parity,
    };
    let log = read_any_imu_log(input)?;
    out!(
        "{}: {} rows, {} IMUs, t = {:.2}..{:.2} s, {} rows skipped (time not increasing, or unreadable tail)",
        input.display(),
        log.t.len(),
        log.count,
        log.t.first().copied().unwrap_or(0.0),
        log.t.last().copied().unwrap_or(0.0),
        log.skipped
    );
    let fmt = |v: &[(f64, f64, Option<usize>)]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|(a, b, k)| match k {
                    Some(k) => format!("{a:.2}-{b:.2} (sensor {k})"),
                    None => format!("{a:.2}-{b:.2}"),
                })
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
        let r = replay_parity(&log, kind, train_start, train_s, None)?;
        out!("{kind:?} (sensor = 3 x IMU + axis):");
        out!(
            "  monitoring from {:.2} s; threshold factors from calibration [GLT, PCA, CUSUM] = [{:.2}, {:.2}, {:.2}]; correlation factor {:.2}",
            r.monitoring_from.unwrap_or(f64::NAN),
            r.threshold_scales[0],
            r.threshold_scales[1],
            r.threshold_scales[2],
            r.correlation_factor
        );
        out!("  parity alarms: {}", fmt(&r.alarms));
        let iso: Vec<String> = r
            .isolations
            .iter()
            .map(|(k, t)| format!("sensor {k} at {t:.2}"))
            .collect();
        out!(
            "  isolations: {}",
            if iso.is_empty() {
                "none".into()
            } else {
                iso.join(", ")
            }
        );
        let st: Vec<String> = r
            .statuses
            .iter()
            .map(|(k, s, t)| format!("{k}:{s:?}@{t:.2}"))
            .collect();
        out!(
            "  statuses: {}",
            if st.is_empty() {
                "all healthy".into()
            } else {
                st.join(", ")
            }
        );
        out!("  common-mode saturation: {}", fmt(&r.saturation));
        out!("  PX4-like alarms: {}", fmt(&r.px4));
        out!("  ArduPilot-like alarms: {}", fmt(&r.ardupilot));
        if !inject_at.is_empty() {
            let (u, scale) = hal_sim::array_sweep::unit(kind);
            out!("  smallest injected bias detected within 15 s ({u}; delay s; * = isolated to the right sensor):");
            out!(
                "  {:>4} {:>4} {:>7} {:>16} {:>16} {:>16}",
                "imu",
                "axis",
                "onset",
                "parity",
                "PX4-like",
                "ArduPilot-like"
            );
            let sweep = injection_sweep(
                &log,
                kind,
                train_start,
                train_s,
                inject_at,
                &injection_sizes(kind),
            )?;
            let cell = |v: Option<(f64, f64)>, star: bool| {
                v.map_or("-".to_string(), |(s, d)| {
                    format!("{:.2}{} ({d:.1})", s * scale, if star { "*" } else { "" })
                })
            };
            for x in sweep {
                out!(
                    "  {:>4} {:>4} {:>7.1} {:>16} {:>16} {:>16}",
                    x.imu,
                    ["x", "y", "z"][x.axis],
                    x.onset,
                    cell(
                        x.parity.map(|(s, d, _)| (s, d)),
                        x.parity.is_some_and(|p| p.2)
                    ),
                    cell(x.px4, false),
                    cell(x.ardupilot, false)
                );
            }
        }
    }
    Ok(())
}

fn plot_scenario(
    name: &str,
    seed: u64,
    out: &std::path::Path,
    opts: &RunOptions,
    only: Option<&[hal_sim::plot::TraceFigure]>,
) -> Result<Vec<PathBuf>> {
    use hal_sim::plot::{plot_parity, plot_trace, TraceFigure as F};
    if name.eq_ignore_ascii_case("s4") {
        return plot_parity(
            &hal_sim::array::ArraySpec::s4(),
            seed,
            &out.join(format!("s4_seed{seed}_parity")),
        );
    }
    let scn = scenario(name)?;
    let trace =
        run::<f32>(&scn, seed, opts).map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
    let all = [
        F::FaultsAndFlags,
        F::Estimates,
        F::Innovations,
        F::Statistic,
    ];
    let mut files = Vec::new();
    for fig in only.unwrap_or(&all) {
        let tag = match fig {
            F::FaultsAndFlags => "faults_flags",
            F::Estimates => "estimates",
            F::Innovations => "innovations",
            F::Statistic => "statistic",
        };
        let stem = out.join(format!("{}_seed{seed}_{tag}", scn.name.as_str()));
        files.extend(plot_trace(&trace, *fig, &stem)?);
    }
    Ok(files)
}

fn finish_campaign(
    rows: &[hal_sim::campaign::CampaignRow],
    summary: &hal_sim::campaign::CampaignSummary,
    csv: Option<PathBuf>,
    json: Option<PathBuf>,
) -> Result<()> {
    if let Some(p) = csv {
        hal_sim::campaign::write_rows(&p, rows)?;
        out!("wrote {} rows to {}", rows.len(), p.display());
    }
    if let Some(p) = json {
        std::fs::write(&p, serde_json::to_string_pretty(summary)?)?;
        out!("wrote summary to {}", p.display());
    }
    Ok(())
}

fn parity_s4(first_seed: u64, seeds: u64) -> Result<()> {
    use hal_sim::array::ArraySpec;
    use hal_sim::array_run::{array_config, run_array};
    if seeds == 0 {
        return Err(anyhow!("--seeds must be at least 1"));
    }
    let spec = ArraySpec::s4();
    let deg = 180.0 / std::f64::consts::PI;
    out!("S4: cone6 gyros, +0.5 deg/s on sensor 5 from t = 6 s, manoeuvre from 1 s, seeds {first_seed}..{}", first_seed + seeds - 1);
    out!(
        "{:>5} {:>9} {:>9} {:>9} {:>12} {:>8} {:>8} {:>12}",
        "seed",
        "PCA s",
        "chi2 s",
        "CUSUM s",
        "isolated@s",
        "FA",
        "PX4/AP",
        "fused deg/s"
    );
    let (mut isolated_ok, mut fa_total) = (0, 0);
    for seed in first_seed..first_seed + seeds {
        let r = run_array::<f32, 6>(&spec, seed, array_config(&spec))?;
        let t = |o: &hal_sim::array_run::MethodOutcome| {
            o.first_alarm.map_or("-".to_string(), |t| format!("{t:.2}"))
        };
        let fa = r.pca.false_alarm_events + r.glt.false_alarm_events + r.cusum.false_alarm_events;
        fa_total += fa;
        if r.isolated.is_some_and(|(k, _)| k == 5) {
            isolated_ok += 1;
        }
        out!(
            "{seed:>5} {:>9} {:>9} {:>9} {:>12} {fa:>8} {:>8} {:>5.3}/{:<6.3}",
            t(&r.pca),
            t(&r.glt),
            t(&r.cusum),
            r.isolated
                .map_or("-".to_string(), |(k, t)| format!("{k}@{t:.2}")),
            format!(
                "{}/{}",
                if r.px4.first_alarm.is_some() {
                    "yes"
                } else {
                    "no"
                },
                if r.ardupilot.first_alarm.is_some() {
                    "yes"
                } else {
                    "no"
                }
            ),
            r.fused_vs_healthy_before_isolation.unwrap_or(f64::NAN) * deg,
            r.fused_vs_healthy_after_isolation.unwrap_or(f64::NAN) * deg,
        );
    }
    out!("isolated to sensor 5 in {isolated_ok}/{seeds} runs; false-alarm events before onset: {fa_total}");
    out!("(fused: RMS of fused rate minus the least squares of the truly healthy sensors, deg/s:");
    out!(" from onset to isolation / from 0.5 s after isolation)");
    Ok(())
}

/// The command line's changes to the S3 two-stage configuration
/// (`cargo sim otsukf`).
#[derive(Debug, Clone, Copy)]
struct OtsTuning {
    /// Multipliers of the accelerometer and gyro fault random walk.
    qf: [f64; 2],
    /// `adapt_gain` per channel.
    gain: Option<imu_fdi::model::ImuVec<f64>>,
    /// `adapt_k`.
    k: Option<f64>,
    /// `adapt_hold_s`.
    hold: Option<f64>,
    /// `adapt_level` (≤ 0: none).
    level: Option<f64>,
}

impl OtsTuning {
    /// The paper's or realistic configuration with these changes.
    fn config<T: imu_fdi::math::Real>(
        &self,
        scn: &hal_sim::Scenario,
        setting: hal_sim::ots::Setting,
    ) -> imu_fdi::monitor::OtsukfConfig<T> {
        let mut c = hal_sim::ots::otsukf_config::<T>(scn, setting);
        for (i, q) in c.fault_psd.iter_mut().enumerate() {
            *q *= T::lit(if i < 3 { self.qf[0] } else { self.qf[1] });
        }
        if let Some(g) = self.gain {
            c.adapt_gain = g.map(T::lit);
        }
        if let Some(k) = self.k {
            c.adapt_k = T::lit(k);
        }
        if let Some(h) = self.hold {
            c.adapt_hold_s = T::lit(h);
        }
        match self.level {
            Some(l) if l > 0.0 => c.adapt_level = Some(T::lit(l)),
            Some(_) => c.adapt_level = None,
            None => {}
        }
        c
    }

    /// Only the fault random walk: what the augmented UKF shares (it has
    /// no adaptation).
    fn fault_walk_only(&self) -> Self {
        Self {
            qf: self.qf,
            gain: None,
            k: None,
            hold: None,
            level: None,
        }
    }
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.cmd {
        Cmd::Parity { first_seed, seeds } => parity_s4(first_seed, seeds)?,
        Cmd::Convert {
            input,
            out,
            gnss,
            att,
        } => {
            let c = hal_sim::log_import::any_to_replay_csv(
                &input,
                gnss.as_deref(),
                att.as_deref(),
                &out,
            )?;
            out!(
                "converted {}: {} rows of {} IMU(s), t = {:.2}..{:.2} s ({:.1} Hz), {} rows with GNSS velocity, {} with attitude",
                input.display(),
                c.rows,
                c.imu_instances,
                c.span.0,
                c.span.1,
                c.imu_rate_hz,
                c.gnss_rows,
                c.att_rows
            );
            out!("wrote {}", out.display());
            if let Some(why) = &c.ended_early {
                out!("warning: the log parser stopped early ({why}); only the part before it was converted");
            }
        }
        Cmd::Plot {
            name,
            seed,
            out,
            detect,
        } => {
            std::fs::create_dir_all(&out)?;
            let files = plot_scenario(&name, seed, &out, &options(&name, &detect), None)?;
            out!("wrote {} files to {}:", files.len(), out.display());
            for f in files {
                out!("  {}", f.display());
            }
        }
        Cmd::Gallery { out } => {
            use hal_sim::plot::TraceFigure as F;
            std::fs::create_dir_all(&out)?;
            let mut files = Vec::new();
            for (name, figs) in [
                ("s1", vec![F::FaultsAndFlags, F::Statistic]),
                ("s2", vec![F::FaultsAndFlags, F::Estimates, F::Innovations]),
                ("s3", vec![F::Estimates]),
            ] {
                let opts = options(
                    name,
                    &DetectOpts {
                        detector: None,
                        statistic: StatisticArg::Normalized,
                        alpha: 1e-6,
                    },
                );
                files.extend(plot_scenario(name, 1, &out, &opts, Some(&figs))?);
            }
            files.extend(plot_scenario("s4", 1, &out, &RunOptions::default(), None)?);
            out!("gallery: wrote {} files to {}", files.len(), out.display());
            for f in files {
                out!("  {}", f.display());
            }
        }
        Cmd::Campaign {
            name,
            runs,
            seed,
            shard,
            csv,
            json,
            detect,
        } => {
            use hal_sim::campaign::{run_campaign, summarise};
            if runs == 0 {
                return Err(anyhow!("--runs must be at least 1"));
            }
            let scn = scenario(&name)?;
            let opts = options(&name, &detect);
            let started = std::time::Instant::now();
            let rows = run_campaign(&scn, runs, seed, shard, &opts)?;
            let secs = started.elapsed().as_secs_f64();
            let summary = summarise(&rows)?;
            out!(
                "campaign {name}, seed {seed}{}: {} runs in {secs:.1} s ({:.1} runs/s on {} threads)",
                shard.map_or(String::new(), |s| format!(", shard {}/{}", s.i, s.n)),
                rows.len(),
                rows.len() as f64 / secs.max(1e-9),
                rayon::current_num_threads()
            );
            out_nl!("{}", summary.table());
            finish_campaign(&rows, &summary, csv, json)?;
        }
        Cmd::Merge { inputs, csv, json } => {
            use hal_sim::campaign::{merge_files, summarise};
            let rows = merge_files(&inputs)?;
            let summary = summarise(&rows)?;
            out!("merged {} files: {} runs", inputs.len(), rows.len());
            out_nl!("{}", summary.table());
            finish_campaign(&rows, &summary, csv, json)?;
        }
        Cmd::ParityReplay {
            input,
            train_start,
            train_s,
            inject_at,
        } => parity_replay_cmd(&input, train_start, train_s, &inject_at)?,
        Cmd::ParitySweep {
            array,
            kind,
            runs,
            hours,
            first_seed,
            json,
        } => {
            use hal_sim::array::{
                cone6_directions, triad_directions, ArrayKind, ArraySpec, Layout,
            };
            use std::f64::consts::{FRAC_PI_2, PI};
            let kind = match kind {
                KindArg::Gyro => ArrayKind::Gyro,
                KindArg::Accel => ArrayKind::Accel,
            };
            match array {
                ArrayArg::Cone6 => parity_sweep(
                    &ArraySpec::fault_free("cone6", cone6_directions(), kind, Layout::Single, 0.0),
                    runs,
                    hours,
                    first_seed,
                    json,
                )?,
                ArrayArg::Triads2 => parity_sweep(
                    &ArraySpec::fault_free(
                        "triads2",
                        triad_directions::<6>(&[0.0, PI]),
                        kind,
                        Layout::Triads,
                        0.0,
                    ),
                    runs,
                    hours,
                    first_seed,
                    json,
                )?,
                ArrayArg::Triads3 => parity_sweep(
                    &ArraySpec::fault_free(
                        "triads3",
                        triad_directions::<9>(&[0.0, FRAC_PI_2, PI]),
                        kind,
                        Layout::Triads,
                        0.0,
                    ),
                    runs,
                    hours,
                    first_seed,
                    json,
                )?,
            }
        }
        Cmd::Scenario {
            name,
            seed,
            seeds,
            detect,
            json,
            trace,
        } => {
            // S4 is the redundant-sensor scenario: the parity monitor's run.
            if name.eq_ignore_ascii_case("s4") {
                return parity_s4(seed, seeds.max(1));
            }
            if name.eq_ignore_ascii_case("s6") {
                return Err(anyhow!(
                    "S6 is the real logs: `replay LOG.ulg|LOG.bin|LOG.csv [--faults TABLE.toml]` \
                     for the UKF monitor, `parity-replay` for redundant IMUs (see README, Real flight logs)"
                ));
            }
            let scn = scenario(&name)?;
            let opts = options(&name, &detect);
            if let Some(p) = trace {
                let t = run::<f32>(&scn, seed, &opts)
                    .map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
                t.write_csv(&p)?;
                out!("wrote trace of seed {seed} to {}", p.display());
            }
            let m = print_run("scenario", &scn, seed, seeds.max(1), &opts)?;
            if scn.faults.iter().any(|r| r.is_hardware()) {
                print_hardware(&scn, seed, seeds.max(1), &opts)?;
            }
            if let Some(p) = json {
                std::fs::write(&p, serde_json::to_string_pretty(&m)?)?;
                out!("wrote {}", p.display());
            }
        }
        Cmd::Demo { seeds } => {
            let seeds = seeds.max(1);
            let s1 = scenario("s1")?;
            let s2 = scenario("s2")?;
            let base = RunOptions::default();
            let a = print_run(
                "S1, threshold method",
                &s1,
                1,
                seeds,
                &RunOptions {
                    detector: Detector::Threshold,
                    ..base
                },
            )?;
            let b = print_run("S2, run-time matrix + GLR (default)", &s2, 1, seeds, &base)?;
            let c = print_run(
                "S2, paper's fixed matrix (erratum applied), for comparison",
                &s2,
                1,
                seeds,
                &RunOptions {
                    detector: Detector::PaperMatrix,
                    ..base
                },
            )?;
            out!(
                "summary: S1 false alarms {}, S2 false alarms {}, S2 paper-matrix false alarms {}",
                a.total_false_alarms(),
                b.total_false_alarms(),
                c.total_false_alarms()
            );
        }
        Cmd::Sweep {
            name,
            factors,
            seeds,
            detect,
        } => {
            let base = scenario(&name)?;
            let opts = options(&name, &detect);
            out!(
                "sweep of {}: fault sizes × factor, {} seeds each, detector {:?}, statistic {:?}",
                base.name,
                seeds,
                opts.detector,
                opts.statistic
            );
            out!(
                "{:>7}  {:>20}  {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}  {:>9} {:>8}",
                "factor",
                "sizes a,b,c (acc)",
                "ax",
                "ay",
                "az",
                "gx",
                "gy",
                "gz",
                "wrong.max",
                "FA.evts"
            );
            for f in factors {
                let mut scn = base.clone();
                for v in scn.sizes.accel.iter_mut().chain(scn.sizes.gyro.iter_mut()) {
                    *v *= f;
                }
                let m = campaign(&scn, 1, seeds.max(1), &opts)?;
                let cells: Vec<String> = m
                    .channels
                    .iter()
                    .map(|c| {
                        format!(
                            "{}/{} {}",
                            c.detected,
                            c.faults,
                            c.detection_rate()
                                .map_or("-".into(), |r| format!("{:.0}%", 100.0 * r))
                        )
                    })
                    .collect();
                let wrong = m
                    .channels
                    .iter()
                    .filter_map(|c| c.wrong_channel_rate())
                    .fold(0.0, f64::max);
                let a = scn.sizes.accel;
                out!(
                    "{:>7}  {:>20}  {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}  {:>8.2}% {:>8}",
                    f,
                    format!("{:.3},{:.3},{:.2}", a[0], a[1], a[2]),
                    cells[0],
                    cells[1],
                    cells[2],
                    cells[3],
                    cells[4],
                    cells[5],
                    100.0 * wrong,
                    m.false_alarm_events
                );
            }
            out!("detection rate counted where |fault| ≥ the scenario's minimum (0.1 m/s², 0.5 °/s) from L after it is reached");
        }
        Cmd::Otsukf {
            name,
            first_seed,
            seeds,
            augmented,
            f32,
            adapt_gain,
            adapt_k,
            adapt_hold,
            adapt_level,
            qf_scale,
            fault_free,
            shape,
        } => {
            use hal_sim::ots::{run_augmented, run_otsukf, RmseAccumulator, Setting, PAPER_RMSE};
            use imu_fdi::model::ImuVec;
            let mut scn = scenario(&name)?;
            if fault_free {
                scn.faults.clear();
            }
            if let Some(shape) = shape.as_deref() {
                let kind = match shape.to_ascii_uppercase().as_str() {
                    "F1" => hal_sim::FaultKind::F1,
                    "F2" => hal_sim::FaultKind::F2,
                    "F3" => hal_sim::FaultKind::F3,
                    other => return Err(anyhow!("--shape {other}: expected F1, F2 or F3")),
                };
                scn.faults.retain(|r| r.kind == kind);
            }
            if seeds == 0 {
                return Err(anyhow!("--seeds must be at least 1"));
            }
            let setting = if name.contains("paper") {
                Setting::Paper
            } else {
                Setting::Realistic
            };
            let qf = match qf_scale.as_deref() {
                None => [1.0, 1.0],
                Some([a, g]) if *a > 0.0 && *g > 0.0 => [*a, *g],
                Some(_) => return Err(anyhow!("--qf-scale needs two positive numbers")),
            };
            let adapt_gain = match adapt_gain.as_deref() {
                None => None,
                Some(g) if g.iter().any(|v| !v.is_finite() || *v < 1.0) => {
                    return Err(anyhow!("--adapt-gain values must be at least 1"))
                }
                Some([g]) => Some(ImuVec::from_element(*g)),
                Some(g) if g.len() == 6 => Some(ImuVec::from_row_slice(g)),
                Some(_) => return Err(anyhow!("--adapt-gain takes one value or six")),
            };
            let tuning = OtsTuning {
                qf,
                gain: adapt_gain,
                k: adapt_k,
                hold: adapt_hold,
                level: adapt_level,
            };
            let (mut two, mut aug) = (RmseAccumulator::default(), RmseAccumulator::default());
            let mut false_flags = 0u64;
            for seed in first_seed..first_seed + seeds {
                let (acc, ff) = if f32 {
                    run_otsukf::<f32>(&scn, seed, tuning.config(&scn, setting))
                } else {
                    run_otsukf::<f64>(&scn, seed, tuning.config(&scn, setting))
                }
                .ok_or_else(|| anyhow!("the two-stage monitor refused its configuration"))?;
                two.merge(&acc);
                false_flags += ff;
                if augmented {
                    let c = tuning.fault_walk_only().config::<f64>(&scn, setting);
                    let a = run_augmented(&scn, seed, &c)
                        .ok_or_else(|| anyhow!("augmented UKF failed"))?;
                    aug.merge(&a);
                }
            }
            out!(
                "{} — SPEC §9 RMSE over seeds {}..{} (states over fault-active samples; each fault over its own)",
                scn.name,
                first_seed,
                first_seed + seeds - 1
            );
            out!("units: u v w m/s; φ θ ψ deg; f_a m/s²; f_g °/s");
            out!(
                "{:<6} {:>12} {:>12} {:>10}",
                "",
                "two-stage",
                if augmented { "augmented" } else { "" },
                "paper"
            );
            let names = [
                "u", "v", "w", "φ", "θ", "ψ", "f_ax", "f_ay", "f_az", "f_p", "f_q", "f_r",
            ];
            let (r2, ra) = (two.rmse(), aug.rmse());
            for i in 0..12 {
                if augmented {
                    out!(
                        "{:<6} {:>12.4} {:>12.4} {:>10.4}",
                        names[i],
                        r2[i],
                        ra[i],
                        PAPER_RMSE[i]
                    );
                } else {
                    out!(
                        "{:<6} {:>12.4} {:>12} {:>10.4}",
                        names[i],
                        r2[i],
                        "",
                        PAPER_RMSE[i]
                    );
                }
            }
            let (q2, qa) = (two.quiet_rms(), aug.quiet_rms());
            out!("fault-free noise: RMS of each fault estimate before its channel's first fault");
            for c in 0..6 {
                if augmented {
                    out!("{:<6} {:>12.4} {:>12.4}", names[6 + c], q2[c], qa[c]);
                } else {
                    out!("{:<6} {:>12.4}", names[6 + c], q2[c]);
                }
            }
            out!("false flags (monitoring samples flagged on a channel without a fault in the last 2 s): {false_flags}");
        }
        Cmd::Detections {
            name,
            seed,
            via_chip: true,
        } => {
            let scn = scenario(&name)?;
            let tally = hal_sim::setup::run_via_chip(&scn, seed, |step| step())
                .ok_or_else(|| anyhow!("the driver or the monitor refused to start"))?;
            tally.print(|line| out!("{line}"));
        }
        Cmd::Detections {
            name,
            seed,
            via_chip: false,
        } => {
            let scn = scenario(&name)?;
            let opts = options(
                &name,
                &DetectOpts {
                    detector: None,
                    statistic: StatisticArg::Normalized,
                    alpha: 1e-6,
                },
            );
            let cfg = monitor_config::<f32>(&scn, &opts);
            let mut monitor = imu_fdi::monitor::UkfMonitor::<f32>::new(cfg)
                .map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
            let mut tally = hal_sim::setup::DetectionTally::new(&scn);
            for s in hal_sim::Simulator::new(&scn, seed) {
                let u =
                    imu_fdi::model::ImuVec::from_fn(|i, _| s.imu.map_or(f32::NAN, |v| v[i] as f32));
                let z = imu_fdi::model::MeasVec::from_fn(|i, _| s.aiding[i] as f32);
                let r = monitor.step(
                    &u,
                    s.dt as f32,
                    &imu_fdi::model::Measurement {
                        z,
                        available: s.aiding_available,
                    },
                );
                tally.record(&s, &r);
            }
            tally.print(|line| out!("{line}"));
        }
        Cmd::Simulate { name, seed, out } => {
            let scn = scenario(&name)?;
            let n = hal_sim::replay::write_simulated(&scn, seed, &out)?;
            out!(
                "wrote {n} rows of {} (seed {seed}) to {}",
                scn.name,
                out.display()
            );
        }
        Cmd::Replay {
            input,
            out,
            summary,
            grace,
            gnss,
            att,
            from,
            to,
            faults,
            fault_offset,
            inject_imu,
            seed,
            profile,
            learn,
            vel_sigma,
            att_sigma_deg,
            detect,
        } => {
            let ropts = options("replay", &detect);
            let sim_cfg = |kind: AidingKind| {
                let scn = match kind {
                    AidingKind::DvlCompass => Scenario::s2(),
                    AidingKind::GnssAttitude => Scenario::s3(),
                };
                let mut c: UkfMonitorConfig<f64> = monitor_config(&scn, &ropts);
                c.detector = ropts.detector;
                c
            };
            let deg = std::f64::consts::PI / 180.0;
            let att_sigma = match att_sigma_deg.as_slice() {
                [a] => [a * deg, a * deg, a * deg],
                [r, p, y] => [r * deg, p * deg, y * deg],
                _ => {
                    return Err(anyhow!(
                        "--att-sigma-deg takes one value or three (roll,pitch,yaw)"
                    ))
                }
            };
            let inject = match faults {
                Some(f) => Some((
                    hal_sim::inject::FaultTable::read(&f)?.shifted(fault_offset),
                    inject_imu,
                )),
                None => None,
            };
            let opts = hal_sim::replay::ReplayOptions {
                grace_s: grace,
                from_s: from,
                to_s: to,
                inject,
                seed,
                profile: profile.into(),
                learn_s: learn,
                vel_sigma,
                att_sigma,
            };
            // A flight log is converted to the SPEC §10 CSV first.
            let is_log = input
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("ulg") || e.eq_ignore_ascii_case("bin"))
                || gnss.is_some()
                || att.is_some()
                || !has_time_column(&input);
            let original = input.clone();
            let input = if is_log {
                let csv = std::env::temp_dir().join(format!(
                    "imu-fdi-{}-{}.csv",
                    std::process::id(),
                    input.file_stem().and_then(|s| s.to_str()).unwrap_or("log")
                ));
                let c = hal_sim::log_import::any_to_replay_csv(
                    &input,
                    gnss.as_deref(),
                    att.as_deref(),
                    &csv,
                )?;
                out!(
                    "converted {}: {} rows of {} IMU(s) at {:.1} Hz, {} with GNSS velocity, {} with attitude",
                    input.display(),
                    c.rows,
                    c.imu_instances,
                    c.imu_rate_hz,
                    c.gnss_rows,
                    c.att_rows
                );
                if let Some(why) = &c.ended_early {
                    out!("warning: the log parser stopped early ({why}); only the part before it was converted");
                }
                csv
            } else {
                input
            };
            let result =
                hal_sim::replay::replay(&input, out.as_deref(), summary.as_deref(), sim_cfg, &opts);
            if is_log {
                // The converted CSV was only an intermediate (`convert` keeps one).
                let _ = std::fs::remove_file(&input);
            }
            let s = result.map_err(|e| {
                if is_log {
                    anyhow!("{} (after conversion): {e:#}", original.display())
                } else {
                    e
                }
            })?;
            out!(
                "replayed {} rows ({} skipped, {} IMU rows rejected) of {} IMU(s) at {:.1} Hz, t = {:.2}..{:.2} s; aiding {}, profile {}, monitoring from {:?} s ({} samples)",
                s.rows,
                s.skipped_rows,
                s.rejected_imu_rows,
                s.imus,
                s.imu_rate_hz,
                s.span_s.0,
                s.span_s.1,
                s.aiding,
                s.profile,
                s.monitoring_from_s,
                s.monitored_samples
            );
            for c in &s.channels {
                let scored = match (c.fault_samples, c.correct_samples, c.false_alarm_samples) {
                    (Some(f), Some(ok), Some(fa)) => format!(
                        "; fault samples {f}, correct {ok}, first correct {:?} s, false-alarm samples {fa}",
                        c.first_correct_s
                    ),
                    _ => String::new(),
                };
                let common = if s.imus >= 2 {
                    format!(
                        " ({} on every IMU at once: aiding/model)",
                        c.common_mode_samples
                    )
                } else {
                    String::new()
                };
                out!(
                    "  {:<8} flagged {:>6} samples{common}, first at {:?} s{scored}",
                    c.channel,
                    c.flagged_samples,
                    c.first_detection_s
                );
            }
            if let Some(p) = out {
                out!("wrote {}", p.display());
            }
            if let Some(p) = summary {
                out!("wrote {}", p.display());
            }
        }
    }
    Ok(())
}

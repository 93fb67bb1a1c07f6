//! `imu-fdi-sim replay`: a SPEC §10 CSV, ULog or DataFlash log through a single-IMU monitor (`--monitor ukf|otsukf`), one output format for both.

use std::path::PathBuf;

use anyhow::{anyhow, Result};
use clap::ValueEnum;
use hal_sim::runner::monitor_config;
use hal_sim::Scenario;
use imu_fdi::model::AidingKind;
use imu_fdi::monitor::UkfMonitorConfig;

use super::{options, DetectOpts};

// The arguments of `replay` (its help text is the doc comment on `Cmd::Replay`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Input CSV.
    input: PathBuf,
    /// Per-row output CSV.
    #[arg(long)]
    out: Option<PathBuf>,
    /// JSON summary.
    #[arg(long)]
    summary: Option<PathBuf>,
    /// The monitor run on every IMU: the UKF innovation monitor or the
    /// optimal two-stage UKF (OTSUKF). Same output for both.
    #[arg(long, value_enum, default_value_t = MonitorArg::Ukf)]
    monitor: MonitorArg,
    /// Bound of the UKF monitor's learned innovation inflation (1: off;
    /// default 25 for the flight profile, 1 for the simulated one).
    #[arg(long)]
    max_inflation: Option<f64>,
    /// Memory of the UKF monitor's learned inflation in flight, s (0: frozen
    /// at the end of learning; default 120 for the flight profile, 0 for
    /// the simulated one). A window more active than what it was learnt at
    /// is learnt, not judged by the UKF's own test.
    #[arg(long)]
    inflation_memory: Option<f64>,
    /// Print the JSON summary (one object) on stdout; the human-readable
    /// lines go to stderr.
    #[arg(long)]
    json: bool,
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
    /// UKF monitor: latency of the aiding, seconds (fused against the
    /// state of its own time, PX4 EKF2-style delayed fusion), or `auto` to
    /// estimate it online from the attitude aiding (up to 32 IMU periods
    /// minus the attitude interval). OTSUKF: the attitude aiding's latency
    /// (brought to now by the gyro's change over it), or `auto` (estimated
    /// online, up to 32 IMU periods); the GNSS velocity's is `--velocity-lag`.
    #[arg(long, value_parser = parse_delay, default_value = "0")]
    aiding_delay: imu_fdi_cli::eval::replay::AidingDelay,
    /// UKF monitor: `auto` learns a constant heading offset between the
    /// attitude aiding and the IMU (±10°, 20 s time constant); `off` trusts
    /// the aiding's yaw.
    #[arg(long, value_enum, default_value_t = HeadingArg::Off)]
    heading_offset: HeadingArg,
    /// Latency of the velocity aiding alone (GNSS/DVL columns), seconds, or
    /// `auto` to fit it (0–0.5 s) on each IMU's learning span from the
    /// velocity changes against the integrated specific force. Each velocity
    /// sample is then fused at the row it describes. Either monitor.
    #[arg(long, value_parser = parse_delay, default_value = "0")]
    velocity_delay: imu_fdi_cli::eval::replay::AidingDelay,
    /// Latency of the GNSS velocity that the monitor compensates itself,
    /// causally, seconds, or `auto` to fit it as `--velocity-delay auto`
    /// does, on each IMU's learning span (flight profile with GNSS aiding;
    /// 0 otherwise). OTSUKF: each velocity brought to the present by the
    /// IMU-propagated change over the lag; `auto` by default. UKF monitor:
    /// the velocity's own latency in the core (`velocity_delay_s`: brought
    /// to the attitude's fusion horizon, `--aiding-delay`, by the state
    /// history; at most 32 IMU periods); without the option it shares the
    /// attitude's latency. Unlike `--velocity-delay` (which re-times the
    /// log's rows, offline) this is what firmware can do.
    #[arg(long, value_parser = parse_delay)]
    velocity_lag: Option<imu_fdi_cli::eval::replay::AidingDelay>,
    /// Flight profile, either monitor: the gyro/attitude-aiding consistency
    /// test (the gyro integrated between attitude epochs against the
    /// aiding's rotation over 2.5–10 s windows, their spread learnt on the
    /// flight); `off` leaves the gyros to the innovation windows alone.
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    attitude_rate: OnOff,
    /// Flight profile, either monitor: the accelerometer/GNSS-velocity
    /// consistency test (the specific force rotated by the attitude aiding
    /// and integrated between GNSS velocity epochs, at a GNSS lag learnt on
    /// the flight, against the velocity change over 3–10 s windows); `off`
    /// leaves the accelerometers to the innovation windows alone.
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    velocity_increment: OnOff,
    /// Flight profile: the largest nominal bias the monitor may learn, as
    /// `ACCEL_XY,ACCEL_Z,GYRO` in m/s² and °/s (or `ACCEL,GYRO`) — the
    /// turn-on bias a calibrated IMU can carry against its aiding. A bias
    /// beyond it present from power-up is reported as a fault at
    /// monitoring start instead of absorbed (the simulated profile takes
    /// 20 × `min_fault`).
    #[arg(long, value_delimiter = ',', default_value = "1.5,3,5")]
    turn_on_bias: Vec<f64>,
    #[command(flatten)]
    detect: DetectOpts,
}

/// `--attitude-rate`, `--velocity-increment`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum OnOff {
    On,
    Off,
}

/// `--heading-offset`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum HeadingArg {
    Off,
    Auto,
}

/// `--aiding-delay SECONDS|auto`.
fn parse_delay(s: &str) -> Result<imu_fdi_cli::eval::replay::AidingDelay, String> {
    use imu_fdi_cli::eval::replay::AidingDelay;
    if s.eq_ignore_ascii_case("auto") {
        return Ok(AidingDelay::Auto);
    }
    match s.parse::<f64>() {
        Ok(d) if d.is_finite() && d >= 0.0 => Ok(AidingDelay::Fixed(d)),
        _ => Err(format!(
            "'{s}' is neither a delay in seconds (≥ 0) nor 'auto'"
        )),
    }
}

/// Runs `replay`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        input,
        out,
        summary,
        monitor,
        max_inflation,
        inflation_memory,
        json,
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
        aiding_delay,
        heading_offset,
        velocity_delay,
        velocity_lag,
        attitude_rate,
        velocity_increment,
        turn_on_bias,
        detect,
    } = args;
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
            imu_fdi_cli::eval::inject::FaultTable::read(&f)?.shifted(fault_offset),
            inject_imu,
        )),
        None => None,
    };
    let positive = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x > 0.0);
    let opts = imu_fdi_cli::eval::replay::ReplayOptions {
        grace_s: grace,
        from_s: from,
        to_s: to,
        inject,
        seed,
        profile: profile.into(),
        learn_s: learn,
        vel_sigma,
        att_sigma,
        monitor: monitor.into(),
        max_inflation,
        inflation_memory,
        aiding_delay,
        estimate_heading_offset: heading_offset == HeadingArg::Auto,
        velocity_delay,
        velocity_lag,
        attitude_rate: attitude_rate == OnOff::On,
        velocity_increment: velocity_increment == OnOff::On,
        turn_on_bias: match turn_on_bias.as_slice() {
            [a, g] if positive(&[*a, *g]) => [*a, *a, g * deg],
            [a, z, g] if positive(&[*a, *z, *g]) => [*a, *z, g * deg],
            _ => {
                return Err(anyhow!(
                    "--turn-on-bias takes two or three positive values: \
                     ACCEL_XY,ACCEL_Z,GYRO (m/s², m/s², °/s) or ACCEL,GYRO"
                ))
            }
        },
    };
    // With --json, stdout carries only the JSON object.
    macro_rules! note {
        ($($arg:tt)*) => {{
            if json {
                eprintln!($($arg)*);
            } else {
                out!($($arg)*);
            }
        }};
    }
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
        let c = imu_fdi_cli::io::log_import::any_to_replay_csv(
            &input,
            gnss.as_deref(),
            att.as_deref(),
            &csv,
        )?;
        note!(
                "converted {}: {} rows of {} IMU(s) at {:.1} Hz, {} with GNSS velocity, {} with attitude",
                input.display(),
                c.rows,
                c.imu_instances,
                c.imu_rate_hz,
                c.gnss_rows,
                c.att_rows
            );
        if let Some(why) = &c.ended_early {
            eprintln!("warning: {why}");
        }
        csv
    } else {
        input
    };
    let result = imu_fdi_cli::eval::replay::replay(
        &input,
        out.as_deref(),
        summary.as_deref(),
        sim_cfg,
        &opts,
    );
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
    for why in s.ended_early.iter().chain(&s.corrupt_cells) {
        eprintln!("warning: {why}");
    }
    note!(
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
        note!(
            "  {:<8} flagged {:>6} samples in {} events{common}, first at {:?} s{scored}",
            c.channel,
            c.flagged_samples,
            c.flag_events,
            c.first_detection_s
        );
    }
    if !s.aiding_delay_s.is_empty() {
        note!(
            "  aiding delay ({}): {} s; heading offset ({}): {}°",
            s.aiding_delay_mode.as_deref().unwrap_or("fixed"),
            joined(&s.aiding_delay_s, 3),
            if s.heading_offset_estimated {
                "estimated"
            } else {
                "off"
            },
            joined(&s.heading_offset_deg, 2)
        );
    }
    note!(
        "  velocity aiding delay ({}): {} s",
        s.velocity_delay_mode,
        joined(&s.velocity_delay_s, 3)
    );
    if !s.ukf_velocity_lag_s.is_empty() {
        note!(
            "  UKF velocity lag compensated: {} s",
            joined(&s.ukf_velocity_lag_s, 3)
        );
    }
    if !s.otsukf_velocity_lag_s.is_empty() {
        note!(
            "  OTSUKF velocity lag compensated: {} s",
            joined(&s.otsukf_velocity_lag_s, 3)
        );
    }
    if let Some(p) = out {
        note!("wrote {}", p.display());
    }
    if let Some(p) = summary {
        note!("wrote {}", p.display());
    }
    if json {
        out!("{}", serde_json::to_string(&s)?);
    }
    Ok(())
}

/// The monitor `replay` runs.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum MonitorArg {
    Ukf,
    Otsukf,
}

impl From<MonitorArg> for imu_fdi_cli::eval::replay_monitor::MonitorKind {
    fn from(m: MonitorArg) -> Self {
        match m {
            MonitorArg::Ukf => Self::Ukf,
            MonitorArg::Otsukf => Self::Otsukf,
        }
    }
}

/// Replay tuning profile.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ProfileArg {
    Sim,
    Flight,
    Auto,
}

impl From<ProfileArg> for imu_fdi_cli::eval::replay::Profile {
    fn from(p: ProfileArg) -> Self {
        match p {
            ProfileArg::Sim => Self::Sim,
            ProfileArg::Flight => Self::Flight,
            ProfileArg::Auto => Self::Auto,
        }
    }
}

/// True when `path` reads as a CSV whose header has the SPEC §10 `t`
/// column (or cannot be read: `replay` then reports it); false for a CSV
/// extract that `convert` maps.
pub(crate) fn has_time_column(path: &std::path::Path) -> bool {
    imu_fdi_cli::io::log_import::open_csv(path).map_or(true, |(_, h)| h.iter().any(|c| c == "t"))
}

/// The values, `decimals` after the point, comma-separated (the text
/// summary's per-IMU lists).
fn joined(v: &[f64], decimals: usize) -> String {
    v.iter()
        .map(|x| format!("{x:.decimals$}"))
        .collect::<Vec<_>>()
        .join(", ")
}

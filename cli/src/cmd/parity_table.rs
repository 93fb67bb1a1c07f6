//! `imu-fdi-sim parity-table`: the issue-14 step table of a multi-IMU log.

use std::path::PathBuf;

use anyhow::{bail, Result};

use hal_sim::array::ArrayKind;
use imu_fdi_cli::eval::parity_replay::{
    format_step_table, power_up_table, read_any_imu_log, step_table, ParityMethod,
};

// The arguments of `parity-table` (help on `Cmd::ParityTable` in main.rs).
#[derive(clap::Args)]
pub(crate) struct Args {
    input: PathBuf,
    /// gyro or accel.
    #[arg(long, default_value = "gyro")]
    kind: String,
    /// Step size, °/s (gyro) or m/s² (accel).
    #[arg(long)]
    size: f64,
    /// Training starts, s of the log (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "60,70,80,90,100")]
    train_starts: Vec<f64>,
    /// Training length, s.
    #[arg(long, default_value_t = 30.0)]
    train_s: f64,
    /// Onsets, s after monitoring starts (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "5,25,45,65,85,105")]
    onsets: Vec<f64>,
    /// Step length, s.
    #[arg(long, default_value_t = 15.0)]
    duration: f64,
    /// End of the judged part of the log, s (log171: the crash at 239 s).
    #[arg(long, default_value_t = 239.0)]
    end: f64,
    /// Instead of steps: the bias present from the first row (a fault at
    /// power-up), isolated within 10 s of monitoring start.
    #[arg(long)]
    power_up: bool,
    /// The multi-scale tests' per-decision false-alarm probability
    /// (default: the flight configuration's, 1e-6).
    #[arg(long)]
    false_alarm: Option<f64>,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `parity-table`.
pub(crate) fn run(a: Args) -> Result<()> {
    let _progress = super::progress::spinner("parity-table: replaying the log per case");
    let kind = match a.kind.as_str() {
        "gyro" => ArrayKind::Gyro,
        "accel" => ArrayKind::Accel,
        other => bail!("--kind: '{other}' is not gyro or accel"),
    };
    if !a.size.is_finite() || a.size <= 0.0 {
        bail!("--size must be a positive number, got {}", a.size);
    }
    let method = match a.false_alarm {
        None => ParityMethod::Flight,
        Some(p) if p > 0.0 && p < 0.5 => ParityMethod::FlightAt(p),
        Some(p) => bail!("--false-alarm: {p} is not a probability in (0, 0.5)"),
    };
    let size = match kind {
        ArrayKind::Gyro => a.size.to_radians(),
        ArrayKind::Accel => a.size,
    };
    let log = read_any_imu_log(&a.input)?;
    for w in &log.warnings {
        eprintln!("warning: {w}");
    }
    // Sizes in the unit the user gave (°/s or m/s²).
    let (unit, scale) = match kind {
        ArrayKind::Gyro => ("deg_s", 180.0 / std::f64::consts::PI),
        ArrayKind::Accel => ("m_s2", 1.0),
    };
    let inj = |i: &imu_fdi_cli::eval::parity_replay::Injection| {
        serde_json::json!({
            "imu": i.imu,
            "channel": imu_fdi::model::CHANNEL_NAMES.get(i.channel).copied().unwrap_or("?"),
            format!("size_{unit}"): i.size * scale,
            "onset_s": i.start,
            "end_s": i.end.is_finite().then_some(i.end),
        })
    };
    let kind_name = if kind == ArrayKind::Gyro {
        "gyro"
    } else {
        "accel"
    };
    if a.power_up {
        let cases = power_up_table(&log, kind, size, &a.train_starts, a.train_s, a.end, method)?;
        let ok = cases.iter().filter(|c| c.delay.is_some()).count();
        let wrong = cases.iter().filter(|c| c.wrong_isolation).count();
        if a.json {
            let rows: Vec<serde_json::Value> = cases
                .iter()
                .map(|c| {
                    serde_json::json!({
                        "train_start_s": c.train_start,
                        "injection": inj(&c.injection),
                        "delay_s": c.delay,
                        "wrong_isolation": c.wrong_isolation,
                    })
                })
                .collect();
            super::json::emit(&serde_json::json!({
                "kind": kind_name,
                "power_up": true,
                "isolated": ok,
                "wrong_isolations": wrong,
                "cases": rows,
            }));
            return Ok(());
        }
        out!(
            "{kind_name} bias {} {} from power-up: {ok}/{} isolated within 10 s of monitoring start; {wrong} cases named a healthy sensor",
            a.size,
            if kind == ArrayKind::Gyro { "°/s" } else { "m/s²" },
            cases.len()
        );
        return Ok(());
    }
    let cases = step_table(
        &log,
        kind,
        size,
        &a.train_starts,
        a.train_s,
        &a.onsets,
        a.duration,
        a.end,
        method,
    )?;
    if a.json {
        let rows: Vec<serde_json::Value> = cases
            .iter()
            .map(|c| {
                serde_json::json!({
                    "train_start_s": c.train_start,
                    "injection": inj(&c.injection),
                    "isolated": c.isolated,
                    "delay_s": c.delay,
                    "false_alarm": c.false_alarm,
                })
            })
            .collect();
        super::json::emit(&serde_json::json!({
            "kind": kind_name,
            "power_up": false,
            "isolated": cases.iter().filter(|c| c.isolated).count(),
            "false_alarms": cases.iter().filter(|c| c.false_alarm).count(),
            "cases": rows,
        }));
        return Ok(());
    }
    out!(
        "{}",
        format_step_table(kind, size, &cases, a.end).trim_end()
    );
    Ok(())
}

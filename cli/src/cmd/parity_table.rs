//! `imu-fdi-sim parity-table`: the issue-14 step table of a multi-IMU log.

use std::path::PathBuf;

use anyhow::{bail, Result};

use hal_sim::array::ArrayKind;
use imu_fdi_cli::eval::parity_replay::{
    format_step_table, power_up_table, read_any_imu_log, step_table,
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
}

/// Runs `parity-table`.
pub(crate) fn run(a: Args) -> Result<()> {
    let kind = match a.kind.as_str() {
        "gyro" => ArrayKind::Gyro,
        "accel" => ArrayKind::Accel,
        other => bail!("--kind: '{other}' is not gyro or accel"),
    };
    if !a.size.is_finite() || a.size <= 0.0 {
        bail!("--size must be a positive number, got {}", a.size);
    }
    let size = match kind {
        ArrayKind::Gyro => a.size.to_radians(),
        ArrayKind::Accel => a.size,
    };
    let log = read_any_imu_log(&a.input)?;
    for w in &log.warnings {
        eprintln!("warning: {w}");
    }
    if a.power_up {
        let cases = power_up_table(&log, kind, size, &a.train_starts, a.train_s, a.end)?;
        let ok = cases.iter().filter(|c| c.delay.is_some()).count();
        let wrong = cases.iter().filter(|c| c.wrong_isolation).count();
        out!(
            "{kind:?} bias {} from power-up: {ok}/{} isolated within 10 s of monitoring start; {wrong} cases named a healthy sensor",
            a.size,
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
    )?;
    out!(
        "{}",
        format_step_table(kind, size, &cases, a.end).trim_end()
    );
    Ok(())
}

//! `imu-fdi-sim convert`: Converts a flight log to the SPEC §10 replay CSV: a PX4 ULog (.ulg: primary IMU from sensor_combined, GNSS velocity with a 3-D fix, attitude quaternion -> Euler) or an ArduPilot DataFlash log (.bin: IMU/IMU2/IMU3, GPS velocity with a 3-D fix, ATT).

use std::path::PathBuf;

use anyhow::Result;

// The arguments of `convert` (its help text is the doc comment on `Cmd::Convert`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    input: PathBuf,
    #[arg(long)]
    out: PathBuf,
    /// GNSS velocity CSV of a CSV extract (time_s, vel_n_m_s, …).
    #[arg(long)]
    gnss: Option<PathBuf>,
    /// Attitude CSV of a CSV extract (time_s, q_w… or roll_deg…).
    #[arg(long)]
    att: Option<PathBuf>,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `convert`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        input,
        out,
        gnss,
        att,
        json,
    } = args;
    let c = imu_fdi_cli::io::log_import::any_to_replay_csv(
        &input,
        gnss.as_deref(),
        att.as_deref(),
        &out,
    )?;
    if let Some(why) = &c.ended_early {
        eprintln!("warning: {why}");
    }
    if json {
        super::json::emit(&serde_json::json!({
            "input": input.display().to_string(),
            "output": out.display().to_string(),
            "rows": c.rows,
            "imus": c.imu_instances,
            "start_s": c.span.0,
            "end_s": c.span.1,
            "imu_rate_hz": c.imu_rate_hz,
            "gnss_rows": c.gnss_rows,
            "attitude_rows": c.att_rows,
            "ended_early": c.ended_early,
        }));
        return Ok(());
    }
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
    Ok(())
}

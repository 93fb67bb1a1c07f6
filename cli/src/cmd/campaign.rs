//! `imu-fdi-sim campaign`: Monte-Carlo campaign: N seeded runs of a scenario, each with one random fault (onset, channel, shape, sign, size), in parallel over all cores; prints detection rate, false alarms per hour, delay, isolation accuracy and RMSE with 95 % intervals.

use std::path::PathBuf;

use anyhow::{anyhow, Result};

use super::{options, scenario, DetectOpts};

// The arguments of `campaign` (its help text is the doc comment on `Cmd::Campaign`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Built-in scenario whose vehicle, sensors and aiding are used.
    #[arg(default_value = "s2")]
    name: String,
    #[arg(long, default_value_t = 1000)]
    runs: u64,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Only this machine's share: i/n takes runs k with k mod n = i - 1.
    #[arg(long)]
    shard: Option<imu_fdi_cli::eval::campaign::Shard>,
    /// Per-run rows (CSV), the input of `merge`.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// One JSON object on stdout instead of text (docs/cli-json.md); with
    /// a FILE, the text as usual and the object written to FILE.
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    json: Option<PathBuf>,
    #[command(flatten)]
    detect: DetectOpts,
}

/// Runs `campaign`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        name,
        runs,
        seed,
        shard,
        csv,
        json,
        detect,
    } = args;
    use imu_fdi_cli::eval::campaign::{run_campaign, summarise};
    if runs == 0 {
        return Err(anyhow!("--runs must be at least 1"));
    }
    let scn = scenario(&name)?;
    let opts = options(&name, &detect);
    let started = std::time::Instant::now();
    let rows = run_campaign(&scn, runs, seed, shard, &opts)?;
    let secs = started.elapsed().as_secs_f64();
    let summary = summarise(&rows)?;
    let v = serde_json::json!({
        "scenario": name,
        "seed": seed,
        "shard": shard.map(|s| format!("{}/{}", s.i, s.n)),
        "elapsed_s": secs,
        "threads": rayon::current_num_threads(),
        "summary": super::json::campaign_summary(&summary),
    });
    if super::json::to_stdout(json.as_deref()) {
        if let Some(p) = csv {
            imu_fdi_cli::eval::campaign::write_rows(&p, &rows)?;
        }
        super::json::emit(&v);
        return Ok(());
    }
    out!(
        "campaign {name}, seed {seed}{}: {} runs in {secs:.1} s ({:.1} runs/s on {} threads)",
        shard.map_or(String::new(), |s| format!(", shard {}/{}", s.i, s.n)),
        rows.len(),
        rows.len() as f64 / secs.max(1e-9),
        rayon::current_num_threads()
    );
    out_nl!("{}", summary.table());
    finish_campaign(&rows, csv, json, &v)?;
    Ok(())
}

pub(crate) fn finish_campaign(
    rows: &[imu_fdi_cli::eval::campaign::CampaignRow],
    csv: Option<PathBuf>,
    json: Option<PathBuf>,
    v: &serde_json::Value,
) -> Result<()> {
    if let Some(p) = csv {
        imu_fdi_cli::eval::campaign::write_rows(&p, rows)?;
        out!("wrote {} rows to {}", rows.len(), p.display());
    }
    super::json::write(&json, v)?;
    Ok(())
}

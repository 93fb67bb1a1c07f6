//! `imu-fdi-sim simulate`: Write a simulated run in the SPEC §10 replay format (with truth columns).

use std::path::PathBuf;

use anyhow::Result;

use super::scenario;

// The arguments of `simulate` (its help text is the doc comment on `Cmd::Simulate`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Scenario name.
    name: String,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output CSV.
    #[arg(long)]
    out: PathBuf,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `simulate`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        name,
        seed,
        out,
        json,
    } = args;
    let scn = scenario(&name)?;
    let n = imu_fdi_cli::eval::replay::write_simulated(&scn, seed, &out)?;
    if json {
        super::json::emit(&serde_json::json!({
            "scenario": scn.name.as_str(),
            "seed": seed,
            "rows": n,
            "output": out.display().to_string(),
        }));
        return Ok(());
    }
    out!(
        "wrote {n} rows of {} (seed {seed}) to {}",
        scn.name,
        out.display()
    );
    Ok(())
}

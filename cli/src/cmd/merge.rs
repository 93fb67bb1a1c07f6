//! `imu-fdi-sim merge`: Merges the per-run CSVs of campaign shards into one table.

use std::path::PathBuf;

use anyhow::Result;

use super::campaign::finish_campaign;

// The arguments of `merge` (its help text is the doc comment on `Cmd::Merge`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    #[arg(long)]
    csv: Option<PathBuf>,
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `merge`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args { inputs, csv, json } = args;
    use imu_fdi_cli::eval::campaign::{merge_files, summarise};
    let rows = merge_files(&inputs)?;
    let summary = summarise(&rows)?;
    out!("merged {} files: {} runs", inputs.len(), rows.len());
    out_nl!("{}", summary.table());
    finish_campaign(&rows, &summary, csv, json)?;
    Ok(())
}

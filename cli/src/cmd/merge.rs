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
    /// One JSON object on stdout instead of text (docs/cli-json.md); with
    /// a FILE, the text as usual and the object written to FILE.
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    json: Option<PathBuf>,
}

/// Runs `merge`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args { inputs, csv, json } = args;
    use imu_fdi_cli::eval::campaign::{merge_files, summarise};
    let rows = merge_files(&inputs)?;
    let summary = summarise(&rows)?;
    let v = serde_json::json!({
        "files": super::json::files(&inputs),
        "summary": super::json::campaign_summary(&summary),
    });
    if super::json::to_stdout(json.as_deref()) {
        if let Some(p) = csv {
            imu_fdi_cli::eval::campaign::write_rows(&p, &rows)?;
        }
        super::json::emit(&v);
        return Ok(());
    }
    out!("merged {} files: {} runs", inputs.len(), rows.len());
    out_nl!("{}", summary.table());
    finish_campaign(&rows, csv, json, &v)?;
    Ok(())
}

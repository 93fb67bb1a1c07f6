//! `imu-fdi-sim gallery`: The README gallery: S1–S4 figures (seed 1) as PNG and SVG.

use std::path::PathBuf;

use anyhow::Result;
use hal_sim::runner::RunOptions;

use super::plot::plot_scenario;
use super::{options, DetectOpts, StatisticArg};

// The arguments of `gallery` (its help text is the doc comment on `Cmd::Gallery`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    #[arg(long, default_value = "docs/gallery")]
    out: PathBuf,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `gallery`.
pub(crate) fn run(args: Args) -> Result<()> {
    let _progress = super::progress::spinner("gallery");
    let Args { out, json } = args;
    use imu_fdi_cli::plot::TraceFigure as F;
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
    if json {
        super::json::emit(&serde_json::json!({ "files": super::json::files(&files) }));
        return Ok(());
    }
    out!("gallery: wrote {} files to {}", files.len(), out.display());
    for f in files {
        out!("  {}", f.display());
    }
    Ok(())
}

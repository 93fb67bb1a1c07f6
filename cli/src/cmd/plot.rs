//! `imu-fdi-sim plot`: The papers' figures of one run as PNG and SVG: injected fault vs flag, estimate vs truth, innovations ±3σ, statistic vs threshold (UKF scenarios), or the parity pattern and χ² (s4).

use std::path::PathBuf;

use anyhow::{anyhow, Result};
use hal_sim::runner::{self, RunOptions};

use super::{options, scenario, DetectOpts};

// The arguments of `plot` (its help text is the doc comment on `Cmd::Plot`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    name: String,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long, default_value = "plots")]
    out: PathBuf,
    #[command(flatten)]
    detect: DetectOpts,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `plot`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        name,
        seed,
        out,
        detect,
        json,
    } = args;
    std::fs::create_dir_all(&out)?;
    let files = plot_scenario(&name, seed, &out, &options(&name, &detect), None)?;
    if json {
        super::json::emit(&serde_json::json!({
            "scenario": name,
            "seed": seed,
            "files": super::json::files(&files),
        }));
        return Ok(());
    }
    out!("wrote {} files to {}:", files.len(), out.display());
    for f in files {
        out!("  {}", f.display());
    }
    Ok(())
}

pub(crate) fn plot_scenario(
    name: &str,
    seed: u64,
    out: &std::path::Path,
    opts: &RunOptions,
    only: Option<&[imu_fdi_cli::plot::TraceFigure]>,
) -> Result<Vec<PathBuf>> {
    use imu_fdi_cli::plot::{plot_parity, plot_trace, TraceFigure as F};
    if name.eq_ignore_ascii_case("s4") {
        return plot_parity(
            &hal_sim::array::ArraySpec::s4(),
            seed,
            &out.join(format!("s4_seed{seed}_parity")),
        );
    }
    let scn = scenario(name)?;
    let trace = runner::run::<f32>(&scn, seed, opts)
        .map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
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

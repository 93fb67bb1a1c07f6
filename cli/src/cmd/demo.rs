//! `imu-fdi-sim demo`: S1 (threshold method) and S2 (run-time matrix + GLR, and the paper's fixed matrix) in one go.

use anyhow::Result;
use hal_sim::runner::RunOptions;
use imu_fdi::detect::Detector;

use super::{print_run, scenario};

// The arguments of `demo` (its help text is the doc comment on `Cmd::Demo`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Number of seeds per scenario.
    #[arg(long, default_value_t = 5)]
    seeds: u64,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `demo`.
pub(crate) fn run(args: Args) -> Result<()> {
    let _progress = super::progress::spinner("demo: S1 and S2");
    let Args { seeds, json } = args;
    let seeds = seeds.max(1);
    let s1 = scenario("s1")?;
    let s2 = scenario("s2")?;
    let base = RunOptions::default();
    let a = print_run(
        "S1, threshold method",
        &s1,
        1,
        seeds,
        &RunOptions {
            detector: Detector::Threshold,
            ..base
        },
        !json,
    )?;
    let b = print_run(
        "S2, run-time matrix + GLR (default)",
        &s2,
        1,
        seeds,
        &base,
        !json,
    )?;
    let c = print_run(
        "S2, paper's fixed matrix (erratum applied), for comparison",
        &s2,
        1,
        seeds,
        &RunOptions {
            detector: Detector::PaperMatrix,
            ..base
        },
        !json,
    )?;
    if json {
        let run = |name: &str, d: Detector, m: &hal_sim::metrics::RunMetrics| {
            serde_json::json!({
                "scenario": name,
                "detector": super::detector_name(d),
                "metrics": super::json::metrics(m),
            })
        };
        super::json::emit(&serde_json::json!({
            "seeds": seeds,
            "runs": [
                run("s1", Detector::Threshold, &a),
                run("s2", base.detector, &b),
                run("s2", Detector::PaperMatrix, &c),
            ],
        }));
        return Ok(());
    }
    out!(
        "summary: S1 false alarms {}, S2 false alarms {}, S2 paper-matrix false alarms {}",
        a.total_false_alarms(),
        b.total_false_alarms(),
        c.total_false_alarms()
    );
    Ok(())
}

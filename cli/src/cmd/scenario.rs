//! `imu-fdi-sim scenario`: Run a scenario over seeds and print the per-channel table: a built-in (s1, s2, s3, s3-paper, s5, auv-hour, aircraft-hour; s4 runs the parity monitor on the cone of six gyros) or a .toml scenario file.

use std::path::PathBuf;

use anyhow::{anyhow, Result};
use hal_sim::runner::{self, RunOptions};
use hal_sim::Scenario;

use super::parity::parity_s4;
use super::{options, print_run, scenario, DetectOpts};

// The arguments of `scenario` (its help text is the doc comment on `Cmd::Scenario`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Scenario name.
    name: String,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Number of seeds.
    #[arg(long, default_value_t = 5)]
    seeds: u64,
    #[command(flatten)]
    detect: DetectOpts,
    /// One JSON object on stdout instead of text (docs/cli-json.md); with
    /// a FILE, the text as usual and the object written to FILE.
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write the first seed's per-sample trace as CSV here.
    #[arg(long)]
    trace: Option<PathBuf>,
}

/// Runs `scenario`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        name,
        seed,
        seeds,
        detect,
        json,
        trace,
    } = args;
    // S4 is the redundant-sensor scenario: the parity monitor's run.
    if name.eq_ignore_ascii_case("s4") {
        if json
            .as_ref()
            .is_some_and(|p| !super::json::to_stdout(Some(p)))
        {
            return Err(anyhow!(
                "--json FILE: s4 prints its JSON on stdout (`--json` alone)"
            ));
        }
        return parity_s4(seed, seeds.max(1), json.is_some());
    }
    if name.eq_ignore_ascii_case("s6") {
        return Err(anyhow!(
                "S6 is the real logs: `replay LOG.ulg|LOG.bin|LOG.csv [--faults TABLE.toml]` \
                 for the UKF monitor, `parity-replay` for redundant IMUs (see README, Real flight logs)"
            ));
    }
    let _progress = super::progress::spinner("scenario");
    let scn = scenario(&name)?;
    let opts = options(&name, &detect);
    if let Some(p) = trace {
        let t = runner::run::<f32>(&scn, seed, &opts)
            .map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
        t.write_csv(&p)?;
        out!("wrote trace of seed {seed} to {}", p.display());
    }
    let text = !super::json::to_stdout(json.as_deref());
    let m = print_run("scenario", &scn, seed, seeds.max(1), &opts, text)?;
    if text && scn.faults.iter().any(|r| r.is_hardware()) {
        print_hardware(&scn, seed, seeds.max(1), &opts)?;
    }
    let v = serde_json::json!({
        "scenario": scn.name.as_str(),
        "first_seed": seed,
        "seeds": seeds.max(1),
        "detector": super::detector_name(opts.detector),
        "statistic": super::statistic_name(opts.statistic),
        "alpha_fraction": opts.alpha,
        "metrics": super::json::metrics(&m),
    });
    super::json::write(&json, &v)?;
    Ok(())
}

/// The S5 table: how each hardware fault row was seen over the seeds.
pub(crate) fn print_hardware(
    scn: &Scenario,
    first: u64,
    seeds: u64,
    opts: &RunOptions,
) -> Result<()> {
    let mut per_row: Vec<Vec<hal_sim::metrics::HardwareDetection>> = Vec::new();
    for seed in first..first + seeds {
        let t = runner::run::<f32>(scn, seed, opts)
            .map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
        for (i, d) in hal_sim::metrics::hardware_detections(&t)
            .into_iter()
            .enumerate()
        {
            if per_row.len() <= i {
                per_row.push(Vec::new());
            }
            if let Some(v) = per_row.get_mut(i) {
                v.push(d);
            }
        }
    }
    out!("hardware faults over {seeds} seeds (seen = a health flag, or a flag on the faulty channel, from onset to end + L):");
    out!("  fault                  ch  interval s     seen  delay mean/max s  by health  other-channel flag samples");
    for ds in &per_row {
        let Some(d0) = ds.first() else { continue };
        let delays: Vec<f64> = ds.iter().filter_map(|d| d.first_seen()).collect();
        let by_health = ds.iter().filter(|d| d.first_health.is_some()).count();
        let other: usize = ds.iter().map(|d| d.other_channel_samples).sum();
        let (mean, max) = if delays.is_empty() {
            ("-".to_string(), "-".to_string())
        } else {
            (
                format!("{:.2}", delays.iter().sum::<f64>() / delays.len() as f64),
                format!("{:.2}", delays.iter().copied().fold(0.0, f64::max)),
            )
        };
        out!(
            "  {:<22} {:<3} {:>5.1}-{:<5.1}  {:>3}/{:<3}  {:>6}/{:<6}     {:>3}/{:<3}  {}",
            d0.kind,
            d0.channel,
            d0.start,
            d0.end,
            delays.len(),
            ds.len(),
            mean,
            max,
            by_health,
            ds.len(),
            other
        );
    }
    Ok(())
}

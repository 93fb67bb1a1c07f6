//! `imu-fdi-sim detections`: First detection of every fault row of one seed, in the same format as the QEMU image prints (for diffing host vs target).

use anyhow::{anyhow, Result};
use hal_sim::runner::monitor_config;

use super::{options, scenario, DetectOpts, StatisticArg};

// The arguments of `detections` (its help text is the doc comment on `Cmd::Detections`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Scenario name.
    name: String,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Feed the monitor as the firmware does: the ICM-42688-P driver
    /// reading the emulated chip, into the periodic Monitor task.
    #[arg(long)]
    via_chip: bool,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `detections`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        name,
        seed,
        via_chip,
        json,
    } = args;
    if via_chip {
        let scn = scenario(&name)?;
        let tally = hal_sim::setup::run_via_chip(&scn, seed, |step| step())
            .ok_or_else(|| anyhow!("the driver or the monitor refused to start"))?;
        print_tally(&tally, &name, seed, json);
        return Ok(());
    }
    let scn = scenario(&name)?;
    let opts = options(
        &name,
        &DetectOpts {
            detector: None,
            statistic: StatisticArg::Normalized,
            alpha: 1e-6,
        },
    );
    let cfg = monitor_config::<f32>(&scn, &opts);
    let mut monitor = imu_fdi::monitor::UkfMonitor::<f32>::new(cfg)
        .map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
    let mut tally = hal_sim::setup::DetectionTally::new(&scn);
    for s in hal_sim::Simulator::new(&scn, seed) {
        let u = imu_fdi::model::ImuVec::from_fn(|i, _| s.imu.map_or(f32::NAN, |v| v[i] as f32));
        let z = imu_fdi::model::MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let r = monitor.step(
            &u,
            s.dt as f32,
            &imu_fdi::model::Measurement {
                z,
                available: s.aiding_available,
            },
        );
        tally.record(&s, &r);
    }
    print_tally(&tally, &name, seed, json);
    Ok(())
}

/// The tally as text (the lines the QEMU image prints, diffed by CI) or
/// as one JSON object.
fn print_tally(tally: &hal_sim::setup::DetectionTally, name: &str, seed: u64, json: bool) {
    if !json {
        tally.print(|line| out!("{line}"));
        return;
    }
    let faults: Vec<serde_json::Value> = tally
        .rows()
        .iter()
        .map(|(row, first)| {
            serde_json::json!({
                "channel": imu_fdi::model::CHANNEL_NAMES.get(row.channel).copied().unwrap_or("?"),
                "start_s": row.start,
                "end_s": row.end,
                "detected_s": first,
                "delay_s": first.map(|t| t - row.start),
            })
        })
        .collect();
    super::json::emit(&serde_json::json!({
        "scenario": name,
        "seed": seed,
        "faults": faults,
    }));
}

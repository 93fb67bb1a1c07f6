//! `imu-fdi-sim sweep`: Scale the fault sizes a, b, c of a scenario and print detection per channel for each scale.

use anyhow::Result;

use super::{campaign, options, scenario, DetectOpts};

// The arguments of `sweep` (its help text is the doc comment on `Cmd::Sweep`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Scenario name.
    name: String,
    /// Scale factors applied to every fault size.
    #[arg(long, value_delimiter = ',', default_value = "0.25,0.5,1,2,4")]
    factors: Vec<f64>,
    /// Number of seeds per factor.
    #[arg(long, default_value_t = 5)]
    seeds: u64,
    #[command(flatten)]
    detect: DetectOpts,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `sweep`.
pub(crate) fn run(args: Args) -> Result<()> {
    let _progress = super::progress::spinner("sweep");
    let Args {
        name,
        factors,
        seeds,
        detect,
        json,
    } = args;
    let base = scenario(&name)?;
    let opts = options(&name, &detect);
    macro_rules! text {
        ($($a:tt)*) => {
            if !json {
                out!($($a)*);
            }
        };
    }
    let mut rows = Vec::new();
    text!(
        "sweep of {}: fault sizes × factor, {} seeds each, detector {}, statistic {}",
        base.name,
        seeds,
        super::detector_name(opts.detector),
        super::statistic_name(opts.statistic)
    );
    text!(
        "{:>7}  {:>20}  {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}  {:>9} {:>8}",
        "factor",
        "sizes a,b,c (acc)",
        "ax",
        "ay",
        "az",
        "gx",
        "gy",
        "gz",
        "wrong.max",
        "FA.evts"
    );
    for f in factors {
        let mut scn = base.clone();
        for v in scn.sizes.accel.iter_mut().chain(scn.sizes.gyro.iter_mut()) {
            *v *= f;
        }
        let m = campaign(&scn, 1, seeds.max(1), &opts)?;
        let cells: Vec<String> = m
            .channels
            .iter()
            .map(|c| {
                format!(
                    "{}/{} {}",
                    c.detected,
                    c.faults,
                    c.detection_rate()
                        .map_or("-".into(), |r| format!("{:.0}%", 100.0 * r))
                )
            })
            .collect();
        let wrong = m
            .channels
            .iter()
            .filter_map(|c| c.wrong_channel_rate())
            .fold(0.0, f64::max);
        let a = scn.sizes.accel;
        let g = scn.sizes.gyro;
        rows.push(serde_json::json!({
            "scale_factor": f,
            "accel_a_m_s2": a[0],
            "accel_b_m_s3": a[1],
            "accel_c_m_s2": a[2],
            "gyro_a_rad_s": g[0],
            "gyro_b_rad_s2": g[1],
            "gyro_c_rad_s": g[2],
            "max_wrong_channel_fraction": wrong,
            "metrics": super::json::metrics(&m),
        }));
        text!(
            "{:>7}  {:>20}  {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}  {:>8.2}% {:>8}",
            f,
            format!("{:.3},{:.3},{:.2}", a[0], a[1], a[2]),
            cells[0],
            cells[1],
            cells[2],
            cells[3],
            cells[4],
            cells[5],
            100.0 * wrong,
            m.false_alarm_events
        );
    }
    if json {
        super::json::emit(&serde_json::json!({
            "scenario": base.name.as_str(),
            "seeds": seeds.max(1),
            "detector": super::detector_name(opts.detector),
            "statistic": super::statistic_name(opts.statistic),
            "factors": rows,
        }));
        return Ok(());
    }
    out!("detection rate counted where |fault| ≥ the scenario's minimum (0.1 m/s², 0.5 °/s) from L after it is reached");
    Ok(())
}

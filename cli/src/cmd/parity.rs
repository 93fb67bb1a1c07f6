//! `imu-fdi-sim parity`: S4 (parity paper): 0.5 °/s bias on sensor 5 of a manoeuvring cone6 gyro array; parity monitor (PCA, χ², CUSUM) beside the PX4-like and ArduPilot-like baselines, over several seeds.

use anyhow::{anyhow, Result};

// The arguments of `parity` (its help text is the doc comment on `Cmd::Parity`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    #[arg(long, default_value_t = 20)]
    seeds: u64,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `parity`.
pub(crate) fn run(args: Args) -> Result<()> {
    parity_s4(args.first_seed, args.seeds, args.json)
}

pub(crate) fn parity_s4(first_seed: u64, seeds: u64, json: bool) -> Result<()> {
    let _progress = super::progress::spinner("parity: S4 seeds");
    use hal_sim::array::ArraySpec;
    use imu_fdi_cli::eval::array_run::{array_config, run_array};
    if seeds == 0 {
        return Err(anyhow!("--seeds must be at least 1"));
    }
    let spec = ArraySpec::s4();
    // Text lines only without --json.
    macro_rules! text {
        ($($a:tt)*) => {
            if !json {
                out!($($a)*);
            }
        };
    }
    let mut runs_json = Vec::new();
    let deg = 180.0 / std::f64::consts::PI;
    text!("S4: cone6 gyros, +0.5 deg/s on sensor 5 from t = 6 s, manoeuvre from 1 s, seeds {first_seed}..{}", first_seed + seeds - 1);
    text!(
        "{:>5} {:>9} {:>9} {:>9} {:>12} {:>8} {:>8} {:>12}",
        "seed",
        "PCA s",
        "chi2 s",
        "CUSUM s",
        "isolated@s",
        "FA",
        "PX4/AP",
        "fused deg/s"
    );
    let (mut isolated_ok, mut fa_total) = (0, 0);
    for seed in first_seed..first_seed + seeds {
        let r = run_array::<f32, 6>(&spec, seed, array_config(&spec))?;
        let t = |o: &imu_fdi_cli::eval::array_run::MethodOutcome| {
            o.first_alarm.map_or("-".to_string(), |t| format!("{t:.2}"))
        };
        let fa = r.pca.false_alarm_events + r.glt.false_alarm_events + r.cusum.false_alarm_events;
        fa_total += fa;
        if r.isolated.is_some_and(|(k, _)| k == 5) {
            isolated_ok += 1;
        }
        runs_json.push(serde_json::json!({
            "seed": seed,
            "pca_first_alarm_s": r.pca.first_alarm,
            "chi2_first_alarm_s": r.glt.first_alarm,
            "cusum_first_alarm_s": r.cusum.first_alarm,
            "isolated_sensor": r.isolated.map(|(k, _)| k),
            "isolated_at_s": r.isolated.map(|(_, t)| t),
            "false_alarm_events": fa,
            "px4_alarm_s": r.px4.first_alarm,
            "ardupilot_alarm_s": r.ardupilot.first_alarm,
            "fused_error_before_isolation_deg_s": r.fused_vs_healthy_before_isolation.map(|v| v * deg),
            "fused_error_after_isolation_deg_s": r.fused_vs_healthy_after_isolation.map(|v| v * deg),
        }));
        text!(
            "{seed:>5} {:>9} {:>9} {:>9} {:>12} {fa:>8} {:>8} {:>5.3}/{:<6.3}",
            t(&r.pca),
            t(&r.glt),
            t(&r.cusum),
            r.isolated
                .map_or("-".to_string(), |(k, t)| format!("{k}@{t:.2}")),
            format!(
                "{}/{}",
                if r.px4.first_alarm.is_some() {
                    "yes"
                } else {
                    "no"
                },
                if r.ardupilot.first_alarm.is_some() {
                    "yes"
                } else {
                    "no"
                }
            ),
            r.fused_vs_healthy_before_isolation.unwrap_or(f64::NAN) * deg,
            r.fused_vs_healthy_after_isolation.unwrap_or(f64::NAN) * deg,
        );
    }
    text!("isolated to sensor 5 in {isolated_ok}/{seeds} runs; false-alarm events before onset: {fa_total}");
    text!("(fused: RMS of fused rate minus the least squares of the truly healthy sensors, deg/s:");
    text!(" from onset to isolation / from 0.5 s after isolation)");
    if json {
        super::json::emit(&serde_json::json!({
            "scenario": "s4",
            "fault": "+0.5 °/s bias on sensor 5 of the cone6 gyro array from 6 s",
            "onset_s": 6.0,
            "first_seed": first_seed,
            "seeds": seeds,
            "isolated_right": isolated_ok,
            "false_alarm_events": fa_total,
            "runs": runs_json,
        }));
    }
    Ok(())
}

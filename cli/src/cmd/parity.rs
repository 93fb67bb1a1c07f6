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
}

/// Runs `parity`.
pub(crate) fn run(args: Args) -> Result<()> {
    parity_s4(args.first_seed, args.seeds)
}

pub(crate) fn parity_s4(first_seed: u64, seeds: u64) -> Result<()> {
    use hal_sim::array::ArraySpec;
    use imu_fdi_cli::eval::array_run::{array_config, run_array};
    if seeds == 0 {
        return Err(anyhow!("--seeds must be at least 1"));
    }
    let spec = ArraySpec::s4();
    let deg = 180.0 / std::f64::consts::PI;
    out!("S4: cone6 gyros, +0.5 deg/s on sensor 5 from t = 6 s, manoeuvre from 1 s, seeds {first_seed}..{}", first_seed + seeds - 1);
    out!(
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
        out!(
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
    out!("isolated to sensor 5 in {isolated_ok}/{seeds} runs; false-alarm events before onset: {fa_total}");
    out!("(fused: RMS of fused rate minus the least squares of the truly healthy sensors, deg/s:");
    out!(" from onset to isolation / from 0.5 s after isolation)");
    Ok(())
}

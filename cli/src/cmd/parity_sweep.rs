//! `imu-fdi-sim parity-sweep`: Smallest bias each method detects in >= 99 % of runs at zero false alarms over fault-free hours, with its delay (redundant arrays).

use std::path::PathBuf;

use anyhow::{anyhow, Result};
use clap::ValueEnum;

// The arguments of `parity-sweep` (its help text is the doc comment on `Cmd::ParitySweep`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    #[arg(long, value_enum, default_value = "triads3")]
    array: ArrayArg,
    #[arg(long, value_enum, default_value = "gyro")]
    kind: KindArg,
    /// Runs per bias size.
    #[arg(long, default_value_t = 100)]
    runs: u32,
    /// Fault-free simulated hours for the false-alarm count.
    #[arg(long, default_value_t = 1)]
    hours: u32,
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// One JSON object on stdout instead of text (docs/cli-json.md); with
    /// a FILE, the text as usual and the object written to FILE.
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    json: Option<PathBuf>,
}

/// Runs `parity-sweep`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        array,
        kind,
        runs,
        hours,
        first_seed,
        json,
    } = args;
    use hal_sim::array::{cone6_directions, triad_directions, ArrayKind, ArraySpec, Layout};
    use std::f64::consts::{FRAC_PI_2, PI};
    let kind = match kind {
        KindArg::Gyro => ArrayKind::Gyro,
        KindArg::Accel => ArrayKind::Accel,
    };
    match array {
        ArrayArg::Cone6 => parity_sweep(
            &ArraySpec::fault_free("cone6", cone6_directions(), kind, Layout::Single, 0.0),
            runs,
            hours,
            first_seed,
            json,
        )?,
        ArrayArg::Triads2 => parity_sweep(
            &ArraySpec::fault_free(
                "triads2",
                triad_directions::<6>(&[0.0, PI]),
                kind,
                Layout::Triads,
                0.0,
            ),
            runs,
            hours,
            first_seed,
            json,
        )?,
        ArrayArg::Triads3 => parity_sweep(
            &ArraySpec::fault_free(
                "triads3",
                triad_directions::<9>(&[0.0, FRAC_PI_2, PI]),
                kind,
                Layout::Triads,
                0.0,
            ),
            runs,
            hours,
            first_seed,
            json,
        )?,
    }
    Ok(())
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ArrayArg {
    /// Six single-axis sensors on the parity paper's cone.
    Cone6,
    /// Two IMUs, the second yawed 180° (detect only: axes parallel).
    Triads2,
    /// Three IMUs yawed 0°, 90°, 180° (per-axis 2-of-3 isolation).
    Triads3,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum KindArg {
    Gyro,
    Accel,
}

pub(crate) fn parity_sweep<const N: usize>(
    spec: &hal_sim::array::ArraySpec<N>,
    runs: u32,
    hours: u32,
    first_seed: u64,
    json: Option<PathBuf>,
) -> Result<()> {
    use imu_fdi_cli::eval::array_sweep::{default_sizes, format_sweep, sweep};
    if runs == 0 {
        return Err(anyhow!("--runs must be at least 1"));
    }
    let started = std::time::Instant::now();
    let _progress = super::progress::spinner("parity-sweep");
    let sizes = default_sizes(spec.kind);
    let result = sweep(spec, &sizes, runs, hours, first_seed)?;
    let unit = match spec.kind {
        hal_sim::array::ArrayKind::Gyro => "rad_s",
        hal_sim::array::ArrayKind::Accel => "m_s2",
    };
    let methods: Vec<serde_json::Value> = result
        .iter()
        .map(|m| {
            serde_json::json!({
                "method": m.method,
                "false_alarm_events": m.false_alarms,
                format!("min_detected_{unit}"): m.min_detected().map(|s| s.size),
                "sizes": m.sizes.iter().map(|s| serde_json::json!({
                    format!("size_{unit}"): s.size,
                    "detected": s.detected,
                    "runs": s.runs,
                    "mean_delay_s": s.mean_delay,
                    "max_delay_s": s.max_delay,
                    "correct_blame": s.correct_blame,
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    let v = serde_json::json!({
        "array": spec.name,
        "kind": if unit == "rad_s" { "gyro" } else { "accel" },
        "runs": runs,
        "fault_free_h": hours,
        "first_seed": first_seed,
        "elapsed_s": started.elapsed().as_secs_f64(),
        "methods": methods,
    });
    if super::json::to_stdout(json.as_deref()) {
        super::json::emit(&v);
        return Ok(());
    }
    out!(
        "{} {} array, {} sizes x {runs} runs, {hours} fault-free h ({:.1} s):",
        spec.name,
        if unit == "rad_s" { "gyro" } else { "accel" },
        sizes.len(),
        started.elapsed().as_secs_f64()
    );
    out_nl!("{}", format_sweep(spec.kind, &result, runs, hours));
    super::json::write(&json, &v)?;
    Ok(())
}

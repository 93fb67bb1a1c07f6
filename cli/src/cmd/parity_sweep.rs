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
    /// Also write the full per-size results as JSON.
    #[arg(long)]
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
    let sizes = default_sizes(spec.kind);
    let result = sweep(spec, &sizes, runs, hours, first_seed)?;
    out!(
        "{} {:?} array, {} sizes x {runs} runs, {hours} fault-free h ({:.1} s):",
        spec.name,
        spec.kind,
        sizes.len(),
        started.elapsed().as_secs_f64()
    );
    out_nl!("{}", format_sweep(spec.kind, &result, runs, hours));
    if let Some(p) = json {
        std::fs::write(&p, serde_json::to_string_pretty(&result)?)?;
        out!("wrote {}", p.display());
    }
    Ok(())
}

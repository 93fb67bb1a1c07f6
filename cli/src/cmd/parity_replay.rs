//! `imu-fdi-sim parity-replay`: Replays a log of three synchronous IMUs (SPEC §10 `imu{k}_…` columns) through the parity monitor and the baselines.

use std::path::PathBuf;

use anyhow::Result;

// The arguments of `parity-replay` (its help text is the doc comment on `Cmd::ParityReplay`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    input: PathBuf,
    /// Log time training starts (in flight: vibration must be in it).
    #[arg(long, default_value_t = 80.0)]
    train_start: f64,
    /// Training + calibration length, s.
    #[arg(long, default_value_t = 30.0)]
    train_s: f64,
    /// Inject biases on every channel at these onsets (comma-separated,
    /// s) and report the smallest detected per method.
    #[arg(long, value_delimiter = ',')]
    inject_at: Vec<f64>,
}

/// Runs `parity-replay`.
pub(crate) fn run(args: Args) -> Result<()> {
    parity_replay_cmd(&args.input, args.train_start, args.train_s, &args.inject_at)
}

pub(crate) fn parity_replay_cmd(
    input: &std::path::Path,
    train_start: f64,
    train_s: f64,
    inject_at: &[f64],
) -> Result<()> {
    use hal_sim::array::ArrayKind;
    use imu_fdi_cli::eval::parity_replay::{
        injection_sizes, injection_sweep, read_any_imu_log, replay_parity,
    };
    let log = read_any_imu_log(input)?;
    out!(
        "{}: {} rows, {} IMUs, t = {:.2}..{:.2} s, {} rows skipped (time not increasing, or unreadable tail)",
        input.display(),
        log.t.len(),
        log.count,
        log.t.first().copied().unwrap_or(0.0),
        log.t.last().copied().unwrap_or(0.0),
        log.skipped
    );
    let fmt = |v: &[(f64, f64, Option<usize>)]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|(a, b, k)| match k {
                    Some(k) => format!("{a:.2}-{b:.2} (sensor {k})"),
                    None => format!("{a:.2}-{b:.2}"),
                })
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    for kind in [ArrayKind::Gyro, ArrayKind::Accel] {
        let r = replay_parity(&log, kind, train_start, train_s, None)?;
        out!("{kind:?} (sensor = 3 x IMU + axis):");
        out!(
            "  monitoring from {:.2} s; threshold factors from calibration [GLT, PCA, CUSUM] = [{:.2}, {:.2}, {:.2}]; correlation factor {:.2}",
            r.monitoring_from.unwrap_or(f64::NAN),
            r.threshold_scales[0],
            r.threshold_scales[1],
            r.threshold_scales[2],
            r.correlation_factor
        );
        out!("  parity alarms: {}", fmt(&r.alarms));
        let iso: Vec<String> = r
            .isolations
            .iter()
            .map(|(k, t)| format!("sensor {k} at {t:.2}"))
            .collect();
        out!(
            "  isolations: {}",
            if iso.is_empty() {
                "none".into()
            } else {
                iso.join(", ")
            }
        );
        let st: Vec<String> = r
            .statuses
            .iter()
            .map(|(k, s, t)| format!("{k}:{s:?}@{t:.2}"))
            .collect();
        out!(
            "  statuses: {}",
            if st.is_empty() {
                "all healthy".into()
            } else {
                st.join(", ")
            }
        );
        out!("  common-mode saturation: {}", fmt(&r.saturation));
        out!("  PX4-like alarms: {}", fmt(&r.px4));
        out!("  ArduPilot-like alarms: {}", fmt(&r.ardupilot));
        if !inject_at.is_empty() {
            let (u, scale) = imu_fdi_cli::eval::array_sweep::unit(kind);
            out!("  smallest injected bias detected within 15 s ({u}; delay s; * = isolated to the right sensor):");
            out!(
                "  {:>4} {:>4} {:>7} {:>16} {:>16} {:>16}",
                "imu",
                "axis",
                "onset",
                "parity",
                "PX4-like",
                "ArduPilot-like"
            );
            let sweep = injection_sweep(
                &log,
                kind,
                train_start,
                train_s,
                inject_at,
                &injection_sizes(kind),
            )?;
            let cell = |v: Option<(f64, f64)>, star: bool| {
                v.map_or("-".to_string(), |(s, d)| {
                    format!("{:.2}{} ({d:.1})", s * scale, if star { "*" } else { "" })
                })
            };
            for x in sweep {
                out!(
                    "  {:>4} {:>4} {:>7.1} {:>16} {:>16} {:>16}",
                    x.imu,
                    ["x", "y", "z"][x.axis],
                    x.onset,
                    cell(
                        x.parity.map(|(s, d, _)| (s, d)),
                        x.parity.is_some_and(|p| p.2)
                    ),
                    cell(x.px4, false),
                    cell(x.ardupilot, false)
                );
            }
        }
    }
    Ok(())
}

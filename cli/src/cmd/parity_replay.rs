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
    /// Parity tests: `flight` (in-flight calibration, multi-scale tests
    /// with learned covariances; for real logs) or `glt-cusum` (the
    /// simulator's white-noise χ²/CUSUM with calibrated thresholds).
    #[arg(long, default_value = "flight")]
    method: String,
    /// With `--method flight`: the multi-scale tests' per-decision
    /// false-alarm probability (default 1e-6).
    #[arg(long)]
    false_alarm: Option<f64>,
    /// One bias to inject: IMU,CHANNEL,SIZE,START or IMU,CHANNEL,SIZE,START,END (channel 0–5 =
    /// ax ay az gx gy gz; size in m/s² or °/s; times in s of the log).
    #[arg(long, value_delimiter = ',')]
    inject: Vec<f64>,
    /// Print one JSON object instead of text: {"gyro": {"monitoring_from_s",
    /// "power_up_judged", "alarms": [{"start_s", "end_s", "sensor"}], "isolations": [{"sensor",
    /// "t_s"}], "statuses": [...], "readmissions": [{"sensor", "t_s"}], "not_judging":
    /// [{"start_s", "end_s", "phase"}]}, "accel": {...}},
    /// sensor = 3·IMU + axis.
    #[arg(long)]
    json: bool,
}

/// The `--method` value.
pub(crate) fn method(name: &str) -> Result<imu_fdi_cli::eval::parity_replay::ParityMethod> {
    use imu_fdi_cli::eval::parity_replay::ParityMethod;
    match name {
        "flight" => Ok(ParityMethod::Flight),
        "glt-cusum" => Ok(ParityMethod::GltCusum),
        other => anyhow::bail!("--method: '{other}' is not a method (flight, glt-cusum)"),
    }
}

/// The `--inject` value.
fn injection(v: &[f64]) -> Result<Option<imu_fdi_cli::eval::parity_replay::Injection>> {
    use imu_fdi_cli::eval::parity_replay::Injection;
    match v {
        [] => Ok(None),
        [imu, ch, size, start, rest @ ..] if rest.len() <= 1 => {
            if !(0.0..3.0).contains(imu)
                || !(0.0..6.0).contains(ch)
                || imu.fract() != 0.0
                || ch.fract() != 0.0
            {
                anyhow::bail!("--inject: IMU must be 0–2 and CHANNEL 0–5, got {imu},{ch}");
            }
            if !size.is_finite() || !start.is_finite() {
                anyhow::bail!("--inject: SIZE and START must be finite numbers");
            }
            let channel = *ch as usize;
            let size = if channel >= 3 {
                size.to_radians()
            } else {
                *size
            };
            Ok(Some(Injection {
                imu: *imu as usize,
                channel,
                size,
                start: *start,
                end: rest.first().copied().unwrap_or(f64::INFINITY),
            }))
        }
        _ => anyhow::bail!("--inject takes IMU,CHANNEL,SIZE,START[,END]"),
    }
}

/// The method with `--false-alarm` applied (flight only).
fn method_at(
    name: &str,
    false_alarm: Option<f64>,
) -> Result<imu_fdi_cli::eval::parity_replay::ParityMethod> {
    use imu_fdi_cli::eval::parity_replay::ParityMethod;
    match (method(name)?, false_alarm) {
        (m, None) => Ok(m),
        (ParityMethod::Flight, Some(p)) if p > 0.0 && p < 0.5 => Ok(ParityMethod::FlightAt(p)),
        (ParityMethod::Flight, Some(p)) => {
            anyhow::bail!("--false-alarm: {p} is not a probability in (0, 0.5)")
        }
        (_, Some(_)) => anyhow::bail!("--false-alarm applies to --method flight only"),
    }
}

/// Runs `parity-replay`.
pub(crate) fn run(args: Args) -> Result<()> {
    let method = method_at(&args.method, args.false_alarm)?;
    let inj = injection(&args.inject)?;
    if args.json {
        let log = imu_fdi_cli::eval::parity_replay::read_any_imu_log(&args.input)?;
        for w in &log.warnings {
            eprintln!("warning: {w}");
        }
        let v = imu_fdi_cli::eval::parity_replay::replay_json(
            &log,
            args.train_start,
            args.train_s,
            method,
            inj,
        )?;
        println!("{v}");
        return Ok(());
    }
    parity_replay_cmd(
        &args.input,
        args.train_start,
        args.train_s,
        &args.inject_at,
        method,
        inj,
    )
}

pub(crate) fn parity_replay_cmd(
    input: &std::path::Path,
    train_start: f64,
    train_s: f64,
    inject_at: &[f64],
    method: imu_fdi_cli::eval::parity_replay::ParityMethod,
    inj: Option<imu_fdi_cli::eval::parity_replay::Injection>,
) -> Result<()> {
    use hal_sim::array::ArrayKind;
    use imu_fdi_cli::eval::parity_replay::{
        injection_sizes, injection_sweep, read_any_imu_log, replay_parity_with,
    };
    let log = read_any_imu_log(input)?;
    for w in &log.warnings {
        eprintln!("warning: {w}");
    }
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
        let inj = inj.filter(|i| (i.channel >= 3) == (kind == ArrayKind::Gyro));
        let r = replay_parity_with(&log, kind, train_start, train_s, inj, method)?;
        let kind_name = if kind == ArrayKind::Gyro {
            "gyro"
        } else {
            "accel"
        };
        out!("{kind_name} (sensor = 3 x IMU + axis):");
        if method == imu_fdi_cli::eval::parity_replay::ParityMethod::GltCusum {
            out!(
                "  monitoring from {:.2} s; threshold factors from calibration [GLT, PCA, CUSUM] = [{:.2}, {:.2}, {:.2}]; correlation factor {:.2}",
                r.monitoring_from.unwrap_or(f64::NAN),
                r.threshold_scales[0],
                r.threshold_scales[1],
                r.threshold_scales[2],
                r.correlation_factor
            );
        } else {
            match r.monitoring_from {
                Some(t) => {
                    out!("  monitoring from {t:.2} s (multi-scale tests, in-flight calibration)")
                }
                None => out!("  never monitoring: the log ends before training does"),
            }
        }
        if !r.power_up_judged {
            // Never silent: "no alarm" here does not cover a sensor that
            // was already faulty when training began.
            out!("  a bias present since power-up is not judged (learned as the sensor's turn-on offset)");
        }
        if r.rest_common_mode {
            out!("  at rest, two or more gyros beyond the offset limit: not judged, none named (a steady turn, or several faulty gyros)");
        }
        if !r.not_judging.is_empty() {
            let off: Vec<String> = r
                .not_judging
                .iter()
                .map(|(a, b, p)| format!("{a:.2}-{b:.2} s ({p:?})"))
                .collect();
            out!("  not judging (no alarm covers these): {}", off.join(", "));
        }
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
        let back: Vec<String> = r
            .readmissions
            .iter()
            .map(|(k, t)| format!("sensor {k} at {t:.2}"))
            .collect();
        out!(
            "  re-admissions: {}",
            if back.is_empty() {
                "none".into()
            } else {
                back.join(", ")
            }
        );
        let st: Vec<String> = r
            .statuses
            .iter()
            .map(|(k, s, t)| {
                format!(
                    "sensor {k} {} at {t:.2} s",
                    imu_fdi_cli::report::parity::status_text(*s)
                )
            })
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
                method,
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

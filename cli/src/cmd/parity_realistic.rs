//! `imu-fdi-sim parity-realistic`: the parity monitor for real flights on
//! the realistic simulated profile (fitted to log171).

use anyhow::{bail, Result};

use hal_sim::array::ArrayKind;
use hal_sim::realistic::RealisticProfile;
use imu_fdi_cli::eval::parity_campaign::{fault_free_flights_on, steps_on, STEP_ONSET_S, TRAIN_S};

// The arguments of `parity-realistic` (help on `Cmd::ParityRealistic`).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// gyro, accel or both.
    #[arg(long, default_value = "both")]
    kind: String,
    /// Fault-free hours (flights of `--flight-hours`, seeds from
    /// `--fault-free-seed`).
    #[arg(long, default_value_t = 10)]
    hours: u32,
    /// Length of each fault-free flight, h: `--hours` is flown as
    /// `⌈hours / flight-hours⌉` flights (what the monitor learns over more
    /// than an hour shows only in longer flights).
    #[arg(long, default_value_t = 1)]
    flight_hours: u32,
    /// Rounds of steps per size (18 flights each: IMU × axis × sign).
    #[arg(long, default_value_t = 2)]
    rounds: u64,
    /// First seed of the fault-free flights (one per hour): pick others to
    /// see the figures on flights the tuning never saw.
    #[arg(long, default_value_t = 1000)]
    fault_free_seed: u64,
    /// First seed of the step flights (one per case).
    #[arg(long, default_value_t = 1)]
    step_seed: u64,
    /// Onset of the steps, s of flight (training takes the first 30 s):
    /// the default judges them in the first minute of monitoring; e.g. 630
    /// judges them 10 min in, against covariances learnt in flight.
    #[arg(long, default_value_t = STEP_ONSET_S)]
    step_onset: f64,
    /// Log the IMUs integrated over each interval (delta angle / delta
    /// velocity, as a FIFO driver hands them) instead of point-sampled.
    #[arg(long)]
    integrated: bool,
    /// Also print each fault-free alarm event (text only): when, on which
    /// window length, the suspect and its estimated bias, what was
    /// isolated, and how far the suspect's simulated bias had really
    /// drifted from its mean over the 2 minutes before.
    #[arg(long)]
    events: bool,
    /// The multi-scale tests' per-decision false-alarm probability
    /// (default: the flight configuration's, 1e-6): lower trades
    /// sensitivity for fewer false alarms (`scripts/parity-min-detectable.sh`
    /// sweeps it).
    #[arg(long)]
    false_alarm: Option<f64>,
    /// Step sizes, comma-separated (°/s for gyros, m/s² for
    /// accelerometers; default 0.5,1,2,3 and 0.1,0.2,0.3,0.5).
    #[arg(long, value_delimiter = ',')]
    sizes: Option<Vec<f64>>,
    /// One JSON object on stdout instead of text (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `parity-realistic`.
pub(crate) fn run(a: Args) -> Result<()> {
    let _progress = super::progress::spinner("parity-realistic: simulated flights");
    let kinds: &[ArrayKind] = match a.kind.as_str() {
        "gyro" => &[ArrayKind::Gyro],
        "accel" => &[ArrayKind::Accel],
        "both" => &[ArrayKind::Gyro, ArrayKind::Accel],
        other => bail!("--kind: '{other}' is not gyro, accel or both"),
    };
    // After training (and the first decision), within a day of flight.
    if !(a.step_onset >= TRAIN_S + 5.0 && a.step_onset <= 86_400.0) {
        bail!(
            "--step-onset: {} s is not between {} s (training ends at {TRAIN_S} s) and 86400 s",
            a.step_onset,
            TRAIN_S + 5.0
        );
    }
    if let Some(p) = a.false_alarm {
        if !(p > 0.0 && p < 0.5) {
            bail!("--false-alarm: {p} is not a probability in (0, 0.5)");
        }
    }
    if let Some(bad) = a
        .sizes
        .iter()
        .flatten()
        .find(|s| !(s.is_finite() && **s > 0.0))
    {
        bail!("--sizes: {bad} is not a positive step size");
    }
    if a.flight_hours == 0 {
        bail!("--flight-hours: must be at least 1");
    }
    let flights = a.hours.div_ceil(a.flight_hours);
    let profile = if a.integrated {
        RealisticProfile::log171().integrated()
    } else {
        RealisticProfile::log171()
    };
    let mut kinds_json = Vec::new();
    for &kind in kinds {
        let ff = fault_free_flights_on(
            &profile,
            kind,
            flights,
            a.flight_hours,
            a.fault_free_seed,
            a.false_alarm,
        )?;
        let mut steps_json = Vec::new();
        if !a.json {
            out!(
                "{}: {:.2} h fault-free: {} alarm events ({:.2}/h), {} sensors isolated ({} re-admitted){}",
                if kind == ArrayKind::Gyro {
                    "gyro"
                } else {
                    "accel"
                },
                ff.hours,
                ff.alarm_events,
                ff.alarm_events as f64 / ff.hours.max(1e-9),
                ff.isolations,
                ff.readmissions,
                if kind == ArrayKind::Gyro {
                    format!(", {:.1} s judged at rest", ff.at_rest_s)
                } else {
                    String::new()
                }
            );
            if a.events {
                for e in &ff.events {
                    out!(
                        "  seed {} t {:.0} s ({:.0} s monitored): {:.2}× threshold on the {:.1}-s window, sensor {} bias {:+.3} {}, isolated {}; its simulated bias drifted {:+.3} {}",
                        e.seed,
                        e.t,
                        e.since_monitoring,
                        e.ratio,
                        e.window_s,
                        e.suspect,
                        e.bias,
                        if kind == ArrayKind::Gyro { "°/s" } else { "m/s²" },
                        e.isolated.map_or("none".into(), |k| k.to_string()),
                        e.true_drift,
                        if kind == ArrayKind::Gyro { "°/s" } else { "m/s²" },
                    );
                }
            }
        }
        let (unit, default_sizes): (&str, &[f64]) = match kind {
            ArrayKind::Gyro => ("°/s", &[0.5, 1.0, 2.0, 3.0]),
            ArrayKind::Accel => ("m/s²", &[0.1, 0.2, 0.3, 0.5]),
        };
        for &s in a.sizes.as_deref().unwrap_or(default_sizes) {
            let si = match kind {
                ArrayKind::Gyro => s.to_radians(),
                ArrayKind::Accel => s,
            };
            let r = steps_on(
                &profile,
                kind,
                si,
                a.rounds,
                a.step_seed,
                a.step_onset,
                a.false_alarm,
            )?;
            let med = r.delays.get(r.delays.len() / 2).copied();
            steps_json.push(serde_json::json!({
                format!("size_{}", if unit == "°/s" { "deg_s" } else { "m_s2" }): s,
                "isolated": r.isolated,
                "detected": r.detected,
                "cases": r.cases,
                "flights_with_false_alarm": r.false_alarms,
                "median_delay_s": med,
            }));
            if a.json {
                continue;
            }
            out!(
                "  step {s} {unit}: {}/{} isolated within 10 s ({} detected), {} flights with a false alarm, median delay {}",
                r.isolated,
                r.cases,
                r.detected,
                r.false_alarms,
                med.map_or("-".into(), |d| format!("{d:.1} s"))
            );
        }
        kinds_json.push(serde_json::json!({
            "kind": if kind == ArrayKind::Gyro { "gyro" } else { "accel" },
            "integrated": a.integrated,
            "step_onset_s": a.step_onset,
            "false_alarm": a.false_alarm,
            "fault_free_h": ff.hours,
            "fault_free_flight_h": a.flight_hours,
            "fault_free_alarm_events": ff.alarm_events,
            "fault_free_alarms_per_hour": ff.alarm_events as f64 / ff.hours.max(1e-9),
            "fault_free_isolations": ff.isolations,
            "fault_free_readmissions": ff.readmissions,
            "fault_free_at_rest_s": ff.at_rest_s,
            "steps": steps_json,
        }));
    }
    if a.json {
        super::json::emit(&serde_json::json!({ "kinds": kinds_json }));
    }
    Ok(())
}

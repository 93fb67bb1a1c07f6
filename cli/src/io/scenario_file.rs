//! Scenarios as TOML files: vehicle profile, duration, IMU error model,
//! aiding rates and noise, fault sizes and a fault table written like the
//! papers' tables. The built-in scenarios ship as such files in
//! `scenarios/` (a test keeps them identical to the built-ins).

use std::path::Path;

use anyhow::{Context, Result};

use hal_sim::fault::{FaultKind, FaultRow, FaultSizes};
use hal_sim::scenario::Scenario;

/// Reads a scenario file; errors name the file and, for syntax or field
/// errors, the line and column.
pub fn read_scenario(path: &Path) -> Result<Scenario> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    parse_scenario(&text).with_context(|| format!("{}: not a valid scenario file", path.display()))
}

/// Longest scenario, s (about 11.6 days).
pub const MAX_DURATION_S: f64 = 1e6;
/// Highest IMU or aiding rate, Hz.
pub const MAX_RATE_HZ: f64 = 1e5;
/// Most IMU samples one run may simulate (duration × rate).
pub const MAX_SAMPLES: f64 = 1e9;
/// Largest magnitude of any other number in a scenario or fault table
/// (noise, bias, sizes, σ, fault parameters).
pub const MAX_VALUE: f64 = 1e6;

/// `x` finite and within `[lo, hi]`, else an error naming `field`.
fn bounded(field: &str, x: f64, lo: f64, hi: f64, unit: &str) -> Result<()> {
    if x.is_finite() && x >= lo && x <= hi {
        Ok(())
    } else {
        anyhow::bail!("{field} = {x}: must be a finite number from {lo} to {hi}{unit}")
    }
}

/// `x` finite, > 0 and at most `hi`, else an error naming `field`.
fn positive(field: &str, x: f64, hi: f64, unit: &str) -> Result<()> {
    if x.is_finite() && x > 0.0 && x <= hi {
        Ok(())
    } else {
        anyhow::bail!("{field} = {x}: must be a finite number > 0 and at most {hi}{unit}")
    }
}

/// Checks a fault table's rows: channel 0–5, finite times with
/// 0 ≤ start < end ≤ [`MAX_DURATION_S`], a sign of ±1-sized magnitude and
/// finite fault parameters. Errors name the row (`faults[i]`) and field.
pub fn validate_faults(faults: &[FaultRow]) -> Result<()> {
    for (i, r) in faults.iter().enumerate() {
        if r.channel > 5 {
            anyhow::bail!("faults[{i}].channel = {}: channel must be 0–5", r.channel);
        }
        bounded(
            &format!("faults[{i}].start"),
            r.start,
            -MAX_DURATION_S,
            MAX_DURATION_S,
            " s",
        )?;
        bounded(
            &format!("faults[{i}].end"),
            r.end,
            -MAX_DURATION_S,
            MAX_DURATION_S,
            " s",
        )?;
        if r.end <= r.start {
            anyhow::bail!(
                "fault row on channel {} from {} to {} s: channel must be 0–5 and end > start",
                r.channel,
                r.start,
                r.end
            );
        }
        bounded(
            &format!("faults[{i}].sign"),
            r.sign,
            -MAX_VALUE,
            MAX_VALUE,
            "",
        )?;
        let param = match r.kind {
            FaultKind::Clip(x)
            | FaultKind::Spikes(x)
            | FaultKind::NoiseIncrease(x)
            | FaultKind::ScaleFactor(x) => Some(x),
            _ => None,
        };
        if let Some(x) = param {
            bounded(
                &format!("faults[{i}].kind ({:?})", r.kind),
                x,
                -MAX_VALUE,
                MAX_VALUE,
                "",
            )?;
        }
    }
    Ok(())
}

/// Checks fault sizes: every value finite with magnitude ≤ [`MAX_VALUE`].
pub fn validate_sizes(sizes: &FaultSizes) -> Result<()> {
    for (name, v) in [
        ("sizes.accel", &sizes.accel[..]),
        ("sizes.gyro", &sizes.gyro[..]),
        ("sizes.f_unit", &sizes.f_unit[..]),
    ] {
        for (k, x) in v.iter().enumerate() {
            bounded(&format!("{name}[{k}]"), *x, -MAX_VALUE, MAX_VALUE, "")?;
        }
    }
    Ok(())
}

/// Checks every number of a scenario before anything is simulated (or
/// allocated): durations, rates and sample counts bounded, σ, noise and
/// sizes finite and bounded. Errors name the field.
pub fn validate_scenario(scn: &Scenario) -> Result<()> {
    positive("duration_s", scn.duration_s, MAX_DURATION_S, " s")?;
    positive("imu_rate_hz", scn.imu_rate_hz, MAX_RATE_HZ, " Hz")?;
    let samples = scn.duration_s * scn.imu_rate_hz;
    if samples > MAX_SAMPLES {
        anyhow::bail!(
            "duration_s × imu_rate_hz = {samples:.3e} samples: at most {MAX_SAMPLES:.0e} per run"
        );
    }
    let a = &scn.aiding;
    bounded("aiding.vel_rate_hz", a.vel_rate_hz, 0.0, MAX_RATE_HZ, " Hz")?;
    bounded("aiding.att_rate_hz", a.att_rate_hz, 0.0, MAX_RATE_HZ, " Hz")?;
    bounded("aiding.vel_sigma", a.vel_sigma, 0.0, MAX_VALUE, " m/s")?;
    for (k, x) in a.att_sigma.iter().enumerate() {
        bounded(
            &format!("aiding.att_sigma[{k}]"),
            *x,
            0.0,
            MAX_VALUE,
            " rad",
        )?;
    }
    bounded("aiding.delay_s", a.delay_s, 0.0, MAX_DURATION_S, " s")?;
    for (triad, e) in [
        ("accel", &scn.imu_errors.accel),
        ("gyro", &scn.imu_errors.gyro),
    ] {
        for (field, x) in [
            ("noise_density", e.noise_density),
            ("turn_on_bias", e.turn_on_bias),
            ("bias_random_walk", e.bias_random_walk),
            ("scale_factor", e.scale_factor),
            ("misalignment", e.misalignment),
            ("full_scale", e.full_scale),
            ("lsb", e.lsb),
        ] {
            bounded(
                &format!("imu_errors.{triad}.{field}"),
                x,
                0.0,
                MAX_VALUE,
                "",
            )?;
        }
    }
    for (k, x) in scn.min_fault.iter().enumerate() {
        bounded(&format!("min_fault[{k}]"), *x, 0.0, MAX_VALUE, "")?;
    }
    validate_sizes(&scn.sizes)?;
    validate_faults(&scn.faults)
}

/// Parses scenario TOML and checks it ([`validate_scenario`]).
pub fn parse_scenario(text: &str) -> Result<Scenario> {
    let scn: Scenario = toml::from_str(text).map_err(|e| toml_error(text, &e))?;
    validate_scenario(&scn)?;
    Ok(scn)
}

/// A TOML error on one line: `line L, column C: message` (the `toml`
/// crate's `Display` adds the source line and a caret on lines of their own).
pub fn toml_error(text: &str, e: &toml::de::Error) -> anyhow::Error {
    let msg = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
    match e.span() {
        Some(span) => {
            let before = text.get(..span.start).unwrap_or(text);
            let line = before.matches('\n').count() + 1;
            let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            let src: String = text
                .lines()
                .nth(line - 1)
                .unwrap_or("")
                .trim()
                .chars()
                .take(60)
                .collect();
            anyhow::anyhow!("line {line}, column {col} (`{src}`): {msg}")
        }
        None => anyhow::anyhow!("{msg}"),
    }
}

/// A scenario as TOML text, with a header comment.
pub fn scenario_toml(scn: &Scenario) -> Result<String> {
    let body = toml::to_string_pretty(scn)?;
    Ok(format!(
        "# imu-fdi scenario '{}' (hal-sim). Channels 0-5 = a_x a_y a_z p q r;\n\
         # units m/s, m/s^2, rad, rad/s; fault kinds E1-E3 (sizes.accel/gyro = [a, b, c]),\n\
         # F1-F3 (sizes.f_unit), or hardware: Stuck, Dropout, Clip, Spikes, NoiseIncrease, ScaleFactor.\n\n{body}",
        scn.name
    ))
}

/// Loads a built-in name or, if `name` ends in `.toml`, a scenario file.
pub fn load_scenario(name: &str) -> Result<Scenario> {
    if name.ends_with(".toml") {
        return read_scenario(Path::new(name));
    }
    Scenario::builtin(name).ok_or_else(|| {
        anyhow::anyhow!(
            "unknown scenario '{name}'; built-ins: {} (or a path to a .toml file)",
            Scenario::BUILTIN.join(", ")
        )
    })
}

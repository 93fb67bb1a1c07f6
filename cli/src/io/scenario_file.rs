//! Scenarios as TOML files: vehicle profile, duration, IMU error model,
//! aiding rates and noise, fault sizes and a fault table written like the
//! papers' tables. The built-in scenarios ship as such files in
//! `scenarios/` (a test keeps them identical to the built-ins).

use std::path::Path;

use anyhow::{Context, Result};

use hal_sim::scenario::Scenario;

/// Reads a scenario file; errors name the file and, for syntax or field
/// errors, the line and column.
pub fn read_scenario(path: &Path) -> Result<Scenario> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    parse_scenario(&text).with_context(|| format!("{}: not a valid scenario file", path.display()))
}

/// Parses scenario TOML.
pub fn parse_scenario(text: &str) -> Result<Scenario> {
    let scn: Scenario = toml::from_str(text).map_err(|e| anyhow::anyhow!("{e}"))?;
    if !(scn.duration_s > 0.0 && scn.imu_rate_hz > 0.0) {
        anyhow::bail!("duration_s and imu_rate_hz must be positive");
    }
    if let Some(r) = scn.faults.iter().find(|r| {
        r.channel > 5 || r.end.partial_cmp(&r.start) != Some(core::cmp::Ordering::Greater)
    }) {
        anyhow::bail!(
            "fault row on channel {} from {} to {} s: channel must be 0–5 and end > start",
            r.channel,
            r.start,
            r.end
        );
    }
    Ok(scn)
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

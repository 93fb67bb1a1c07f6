//! `--json` on every subcommand: one JSON object on stdout, keys in
//! snake_case with their unit in the name (`_s`, `_hz`, `_m_s2`, `_rad_s`,
//! `_deg_s`, …; dimensionless fractions `_fraction`), integers are counts.
//! The convention is written down in `docs/cli-json.md`; the test
//! `cli/tests/json_schema.rs` checks every subcommand against it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use hal_sim::metrics::RunMetrics;
use imu_fdi::model::CHANNEL_NAMES;
use serde_json::{json, Value};

/// Where `--json [FILE]` sends the object: bare `--json` is stdout only
/// (no text), `--json FILE` writes FILE beside the usual text.
pub(crate) fn to_stdout(dest: Option<&Path>) -> bool {
    dest == Some(Path::new("-"))
}

/// Prints `v` as one line on stdout.
pub(crate) fn emit(v: &Value) {
    out!("{v}");
}

/// Writes `v` to `dest` (`-`: stdout, no "wrote" line) and says so on
/// stdout otherwise.
pub(crate) fn write(dest: &Option<PathBuf>, v: &Value) -> Result<()> {
    match dest.as_deref() {
        None => Ok(()),
        Some(p) if to_stdout(Some(p)) => {
            emit(v);
            Ok(())
        }
        Some(p) => {
            std::fs::write(p, serde_json::to_string_pretty(v)?)
                .with_context(|| format!("cannot write {}", p.display()))?;
            out!("wrote {}", p.display());
            Ok(())
        }
    }
}

/// The unit suffix of IMU channel `i` (0–2 accelerometer, 3–5 gyro).
pub(crate) fn channel_unit(i: usize) -> &'static str {
    if i < 3 {
        "m_s2"
    } else {
        "rad_s"
    }
}

/// A [`RunMetrics`] (the per-channel table of `scenario`, `demo`,
/// `sweep`) in the JSON convention.
pub(crate) fn metrics(m: &RunMetrics) -> Value {
    let channels: Vec<Value> = m
        .channels
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let u = channel_unit(i);
            json!({
                "channel": CHANNEL_NAMES.get(i).copied().unwrap_or("?"),
                "faults": c.faults,
                "detected": c.detected,
                "detection_fraction": c.detection_rate(),
                "false_alarm_fraction": c.false_alarm_rate(),
                "wrong_channel_fraction": c.wrong_channel_rate(),
                "mean_delay_s": c.delay_mean(),
                "max_delay_s": (c.delay_n > 0).then_some(c.delay_max),
                format!("rmse_{u}"): c.rmse(),
                format!("rmse_as_written_{u}"): c.rmse_as_written(),
            })
        })
        .collect();
    let r = &m.residual_rms;
    let s = &m.state_rmse;
    json!({
        "runs": m.runs,
        "latency_s": m.latency_s,
        "fault_free_monitored_s": m.free_time_s,
        "false_alarm_events": m.false_alarm_events,
        "covariance_resets": m.covariance_resets,
        "channels": channels,
        "residual_bias_rms": {
            "ax_m_s2": r[0], "ay_m_s2": r[1], "az_m_s2": r[2],
            "gx_rad_s": r[3], "gy_rad_s": r[4], "gz_rad_s": r[5],
        },
        "state_rmse": {
            "u_m_s": s[0], "v_m_s": s[1], "w_m_s": s[2],
            "roll_rad": s[3], "pitch_rad": s[4], "yaw_rad": s[5],
        },
    })
}

/// A campaign summary in the JSON convention (intervals as `{value, low,
/// high}` under a key carrying the unit).
pub(crate) fn campaign_summary(s: &imu_fdi_cli::eval::campaign::CampaignSummary) -> Value {
    let iv = |i: &imu_fdi_cli::eval::campaign::Interval| json!({"value": i.value, "low": i.low, "high": i.high});
    json!({
        "runs": s.runs,
        "first_index": s.index_range.0,
        "last_index": s.index_range.1,
        "detection_fraction": iv(&s.detection_rate),
        "sample_detection_fraction": iv(&s.sample_detection_rate),
        "false_alarms_per_hour": iv(&s.false_alarms_per_hour),
        "fault_free_h": s.fault_free_hours,
        "delay_s": iv(&s.delay_s),
        "isolation_fraction": iv(&s.isolation_accuracy),
        "rmse_accel_m_s2": iv(&s.rmse_accel),
        "rmse_gyro_deg_s": iv(&s.rmse_gyro_deg),
    })
}

/// Files written, as strings.
pub(crate) fn files(v: &[PathBuf]) -> Value {
    json!(v
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>())
}

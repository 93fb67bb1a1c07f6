//! SPEC §10 replay: CSV in (IMU + aiding, optional truth), CSV and JSON out.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use imu_fdi::model::{AidingKind, ImuVec, MeasVec, Measurement, CHANNEL_NAMES};
use imu_fdi::monitor::{Phase, UkfMonitor, UkfMonitorConfig};

use crate::scenario::Scenario;
use crate::sim::Simulator;

const IMU_COLS: [&str; 6] = [
    "imu0_ax", "imu0_ay", "imu0_az", "imu0_gx", "imu0_gy", "imu0_gz",
];
const DVL_COLS: [&str; 3] = ["dvl_u", "dvl_v", "dvl_w"];
const GNSS_COLS: [&str; 3] = ["gnss_vn", "gnss_ve", "gnss_vd"];
const ATT_COLS: [&str; 3] = ["att_roll", "att_pitch", "att_yaw"];

/// Per-channel summary of a replay.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ChannelSummary {
    /// Channel name.
    pub channel: String,
    /// Samples flagged (either sign).
    pub flagged_samples: usize,
    /// Time of the first flag, s.
    pub first_detection_s: Option<f64>,
    /// With truth columns: fault-active monitored samples.
    pub fault_samples: Option<usize>,
    /// With truth: of those, flagged with the right sign.
    pub correct_samples: Option<usize>,
    /// With truth: fault-free monitored samples flagged.
    pub false_alarm_samples: Option<usize>,
}

/// What a replay did.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ReplaySummary {
    /// Input rows read.
    pub rows: usize,
    /// Rows skipped (non-increasing or missing time, unparsable values).
    pub skipped_rows: usize,
    /// Rows whose IMU sample the monitor rejected (NaN, out of range).
    pub rejected_imu_rows: usize,
    /// Aiding model detected from the columns.
    pub aiding: String,
    /// Time monitoring started, s.
    pub monitoring_from_s: Option<f64>,
    /// Per channel.
    pub channels: Vec<ChannelSummary>,
}

fn parse_opt(rec: &csv::StringRecord, idx: Option<usize>) -> Option<f64> {
    let s = rec.get(idx?)?.trim();
    if s.is_empty() {
        return None;
    }
    s.parse::<f64>().ok()
}

/// Replays `input` through a monitor configured by `cfg` (its aiding kind is
/// overridden by the columns present) and writes `out` / `summary`.
///
/// With truth columns, flags within `grace_s` after the last fault-active row
/// count neither as false alarms nor as detections (the window is flushing),
/// as in the scenario metrics.
pub fn replay(
    input: &Path,
    out: Option<&Path>,
    summary: Option<&Path>,
    mut cfg: UkfMonitorConfig<f64>,
    grace_s: f64,
) -> Result<ReplaySummary> {
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(input)
        .with_context(|| format!("cannot open {}", input.display()))?;
    let headers = rdr
        .headers()
        .with_context(|| format!("{}: no header row", input.display()))?
        .clone();
    let col: HashMap<&str, usize> = headers.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let find = |name: &str| col.get(name).copied();
    let t_idx = find("t").with_context(|| format!("{}: missing column 't'", input.display()))?;
    let imu_idx: Vec<usize> = IMU_COLS
        .iter()
        .map(|c| find(c).with_context(|| format!("{}: missing column '{c}'", input.display())))
        .collect::<Result<_>>()?;
    let has_dvl = DVL_COLS.iter().any(|c| find(c).is_some());
    let has_gnss = GNSS_COLS.iter().any(|c| find(c).is_some());
    let (kind, vel_cols) = match (has_dvl, has_gnss) {
        (true, false) | (false, false) => (AidingKind::DvlCompass, DVL_COLS),
        (false, true) => (AidingKind::GnssAttitude, GNSS_COLS),
        (true, true) => bail!(
            "{}: both dvl_* and gnss_* columns; give one aiding source",
            input.display()
        ),
    };
    cfg.aiding = kind;
    let vel_idx: Vec<Option<usize>> = vel_cols.iter().map(|c| find(c)).collect();
    let att_idx: Vec<Option<usize>> = ATT_COLS.iter().map(|c| find(c)).collect();
    let truth_idx: Vec<Option<usize>> = CHANNEL_NAMES
        .iter()
        .map(|c| find(&format!("fault_imu0_{c}")))
        .collect();
    let has_truth = truth_idx.iter().all(|i| i.is_some());

    let mut monitor = UkfMonitor::<f64>::new(cfg)
        .map_err(|e| anyhow::anyhow!("invalid monitor configuration: {e:?}"))?;
    let mut writer = match out {
        Some(p) => Some(
            csv::Writer::from_path(p).with_context(|| format!("cannot write {}", p.display()))?,
        ),
        None => None,
    };
    if let Some(w) = writer.as_mut() {
        let mut h = vec!["t".to_string()];
        for s in ["x_u", "x_v", "x_w", "x_roll", "x_pitch", "x_yaw"] {
            h.push(s.into());
        }
        for c in CHANNEL_NAMES {
            h.push(format!("flag_{c}"));
        }
        for c in CHANNEL_NAMES {
            h.push(format!("fhat_{c}"));
        }
        w.write_record(&h)?;
    }
    let mut sum = ReplaySummary {
        aiding: format!("{kind:?}"),
        channels: CHANNEL_NAMES
            .iter()
            .map(|c| ChannelSummary {
                channel: (*c).into(),
                fault_samples: has_truth.then_some(0),
                correct_samples: has_truth.then_some(0),
                false_alarm_samples: has_truth.then_some(0),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    };
    let mut last_t: Option<f64> = None;
    let mut last_fault_t = f64::NEG_INFINITY;
    let mut nominal_dt = monitor.config().imu_period;
    for (line, rec) in rdr.records().enumerate() {
        let rec =
            rec.with_context(|| format!("{}: bad CSV at data row {}", input.display(), line + 1))?;
        sum.rows += 1;
        let Some(t) = parse_opt(&rec, Some(t_idx)) else {
            sum.skipped_rows += 1;
            continue;
        };
        if last_t.is_some_and(|lt| t <= lt) || !t.is_finite() {
            sum.skipped_rows += 1;
            continue;
        }
        let dt = match last_t {
            Some(lt) => t - lt,
            None => nominal_dt,
        };
        if last_t.is_some() && sum.rows == 2 {
            nominal_dt = dt;
        }
        last_t = Some(t);
        let imu =
            ImuVec::from_fn(|i, _| parse_opt(&rec, imu_idx.get(i).copied()).unwrap_or(f64::NAN));
        let mut z = MeasVec::zeros();
        let mut avail = [false; 6];
        for (i, idx) in vel_idx.iter().chain(att_idx.iter()).enumerate() {
            if let Some(v) = parse_opt(&rec, *idx) {
                z[i] = v;
                avail[i] = true;
            }
        }
        let r = monitor.step(
            &imu,
            dt,
            &Measurement {
                z,
                available: avail,
            },
        );
        if r.health.input_invalid {
            sum.rejected_imu_rows += 1;
        }
        if r.phase == Phase::Monitoring && sum.monitoring_from_s.is_none() {
            sum.monitoring_from_s = Some(t);
        }
        let truth: Option<Vec<f64>> = has_truth.then(|| {
            truth_idx
                .iter()
                .map(|i| parse_opt(&rec, *i).unwrap_or(0.0))
                .collect()
        });
        let any_fault = truth
            .as_ref()
            .is_some_and(|tr| tr.iter().any(|v| *v != 0.0));
        if any_fault {
            last_fault_t = t;
        }
        let in_grace = !any_fault && t - last_fault_t < grace_s;
        for (i, ch) in sum.channels.iter_mut().enumerate() {
            let flag = r.status[i].sign();
            let flagged = flag.is_some_and(|f| f != 0);
            if flagged {
                ch.flagged_samples += 1;
                ch.first_detection_s.get_or_insert(t);
            }
            if let (Some(tr), Some(f)) = (truth.as_ref(), flag) {
                let fv = tr.get(i).copied().unwrap_or(0.0);
                if fv != 0.0 {
                    *ch.fault_samples.get_or_insert(0) += 1;
                    let want = if fv > 0.0 { 1 } else { -1 };
                    *ch.correct_samples.get_or_insert(0) += usize::from(f == want);
                } else if !any_fault && !in_grace && flagged {
                    *ch.false_alarm_samples.get_or_insert(0) += 1;
                }
            }
        }
        if let Some(w) = writer.as_mut() {
            let mut row = vec![format!("{t}")];
            for v in r.state.iter() {
                row.push(format!("{v}"));
            }
            for s in r.status.iter() {
                row.push(s.sign().map_or(String::new(), |v| v.to_string()));
            }
            for v in r.fault_estimate.iter() {
                row.push(format!("{v}"));
            }
            w.write_record(&row)?;
        }
    }
    if let Some(mut w) = writer {
        w.flush()?;
    }
    if let Some(p) = summary {
        std::fs::write(p, serde_json::to_string_pretty(&sum)?)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    Ok(sum)
}

/// Writes a simulated run in the SPEC §10 input format, with truth columns
/// (`fault_imu0_*`, `truth_*`) that `replay` scores against.
pub fn write_simulated(scn: &Scenario, seed: u64, path: &Path) -> Result<u64> {
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("cannot write {}", path.display()))?;
    let vel = match scn.aiding.kind {
        AidingKind::DvlCompass => DVL_COLS,
        AidingKind::GnssAttitude => GNSS_COLS,
    };
    let mut h: Vec<String> = vec!["t".into()];
    h.extend(IMU_COLS.iter().map(|s| s.to_string()));
    h.extend(vel.iter().map(|s| s.to_string()));
    h.extend(ATT_COLS.iter().map(|s| s.to_string()));
    h.extend(CHANNEL_NAMES.iter().map(|c| format!("fault_imu0_{c}")));
    h.extend(
        [
            "truth_u",
            "truth_v",
            "truth_w",
            "truth_roll",
            "truth_pitch",
            "truth_yaw",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    w.write_record(&h)?;
    let mut n = 0;
    for s in Simulator::new(scn, seed) {
        let mut row = vec![format!("{:.4}", s.t)];
        match s.imu {
            Some(v) => row.extend(v.iter().map(|x| format!("{x:.9e}"))),
            None => row.extend(std::iter::repeat_n(String::new(), 6)),
        }
        for i in 0..6 {
            row.push(if s.aiding_available[i] {
                format!("{:.9e}", s.aiding[i])
            } else {
                String::new()
            });
        }
        row.extend(s.fault.iter().map(|x| format!("{x:.9e}")));
        row.extend(s.truth.state.iter().map(|x| format!("{x:.9e}")));
        w.write_record(&row)?;
        n += 1;
    }
    w.flush()?;
    Ok(n)
}

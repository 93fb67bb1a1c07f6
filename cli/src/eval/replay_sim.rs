//! Simulated runs written in the SPEC §10 replay format, with truth columns.

use std::path::Path;

use anyhow::{Context, Result};
use hal_sim::scenario::Scenario;
use hal_sim::sim::Simulator;
use imu_fdi::model::{AidingKind, CHANNEL_NAMES};

use super::replay::{ATT_COLS, DVL_COLS, GNSS_COLS, IMU_COLS};

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

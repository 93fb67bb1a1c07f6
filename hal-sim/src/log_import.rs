//! PX4 ULog → SPEC §10 replay CSV: the primary IMU (`sensor_combined`), GNSS
//! velocity (`vehicle_gps_position` or `sensor_gps`, 3-D fix and valid NED
//! velocity only) and attitude (`vehicle_attitude` quaternion → ZYX Euler),
//! each aiding sample on the first IMU row at or after its timestamp.
//! Parsed with the `px4-ulog` crate (Auterion, MIT).
//!
//! The attitude PX4 logs comes from its own EKF on the same IMU: it is not
//! an independent sensor (SPEC §8 S6), so give it a wide R when replaying.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use px4_ulog::full_parser::{read_file, SomeVec};

/// What a conversion produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportSummary {
    /// IMU rows written.
    pub rows: usize,
    /// First and last time, s.
    pub span: (f64, f64),
    /// Mean IMU rate, Hz.
    pub imu_rate_hz: f64,
    /// Rows carrying a GNSS velocity.
    pub gnss_rows: usize,
    /// Rows carrying an attitude.
    pub att_rows: usize,
}

fn column(fields: &HashMap<String, SomeVec>, name: &str) -> Option<Vec<f64>> {
    Some(match fields.get(name)? {
        SomeVec::Int8(v) => v.iter().map(|x| f64::from(*x)).collect(),
        SomeVec::UInt8(v) => v.iter().map(|x| f64::from(*x)).collect(),
        SomeVec::Int16(v) => v.iter().map(|x| f64::from(*x)).collect(),
        SomeVec::UInt16(v) => v.iter().map(|x| f64::from(*x)).collect(),
        SomeVec::Int32(v) => v.iter().map(|x| f64::from(*x)).collect(),
        SomeVec::UInt32(v) => v.iter().map(|x| f64::from(*x)).collect(),
        SomeVec::Int64(v) => v.iter().map(|x| *x as f64).collect(),
        SomeVec::UInt64(v) => v.iter().map(|x| *x as f64).collect(),
        SomeVec::Float(v) => v.iter().map(|x| f64::from(*x)).collect(),
        SomeVec::Double(v) => v.clone(),
        SomeVec::Bool(v) => v.iter().map(|x| f64::from(u8::from(*x))).collect(),
        SomeVec::Char(_) => return None,
    })
}

/// ZYX Euler angles (roll, pitch, yaw) of a Hamilton quaternion `[w, x, y, z]`
/// rotating body FRD into NED.
pub fn quaternion_to_euler(q: [f64; 4]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw]
}

/// Converts a `.ulg` to a SPEC §10 CSV at `out`.
pub fn ulog_to_replay_csv(input: &Path, out: &Path) -> Result<ImportSummary> {
    let name = input
        .to_str()
        .with_context(|| format!("{}: path is not UTF-8", input.display()))?;
    let parsed = read_file(name)
        .with_context(|| format!("{}: not a readable ULog file", input.display()))?;
    let first = |topic: &str| parsed.messages.get(topic).and_then(|m| m.values().next());
    let imu = first("sensor_combined")
        .with_context(|| format!("{}: no sensor_combined topic", input.display()))?;
    let col = |f: &HashMap<String, SomeVec>, n: &str| {
        column(f, n).with_context(|| format!("{}: missing field {n}", input.display()))
    };
    let t_imu = col(imu, "timestamp")?;
    let g: Vec<Vec<f64>> = (0..3)
        .map(|i| col(imu, &format!("gyro_rad[{i}]")))
        .collect::<Result<_>>()?;
    let a: Vec<Vec<f64>> = (0..3)
        .map(|i| col(imu, &format!("accelerometer_m_s2[{i}]")))
        .collect::<Result<_>>()?;
    if t_imu.len() < 10 {
        bail!("{}: fewer than 10 IMU samples", input.display());
    }
    let n = t_imu.len();
    let mut gnss: Vec<Option<[f64; 3]>> = vec![None; n];
    let mut att: Vec<Option<[f64; 3]>> = vec![None; n];
    // Index of the first IMU row at or after time t (µs).
    let slot = |t: f64| t_imu.partition_point(|x| *x < t);
    if let Some(f) = first("vehicle_gps_position").or_else(|| first("sensor_gps")) {
        let (t, vn, ve, vd) = (
            col(f, "timestamp")?,
            col(f, "vel_n_m_s")?,
            col(f, "vel_e_m_s")?,
            col(f, "vel_d_m_s")?,
        );
        let valid = column(f, "vel_ned_valid").unwrap_or_else(|| vec![1.0; t.len()]);
        let fix = column(f, "fix_type").unwrap_or_else(|| vec![3.0; t.len()]);
        for i in 0..t.len() {
            if valid[i] > 0.5 && fix[i] >= 3.0 {
                if let Some(s) = gnss.get_mut(slot(t[i])) {
                    *s = Some([vn[i], ve[i], vd[i]]);
                }
            }
        }
    }
    if let Some(f) = first("vehicle_attitude") {
        let t = col(f, "timestamp")?;
        let q: Vec<Vec<f64>> = (0..4)
            .map(|i| col(f, &format!("q[{i}]")))
            .collect::<Result<_>>()?;
        for i in 0..t.len() {
            if let Some(s) = att.get_mut(slot(t[i])) {
                *s = Some(quaternion_to_euler([q[0][i], q[1][i], q[2][i], q[3][i]]));
            }
        }
    }
    let mut w =
        csv::Writer::from_path(out).with_context(|| format!("cannot write {}", out.display()))?;
    w.write_record([
        "t",
        "imu0_ax",
        "imu0_ay",
        "imu0_az",
        "imu0_gx",
        "imu0_gy",
        "imu0_gz",
        "gnss_vn",
        "gnss_ve",
        "gnss_vd",
        "att_roll",
        "att_pitch",
        "att_yaw",
    ])?;
    let cell = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x}"));
    let mut last_t = f64::NEG_INFINITY;
    let mut rows = 0;
    for i in 0..n {
        let t = t_imu[i] * 1e-6;
        if t <= last_t {
            continue;
        }
        last_t = t;
        let mut rec = vec![format!("{t}")];
        rec.extend((0..3).map(|k| format!("{}", a[k][i])));
        rec.extend((0..3).map(|k| format!("{}", g[k][i])));
        rec.extend((0..3).map(|k| cell(gnss[i].map(|v| v[k]))));
        rec.extend((0..3).map(|k| cell(att[i].map(|v| v[k]))));
        w.write_record(&rec)?;
        rows += 1;
    }
    w.flush()?;
    let span = (t_imu[0] * 1e-6, t_imu[n - 1] * 1e-6);
    Ok(ImportSummary {
        rows,
        span,
        imu_rate_hz: (n - 1) as f64 / (span.1 - span.0).max(1e-9),
        gnss_rows: gnss.iter().filter(|x| x.is_some()).count(),
        att_rows: att.iter().filter(|x| x.is_some()).count(),
    })
}

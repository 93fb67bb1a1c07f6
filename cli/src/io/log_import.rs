//! Flight logs → SPEC §10 replay CSV.
//!
//! - PX4 ULog (`px4-ulog` crate, Auterion, MIT): the primary IMU
//!   (`sensor_combined`), GNSS velocity (`vehicle_gps_position` or
//!   `sensor_gps`, 3-D fix and valid NED velocity only) and attitude
//!   (`vehicle_attitude` quaternion → ZYX Euler). The per-instance
//!   `vehicle_imu` topics are left out: PX4's default logging records them at
//!   1–2 Hz, unaligned, which no IMU monitor can use.
//! - ArduPilot DataFlash (`ardupilot-binlog` crate): every IMU instance
//!   (synchronous rows), GPS velocity and ATT.
//!
//! Each aiding sample goes on the first IMU row at or after its timestamp.
//! The attitude either autopilot logs comes from its own estimator on the
//! same IMUs: it is not an independent sensor (SPEC §8 S6), so give it a
//! wide R when replaying.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use imu_fdi::math::wrap_pi_f64;
use px4_ulog::full_parser::{read_file, SomeVec};

/// What a conversion produced.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportSummary {
    /// IMU rows written.
    pub rows: usize,
    /// First and last time, s.
    pub span: (f64, f64),
    /// Mean IMU rate, Hz.
    pub imu_rate_hz: f64,
    /// IMU instances written (`imu0_…`, `imu1_…`, …).
    pub imu_instances: usize,
    /// Rows carrying a GNSS velocity.
    pub gnss_rows: usize,
    /// Rows carrying an attitude.
    pub att_rows: usize,
    /// Why the parser stopped early, if it did (only the valid prefix of
    /// the log was converted).
    pub ended_early: Option<String>,
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
    let rows = ReplayRows {
        t: t_imu.iter().map(|t| t * 1e-6).collect(),
        imus: (0..n)
            .map(|i| vec![[a[0][i], a[1][i], a[2][i], g[0][i], g[1][i], g[2][i]]])
            .collect(),
        gnss,
        att,
    };
    let mut summary = write_replay_csv(out, &rows)?;
    summary.ended_early = match &parsed.completeness {
        px4_ulog::stream_parser::model::Completeness::Complete => None,
        px4_ulog::stream_parser::model::Completeness::Truncated => {
            Some("the file ends partway through a record".into())
        }
        px4_ulog::stream_parser::model::Completeness::MalformedRecord(why) => {
            Some(format!("malformed record: {why}"))
        }
    };
    Ok(summary)
}

/// IMU rows with the aiding that arrived at each row, ready for
/// [`write_replay_csv`].
#[derive(Debug, Clone, Default)]
pub struct ReplayRows {
    /// Row times, s.
    pub t: Vec<f64>,
    /// Per row, per IMU instance: `[a_x, a_y, a_z, p, q, r]`.
    pub imus: Vec<Vec<[f64; 6]>>,
    /// Per row: GNSS NED velocity, if one arrived.
    pub gnss: Vec<Option<[f64; 3]>>,
    /// Per row: roll, pitch, yaw (rad), if one arrived.
    pub att: Vec<Option<[f64; 3]>>,
}

/// Writes `rows` as a SPEC §10 CSV (`imu{k}_…` per instance, `gnss_*`,
/// `att_*`); rows whose time does not increase are dropped.
pub fn write_replay_csv(out: &Path, rows: &ReplayRows) -> Result<ImportSummary> {
    let n = rows.t.len();
    let instances = rows.imus.iter().map(Vec::len).max().unwrap_or(0);
    if n < 10 || instances == 0 {
        bail!("fewer than 10 IMU samples to write to {}", out.display());
    }
    let mut w =
        csv::Writer::from_path(out).with_context(|| format!("cannot write {}", out.display()))?;
    let mut header = vec!["t".to_string()];
    for k in 0..instances {
        for c in ["ax", "ay", "az", "gx", "gy", "gz"] {
            header.push(format!("imu{k}_{c}"));
        }
    }
    for c in [
        "gnss_vn",
        "gnss_ve",
        "gnss_vd",
        "att_roll",
        "att_pitch",
        "att_yaw",
    ] {
        header.push(c.into());
    }
    w.write_record(&header)?;
    let cell = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x}"));
    let mut last_t = f64::NEG_INFINITY;
    let mut written = 0;
    let (mut gnss_rows, mut att_rows) = (0, 0);
    for (i, &t) in rows.t.iter().enumerate() {
        if t <= last_t || !t.is_finite() {
            continue;
        }
        last_t = t;
        let mut rec = vec![format!("{t}")];
        let imus = rows.imus.get(i).map_or(&[][..], Vec::as_slice);
        for k in 0..instances {
            let s = imus.get(k);
            rec.extend((0..6).map(|c| cell(s.and_then(|s| s.get(c).copied()))));
        }
        let g = rows.gnss.get(i).copied().flatten();
        let a = rows.att.get(i).copied().flatten();
        gnss_rows += usize::from(g.is_some());
        att_rows += usize::from(a.is_some());
        rec.extend((0..3).map(|k| cell(g.map(|v| v[k]))));
        rec.extend((0..3).map(|k| cell(a.map(|v| v[k]))));
        w.write_record(&rec)?;
        written += 1;
    }
    w.flush()?;
    let span = (
        rows.t.first().copied().unwrap_or(0.0),
        rows.t.last().copied().unwrap_or(0.0),
    );
    Ok(ImportSummary {
        rows: written,
        span,
        imu_rate_hz: (n - 1) as f64 / (span.1 - span.0).max(1e-9),
        imu_instances: instances,
        gnss_rows,
        att_rows,
        ended_early: None,
    })
}

/// Converts an ArduPilot DataFlash `.bin` to a SPEC §10 CSV at `out`: every
/// IMU instance (IMU, IMU2, IMU3, synchronous rows only), GPS velocity with a
/// 3-D fix (`Spd`·cos/sin `GCrs`, `VZ`) and the ATT attitude (degrees → rad),
/// each aiding sample on the first IMU row at or after its time. Parsed with
/// the `ardupilot-binlog` crate.
///
/// ATT is ArduPilot's own estimate from the same IMUs: not an independent
/// sensor (SPEC §8 S6), so give it a wide R when replaying.
pub fn dataflash_to_replay_csv(input: &Path, out: &Path) -> Result<ImportSummary> {
    let log = crate::eval::parity_replay::read_dataflash_imus(input)?;
    let n = log.t.len();
    let mut gnss: Vec<Option<[f64; 3]>> = vec![None; n];
    let mut att: Vec<Option<[f64; 3]>> = vec![None; n];
    let slot = |t: f64| log.t.partition_point(|x| *x < t);
    let file = ardupilot_binlog::File::open(input)
        .with_context(|| format!("cannot read {}", input.display()))?;
    let entries = file
        .entries()
        .with_context(|| format!("{}: not a DataFlash log", input.display()))?;
    let deg = std::f64::consts::PI / 180.0;
    for e in entries {
        // A corrupt or truncated tail: keep what was read.
        let Ok(e) = e else { break };
        let is_gps = e.name == "GPS";
        if !is_gps && e.name != "ATT" {
            continue;
        }
        // Old GPS messages carry GPS time of week in TimeMS and boot time in T.
        let boot_ms = if is_gps { "T" } else { "TimeMS" };
        // (Integer fields decode as signed or unsigned by format: read as f64.)
        let t_us = e
            .get_f64("TimeUS")
            .or_else(|| e.get_f64(boot_ms).map(|ms| ms * 1000.0))
            .or(e.timestamp_usec.map(|t| t as f64));
        let Some(t_us) = t_us else { continue };
        let v = |k: &str| e.get_f64(k).unwrap_or(f64::NAN);
        let idx = slot(t_us * 1e-6);
        if is_gps {
            if v("Status") < 3.0 {
                continue;
            }
            let (spd, crs) = (v("Spd"), v("GCrs") * deg);
            let vel = [spd * crs.cos(), spd * crs.sin(), v("VZ")];
            if let (true, Some(s)) = (vel.iter().all(|x| x.is_finite()), gnss.get_mut(idx)) {
                *s = Some(vel);
            }
        } else {
            let a = [
                v("Roll") * deg,
                v("Pitch") * deg,
                wrap_pi_f64(v("Yaw") * deg),
            ];
            if let (true, Some(s)) = (a.iter().all(|x| x.is_finite()), att.get_mut(idx)) {
                *s = Some(a);
            }
        }
    }
    let rows = ReplayRows {
        t: log.t,
        imus: log.imus,
        gnss,
        att,
    };
    write_replay_csv(out, &rows)
}

/// Converts a `.ulg` or `.bin` log, or a CSV extract (with its GNSS and
/// attitude files, see [`csv_extracts_to_replay_csv`]), to a SPEC §10 CSV.
pub fn any_to_replay_csv(
    input: &Path,
    gnss: Option<&Path>,
    att: Option<&Path>,
    out: &Path,
) -> Result<ImportSummary> {
    let is_csv = input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        return csv_extracts_to_replay_csv(input, gnss, att, out);
    }
    if gnss.is_some() || att.is_some() {
        bail!(
            "{}: --gnss and --att go with a CSV extract; a .ulg or .bin carries its own aiding",
            input.display()
        );
    }
    log_to_replay_csv(input, out)
}

/// Converts a `.ulg` or `.bin` log to a SPEC §10 CSV by its extension.
pub fn log_to_replay_csv(input: &Path, out: &Path) -> Result<ImportSummary> {
    match input
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("ulg") => ulog_to_replay_csv(input, out),
        Some("bin") => dataflash_to_replay_csv(input, out),
        _ => bail!(
            "{}: unknown file type (expected a PX4 .ulg or an ArduPilot DataFlash .bin)",
            input.display()
        ),
    }
}

/// An IMU column layout of a CSV extract not in SPEC §10 form
/// (`../shared/data/SOURCES.md`): per IMU instance the six column indices
/// `[a_x, a_y, a_z, p, q, r]`, the scales to m/s² and rad/s, the axis signs
/// to FRD.
struct ImuLayout {
    columns: Vec<[usize; 6]>,
    accel_scale: f64,
    gyro_scale: f64,
    signs: [f64; 6],
}

/// Column names `[a_x … r]`, scales and signs of one known extract layout;
/// `{k}` in a name stands for the IMU instance.
struct KnownLayout {
    names: [&'static str; 6],
    accel_scale: f64,
    gyro_scale: f64,
    signs: [f64; 6],
}

const KNOWN_LAYOUTS: [KnownLayout; 3] = [
    // ArduPilot log171 extract: one or more IMUs.
    KnownLayout {
        names: [
            "imu{k}_accel_x_m_s2",
            "imu{k}_accel_y_m_s2",
            "imu{k}_accel_z_m_s2",
            "imu{k}_gyro_x_rad_s",
            "imu{k}_gyro_y_rad_s",
            "imu{k}_gyro_z_rad_s",
        ],
        accel_scale: 1.0,
        gyro_scale: 1.0,
        signs: [1.0; 6],
    },
    // PX4 sensor_combined extract.
    KnownLayout {
        names: [
            "accel_x_m_s2",
            "accel_y_m_s2",
            "accel_z_m_s2",
            "gyro_x_rad_s",
            "gyro_y_rad_s",
            "gyro_z_rad_s",
        ],
        accel_scale: 1.0,
        gyro_scale: 1.0,
        signs: [1.0; 6],
    },
    // x-io (Fusion example): g and deg/s, z up (gravity reads +1 g at rest):
    // x forward, y left, z up → FRD is a half turn about x.
    KnownLayout {
        names: [
            "Accelerometer X (g)",
            "Accelerometer Y (g)",
            "Accelerometer Z (g)",
            "Gyroscope X (deg/s)",
            "Gyroscope Y (deg/s)",
            "Gyroscope Z (deg/s)",
        ],
        accel_scale: 9.80665,
        gyro_scale: std::f64::consts::PI / 180.0,
        signs: [1.0, -1.0, -1.0, 1.0, -1.0, -1.0],
    },
];

fn imu_layout(headers: &csv::StringRecord) -> Option<ImuLayout> {
    let find = |name: &str| headers.iter().position(|h| h.trim() == name);
    KNOWN_LAYOUTS.iter().find_map(|l| {
        let per_instance = l.names.iter().any(|n| n.contains("{k}"));
        let mut columns = Vec::new();
        for k in 0..if per_instance { usize::MAX } else { 1 } {
            let idx = l.names.map(|n| find(&n.replace("{k}", &k.to_string())));
            match idx {
                [Some(a), Some(b), Some(c), Some(d), Some(e), Some(f)] => {
                    columns.push([a, b, c, d, e, f]);
                }
                _ => break,
            }
        }
        (!columns.is_empty()).then_some(ImuLayout {
            columns,
            accel_scale: l.accel_scale,
            gyro_scale: l.gyro_scale,
            signs: l.signs,
        })
    })
}

/// Opens a CSV (cells trimmed) and reads its header row; errors name the file.
pub fn open_csv(path: &Path) -> Result<(csv::Reader<std::fs::File>, csv::StringRecord)> {
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    let headers = rdr
        .headers()
        .with_context(|| format!("{}: no header row", path.display()))?
        .clone();
    Ok((rdr, headers))
}

fn read_table(path: &Path) -> Result<(csv::StringRecord, Vec<csv::StringRecord>)> {
    let (mut rdr, headers) = open_csv(path)?;
    let mut rows = Vec::new();
    for (i, r) in rdr.records().enumerate() {
        rows.push(r.with_context(|| format!("{}: bad CSV at line {}", path.display(), i + 2))?);
    }
    Ok((headers, rows))
}

fn cell(r: &csv::StringRecord, i: Option<usize>) -> Option<f64> {
    r.get(i?)?
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
}

fn time_column(headers: &csv::StringRecord, path: &Path) -> Result<usize> {
    ["time_s", "Time (s)", "t"]
        .iter()
        .find_map(|n| headers.iter().position(|h| h.trim() == *n))
        .with_context(|| format!("{}: no time column (time_s, Time (s) or t)", path.display()))
}

/// Maps the CSV extracts of `../shared/data` (names, degrees, quaternions,
/// fix flags; see its `SOURCES.md`) to a SPEC §10 CSV: an IMU file
/// (`imu{k}_gyro_x_rad_s …`, `gyro_x_rad_s …`, or x-io's g and deg/s with z
/// up), optionally a GNSS file (`vel_n_m_s …`, kept where `fix_status` or
/// `fix_type` ≥ 3 and `vel_ned_valid` ≠ 0) and an attitude file (`q_w …`
/// body→NED, or `roll_deg …`). Aiding goes on the first IMU row at or after
/// its time.
pub fn csv_extracts_to_replay_csv(
    imu: &Path,
    gnss: Option<&Path>,
    att: Option<&Path>,
    out: &Path,
) -> Result<ImportSummary> {
    let (h, rows) = read_table(imu)?;
    let ti = time_column(&h, imu)?;
    let layout = imu_layout(&h).with_context(|| {
        format!(
            "{}: unknown IMU columns (expected imu0_gyro_x_rad_s…, gyro_x_rad_s… or x-io's 'Gyroscope X (deg/s)'…)",
            imu.display()
        )
    })?;
    let mut t = Vec::with_capacity(rows.len());
    let mut imus = Vec::with_capacity(rows.len());
    for r in &rows {
        let Some(time) = cell(r, Some(ti)) else {
            continue;
        };
        t.push(time);
        imus.push(
            layout
                .columns
                .iter()
                .map(|c| {
                    core::array::from_fn(|i| {
                        let scale = if i < 3 {
                            layout.accel_scale
                        } else {
                            layout.gyro_scale
                        };
                        cell(r, c.get(i).copied()).map_or(f64::NAN, |v| v * scale * layout.signs[i])
                    })
                })
                .collect(),
        );
    }
    let n = t.len();
    let slot = |x: f64| t.partition_point(|v| *v < x);
    let mut gnss_rows: Vec<Option<[f64; 3]>> = vec![None; n];
    if let Some(p) = gnss {
        let (h, rows) = read_table(p)?;
        let ti = time_column(&h, p)?;
        let f = |name: &str| h.iter().position(|x| x.trim() == name);
        let v = ["vel_n_m_s", "vel_e_m_s", "vel_d_m_s"].map(&f);
        if v.iter().any(Option::is_none) {
            bail!("{}: missing vel_n_m_s, vel_e_m_s or vel_d_m_s", p.display());
        }
        let fix = f("fix_status").or_else(|| f("fix_type"));
        let valid = f("vel_ned_valid");
        for r in &rows {
            let (Some(time), Some(vn), Some(ve), Some(vd)) = (
                cell(r, Some(ti)),
                cell(r, v[0]),
                cell(r, v[1]),
                cell(r, v[2]),
            ) else {
                continue;
            };
            let fixed = fix.is_none_or(|i| cell(r, Some(i)).is_some_and(|x| x >= 3.0));
            let ok = valid.is_none_or(|i| cell(r, Some(i)).is_some_and(|x| x != 0.0));
            if let (true, Some(s)) = (fixed && ok, gnss_rows.get_mut(slot(time))) {
                *s = Some([vn, ve, vd]);
            }
        }
    }
    let mut att_rows: Vec<Option<[f64; 3]>> = vec![None; n];
    if let Some(p) = att {
        let (h, rows) = read_table(p)?;
        let ti = time_column(&h, p)?;
        let f = |name: &str| h.iter().position(|x| x.trim() == name);
        let q = ["q_w", "q_x", "q_y", "q_z"].map(&f);
        let e = ["roll_deg", "pitch_deg", "yaw_deg"].map(&f);
        let deg = std::f64::consts::PI / 180.0;
        for r in &rows {
            let Some(time) = cell(r, Some(ti)) else {
                continue;
            };
            let a = match (cell(r, q[0]), cell(r, q[1]), cell(r, q[2]), cell(r, q[3])) {
                (Some(w), Some(x), Some(y), Some(z)) => Some(quaternion_to_euler([w, x, y, z])),
                _ => match (cell(r, e[0]), cell(r, e[1]), cell(r, e[2])) {
                    (Some(ro), Some(pi), Some(ya)) => {
                        Some([ro * deg, pi * deg, wrap_pi_f64(ya * deg)])
                    }
                    _ => None,
                },
            };
            if a.is_none() && q[0].is_none() && e[0].is_none() {
                bail!("{}: missing q_w…q_z or roll_deg…yaw_deg", p.display());
            }
            if let (Some(a), Some(s)) = (a, att_rows.get_mut(slot(time))) {
                *s = Some(a);
            }
        }
    }
    write_replay_csv(
        out,
        &ReplayRows {
            t,
            imus,
            gnss: gnss_rows,
            att: att_rows,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("imu-fdi-extract-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join(name);
        std::fs::write(&p, text).expect("write");
        p
    }

    fn rows(p: &Path) -> Vec<Vec<String>> {
        let mut r = csv::Reader::from_path(p).expect("csv");
        r.records()
            .map(|x| x.expect("row").iter().map(str::to_string).collect())
            .collect()
    }

    #[test]
    fn px4_style_extracts_map_units_fix_flags_and_quaternions() {
        let mut imu = String::from("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n");
        for k in 0..12 {
            imu += &format!("{},0.1,0.2,0.3,1,2,-9.8\n", 10.0 + 0.01 * k as f64);
        }
        let imu = write("imu.csv", &imu);
        let gnss = write(
            "gnss.csv",
            "time_s,vel_n_m_s,vel_e_m_s,vel_d_m_s,vel_ned_valid,fix_type\n\
             10.02,1,2,3,1,3\n10.05,4,5,6,1,2\n10.07,7,8,9,0,4\n",
        );
        // 90° yaw about z: q = (cos 45°, 0, 0, sin 45°).
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let att = write(
            "att.csv",
            &format!("time_s,q_w,q_x,q_y,q_z\n10.031,{h},0,0,{h}\n"),
        );
        let out = write("out.csv", "");
        let s = csv_extracts_to_replay_csv(&imu, Some(&gnss), Some(&att), &out).expect("maps");
        assert_eq!(
            (s.rows, s.imu_instances, s.gnss_rows, s.att_rows),
            (12, 1, 1, 1)
        );
        let r = rows(&out);
        // IMU columns reordered to a_x a_y a_z p q r.
        assert_eq!(&r[0][1..7], &["1", "2", "-9.8", "0.1", "0.2", "0.3"]);
        // Only the 3-D fix with valid velocity, on the row at or after it.
        assert_eq!(&r[2][7..10], &["1", "2", "3"]);
        assert!(r.iter().enumerate().all(|(i, x)| i == 2 || x[7].is_empty()));
        let yaw: f64 = r[4][12].parse().expect("yaw");
        assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "{yaw}");
    }

    #[test]
    fn xio_extract_is_turned_to_frd_si_units_and_unknown_columns_are_named() {
        let mut x = String::from("Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)\n");
        for k in 0..10 {
            x += &format!("{},180,90,-90,0,0.5,1\n", 0.01 * k as f64);
        }
        let xio = write("xio.csv", &x);
        let out = write("xio-out.csv", "");
        csv_extracts_to_replay_csv(&xio, None, None, &out).expect("maps");
        let r = rows(&out);
        let v: Vec<f64> = r[0][1..7]
            .iter()
            .map(|c| c.parse().expect("number"))
            .collect();
        let pi = std::f64::consts::PI;
        let want = [0.0, -0.5 * 9.80665, -9.80665, pi, -pi / 2.0, pi / 2.0];
        for (a, b) in v.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{v:?}");
        }
        let bad = write("bad.csv", "time_s,foo\n1,2\n");
        let e = csv_extracts_to_replay_csv(&bad, None, None, &out).unwrap_err();
        assert!(
            e.to_string().contains("bad.csv: unknown IMU columns"),
            "{e}"
        );
    }
}

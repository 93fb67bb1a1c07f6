//! CSV extracts not in SPEC §10 form (`../shared/data`: `imu{k}_gyro_x_rad_s…`,
//! `gyro_x_rad_s…`, or x-io's g and deg/s with z up), with their GNSS velocity
//! and attitude files, mapped to the SPEC §10 replay CSV.

use std::path::Path;

use anyhow::{bail, Context, Result};
use imu_fdi::math::wrap_pi_f64;

use super::log_import::{
    open_csv, quaternion_to_euler, write_replay_csv, CsvRows, ImportSummary, ReplayRows,
};

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

const KNOWN_LAYOUTS: [KnownLayout; 4] = [
    // SPEC §10 IMU columns (e.g. `tests/data/ap_log171_3imu.csv`), given with
    // separate GNSS velocity and attitude files.
    KnownLayout {
        names: [
            "imu{k}_ax",
            "imu{k}_ay",
            "imu{k}_az",
            "imu{k}_gx",
            "imu{k}_gy",
            "imu{k}_gz",
        ],
        accel_scale: 1.0,
        gyro_scale: 1.0,
        signs: [1.0; 6],
    },
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

/// The header and the rows of a CSV extract. A last row cut short (the
/// extract ends mid-write) is dropped, as [`CsvRows`] does, and its warning
/// pushed on `cut`.
fn read_table(
    path: &Path,
    cut: &mut Vec<String>,
) -> Result<(csv::StringRecord, Vec<csv::StringRecord>)> {
    let (mut rdr, headers) = open_csv(path)?;
    let mut records = CsvRows::new(&mut rdr, path, headers.len());
    let rows = records
        .by_ref()
        .map(|row| row.map(|(_, rec)| rec))
        .collect::<Result<Vec<_>>>()?;
    cut.extend(records.notes());
    Ok((headers, rows))
}

fn cell(r: &csv::StringRecord, i: Option<usize>) -> Option<f64> {
    r.get(i?)?
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
}

/// `(line, t)` of the rows whose time cell is a finite number.
fn finite_times(rows: &[csv::StringRecord], ti: usize) -> Vec<(usize, f64)> {
    rows.iter()
        .enumerate()
        .filter_map(|(i, r)| cell(r, Some(ti)).map(|t| (i + 2, t)))
        .collect()
}

fn time_column(headers: &csv::StringRecord, path: &Path) -> Result<usize> {
    ["time_s", "Time (s)", "t"]
        .iter()
        .find_map(|n| headers.iter().position(|h| h.trim() == *n))
        .with_context(|| format!("{}: no time column (time_s, Time (s) or t)", path.display()))
}

/// Maps the CSV extracts of `../shared/data` (names, degrees, quaternions,
/// fix flags; see its `SOURCES.md`) to a SPEC §10 CSV: an IMU file
/// (`imu{k}_gyro_x_rad_s …`, `gyro_x_rad_s …`, x-io's g and deg/s with z
/// up, or SPEC §10's own `imu{k}_ax …` with `t`), optionally a GNSS file (`vel_n_m_s …`, kept where `fix_status` or
/// `fix_type` ≥ 3 and `vel_ned_valid` ≠ 0) and an attitude file (`q_w …`
/// body→NED, or `roll_deg …`). Aiding goes on the first IMU row at or after
/// its time.
pub fn csv_extracts_to_replay_csv(
    imu: &Path,
    gnss: Option<&Path>,
    att: Option<&Path>,
    out: &Path,
) -> Result<ImportSummary> {
    let mut cut = Vec::new();
    let (h, rows) = read_table(imu, &mut cut)?;
    let ti = time_column(&h, imu)?;
    let layout = imu_layout(&h).with_context(|| {
        format!(
            "{}: unknown IMU columns (expected imu0_ax…, imu0_gyro_x_rad_s…, gyro_x_rad_s… or x-io's 'Gyroscope X (deg/s)'…)",
            imu.display()
        )
    })?;
    use super::csv_checks::{check_times, parse_cell, ColumnData};
    let header_name = |i: usize| h.get(i).unwrap_or("?").to_string();
    let time_name = header_name(ti);
    let names: Vec<[String; 6]> = layout.columns.iter().map(|c| c.map(header_name)).collect();
    let mut data = ColumnData::new(names.iter().flatten().cloned().collect());
    let mut times = Vec::with_capacity(rows.len());
    let mut t = Vec::with_capacity(rows.len());
    let mut imus = Vec::with_capacity(rows.len());
    for (line, r) in rows.iter().enumerate() {
        let line = line + 2;
        let time = parse_cell(imu, line, &time_name, r.get(ti))?;
        let mut sample = Vec::with_capacity(layout.columns.len());
        for (k, c) in layout.columns.iter().enumerate() {
            let mut v = [f64::NAN; 6];
            for (i, slot) in v.iter_mut().enumerate() {
                let scale = if i < 3 {
                    layout.accel_scale
                } else {
                    layout.gyro_scale
                };
                let x = parse_cell(imu, line, &names[k][i], r.get(c[i]))?;
                *slot = data.screen_imu(6 * k + i, line, x * scale * layout.signs[i]);
            }
            sample.push(v);
        }
        if !time.is_finite() {
            continue;
        }
        times.push((line, time));
        t.push(time);
        imus.push(sample);
    }
    check_times(imu, &time_name, &times)?;
    data.check(imu)?;
    cut.extend(data.warning(imu));
    let n = t.len();
    // Named here, on the input: the writer's own check can only name its
    // output file.
    if n < 10 {
        bail!("{}: fewer than 10 IMU samples", imu.display());
    }
    let slot = |x: f64| t.partition_point(|v| *v < x);
    let mut gnss_rows: Vec<Option<[f64; 3]>> = vec![None; n];
    if let Some(p) = gnss {
        let (h, rows) = read_table(p, &mut cut)?;
        let ti = time_column(&h, p)?;
        let f = |name: &str| h.iter().position(|x| x.trim() == name);
        let v = ["vel_n_m_s", "vel_e_m_s", "vel_d_m_s"].map(&f);
        if v.iter().any(Option::is_none) {
            bail!("{}: missing vel_n_m_s, vel_e_m_s or vel_d_m_s", p.display());
        }
        check_times(p, "time", &finite_times(&rows, ti))?;
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
        let (h, rows) = read_table(p, &mut cut)?;
        let ti = time_column(&h, p)?;
        let f = |name: &str| h.iter().position(|x| x.trim() == name);
        let q = ["q_w", "q_x", "q_y", "q_z"].map(&f);
        let e = ["roll_deg", "pitch_deg", "yaw_deg"].map(&f);
        check_times(p, "time", &finite_times(&rows, ti))?;
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
    let mut summary = write_replay_csv(
        out,
        &ReplayRows {
            t,
            imus,
            gnss: gnss_rows,
            att: att_rows,
        },
    )?;
    summary.ended_early = (!cut.is_empty()).then(|| cut.join("; "));
    Ok(summary)
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
    fn too_few_rows_is_an_error_naming_the_input() {
        let imu = write(
            "few_rows_imu.csv",
            "t,imu0_ax,imu0_ay,imu0_az,imu0_gx,imu0_gy,imu0_gz\n0.0,0,0,-9.8,0,0,0\n0.1,0,0,-9.8,0,0,0\n",
        );
        let out = imu.with_extension("out.csv");
        let e = csv_extracts_to_replay_csv(&imu, None, None, &out).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.starts_with(&imu.display().to_string()), "{msg}");
        assert!(msg.contains("fewer than 10 IMU samples"), "{msg}");
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

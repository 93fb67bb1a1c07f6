//! Reading a SPEC §10 CSV for `replay`: the columns it has (IMU triads,
//! DVL or GNSS velocity, attitude, fault truth), the rows in the replay's
//! time span, every cell checked, and the log's median period.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use imu_fdi::model::{AidingKind, CHANNEL_NAMES};

use super::replay::{ReplayOptions, ReplaySummary, ATT_COLS, DVL_COLS, GNSS_COLS, IMU_COLS};
use crate::io::csv_checks::{check_times, parse_cell, ColumnData};

/// One input row.
pub(super) struct Row {
    pub t: f64,
    pub imus: Vec<[f64; 6]>,
    pub z: [f64; 6],
    pub avail: [bool; 6],
    /// Per IMU: the fault truth, if the file (or the injection) has it.
    pub truth: Vec<Option<[f64; 6]>>,
}

/// What [`read_log`] gives the replay.
pub(super) struct Log {
    /// The aiding the columns hold.
    pub kind: AidingKind,
    /// IMU triads in the file.
    pub imus: usize,
    /// The file has fault-truth columns.
    pub file_truth: bool,
    /// The rows in the time span, with an increasing finite `t`.
    pub rows: Vec<Row>,
    /// The log's median period, s.
    pub dt: f64,
}

fn parse_opt(rec: &csv::StringRecord, idx: Option<usize>) -> Option<f64> {
    let s = rec.get(idx?)?.trim();
    if s.is_empty() {
        return None;
    }
    s.parse::<f64>().ok()
}

fn imu_cols(k: usize) -> [String; 6] {
    ["ax", "ay", "az", "gx", "gy", "gz"].map(|c| format!("imu{k}_{c}"))
}

/// Reads `input` within `opts`' span; counts rows, skipped rows and a cut
/// tail into `sum`. A bad cell, too few rows or no aiding at all is an
/// error naming the file.
pub(super) fn read_log(input: &Path, opts: &ReplayOptions, sum: &mut ReplaySummary) -> Result<Log> {
    let (mut rdr, headers) = crate::io::log_import::open_csv(input)?;
    let col: HashMap<&str, usize> = headers.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let find = |name: &str| col.get(name).copied();
    let t_idx = find("t").with_context(|| format!("{}: missing column 't'", input.display()))?;
    let imu_idx: Vec<Vec<usize>> = (0..)
        .map_while(|k| {
            imu_cols(k)
                .iter()
                .map(|c| find(c))
                .collect::<Option<Vec<_>>>()
        })
        .collect();
    if imu_idx.is_empty() {
        let missing = IMU_COLS
            .iter()
            .find(|c| find(c).is_none())
            .unwrap_or(&"imu0_ax");
        bail!("{}: missing column '{missing}'", input.display());
    }
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
    let vel_idx: Vec<Option<usize>> = vel_cols.iter().map(|c| find(c)).collect();
    let att_idx: Vec<Option<usize>> = ATT_COLS.iter().map(|c| find(c)).collect();
    let truth_idx: Vec<Option<Vec<usize>>> = (0..imu_idx.len())
        .map(|k| {
            CHANNEL_NAMES
                .iter()
                .map(|c| find(&format!("fault_imu{k}_{c}")))
                .collect::<Option<Vec<_>>>()
        })
        .collect();
    let file_truth = truth_idx.iter().any(Option::is_some);

    sum.aiding = format!("{kind:?}");
    // --- read ---------------------------------------------------------------
    let imu_names: Vec<[String; 6]> = (0..imu_idx.len()).map(imu_cols).collect();
    let mut data = ColumnData::new(imu_names.iter().flatten().cloned().collect());
    let mut times = Vec::new();
    let mut rows: Vec<Row> = Vec::new();
    let mut last_t: Option<f64> = None;
    let mut csv_rows = crate::io::log_import::CsvRows::new(&mut rdr, input, headers.len());
    for row in csv_rows.by_ref() {
        let (line, rec) = row?;
        sum.rows += 1;
        let t = parse_cell(input, line, "t", rec.get(t_idx))?;
        let mut imus: Vec<[f64; 6]> = Vec::with_capacity(imu_idx.len());
        for (k, idx) in imu_idx.iter().enumerate() {
            let mut v = [f64::NAN; 6];
            for (ch, (i, slot)) in idx.iter().zip(v.iter_mut()).enumerate() {
                let name = &imu_names[k][ch];
                let x = parse_cell(input, line, name, rec.get(*i))?;
                *slot = data.screen_imu(6 * k + ch, line, x);
            }
            imus.push(v);
        }
        // Aiding cells: empty or NaN is "no sample"; text is an error.
        for (name, idx) in vel_cols
            .iter()
            .chain(ATT_COLS.iter())
            .zip(vel_idx.iter().chain(att_idx.iter()))
        {
            if let Some(idx) = idx {
                parse_cell(input, line, name, rec.get(*idx))?;
            }
        }
        let Some(t) = Some(t).filter(|t| t.is_finite()) else {
            sum.skipped_rows += 1;
            continue;
        };
        times.push((line, t));
        if last_t.is_some_and(|lt| t <= lt) {
            sum.skipped_rows += 1;
            continue;
        }
        last_t = Some(t);
        if opts.from_s.is_some_and(|f| t < f) || opts.to_s.is_some_and(|e| t > e) {
            continue;
        }
        let mut z = [0.0; 6];
        let mut avail = [false; 6];
        for (i, idx) in vel_idx.iter().chain(att_idx.iter()).enumerate() {
            if let (Some(v), Some(zi), Some(ai)) =
                (parse_opt(&rec, *idx), z.get_mut(i), avail.get_mut(i))
            {
                *zi = v;
                *ai = true;
            }
        }
        let truth = truth_idx
            .iter()
            .map(|idx| {
                idx.as_ref().map(|idx| {
                    core::array::from_fn(|i| parse_opt(&rec, idx.get(i).copied()).unwrap_or(0.0))
                })
            })
            .collect();
        rows.push(Row {
            t,
            imus,
            z,
            avail,
            truth,
        });
    }
    sum.ended_early = csv_rows.notes();
    check_times(input, "t", &times)?;
    if rows.len() < 10 {
        bail!(
            "{}: fewer than 10 usable rows{}",
            input.display(),
            opts.from_s
                .map_or(String::new(), |f| format!(" after {f} s"))
        );
    }
    data.check(input)?;
    sum.corrupt_cells = data.warning(input);
    if !rows.iter().any(|r| r.avail.iter().any(|a| *a)) {
        bail!(
            "{}: no aiding in the file (every dvl_*, gnss_* and att_* cell empty or absent): \
             the UKF monitor needs a velocity or attitude reference to compare the IMU with; \
             redundant IMUs without one go to `parity-replay`",
            input.display()
        );
    }
    // The monitor's period is the log's median step, not an assumption.
    let mut dts: Vec<f64> = rows.windows(2).map(|w| w[1].t - w[0].t).collect();
    dts.sort_by(f64::total_cmp);
    let dt = dts.get(dts.len() / 2).copied().unwrap_or(0.01);
    sum.imu_rate_hz = 1.0 / dt;

    Ok(Log {
        kind,
        imus: imu_idx.len(),
        file_truth,
        rows,
        dt,
    })
}

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
//! - CSV extracts not in SPEC §10 form: [`super::csv_extract`].
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

// The CSV-extract mapping is its own module; `any_to_replay_csv` dispatches
// to it, and its old path here keeps working.
pub use super::csv_extract::csv_extracts_to_replay_csv;

/// True when an IMU sample `[a_x, a_y, a_z, p, q, r]` is finite and below
/// 2000 m/s² and 200 rad/s: anything beyond is a corrupt record.
pub fn plausible_imu(v: &[f64; 6]) -> bool {
    v.iter()
        .enumerate()
        .all(|(i, x)| x.is_finite() && x.abs() <= if i < 3 { 2000.0 } else { 200.0 })
}

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
    /// How far the log was read and what was skipped, if anything (one
    /// line naming the file, for a warning on stderr); `None` for a clean
    /// log.
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

/// The text of a px4-ulog error: the crate wraps its parse errors in an
/// `io::Error` formatted with `{:?}`; keep only their description.
fn ulog_error_text(e: &std::io::Error) -> String {
    let s = e.to_string();
    match s.split_once("description: \"") {
        Some((_, rest)) => rest
            .rsplit_once('"')
            .map_or(rest, |(d, _)| d)
            .replace("\\\"", "\""),
        None if s.contains('{') || s.contains("Some(") => format!("{:?}", e.kind()).to_lowercase(),
        None => s,
    }
}

/// Converts a `.ulg` to a SPEC §10 CSV at `out`.
pub fn ulog_to_replay_csv(input: &Path, out: &Path) -> Result<ImportSummary> {
    let name = input
        .to_str()
        .with_context(|| format!("{}: path is not UTF-8", input.display()))?;
    // px4-ulog indexes slices with lengths read from the file and panics on
    // some corrupt files: the panic becomes an error naming the file.
    let parsed = match crate::io::guard::catch_quietly(|| read_file(name)) {
        Ok(r) => r.map_err(|e| {
            anyhow::anyhow!(
                "{}: not a readable ULog file: {}",
                input.display(),
                ulog_error_text(&e)
            )
        })?,
        Err(why) => bail!(
            "{}: corrupt ULog: the parser failed ({why})",
            input.display()
        ),
    };
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
        for (i, ti) in t.iter().enumerate() {
            let (Some(ok), Some(fx), Some(n), Some(e), Some(d)) =
                (valid.get(i), fix.get(i), vn.get(i), ve.get(i), vd.get(i))
            else {
                break;
            };
            if *ok > 0.5 && *fx >= 3.0 {
                if let Some(s) = gnss.get_mut(slot(*ti)) {
                    *s = Some([*n, *e, *d]);
                }
            }
        }
    }
    if let Some(f) = first("vehicle_attitude") {
        let t = col(f, "timestamp")?;
        let q: Vec<Vec<f64>> = (0..4)
            .map(|i| col(f, &format!("q[{i}]")))
            .collect::<Result<_>>()?;
        for (i, ti) in t.iter().enumerate() {
            let (Some(w), Some(x), Some(y), Some(z)) =
                (q[0].get(i), q[1].get(i), q[2].get(i), q[3].get(i))
            else {
                break;
            };
            if let Some(s) = att.get_mut(slot(*ti)) {
                *s = Some(quaternion_to_euler([*w, *x, *y, *z]));
            }
        }
    }
    let sample = |i: usize| -> Option<[f64; 6]> {
        let v = [
            *a[0].get(i)?,
            *a[1].get(i)?,
            *a[2].get(i)?,
            *g[0].get(i)?,
            *g[1].get(i)?,
            *g[2].get(i)?,
        ];
        plausible_imu(&v).then_some(v)
    };
    let mut t_rows = Vec::with_capacity(n);
    let mut imus = Vec::with_capacity(n);
    let mut implausible = 0usize;
    for (i, t) in t_imu.iter().enumerate() {
        match sample(i) {
            Some(v) => {
                t_rows.push(t * 1e-6);
                imus.push(vec![v]);
            }
            None => {
                // Keep the row (its aiding slot) without an IMU sample.
                implausible += 1;
                t_rows.push(f64::NAN);
                imus.push(Vec::new());
            }
        }
    }
    let rows = ReplayRows {
        t: t_rows,
        imus,
        gnss,
        att,
    };
    let mut summary = write_replay_csv(out, &rows).map_err(|e| {
        anyhow::anyhow!(
            "{}: no usable IMU rows ({implausible} of {n} samples non-finite or implausible): {e}",
            input.display()
        )
    })?;
    let mut problems = Vec::new();
    match &parsed.completeness {
        px4_ulog::stream_parser::model::Completeness::Complete => {}
        px4_ulog::stream_parser::model::Completeness::Truncated => {
            problems.push("stopped where the file ends partway through a record".to_string());
        }
        px4_ulog::stream_parser::model::Completeness::MalformedRecord(why) => {
            problems.push(format!("stopped at a malformed record: {why}"));
        }
    }
    if implausible > 0 {
        problems.push(format!(
            "dropped {implausible} IMU samples with non-finite or implausible values"
        ));
    }
    if !problems.is_empty() {
        summary.ended_early = Some(format!(
            "{}: read {} IMU rows up to t = {:.1} s; {}",
            input.display(),
            summary.rows,
            summary.span.1,
            problems.join("; ")
        ));
    }
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
    let (mut first_t, mut last_t) = (f64::NAN, f64::NEG_INFINITY);
    let mut written = 0usize;
    let (mut gnss_rows, mut att_rows) = (0, 0);
    for (i, &t) in rows.t.iter().enumerate() {
        if t <= last_t || !t.is_finite() {
            continue;
        }
        if written == 0 {
            first_t = t;
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
    if written < 10 {
        bail!(
            "fewer than 10 IMU rows with a finite, increasing time to write to {}",
            out.display()
        );
    }
    let span = (first_t, last_t);
    Ok(ImportSummary {
        rows: written,
        span,
        imu_rate_hz: (written - 1) as f64 / (span.1 - span.0).max(1e-9),
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
    let bytes = std::fs::read(input).with_context(|| format!("cannot read {}", input.display()))?;
    let deg = std::f64::consts::PI / 180.0;
    let parsed = super::guard::catch_quietly(|| {
        for e in ardupilot_binlog::Reader::new(std::io::Cursor::new(&bytes[..])) {
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
            let Some(t_us) = t_us.filter(|t| t.is_finite()) else {
                continue;
            };
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
    });
    if let Err(why) = parsed {
        bail!(
            "{}: corrupt DataFlash log: the parser failed ({why})",
            input.display()
        );
    }
    let warnings = log.warnings.join("; ");
    let rows = ReplayRows {
        t: log.t,
        imus: log.imus,
        gnss,
        att,
    };
    let mut summary = write_replay_csv(out, &rows)?;
    summary.ended_early = (!warnings.is_empty()).then_some(warnings);
    Ok(summary)
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

/// Opens a CSV (cells trimmed) and reads its header row; errors name the file.
///
/// The reader is flexible (rows may differ in length from the header) so
/// that [`CsvRows`] can tell a log cut mid-row at its end from a malformed
/// row inside it; read its rows through [`CsvRows`].
pub fn open_csv(path: &Path) -> Result<(csv::Reader<std::fs::File>, csv::StringRecord)> {
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(true)
        .from_path(path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    let headers = rdr
        .headers()
        .with_context(|| format!("{}: no header row", path.display()))?
        .clone();
    Ok((rdr, headers))
}

/// The data rows of a CSV opened with [`open_csv`], each with its line
/// number (the header is line 1).
///
/// A logger that stops mid-write (power cut, crash, a file copied while
/// open) leaves a last row with fewer cells than the header: that row is
/// dropped and [`CsvRows::cut_tail`] says so, as the binary log readers stop
/// at a cut record. A row of the wrong length anywhere else is an error
/// naming the file and the line, and so is a CSV syntax error. A row
/// identical to the one before it, cell for cell (a logger or an export
/// writing rows twice), is skipped and counted: it carries no sample, and
/// counted as a time that does not increase it made a file whose every row
/// was doubled look unsorted.
pub struct CsvRows<'a> {
    records: std::iter::Peekable<csv::StringRecordsIter<'a, std::fs::File>>,
    path: &'a Path,
    width: usize,
    line: usize,
    /// Set when the last row was cut short and dropped: one line naming the
    /// file, the line and the cells it had, for stderr.
    pub cut_tail: Option<String>,
    previous: Option<csv::StringRecord>,
    repeated: usize,
    first_repeated: usize,
}

impl<'a> CsvRows<'a> {
    /// The rows of `rdr`, whose header row (read by [`open_csv`]) has
    /// `width` cells; `path` names the file in errors.
    pub fn new(rdr: &'a mut csv::Reader<std::fs::File>, path: &'a Path, width: usize) -> Self {
        Self {
            records: rdr.records().peekable(),
            path,
            width,
            line: 1,
            cut_tail: None,
            previous: None,
            repeated: 0,
            first_repeated: 0,
        }
    }

    /// What the reader dropped, one line for stderr, once the rows are
    /// read: the cut last row and the repeated rows skipped.
    pub fn notes(&mut self) -> Option<String> {
        let repeated = (self.repeated > 0).then(|| {
            format!(
                "{}: skipped {} rows identical to the row before them (the first at line {})",
                self.path.display(),
                self.repeated,
                self.first_repeated
            )
        });
        let notes: Vec<String> = self.cut_tail.take().into_iter().chain(repeated).collect();
        self.repeated = 0;
        (!notes.is_empty()).then(|| notes.join("; "))
    }
}

impl Iterator for CsvRows<'_> {
    type Item = Result<(usize, csv::StringRecord)>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let rec = self.records.next()?;
            self.line += 1;
            let line = self.line;
            let rec = match rec {
                Ok(rec) => rec,
                Err(e) => {
                    return Some(Err(anyhow::Error::new(e).context(format!(
                        "{}: bad CSV at line {line}",
                        self.path.display()
                    ))))
                }
            };
            if rec.len() != self.width {
                return self.short_row(line, &rec);
            }
            if self.previous.as_ref() == Some(&rec) {
                if self.repeated == 0 {
                    self.first_repeated = line;
                }
                self.repeated += 1;
                continue;
            }
            self.previous = Some(rec.clone());
            return Some(Ok((line, rec)));
        }
    }
}

impl CsvRows<'_> {
    /// A row whose cell count is not the header's: the cut last row, or an
    /// error naming the line.
    fn short_row(
        &mut self,
        line: usize,
        rec: &csv::StringRecord,
    ) -> Option<Result<(usize, csv::StringRecord)>> {
        if rec.len() < self.width && self.records.peek().is_none() {
            self.cut_tail = Some(format!(
                "{}: the last row (line {line}) has {} of {} cells: the log ends mid-row; read up \
                 to line {}",
                self.path.display(),
                rec.len(),
                self.width,
                line - 1
            ));
            return None;
        }
        Some(Err(anyhow::anyhow!(
            "{}: bad CSV at line {line}: {} cells, the header has {}",
            self.path.display(),
            rec.len(),
            self.width
        )))
    }
}

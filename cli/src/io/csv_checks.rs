//! Plausibility checks shared by the CSV readers (SPEC §10 replay CSVs and
//! CSV extracts): a time column in seconds that increases, IMU columns
//! that carry numbers of a plausible size. Errors name the file, the line
//! (where one applies) and the column.

use std::path::Path;

use anyhow::{bail, Result};

/// Smallest plausible median time step, s (a 100 kHz IMU).
pub const MIN_MEDIAN_STEP_S: f64 = 1e-5;
/// Largest plausible median time step, s.
pub const MAX_MEDIAN_STEP_S: f64 = 10.0;
/// Share of rows whose time may repeat or go backwards before the file is
/// refused rather than those rows skipped.
pub const MAX_NON_INCREASING_SHARE: f64 = 0.1;
/// Largest plausible |acceleration|, m/s² (≈ 200 g).
pub const MAX_ACCEL: f64 = 2000.0;
/// Largest plausible |angular rate|, rad/s (≈ 11 500 °/s).
pub const MAX_GYRO: f64 = 200.0;

/// Checks the times of a CSV's rows, given as `(line, t)` for every row
/// whose time cell held a finite number: at most
/// [`MAX_NON_INCREASING_SHARE`] of them may fail to increase (the readers
/// skip those), and the median step must lie within
/// [`MIN_MEDIAN_STEP_S`]…[`MAX_MEDIAN_STEP_S`] (a step of 10⁴ looks like
/// microseconds, 10⁷ like nanoseconds).
pub fn check_times(path: &Path, column: &str, times: &[(usize, f64)]) -> Result<()> {
    if times.len() < 2 {
        return Ok(());
    }
    let mut bad = 0usize;
    let mut first_bad = None;
    let mut steps = Vec::with_capacity(times.len());
    let mut last = times[0].1;
    for &(line, t) in &times[1..] {
        if t <= last {
            bad += 1;
            first_bad.get_or_insert((line, t, last));
        } else {
            steps.push(t - last);
            last = t;
        }
    }
    if let Some((line, t, prev)) = first_bad {
        if bad as f64 > MAX_NON_INCREASING_SHARE * (times.len() - 1) as f64 {
            bail!(
                "{}: line {line}, column '{column}': time {t} does not increase (previous {prev}); \
                 {bad} of {} rows repeat or go back in time: sort the file by time",
                path.display(),
                times.len()
            );
        }
    }
    if steps.is_empty() {
        return Ok(());
    }
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    if median > MAX_MEDIAN_STEP_S {
        let unit = if median >= 1e5 {
            "nanoseconds"
        } else if median >= 100.0 {
            "microseconds"
        } else {
            "milliseconds"
        };
        bail!(
            "{}: column '{column}': median time step {median} s ({:.3e} Hz): timestamps look like \
             {unit}; expected seconds",
            path.display(),
            1.0 / median
        );
    }
    if median < MIN_MEDIAN_STEP_S {
        bail!(
            "{}: column '{column}': median time step {median:e} s (above {:.0} kHz) is \
             implausible; expected seconds",
            path.display(),
            1e-3 / MIN_MEDIAN_STEP_S
        );
    }
    Ok(())
}

/// Counts each IMU column's finite values and screens its corrupt cells.
///
/// A cell that parses to an infinite number, or to one beyond
/// [`MAX_ACCEL`] / [`MAX_GYRO`], is a corrupt cell (a flipped bit, a
/// logger's overflow): it is read as a missing sample, as the DataFlash
/// and ULog readers drop such samples, and counted for one warning. A
/// column where such cells outnumber the plausible ones is an error (a
/// unit mix-up: milli-g, millidegrees per second), as is a column without
/// a finite value.
#[derive(Debug, Clone)]
pub struct ColumnData {
    names: Vec<String>,
    finite: Vec<usize>,
    corrupt: Vec<usize>,
    first_corrupt: Option<(usize, usize)>,
}

impl ColumnData {
    /// Columns to watch, by name.
    pub fn new(names: Vec<String>) -> Self {
        let n = names.len();
        Self {
            names,
            finite: vec![0; n],
            corrupt: vec![0; n],
            first_corrupt: None,
        }
    }

    /// Records one value of column `k`.
    pub fn see(&mut self, k: usize, x: f64) {
        if let (true, Some(c)) = (x.is_finite(), self.finite.get_mut(k)) {
            *c += 1;
        }
    }

    /// Screens IMU value `x` of column `k`, read at `line`: channel
    /// (`k % 6`) 0–2 accelerometer, m/s², 3–5 gyro, rad/s. Returns `x`,
    /// or NaN (a missing sample) for a corrupt cell, and records it.
    pub fn screen_imu(&mut self, k: usize, line: usize, x: f64) -> f64 {
        let max = if k % 6 < 3 { MAX_ACCEL } else { MAX_GYRO };
        let x = if x.is_nan() || x.abs() <= max {
            x
        } else {
            if let Some(c) = self.corrupt.get_mut(k) {
                *c += 1;
            }
            self.first_corrupt.get_or_insert((line, k));
            f64::NAN
        };
        self.see(k, x);
        x
    }

    /// Error naming the file and the first column without a finite value,
    /// or whose corrupt cells outnumber its plausible ones.
    pub fn check(&self, path: &Path) -> Result<()> {
        for (k, name) in self.names.iter().enumerate() {
            let finite = self.finite.get(k).copied().unwrap_or(0);
            let corrupt = self.corrupt.get(k).copied().unwrap_or(0);
            if corrupt > finite {
                let (max, unit) = if k % 6 < 3 {
                    (MAX_ACCEL, "m/s²")
                } else {
                    (MAX_GYRO, "rad/s")
                };
                bail!(
                    "{}: column '{name}': {corrupt} of {} values are infinite or beyond ±{max} {unit} \
                     (a unit mix-up?)",
                    path.display(),
                    corrupt + finite
                );
            }
            if finite == 0 {
                bail!(
                    "{}: column '{name}' has no numeric value (every cell empty or NaN)",
                    path.display()
                );
            }
        }
        Ok(())
    }

    /// One line naming the file, how many corrupt cells were read as
    /// missing samples and the first of them; `None` without any.
    pub fn warning(&self, path: &Path) -> Option<String> {
        let (line, k) = self.first_corrupt?;
        let n: usize = self.corrupt.iter().sum();
        let name = self.names.get(k).map_or("?", String::as_str);
        Some(format!(
            "{}: read {n} IMU cells that are infinite or beyond ±{MAX_ACCEL} m/s² / ±{MAX_GYRO} rad/s \
             as missing samples (the first at line {line}, column '{name}')",
            path.display()
        ))
    }
}

/// Parses a cell: empty or NaN is `Ok(NaN)` (a gap), text that is not a
/// number an error naming the file, line and column.
pub fn parse_cell(path: &Path, line: usize, column: &str, cell: Option<&str>) -> Result<f64> {
    let s = cell.unwrap_or("").trim();
    if s.is_empty() {
        return Ok(f64::NAN);
    }
    s.parse::<f64>().map_err(|_| {
        anyhow::anyhow!(
            "{}: line {line}, column '{}': '{}' is not a number",
            path.display(),
            quoted(column),
            quoted(s)
        )
    })
}

/// Text from a file as it may appear in a one-line message: control
/// characters escaped (a quoted CSV cell can hold newlines — found by the
/// `csv_files` fuzz target), at most 40 characters.
pub fn quoted(s: &str) -> String {
    const MAX: usize = 40;
    let mut out: String = s.chars().take(MAX).flat_map(char::escape_default).collect();
    if s.chars().nth(MAX).is_some() {
        out.push('…');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(step: f64) -> Vec<(usize, f64)> {
        (0..100).map(|k| (k + 2, k as f64 * step)).collect()
    }

    #[test]
    fn a_cell_with_a_newline_gives_a_one_line_error() {
        let p = Path::new("x.csv");
        let e = parse_cell(p, 3, "imu0_gz", Some("0.1,\n60.0,")).unwrap_err();
        let e = format!("{e:#}");
        assert!(
            !e.contains('\n') && e.contains("x.csv") && e.contains("line 3"),
            "{e}"
        );
        let long = "9".repeat(100) + "x";
        let e = format!("{:#}", parse_cell(p, 4, "t", Some(&long)).unwrap_err());
        assert!(e.len() < 150 && e.ends_with("…' is not a number"), "{e}");
    }

    #[test]
    fn time_units_and_order_are_checked() {
        let p = Path::new("x.csv");
        check_times(p, "t", &times(0.01)).expect("seconds");
        let e = check_times(p, "t", &times(1e7)).unwrap_err().to_string();
        assert!(e.contains("x.csv") && e.contains("nanoseconds"), "{e}");
        let e = check_times(p, "t", &times(1e4)).unwrap_err().to_string();
        assert!(e.contains("microseconds"), "{e}");
        let e = check_times(p, "t", &times(1e-9)).unwrap_err().to_string();
        assert!(e.contains("implausible"), "{e}");
        let mut back = times(0.01);
        back.reverse();
        let e = check_times(p, "t", &back).unwrap_err().to_string();
        assert!(e.contains("line 100, column 't'"), "{e}");
        let mut c = ColumnData::new(vec!["a".into(), "b".into()]);
        c.see(0, 1.0);
        c.see(1, f64::NAN);
        let e = c.check(p).unwrap_err().to_string();
        assert!(e.contains("column 'b'"), "{e}");
    }

    #[test]
    fn corrupt_cells_are_missing_samples_and_a_unit_mix_up_is_an_error() {
        let p = Path::new("x.csv");
        // Six columns, one IMU: channel k % 6 (0–2 accel, 3–5 gyro).
        let mut c = ColumnData::new((0..6).map(|i| format!("imu0_{i}")).collect());
        for line in 2..12 {
            assert_eq!(c.screen_imu(0, line, 9.8), 9.8);
            assert_eq!(c.screen_imu(3, line, 0.1), 0.1);
        }
        assert!(c.screen_imu(0, 12, f64::INFINITY).is_nan());
        assert!(c.screen_imu(3, 13, 250.0).is_nan());
        assert!(c.screen_imu(0, 14, f64::NAN).is_nan());
        for k in [1, 2, 4, 5] {
            c.see(k, 1.0);
        }
        c.check(p).expect("two corrupt cells among ten good ones");
        let w = c.warning(p).unwrap_or_default();
        assert!(
            w.contains("x.csv") && w.contains("read 2 IMU cells") && w.contains("line 12"),
            "{w}"
        );
        // Milli-g: every accelerometer cell beyond the limit.
        let mut m = ColumnData::new((0..6).map(|i| format!("imu0_{i}")).collect());
        for line in 2..12 {
            m.screen_imu(2, line, -9806.0);
            for k in [0, 1, 3, 4, 5] {
                m.see(k, 1.0);
            }
        }
        let e = m.check(p).unwrap_err().to_string();
        assert!(e.contains("imu0_2") && e.contains("10 of 10"), "{e}");
    }
}

//! From a log file to a [`FlightReport`]: convert it (ULog, DataFlash) to
//! the SPEC §10 CSV the replays read, run the UKF monitors and, for three
//! IMUs, the parity monitor and baselines.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::parity::ParityOptions;
use super::FlightReport;

/// Options of [`build`].
#[derive(Debug, Clone, Copy)]
pub struct BuildOptions {
    /// The parity monitor's training.
    pub parity: ParityOptions,
}

/// A temporary file removed on drop (the converted CSV).
struct TempFile(PathBuf);

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

fn is_spec_csv(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
        && crate::io::log_import::open_csv(path).is_ok_and(|(_, h)| h.iter().any(|c| c == "t"))
}

/// IMU triads (`imu{k}_ax` …) in a SPEC §10 CSV header.
fn imu_count(csv: &Path) -> Result<usize> {
    let (_, h) = crate::io::log_import::open_csv(csv)?;
    Ok((0..)
        .take_while(|k| h.iter().any(|c| c == format!("imu{k}_ax")))
        .count())
}

/// Builds the report of `input`; `step` is told what runs (progress).
pub fn build(
    input: &Path,
    opts: &BuildOptions,
    step: &mut dyn FnMut(&str),
) -> Result<FlightReport> {
    let mut report = FlightReport {
        source: input.file_name().map_or_else(
            || input.display().to_string(),
            |n| n.to_string_lossy().into(),
        ),
        ..FlightReport::default()
    };
    let _temp;
    let csv = if is_spec_csv(input) {
        input.to_path_buf()
    } else {
        step("converting the log");
        if !input.exists() {
            anyhow::bail!("{}: no such file", input.display());
        }
        let out = std::env::temp_dir().join(format!(
            "imu-fdi-report-{}-{}.csv",
            std::process::id(),
            input.file_stem().and_then(|s| s.to_str()).unwrap_or("log")
        ));
        _temp = TempFile(out.clone());
        let c = crate::io::log_import::any_to_replay_csv(input, None, None, &out)?;
        report.notes.push(format!(
            "converted {}: {} rows of {} IMU(s) at {:.1} Hz, {} with GNSS velocity, {} with attitude",
            report.source, c.rows, c.imu_instances, c.imu_rate_hz, c.gnss_rows, c.att_rows
        ));
        if let Some(why) = &c.ended_early {
            report.notes.push(format!("warning: {why}"));
        }
        out
    };
    let imus = imu_count(&csv)?;
    if imus == 0 {
        anyhow::bail!("{}: no IMU columns (imu0_ax …)", input.display());
    }
    report.imus = imus;
    step("UKF innovation monitor");
    super::ukf::add(&csv, imus, &mut report)?;
    if imus >= 2 {
        step("parity monitor and baselines");
        // A DataFlash log is read at its own IMU timestamps, as
        // `parity-replay` does; anything else through the SPEC CSV.
        let log = if input
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bin"))
        {
            crate::eval::parity_replay::read_dataflash_imus(input)?
        } else {
            crate::eval::parity_replay::read_imu_log(&csv)
                .with_context(|| format!("{}: reading the IMUs", input.display()))?
        };
        for w in &log.warnings {
            // The conversion may have said the same already.
            if !report.notes.iter().any(|n| n.ends_with(w.as_str())) {
                report.notes.push(format!("warning: {w}"));
            }
        }
        super::parity::add(&log, opts.parity, &mut report)?;
    } else {
        report.verdicts.extend(super::verdict::not_judged(
            0,
            "parity",
            "the parity monitor needs three IMUs; the log has 1",
        ));
    }
    // Plots with nothing to draw are left out, and said so.
    let (keep, empty): (Vec<_>, Vec<_>) = std::mem::take(&mut report.plots)
        .into_iter()
        .partition(|p| p.series.iter().any(|s| s.y.iter().any(|v| v.is_finite())));
    for p in empty {
        report.notes.push(format!("no data to plot: {}", p.title));
    }
    report.plots = keep;
    let (lo, hi) = report
        .plots
        .iter()
        .flat_map(|p| p.series.iter())
        .flat_map(|s| [s.t.first().copied(), s.t.last().copied()])
        .flatten()
        .chain(
            report
                .timeline
                .lanes
                .iter()
                .flat_map(|l| l.intervals.iter().flat_map(|i| [i.start_s, i.end_s])),
        )
        .fold((f64::MAX, f64::MIN), |(l, h), t| (l.min(t), h.max(t)));
    report.span_s = if lo <= hi { (lo, hi) } else { (0.0, 1.0) };
    Ok(report)
}

//! Monte-Carlo campaigns: N seeded runs of a scenario, each with one fault
//! of random onset, channel, shape, sign and size; run in parallel (rayon)
//! with a progress bar (indicatif); summarised with 95 % intervals; split
//! across machines with `--shard i/n` and put back together with `merge`.
//!
//! Run `k` of a campaign with seed `s` is fully determined by `s + k`, and
//! every summary is computed from the per-run rows sorted by run index, so
//! a sharded-and-merged campaign gives the same table to the last digit.

use std::path::Path;

use anyhow::{bail, Context, Result};
use indicatif::{ParallelProgressIterator, ProgressBar, ProgressStyle};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

use imu_fdi::monitor::Phase;

use crate::eval::stats_ci::{mean_ci, poisson_ci, wilson_ci};
use hal_sim::fault::{FaultKind, FaultRow};
use hal_sim::metrics::evaluate;
use hal_sim::runner::{run, RunOptions};
use hal_sim::scenario::Scenario;

/// One run of a campaign: what was injected and what the monitor did.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CampaignRow {
    /// Run index within the campaign.
    pub index: u64,
    /// Simulation seed.
    pub seed: u64,
    /// Faulty channel 0–5.
    pub channel: usize,
    /// Shape: 1 step (E1), 2 ramp (E2), 3 slow sine (E3).
    pub shape: u8,
    /// +1 or −1.
    pub sign: f64,
    /// Factor on the scenario's fault sizes.
    pub size_factor: f64,
    /// Onset, s.
    pub onset: f64,
    /// End, s.
    pub end: f64,
    /// Flagged on the right channel with the right sign (1) or not (0).
    pub detected: u8,
    /// Onset (of the detectable fault) to first correct flag, s (NaN if none).
    pub delay_s: f64,
    /// Any channel flagged during the fault (1) or not (0).
    pub any_alarm: u8,
    /// The first channel flagged during the fault was the faulty one (1).
    pub first_flag_right: u8,
    /// Sample detection rate (SPEC §9) of this run (NaN if nothing counted).
    pub hit_rate: f64,
    /// False-alarm events (rising edges) in fault-free time.
    pub false_alarm_events: u64,
    /// Fault-free monitored time, s.
    pub free_time_s: f64,
    /// RMSE of the fault estimate over the fault (NaN if none).
    pub rmse: f64,
}

/// Shapes a campaign draws from.
const SHAPES: [FaultKind; 3] = [FaultKind::E1, FaultKind::E2, FaultKind::E3];

/// The scenario of run `index`: `base` with its fault table replaced by one
/// random fault (onset 15–45 s or within the run, 5–10 s long, size factor
/// log-uniform in [0.5, 2]).
pub fn campaign_scenario(base: &Scenario, seed: u64, index: u64) -> (Scenario, u64) {
    let run_seed = seed.wrapping_add(index);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(run_seed ^ 0x6361_6d70);
    let mut scn = base.clone();
    scn.faults.clear();
    let channel = rng.random_range(0..6);
    let shape = SHAPES[rng.random_range(0..SHAPES.len())];
    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let factor = libm::exp(rng.random_range(libm::log(0.5)..libm::log(2.0)));
    let latest = (base.duration_s - 15.0).max(16.0);
    let onset = rng.random_range(15.0..latest.clamp(15.5, 45.0));
    let length = rng.random_range(5.0..10.0);
    for s in scn.sizes.accel.iter_mut().chain(scn.sizes.gyro.iter_mut()) {
        *s *= factor;
    }
    let _ = scn.faults.push(FaultRow {
        channel,
        start: onset,
        end: (onset + length).min(base.duration_s),
        kind: shape,
        sign,
    });
    (scn, run_seed)
}

fn one_run(base: &Scenario, seed: u64, index: u64, opts: &RunOptions) -> Result<CampaignRow> {
    let (scn, run_seed) = campaign_scenario(base, seed, index);
    let Some(fault) = scn.faults.first().copied() else {
        bail!("campaign scenario without a fault");
    };
    let trace = run::<f32>(&scn, run_seed, opts)
        .map_err(|e| anyhow::anyhow!("monitor configuration: {e:?}"))?;
    let m = evaluate(&trace);
    let c = m.channels.get(fault.channel).copied().unwrap_or_default();
    let mut first_flag = None;
    for r in trace
        .rows
        .iter()
        .filter(|r| fault.active(r.t) && r.phase == Phase::Monitoring)
    {
        if let Some(k) = r.flag.iter().position(|f| f.is_some_and(|v| v != 0)) {
            first_flag = Some(k);
            break;
        }
    }
    let shape = match fault.kind {
        FaultKind::E1 => 1,
        FaultKind::E2 => 2,
        _ => 3,
    };
    Ok(CampaignRow {
        index,
        seed: run_seed,
        channel: fault.channel,
        shape,
        sign: fault.sign,
        size_factor: scn.sizes.accel[0] / base.sizes.accel[0].max(f64::MIN_POSITIVE),
        onset: fault.start,
        end: fault.end,
        detected: u8::from(c.detected > 0),
        delay_s: c.delay_mean().unwrap_or(f64::NAN),
        any_alarm: u8::from(first_flag.is_some()),
        first_flag_right: u8::from(first_flag == Some(fault.channel)),
        hit_rate: c.detection_rate().unwrap_or(f64::NAN),
        false_alarm_events: m.false_alarm_events as u64,
        free_time_s: m.free_time_s,
        rmse: c.rmse().unwrap_or(f64::NAN),
    })
}

/// Which runs of a campaign this machine does: `i` of `n` (1-based) takes
/// the run indices `k` with `k mod n = i − 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 1-based.
    pub i: u64,
    /// Number of shards.
    pub n: u64,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (a, b) = s
            .split_once('/')
            .ok_or_else(|| format!("shard '{s}' is not of the form i/n"))?;
        let i: u64 = a
            .trim()
            .parse()
            .map_err(|_| format!("shard '{s}': '{a}' is not a number"))?;
        let n: u64 = b
            .trim()
            .parse()
            .map_err(|_| format!("shard '{s}': '{b}' is not a number"))?;
        if n == 0 || i == 0 || i > n {
            return Err(format!("shard '{s}': need 1 <= i <= n"));
        }
        Ok(Self { i, n })
    }
}

/// Runs the campaign's runs `0..runs` (those of `shard`, if given) in
/// parallel, with a progress bar on stderr when it is a terminal.
pub fn run_campaign(
    base: &Scenario,
    runs: u64,
    seed: u64,
    shard: Option<Shard>,
    opts: &RunOptions,
) -> Result<Vec<CampaignRow>> {
    let indices: Vec<u64> = (0..runs)
        .filter(|k| shard.is_none_or(|s| k % s.n == s.i - 1))
        .collect();
    let bar = ProgressBar::new(indices.len() as u64);
    if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} runs {per_sec} eta {eta}")
    {
        bar.set_style(style);
    }
    let mut rows: Vec<CampaignRow> = indices
        .par_iter()
        .progress_with(bar)
        .map(|&k| one_run(base, seed, k, opts))
        .collect::<Result<_>>()?;
    rows.sort_by_key(|r| r.index);
    Ok(rows)
}

/// Writes rows as CSV (full `f64` precision: merging re-reads them exactly).
pub fn write_rows(path: &Path, rows: &[CampaignRow]) -> Result<()> {
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("cannot write {}", path.display()))?;
    for r in rows {
        w.serialize(r)?;
    }
    w.flush()?;
    Ok(())
}

/// Reads rows written by [`write_rows`]; errors name the file and line.
pub fn read_rows(path: &Path) -> Result<Vec<CampaignRow>> {
    let mut rdr =
        csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut rows = Vec::new();
    for (i, rec) in rdr.deserialize().enumerate() {
        let row: CampaignRow =
            rec.with_context(|| format!("{}: line {}", path.display(), i + 2))?;
        rows.push(row);
    }
    Ok(rows)
}

/// Merges shards: sorted by run index, a run present twice is an error.
pub fn merge_rows(mut rows: Vec<CampaignRow>) -> Result<Vec<CampaignRow>> {
    rows.sort_by_key(|r| r.index);
    if let Some(w) = rows.windows(2).find(|w| w[0].index == w[1].index) {
        bail!("run {} appears in more than one shard", w[0].index);
    }
    Ok(rows)
}

/// A figure with its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Interval {
    /// Point estimate.
    pub value: f64,
    /// Lower bound.
    pub low: f64,
    /// Upper bound.
    pub high: f64,
}

/// The campaign table.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CampaignSummary {
    /// Runs summarised.
    pub runs: u64,
    /// First and last run index.
    pub index_range: (u64, u64),
    /// Fraction of runs whose fault was flagged on its channel (Wilson).
    pub detection_rate: Interval,
    /// Mean SPEC §9 sample detection rate over runs (normal interval).
    pub sample_detection_rate: Interval,
    /// False-alarm events per fault-free hour (exact Poisson).
    pub false_alarms_per_hour: Interval,
    /// Fault-free hours monitored.
    pub fault_free_hours: f64,
    /// Mean delay over detected runs, s (normal interval).
    pub delay_s: Interval,
    /// Of runs with any alarm during the fault, the first alarm was on the
    /// faulty channel (Wilson).
    pub isolation_accuracy: Interval,
    /// Mean fault-estimate RMSE, m/s² for accelerometer runs.
    pub rmse_accel: Interval,
    /// Mean fault-estimate RMSE, °/s for gyro runs.
    pub rmse_gyro_deg: Interval,
}

/// Summarises rows (sorted by index, so the sums are order-independent).
pub fn summarise(rows: &[CampaignRow]) -> Result<CampaignSummary> {
    if rows.is_empty() {
        bail!("no runs to summarise");
    }
    let n = rows.len() as u64;
    let detected = rows.iter().filter(|r| r.detected == 1).count() as u64;
    let any = rows.iter().filter(|r| r.any_alarm == 1).count() as u64;
    let right = rows.iter().filter(|r| r.first_flag_right == 1).count() as u64;
    let events: u64 = rows.iter().map(|r| r.false_alarm_events).sum();
    let hours: f64 = rows.iter().map(|r| r.free_time_s).sum::<f64>() / 3600.0;
    let (fl, fh) = poisson_ci(events);
    let finite = |f: &dyn Fn(&CampaignRow) -> Option<f64>| -> Vec<f64> {
        rows.iter()
            .filter_map(f)
            .filter(|v| v.is_finite())
            .collect()
    };
    let interval = |v: (f64, f64, f64)| Interval {
        value: v.0,
        low: v.1,
        high: v.2,
    };
    let wilson = |k: u64, m: u64| {
        let (lo, hi) = wilson_ci(k, m);
        Interval {
            value: if m > 0 { k as f64 / m as f64 } else { f64::NAN },
            low: lo,
            high: hi,
        }
    };
    Ok(CampaignSummary {
        runs: n,
        index_range: (
            rows.first().map_or(0, |r| r.index),
            rows.last().map_or(0, |r| r.index),
        ),
        detection_rate: wilson(detected, n),
        sample_detection_rate: interval(mean_ci(&finite(&|r| Some(r.hit_rate)))),
        false_alarms_per_hour: Interval {
            value: events as f64 / hours.max(1e-12),
            low: fl / hours.max(1e-12),
            high: fh / hours.max(1e-12),
        },
        fault_free_hours: hours,
        delay_s: interval(mean_ci(&finite(&|r| {
            (r.detected == 1).then_some(r.delay_s)
        }))),
        isolation_accuracy: wilson(right, any),
        rmse_accel: interval(mean_ci(&finite(&|r| (r.channel < 3).then_some(r.rmse)))),
        rmse_gyro_deg: interval(mean_ci(&finite(&|r| {
            (r.channel >= 3).then_some(r.rmse.to_degrees())
        }))),
    })
}

impl CampaignSummary {
    /// The table as text.
    pub fn table(&self) -> String {
        use core::fmt::Write as _;
        let mut s = String::new();
        let row = |s: &mut String, name: &str, i: &Interval, scale: f64, unit: &str| {
            let _ = writeln!(
                s,
                "{name:<28} {:>10.4} {unit:<6} [{:.4}, {:.4}]",
                i.value * scale,
                i.low * scale,
                i.high * scale
            );
        };
        let _ = writeln!(
            s,
            "{} runs (indices {}..={}); value and 95 % interval",
            self.runs, self.index_range.0, self.index_range.1
        );
        row(
            &mut s,
            "detection rate (runs)",
            &self.detection_rate,
            100.0,
            "%",
        );
        row(
            &mut s,
            "detection rate (samples)",
            &self.sample_detection_rate,
            100.0,
            "%",
        );
        row(
            &mut s,
            "false alarms per hour",
            &self.false_alarms_per_hour,
            1.0,
            "/h",
        );
        row(&mut s, "detection delay", &self.delay_s, 1.0, "s");
        row(
            &mut s,
            "isolation accuracy",
            &self.isolation_accuracy,
            100.0,
            "%",
        );
        row(
            &mut s,
            "fault RMSE, accelerometer",
            &self.rmse_accel,
            1.0,
            "m/s²",
        );
        row(&mut s, "fault RMSE, gyro", &self.rmse_gyro_deg, 1.0, "°/s");
        let _ = writeln!(
            s,
            "fault-free time monitored: {:.3} h",
            self.fault_free_hours
        );
        s
    }
}

/// Reads and merges shard files.
pub fn merge_files(paths: &[std::path::PathBuf]) -> Result<Vec<CampaignRow>> {
    let mut all = Vec::new();
    for p in paths {
        all.extend(read_rows(p)?);
    }
    merge_rows(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parallel campaign (rayon over every core) gives the same rows,
    /// to the bit, as the runs done one after the other on one thread.
    #[test]
    fn parallel_campaign_equals_the_serial_runs() -> Result<()> {
        let base = Scenario::s2();
        let opts = RunOptions::default();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
        let parallel = pool.install(|| run_campaign(&base, 6, 11, None, &opts))?;
        let serial = (0..6)
            .map(|k| one_run(&base, 11, k, &opts))
            .collect::<Result<Vec<_>>>()?;
        assert_eq!(parallel.len(), 6);
        // Debug prints each f64 in its shortest round-trip form (NaN too),
        // so equal text is equal bits.
        assert_eq!(format!("{parallel:?}"), format!("{serial:?}"));
        // Not vacuous: the runs differ from one another.
        assert!(parallel.windows(2).all(|w| w[0].onset != w[1].onset));
        Ok(())
    }
}

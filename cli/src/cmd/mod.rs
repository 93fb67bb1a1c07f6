//! One module per subcommand of `imu-fdi-sim` (each with its `Args` and
//! `run`), and what several of them share: the detector options, loading a
//! scenario, and running one over seeds.

use anyhow::{anyhow, Result};
use clap::ValueEnum;
use hal_sim::metrics::{evaluate, RunMetrics};
use hal_sim::runner::{self, RunOptions};
use hal_sim::Scenario;
use imu_fdi::detect::{Detector, Statistic};

pub(crate) mod campaign;
pub(crate) mod convert;
pub(crate) mod demo;
pub(crate) mod detections;
pub(crate) mod gallery;
pub(crate) mod json;
pub(crate) mod merge;
pub(crate) mod otsukf;
pub(crate) mod parity;
pub(crate) mod parity_realistic;
pub(crate) mod parity_replay;
pub(crate) mod parity_sweep;
pub(crate) mod parity_table;
pub(crate) mod plot;
pub(crate) mod progress;
pub(crate) mod replay;
pub(crate) mod report;
pub(crate) mod scenario;
pub(crate) mod simulate;
pub(crate) mod sweep;

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum DetectorArg {
    /// \[UKF\] §3.1 threshold method.
    Threshold,
    /// Paper's fixed sign matrix (erratum applied).
    Paper,
    /// Paper's matrix exactly as printed.
    PaperAsPrinted,
    /// Run-time sign matrix C⁻¹·flag.
    Runtime,
    /// Run-time signature matrix with GLR isolation (default).
    RuntimeGlr,
}

impl From<DetectorArg> for Detector {
    fn from(d: DetectorArg) -> Self {
        match d {
            DetectorArg::Threshold => Detector::Threshold,
            DetectorArg::Paper => Detector::PaperMatrix,
            DetectorArg::PaperAsPrinted => Detector::PaperMatrixAsPrinted,
            DetectorArg::Runtime => Detector::RuntimeMatrix,
            DetectorArg::RuntimeGlr => Detector::RuntimeMatrixGlr,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum StatisticArg {
    /// The paper's t-test on raw innovations.
    Raw,
    /// t-test on innovations whitened by the filter's S.
    Whitened,
    /// Known-variance normalised-innovation test.
    Normalized,
}

#[derive(clap::Args, Clone)]
pub(crate) struct DetectOpts {
    /// Decision rule (default: the scenario's: threshold for S1, runtime-glr otherwise).
    #[arg(long, value_enum)]
    detector: Option<DetectorArg>,
    /// Samples in the t-test windows.
    #[arg(long, value_enum, default_value = "normalized")]
    statistic: StatisticArg,
    /// Per-tail significance of the t-test.
    #[arg(long, default_value_t = 1e-6)]
    alpha: f64,
}

pub(crate) fn default_detector(name: &str) -> Detector {
    if name.eq_ignore_ascii_case("s1") {
        Detector::Threshold
    } else {
        Detector::RuntimeMatrixGlr
    }
}

pub(crate) fn options(name: &str, d: &DetectOpts) -> RunOptions {
    RunOptions {
        detector: d
            .detector
            .map_or_else(|| default_detector(name), Detector::from),
        statistic: match d.statistic {
            StatisticArg::Raw => Statistic::Raw,
            StatisticArg::Whitened => Statistic::Whitened,
            StatisticArg::Normalized => Statistic::Normalized,
        },
        alpha: d.alpha,
    }
}

pub(crate) fn campaign(
    scn: &Scenario,
    first: u64,
    seeds: u64,
    opts: &RunOptions,
) -> Result<RunMetrics> {
    let mut total = RunMetrics::default();
    for seed in first..first + seeds {
        let trace = runner::run::<f32>(scn, seed, opts)
            .map_err(|e| anyhow!("monitor configuration: {e:?}"))?;
        total.merge(&evaluate(&trace));
    }
    Ok(total)
}

/// The `--detector` name of a decision rule (text and JSON output).
pub(crate) fn detector_name(d: Detector) -> &'static str {
    match d {
        Detector::Threshold => "threshold",
        Detector::PaperMatrix => "paper",
        Detector::PaperMatrixAsPrinted => "paper-as-printed",
        Detector::RuntimeMatrix => "runtime",
        Detector::RuntimeMatrixGlr => "runtime-glr",
    }
}

/// The `--statistic` name of a t-test statistic.
pub(crate) fn statistic_name(s: Statistic) -> &'static str {
    match s {
        Statistic::Raw => "raw",
        Statistic::Whitened => "whitened",
        Statistic::Normalized => "normalized",
    }
}

pub(crate) fn scenario(name: &str) -> Result<Scenario> {
    imu_fdi_cli::io::scenario_file::load_scenario(name)
}

pub(crate) fn print_run(
    title: &str,
    scn: &Scenario,
    first: u64,
    seeds: u64,
    opts: &RunOptions,
    text: bool,
) -> Result<RunMetrics> {
    let m = campaign(scn, first, seeds, opts)?;
    if !text {
        return Ok(m);
    }
    out!(
        "== {title}: {} seeds {}..{}, detector {}, statistic {}, α = {:e} (f32 monitor)",
        scn.name,
        first,
        first + seeds - 1,
        detector_name(opts.detector),
        statistic_name(opts.statistic),
        opts.alpha
    );
    out_nl!("{}", m.table());
    out!();
    Ok(m)
}

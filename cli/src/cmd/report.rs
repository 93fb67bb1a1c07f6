//! `imu-fdi-sim report`: a log replayed into one self-contained HTML page
//! (verdict table, fault estimates with flags, innovations ±3σ, parity
//! residuals and tests, baselines, status timeline), optionally with each
//! plot as a standalone SVG.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use imu_fdi_cli::report::{html, load, parity::ParityOptions, svg, verdict};

// The arguments of `report` (its help text is the doc comment on `Cmd::Report`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log: PX4 ULog (.ulg), ArduPilot DataFlash (.bin) or a SPEC §10 CSV.
    input: PathBuf,
    /// The HTML file to write (default: the log's name with .html, in the
    /// current directory).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write every plot and the timeline as standalone SVGs here.
    #[arg(long)]
    svg_dir: Option<PathBuf>,
    /// Parity monitor (three IMUs): log time its training starts, s
    /// (default: the first row; in flight, vibration must be in it).
    #[arg(long)]
    train_start: Option<f64>,
    /// Parity monitor: training + calibration length, s.
    #[arg(long, default_value_t = 30.0)]
    train_s: f64,
    /// Print one JSON object (verdicts, files, timing) instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs `report`.
pub(crate) fn run(args: Args) -> Result<()> {
    let start = Instant::now();
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from(
            args.input
                .file_stem()
                .map_or_else(|| "report".into(), |s| s.to_string_lossy().to_string()),
        )
        .with_extension("html")
    });
    let opts = load::BuildOptions {
        parity: ParityOptions {
            train_start: args.train_start,
            train_s: args.train_s,
        },
    };
    let bar = super::progress::spinner("report");
    let report = load::build(&args.input, &opts, &mut |what| {
        bar.set_message(format!("{}: {what}", args.input.display()));
    })?;
    bar.set_message("writing".into());
    let page = html::page(&report);
    std::fs::write(&out, &page).with_context(|| format!("cannot write {}", out.display()))?;
    let mut svgs = Vec::new();
    if let Some(dir) = &args.svg_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        for p in &report.plots {
            let path = dir.join(format!("{}.svg", p.id));
            std::fs::write(&path, svg::plot(p, report.span_s))
                .with_context(|| format!("cannot write {}", path.display()))?;
            svgs.push(path);
        }
        let path = dir.join("timeline.svg");
        std::fs::write(&path, svg::timeline(&report.timeline, report.span_s))
            .with_context(|| format!("cannot write {}", path.display()))?;
        svgs.push(path);
    }
    drop(bar);
    let elapsed = start.elapsed().as_secs_f64();
    let [ok, bad, na] = verdict::counts(&report.verdicts);
    if args.json {
        let v = serde_json::json!({
            "input": args.input.display().to_string(),
            "html": out.display().to_string(),
            "html_bytes": page.len(),
            "svgs": svgs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "imus": report.imus,
            "start_s": report.span_s.0,
            "end_s": report.span_s.1,
            "plots": report.plots.len(),
            "healthy": ok,
            "faulty": bad,
            "not_judged": na,
            "verdicts": report.verdicts,
            "notes": report.notes,
            "elapsed_s": elapsed,
        });
        out!("{v}");
        return Ok(());
    }
    out!(
        "{}: {} IMU(s), t = {:.2}..{:.2} s; {} plots; verdicts: {ok} healthy, {bad} faulty, {na} not judged",
        args.input.display(),
        report.imus,
        report.span_s.0,
        report.span_s.1,
        report.plots.len()
    );
    for v in report
        .verdicts
        .iter()
        .filter(|v| v.state == verdict::State::Faulty)
    {
        out!(
            "  faulty: IMU {} {} ({} monitor){}: {}",
            v.imu,
            v.channel,
            v.monitor,
            v.since_s.map_or(String::new(), |t| format!(" at {t:.2} s")),
            v.why
        );
    }
    for n in &report.notes {
        eprintln!("note: {n}");
    }
    out!(
        "wrote {} ({:.1} MB) in {elapsed:.2} s",
        out.display(),
        page.len() as f64 / 1e6
    );
    if let Some(dir) = &args.svg_dir {
        out!("wrote {} SVGs to {}", svgs.len(), dir.display());
    }
    Ok(())
}

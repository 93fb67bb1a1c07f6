//! The papers' figures from any run, as PNG and SVG (plotters, with the
//! DejaVu Sans font embedded so no system font is needed): injected fault
//! against the detection flag, fault estimate against truth, innovations
//! with ±3σ, test statistic against threshold, and the parity PCA pattern.

use std::path::{Path, PathBuf};
use std::sync::Once;

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

use hal_sim::array::{ArraySim, ArraySpec};
use hal_sim::runner::Trace;

const CHANNELS: [&str; 6] = ["a_x", "a_y", "a_z", "p", "q", "r"];
/// Figure size, px.
pub const SIZE: (u32, u32) = (780, 560);
static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Channel unit and display scale (gyro in °/s).
fn unit(ch: usize) -> (&'static str, f64) {
    if ch < 3 {
        ("m/s²", 1.0)
    } else {
        ("°/s", 180.0 / core::f64::consts::PI)
    }
}

/// One panel per channel: named series of (t, value) with colours.
type Series = Vec<(String, RGBColor, Vec<(f64, f64)>)>;

/// A white drawing area with `title` on top; returns the area below it.
fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    font_size: u32,
) -> Result<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(|e| anyhow!("{e:?}"))?;
    root.titled(title, ("sans-serif", font_size))
        .map_err(|e| anyhow!("{e:?}"))
}

fn grid<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    panels: &[(String, Series)],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let root = titled(root, title, 20)?;
    let areas = root.split_evenly((3, 2));
    for (area, (name, series)) in areas.iter().zip(panels.iter()) {
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (_, _, pts) in series {
            for (x, y) in pts.iter().filter(|(x, y)| x.is_finite() && y.is_finite()) {
                x0 = x0.min(*x);
                x1 = x1.max(*x);
                y0 = y0.min(*y);
                y1 = y1.max(*y);
            }
        }
        if x0 > x1 {
            (x0, x1, y0, y1) = (0.0, 1.0, -1.0, 1.0);
        }
        let pad = ((y1 - y0) * 0.08).max(1e-9);
        let mut chart = ChartBuilder::on(area)
            .caption(name, ("sans-serif", 14))
            .margin(6)
            .x_label_area_size(22)
            .y_label_area_size(46)
            .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
            .map_err(|e| anyhow!("{e:?}"))?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .x_labels(6)
            .y_labels(5)
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(|e| anyhow!("{e:?}"))?;
        for (label, color, pts) in series {
            let c = *color;
            chart
                .draw_series(LineSeries::new(
                    pts.iter()
                        .copied()
                        .filter(|(x, y)| x.is_finite() && y.is_finite()),
                    c.stroke_width(1),
                ))
                .map_err(|e| anyhow!("{e:?}"))?
                .label(label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], c));
        }
        legend(&mut chart, 10)?;
    }
    root.present().map_err(|e| anyhow!("{e:?}"))?;
    Ok(())
}

/// Draws the series legend of a chart (framed, semi-transparent).
fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    font: u32,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .label_font(("sans-serif", font))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .draw()
        .map_err(|e| anyhow!("{e:?}"))
}

/// Renders `panels` to `stem.png` and `stem.svg`; returns both paths.
fn render(stem: &Path, title: &str, panels: &[(String, Series)]) -> Result<Vec<PathBuf>> {
    register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    {
        let root = BitMapBackend::new(&png, SIZE).into_drawing_area();
        grid(&root, title, panels)?;
    }
    {
        let root = SVGBackend::new(&svg, SIZE).into_drawing_area();
        grid(&root, title, panels)?;
    }
    Ok(vec![png, svg])
}

const BLUE_: RGBColor = RGBColor(31, 119, 180);
const RED_: RGBColor = RGBColor(214, 39, 40);
const GREY_: RGBColor = RGBColor(127, 127, 127);

fn decimate<T>(v: &[T], max: usize) -> impl Iterator<Item = &T> {
    let step = v.len().div_ceil(max.max(1)).max(1);
    v.iter().step_by(step)
}

/// Which figures [`plot_trace`] draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraceFigure {
    /// Injected fault and the detection flag (scaled to the fault's peak).
    FaultsAndFlags,
    /// Fault estimate against the injected fault.
    Estimates,
    /// Innovations with their ±3σ band.
    Innovations,
    /// Test statistic against its threshold.
    Statistic,
}

/// Draws one figure of a UKF-monitor run to `stem.{png,svg}`.
pub fn plot_trace(trace: &Trace, fig: TraceFigure, stem: &Path) -> Result<Vec<PathBuf>> {
    let rows: Vec<_> = decimate(&trace.rows, 1300).collect();
    let name = trace.scenario.name.as_str();
    let mut panels = Vec::new();
    for ch in 0..6 {
        let (u, k) = unit(ch);
        let col = |f: &dyn Fn(&hal_sim::runner::TraceRow) -> f64| -> Vec<(f64, f64)> {
            rows.iter().map(|r| (r.t, f(r))).collect()
        };
        let series: Series = match fig {
            TraceFigure::FaultsAndFlags => {
                let peak = trace
                    .rows
                    .iter()
                    .map(|r| (r.fault[ch] * k).abs())
                    .fold(0.0, f64::max)
                    .max(1e-9);
                vec![
                    ("injected".into(), BLUE_, col(&|r| r.fault[ch] * k)),
                    (
                        "flag × peak".into(),
                        RED_,
                        col(&|r| f64::from(r.flag[ch].unwrap_or(0)) * peak),
                    ),
                ]
            }
            TraceFigure::Estimates => vec![
                ("injected".into(), BLUE_, col(&|r| r.fault[ch] * k)),
                ("estimate".into(), RED_, col(&|r| r.fhat[ch] * k)),
            ],
            TraceFigure::Innovations => vec![
                ("innovation".into(), BLUE_, col(&|r| r.innovation[ch])),
                ("+3σ".into(), GREY_, col(&|r| 3.0 * r.innovation_sigma[ch])),
                ("−3σ".into(), GREY_, col(&|r| -3.0 * r.innovation_sigma[ch])),
            ],
            TraceFigure::Statistic => vec![
                ("|statistic|".into(), BLUE_, col(&|r| r.t_stat[ch].abs())),
                ("threshold".into(), RED_, col(&|_| trace.t_threshold)),
            ],
        };
        let label = match fig {
            TraceFigure::Innovations => format!(
                "innovation {} (its own unit) vs t [s]",
                ["u", "v", "w", "φ", "θ", "ψ"][ch]
            ),
            TraceFigure::Statistic => format!(
                "{} window statistic vs t [s]",
                ["u", "v", "w", "φ", "θ", "ψ"][ch]
            ),
            _ => format!("{} [{u}] vs t [s]", CHANNELS[ch]),
        };
        panels.push((label, series));
    }
    let title = match fig {
        TraceFigure::FaultsAndFlags => format!(
            "{name} seed {}: injected fault and detection flag",
            trace.seed
        ),
        TraceFigure::Estimates => format!("{name} seed {}: fault estimate and truth", trace.seed),
        TraceFigure::Innovations => format!("{name} seed {}: innovations and ±3σ", trace.seed),
        TraceFigure::Statistic => format!(
            "{name} seed {}: normalised window statistic and threshold",
            trace.seed
        ),
    };
    render(stem, &title, &panels)
}

/// S4-style parity figures of an array run: the \[PAR\] pattern mean
/// (before and after the fault), and the χ² statistic against its threshold.
pub fn plot_parity<const N: usize>(
    spec: &ArraySpec<N>,
    seed: u64,
    stem: &Path,
) -> Result<Vec<PathBuf>> {
    use imu_fdi::parity::{Geometry, ParityMonitor, ParityPhase, Reading};
    let dirs: [[f32; 3]; N] = spec.directions.map(|d| d.map(|x| x as f32));
    let g = Geometry::<f32, N>::new(&dirs).map_err(|e| anyhow!("{e:?}"))?;
    let sim = ArraySim::new(spec, seed);
    let mut cfg = crate::eval::array_run::array_config::<f32, N>(spec);
    cfg.set_lead_in(sim.lead_in_samples());
    let mut m = ParityMonitor::<f32, N, 32>::new(&g, cfg).map_err(|e| anyhow!("{e:?}"))?;
    let onset = spec
        .faults
        .iter()
        .map(|f| f.start)
        .fold(f64::INFINITY, f64::min);
    let (mut before, mut after, mut glt, mut thr) = (vec![], vec![], vec![], vec![]);
    let mut isolated_at = None;
    for s in sim {
        let r: [Reading<f32>; N] = s.readings.map(|r| r.map(|x| x as f32));
        let rep = m.step(&r);
        if rep.isolated.is_some() {
            isolated_at.get_or_insert(s.t);
        }
        if s.training
            || rep.phase != ParityPhase::Monitoring
            || !rep.decision
            || isolated_at.is_some()
        {
            continue;
        }
        let p = (
            f64::from(rep.pattern[0]).to_degrees(),
            f64::from(rep.pattern[1]).to_degrees(),
        );
        if s.t < onset {
            before.push(p);
        } else {
            after.push(p);
        }
        glt.push((s.t, f64::from(rep.glt)));
        thr.push((s.t, f64::from(rep.glt_threshold)));
    }
    register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let title = format!(
        "{} seed {seed}: parity pattern and χ² (fault at {onset} s{})",
        spec.name,
        isolated_at.map_or(String::new(), |t| format!(", isolated at {t:.2} s"))
    );
    {
        let root = BitMapBackend::new(&png, SIZE).into_drawing_area();
        parity_figure(&root, &title, &before, &after, &glt, &thr)?;
    }
    {
        let root = SVGBackend::new(&svg, SIZE).into_drawing_area();
        parity_figure(&root, &title, &before, &after, &glt, &thr)?;
    }
    Ok(vec![png, svg])
}

fn parity_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    before: &[(f64, f64)],
    after: &[(f64, f64)],
    glt: &[(f64, f64)],
    thr: &[(f64, f64)],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let root = titled(root, title, 18)?;
    let (left, right) = root.split_horizontally(SIZE.0 / 2);
    let lim = before
        .iter()
        .chain(after.iter())
        .map(|(x, y)| x.abs().max(y.abs()))
        .fold(1e-6, f64::max)
        * 1.1;
    let mut c = ChartBuilder::on(&left)
        .caption("PCA pattern mean y = Wᵀp̄ [°/s]", ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(24)
        .y_label_area_size(46)
        .build_cartesian_2d(-lim..lim, -lim..lim)
        .map_err(|e| anyhow!("{e:?}"))?;
    c.configure_mesh()
        .light_line_style(WHITE)
        .label_style(("sans-serif", 11))
        .draw()
        .map_err(|e| anyhow!("{e:?}"))?;
    c.draw_series(before.iter().map(|p| Circle::new(*p, 2, GREY_.filled())))
        .map_err(|e| anyhow!("{e:?}"))?
        .label("before the fault")
        .legend(|(x, y)| Circle::new((x + 5, y), 3, GREY_.filled()));
    c.draw_series(after.iter().map(|p| Circle::new(*p, 3, RED_.filled())))
        .map_err(|e| anyhow!("{e:?}"))?
        .label("after the fault")
        .legend(|(x, y)| Circle::new((x + 5, y), 3, RED_.filled()));
    legend(&mut c, 11)?;
    let x0 = glt.first().map_or(0.0, |p| p.0);
    let x1 = glt.last().map_or(1.0, |p| p.0).max(x0 + 1e-6);
    let ymax = glt
        .iter()
        .chain(thr.iter())
        .map(|p| p.1)
        .fold(1.0, f64::max)
        * 1.1;
    let mut c = ChartBuilder::on(&right)
        .caption("window χ² and threshold (log) vs t [s]", ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(24)
        .y_label_area_size(46)
        .build_cartesian_2d(x0..x1, (0.1..ymax).log_scale())
        .map_err(|e| anyhow!("{e:?}"))?;
    c.configure_mesh()
        .light_line_style(WHITE)
        .label_style(("sans-serif", 11))
        .draw()
        .map_err(|e| anyhow!("{e:?}"))?;
    c.draw_series(LineSeries::new(
        glt.iter().map(|(t, v)| (*t, v.max(0.1))),
        BLUE_,
    ))
    .map_err(|e| anyhow!("{e:?}"))?
    .label("χ²")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], BLUE_));
    c.draw_series(LineSeries::new(thr.iter().copied(), RED_))
        .map_err(|e| anyhow!("{e:?}"))?
        .label("threshold")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], RED_));
    legend(&mut c, 11)?;
    root.present().map_err(|e| anyhow!("{e:?}"))?;
    Ok(())
}

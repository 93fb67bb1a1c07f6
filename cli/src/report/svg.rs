//! Standalone SVG of one plot or of the status timeline (`report
//! --svg-dir`): the same drawing as the page's first view, for papers and
//! READMEs. Series are drawn as min/max envelopes per pixel column
//! ([`super::decimate::by_time`]), so no spike disappears.

use std::fmt::Write as _;

use super::decimate::by_time;
use super::{Plot, Stroke, Timeline};

/// Width of the drawing, px.
pub const WIDTH: f64 = 1000.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const PLOT_H: f64 = 220.0;
const STRIP_H: f64 = 12.0;

/// Escapes text for XML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// About `n` round tick values covering `[lo, hi]`.
pub fn ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = hi - lo;
    if span.is_nan() || span <= 0.0 || !span.is_finite() {
        return vec![lo];
    }
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// The y range of a plot: every finite sample and threshold, padded.
pub fn y_range(p: &Plot) -> (f64, f64) {
    let vals = p
        .series
        .iter()
        .flat_map(|s| s.y.iter().copied())
        .chain(p.hlines.iter().map(|h| h.y))
        .filter(|v| v.is_finite());
    let (lo, hi) = vals.fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)));
    if lo > hi {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-9);
    (lo - pad, hi + pad)
}

/// One plot over `span` as an SVG document.
pub fn plot(p: &Plot, span: (f64, f64)) -> String {
    let top = 28.0 + STRIP_H * p.strips.len() as f64;
    let h = top + PLOT_H + 40.0;
    let w = WIDTH - LEFT - RIGHT;
    let (t0, t1) = span;
    let (y0, y1) = y_range(p);
    let x = |t: f64| LEFT + (t - t0) / (t1 - t0).max(1e-9) * w;
    let y = |v: f64| top + (y1 - v) / (y1 - y0) * PLOT_H;
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{h}" viewBox="0 0 {WIDTH} {h}" font-family="sans-serif" font-size="11"><rect width="100%" height="100%" fill="white"/><text x="{LEFT}" y="16" font-size="13" font-weight="bold">{}</text>"#,
        esc(&p.title)
    );
    for (i, strip) in p.strips.iter().enumerate() {
        let sy = 24.0 + STRIP_H * i as f64;
        let _ = write!(
            s,
            r##"<text x="{}" y="{}" text-anchor="end" font-size="9">{}</text><rect x="{LEFT}" y="{sy}" width="{w}" height="{}" fill="#f4f4f4"/>"##,
            LEFT - 4.0,
            sy + 9.0,
            esc(&strip.name),
            STRIP_H - 2.0
        );
        for iv in &strip.intervals {
            let _ = write!(
                s,
                r#"<rect x="{:.1}" y="{sy}" width="{:.1}" height="{}" fill="{}"><title>{}</title></rect>"#,
                x(iv.start_s),
                (x(iv.end_s) - x(iv.start_s)).max(1.0),
                STRIP_H - 2.0,
                iv.color,
                esc(&iv.label)
            );
        }
    }
    let _ = write!(
        s,
        r##"<rect x="{LEFT}" y="{top}" width="{w}" height="{PLOT_H}" fill="none" stroke="#888"/>"##
    );
    for v in ticks(y0, y1, 5) {
        let _ = write!(
            s,
            r##"<line x1="{LEFT}" x2="{}" y1="{:.1}" y2="{:.1}" stroke="#eee"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            LEFT + w,
            y(v),
            y(v),
            LEFT - 4.0,
            y(v) + 4.0,
            fmt_tick(v)
        );
    }
    for v in ticks(t0, t1, 10) {
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{}" text-anchor="middle">{}</text>"#,
            x(v),
            top + PLOT_H + 14.0,
            fmt_tick(v)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">time (s)</text><text x="14" y="{}" transform="rotate(-90 14 {})" text-anchor="middle">{}</text>"#,
        LEFT + w / 2.0,
        top + PLOT_H + 30.0,
        top + PLOT_H / 2.0,
        top + PLOT_H / 2.0,
        esc(&p.unit)
    );
    for hl in &p.hlines {
        let _ = write!(
            s,
            r##"<line x1="{LEFT}" x2="{}" y1="{:.1}" y2="{:.1}" stroke="#000" stroke-dasharray="6 3"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            LEFT + w,
            y(hl.y),
            y(hl.y),
            LEFT + w - 2.0,
            y(hl.y) - 3.0,
            esc(&hl.label)
        );
    }
    for se in &p.series {
        let cols = by_time(&se.t, &se.y, t0, t1 + (t1 - t0) * 1e-9, w as usize);
        let mut d = String::new();
        let mut prev_t1: Option<f64> = None;
        for b in &cols {
            // A gap longer than a few columns breaks the line.
            let gap = prev_t1.is_some_and(|p| x(b.t0) - x(p) > 3.0);
            let cmd = if prev_t1.is_none() || gap { 'M' } else { 'L' };
            let _ = write!(d, "{cmd}{:.1} {:.1}", x(b.t0), y(b.hi));
            if b.lo != b.hi {
                let _ = write!(d, "L{:.1} {:.1}", x(b.t0), y(b.lo));
            }
            prev_t1 = Some(b.t1);
        }
        let dash = match se.stroke {
            Stroke::Solid => "",
            Stroke::Dashed => r#" stroke-dasharray="4 3" stroke-opacity="0.6""#,
        };
        let _ = write!(
            s,
            r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1"{dash}><title>{}</title></path>"#,
            se.color,
            esc(&se.name)
        );
    }
    for m in &p.markers {
        let _ = write!(
            s,
            r#"<line x1="{:.1}" x2="{:.1}" y1="{top}" y2="{}" stroke="{}" stroke-dasharray="2 2"><title>{}</title></line>"#,
            x(m.t_s),
            x(m.t_s),
            top + PLOT_H,
            m.color,
            esc(&m.label)
        );
    }
    // Legend (solid series only: the bounds share their line's colour).
    let mut lx = LEFT + 4.0;
    for se in p.series.iter().filter(|s| s.stroke == Stroke::Solid) {
        let _ = write!(
            s,
            r#"<rect x="{lx:.1}" y="{}" width="10" height="3" fill="{}"/><text x="{:.1}" y="{}">{}</text>"#,
            top + 8.0,
            se.color,
            lx + 13.0,
            top + 12.0,
            esc(&se.name)
        );
        lx += 20.0 + 6.5 * se.name.chars().count() as f64;
    }
    s.push_str("</svg>\n");
    s
}

/// The status timeline over `span` as an SVG document.
pub fn timeline(tl: &Timeline, span: (f64, f64)) -> String {
    let left = 190.0;
    let w = WIDTH - left - RIGHT;
    let lane_h = 16.0;
    let h = 30.0 + lane_h * tl.lanes.len() as f64 + 24.0;
    let (t0, t1) = span;
    let x = |t: f64| left + (t - t0) / (t1 - t0).max(1e-9) * w;
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{h}" viewBox="0 0 {WIDTH} {h}" font-family="sans-serif" font-size="10"><rect width="100%" height="100%" fill="white"/><text x="{left}" y="16" font-size="13" font-weight="bold">Health statuses over time</text>"#
    );
    for (i, lane) in tl.lanes.iter().enumerate() {
        let ly = 24.0 + lane_h * i as f64;
        let _ = write!(
            s,
            r##"<text x="{}" y="{}" text-anchor="end">{}</text><rect x="{left}" y="{ly}" width="{w}" height="{}" fill="#f4f4f4"/>"##,
            left - 4.0,
            ly + 11.0,
            esc(&lane.name),
            lane_h - 3.0
        );
        for iv in &lane.intervals {
            let _ = write!(
                s,
                r#"<rect x="{:.1}" y="{ly}" width="{:.1}" height="{}" fill="{}"><title>{}</title></rect>"#,
                x(iv.start_s),
                (x(iv.end_s) - x(iv.start_s)).max(1.0),
                lane_h - 3.0,
                iv.color,
                esc(&iv.label)
            );
        }
    }
    let base = 24.0 + lane_h * tl.lanes.len() as f64 + 12.0;
    for v in ticks(t0, t1, 10) {
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{base}" text-anchor="middle">{}</text>"#,
            x(v),
            fmt_tick(v)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// A tick label: no trailing zeros, no exponent for ordinary values.
pub fn fmt_tick(v: f64) -> String {
    let v = if v.abs() < 1e-12 { 0.0 } else { v };
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{Series, Strip};

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(ticks(0.0, 10.0, 5), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(
            ticks(60.0, 254.0, 10),
            (3..=12).map(|i| i as f64 * 20.0).collect::<Vec<_>>()
        );
        assert_eq!(fmt_tick(0.30000000000000004), "0.3");
        assert_eq!(ticks(1.0, 1.0, 5), vec![1.0]);
    }

    #[test]
    fn a_spike_reaches_the_svg() {
        let mut p = Plot::new("p", "t <&>", "u");
        let mut s = Series::new("a", "#000", Stroke::Solid);
        for i in 0..100_000 {
            s.push(i as f64 * 0.01, if i == 54_321 { 100.0 } else { 0.0 });
        }
        p.series.push(s);
        p.strips.push(Strip {
            name: "f".into(),
            intervals: vec![],
        });
        let svg = plot(&p, (0.0, 1000.0));
        // y(100) is the top of the plot area (plus the 5 % pad): the path
        // must go there at the spike's column, and the title is escaped.
        let (y0, y1) = y_range(&p);
        let top = 28.0 + STRIP_H;
        let y_spike = top + (y1 - 100.0) / (y1 - y0) * PLOT_H;
        assert!(svg.contains(&format!("{y_spike:.1}")), "{y_spike:.1}");
        assert!(svg.contains("t &lt;&amp;&gt;"));
        assert!(svg.len() < 100_000, "{} bytes", svg.len());
    }
}

//! The self-contained HTML page: the verdict table and notes as HTML, the
//! plots drawn in the browser by a small hand-written script (`page.js`,
//! inlined) from data embedded in the page. No library, no network: the
//! file opens offline.
//!
//! Each series is embedded at full rate up to [`MAX_POINTS`] samples; a
//! longer one is embedded as a min/max envelope of consecutive samples
//! ([`super::decimate::by_count`]), so the page stays a few MB while no
//! spike disappears at any zoom. Series sharing their time stamps share
//! one time array.

use std::fmt::Write as _;

use serde::Serialize;

use super::decimate::by_count;
use super::svg::esc;
use super::verdict::{State, Verdict, CHANNELS};
use super::{FlightReport, HLine, Marker, Strip, Timeline};

/// Most samples of one series embedded as they are.
pub const MAX_POINTS: usize = 60_000;

#[derive(Serialize)]
struct PageSeries<'a> {
    name: &'a str,
    color: &'a str,
    stroke: super::Stroke,
    time: usize,
    lo: Vec<Option<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hi: Option<Vec<Option<f64>>>,
}

#[derive(Serialize)]
struct PagePlot<'a> {
    id: &'a str,
    title: &'a str,
    unit: &'a str,
    series: Vec<PageSeries<'a>>,
    hlines: &'a [HLine],
    markers: &'a [Marker],
    strips: &'a [Strip],
}

#[derive(Serialize)]
struct PageData<'a> {
    span_s: (f64, f64),
    times: Vec<Vec<f64>>,
    plots: Vec<PagePlot<'a>>,
    timeline: &'a Timeline,
}

/// `v` to 5 significant digits (the page draws at 1,000 px: more digits
/// only make the file bigger); NaN and ∞ become `null` (a gap).
fn round(v: f64) -> Option<f64> {
    if !v.is_finite() {
        return None;
    }
    format!("{v:.4e}").parse().ok()
}

fn time_index(times: &mut Vec<Vec<f64>>, t: Vec<f64>) -> usize {
    if let Some(i) = times.iter().position(|x| *x == t) {
        return i;
    }
    times.push(t);
    times.len() - 1
}

/// The page's JSON data (also what `report --json` could embed).
fn data(r: &FlightReport) -> (String, usize) {
    let mut times = Vec::new();
    let mut decimated = 0;
    let plots = r
        .plots
        .iter()
        .map(|p| PagePlot {
            id: &p.id,
            title: &p.title,
            unit: &p.unit,
            series: p
                .series
                .iter()
                .map(|s| {
                    let n = s.t.len();
                    if n <= MAX_POINTS {
                        let t = s.t.iter().map(|x| (x * 1e4).round() / 1e4).collect();
                        PageSeries {
                            name: &s.name,
                            color: &s.color,
                            stroke: s.stroke,
                            time: time_index(&mut times, t),
                            lo: s.y.iter().map(|v| round(*v)).collect(),
                            hi: None,
                        }
                    } else {
                        decimated += 1;
                        let b = by_count(&s.t, &s.y, n.div_ceil(MAX_POINTS));
                        let t = b.iter().map(|b| (b.t0 * 1e4).round() / 1e4).collect();
                        PageSeries {
                            name: &s.name,
                            color: &s.color,
                            stroke: s.stroke,
                            time: time_index(&mut times, t),
                            lo: b.iter().map(|b| round(b.lo)).collect(),
                            hi: Some(b.iter().map(|b| round(b.hi)).collect()),
                        }
                    }
                })
                .collect(),
            hlines: &p.hlines,
            markers: &p.markers,
            strips: &p.strips,
        })
        .collect();
    let d = PageData {
        span_s: r.span_s,
        times,
        plots,
        timeline: &r.timeline,
    };
    // `</` must not end the script element early; `<\/` is the same JSON.
    let json = serde_json::to_string(&d)
        .unwrap_or_else(|_| "{}".into())
        .replace("</", "<\\/");
    (json, decimated)
}

fn cell(v: Option<&Verdict>) -> String {
    match v {
        None => "<td class=\"na\">—</td>".into(),
        Some(v) => {
            let class = match v.state {
                State::Healthy => "ok",
                State::Faulty => "bad",
                State::NotJudged => "na",
            };
            let when = v.since_s.map_or(String::new(), |t| match v.state {
                State::Faulty => format!(" at {t:.2} s"),
                _ => format!(" from {t:.2} s"),
            });
            format!(
                "<td class=\"{class}\"><b>{}</b>{when}<br><small>{}</small></td>",
                v.state.text(),
                esc(&v.why)
            )
        }
    }
}

/// The verdict table: one row per IMU channel, one column per monitor.
fn table(r: &FlightReport) -> String {
    let mut s = String::from(
        "<table id=\"verdicts\"><tr><th>IMU</th><th>channel</th><th>UKF innovation monitor</th><th>parity monitor (three IMUs)</th></tr>",
    );
    for imu in 0..r.imus {
        for ch in CHANNELS {
            let find = |m: &str| {
                r.verdicts
                    .iter()
                    .find(|v| v.imu == imu && v.channel == ch && v.monitor == m)
            };
            let _ = write!(
                s,
                "<tr><td>{imu}</td><td>{ch}</td>{}{}</tr>",
                cell(find("ukf")),
                cell(find("parity"))
            );
        }
    }
    s.push_str("</table>");
    s
}

/// The page.
pub fn page(r: &FlightReport) -> String {
    let (json, decimated) = data(r);
    let [ok, bad, na] = super::verdict::counts(&r.verdicts);
    let mut notes: String = r
        .notes
        .iter()
        .map(|n| format!("<li>{}</li>", esc(n)))
        .collect();
    if decimated > 0 {
        let _ = write!(
            notes,
            "<li>{decimated} series longer than {MAX_POINTS} samples are embedded as min/max envelopes of consecutive samples (no spike is lost; single samples are not shown at the deepest zoom)</li>"
        );
    }
    format!(
        r#"<!DOCTYPE html>
<html lang="en" data-js-errors="0">
<head>
<meta charset="utf-8">
<title>imu-fdi flight report: {src}</title>
<script>
// Every script error is counted on <html> and listed on the page (the
// headless-browser test reads both from the DOM).
window.onerror = function (msg, src, line) {{
  var h = document.documentElement;
  h.setAttribute("data-js-errors", String(+h.getAttribute("data-js-errors") + 1));
  var p = document.getElementById("js-errors");
  if (p) p.textContent += msg + " (line " + line + ")\n";
}};
</script>
<style>
body {{ font-family: sans-serif; margin: 1em auto; max-width: 1100px; color: #222; }}
table {{ border-collapse: collapse; font-size: 13px; width: 100%; }}
td, th {{ border: 1px solid #ccc; padding: 3px 6px; vertical-align: top; text-align: left; }}
td.ok {{ background: #e6f4e6; }} td.bad {{ background: #fbe0e0; }} td.na {{ background: #f0f0f0; color: #555; }}
svg.plot {{ width: 100%; display: block; margin: 6px 0; cursor: grab; font-family: sans-serif; font-size: 11px; user-select: none; }}
#controls {{ position: sticky; top: 0; background: white; padding: 4px 0; border-bottom: 1px solid #ddd; z-index: 1; }}
#js-errors {{ color: #b00; }}
</style>
</head>
<body>
<h1>Flight report: {src}</h1>
<p>{imus} IMU(s), t = {t0:.2} … {t1:.2} s. Verdicts: {ok} healthy, {bad} faulty, {na} not judged.</p>
{table}
<ul>{notes}</ul>
<pre id="js-errors"></pre>
<div id="controls">Time <span id="view"></span> · <button id="zoom-in">zoom in</button> <button id="zoom-out">zoom out</button> <button id="zoom-reset">reset</button> · wheel: zoom, drag: pan, double-click: reset (all plots together)</div>
<div id="timeline"></div>
<div id="plots"></div>
<p><small>imu-fdi {version} · <code>imu-fdi-sim report</code></small></p>
<script type="application/json" id="report-data">{json}</script>
<script>
{js}
</script>
</body>
</html>
"#,
        src = esc(&r.source),
        imus = r.imus,
        t0 = r.span_s.0,
        t1 = r.span_s.1,
        table = table(r),
        version = env!("CARGO_PKG_VERSION"),
        js = include_str!("page.js"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{Plot, Series, Stroke};

    fn report_with(n: usize, spike_at: usize) -> FlightReport {
        let mut s = Series::new("a </script>", "#000", Stroke::Solid);
        for i in 0..n {
            s.push(i as f64 * 0.0025, if i == spike_at { 77.0 } else { 0.5 });
        }
        let mut p = Plot::new("p", "title", "u");
        p.series.push(s.clone());
        let mut s2 = s;
        s2.name = "b".into();
        p.series.push(s2);
        FlightReport {
            source: "x.csv".into(),
            span_s: (0.0, n as f64 * 0.0025),
            plots: vec![p],
            ..FlightReport::default()
        }
    }

    #[test]
    fn a_long_series_is_embedded_as_an_envelope_that_keeps_its_spike() {
        let n = 4 * MAX_POINTS + 3;
        let (json, decimated) = data(&report_with(n, 123_457));
        assert_eq!(decimated, 2);
        let v: serde_json::Value = serde_json::from_str(&json.replace("<\\/", "</")).unwrap();
        let s = &v["plots"][0]["series"][0];
        let hi = s["hi"].as_array().unwrap();
        assert!(hi.len() <= MAX_POINTS, "{}", hi.len());
        assert_eq!(hi.iter().filter(|x| x.as_f64() == Some(77.0)).count(), 1);
        // Both series share one time array.
        assert_eq!(v["times"].as_array().unwrap().len(), 1);
        assert!(!json.contains("</script>"));
    }

    #[test]
    fn a_short_series_is_embedded_sample_by_sample() {
        let (json, decimated) = data(&report_with(1000, 10));
        assert_eq!(decimated, 0);
        let v: serde_json::Value = serde_json::from_str(&json.replace("<\\/", "</")).unwrap();
        let s = &v["plots"][0]["series"][0];
        assert!(s.get("hi").is_none());
        assert_eq!(s["lo"].as_array().unwrap().len(), 1000);
        assert_eq!(s["lo"][10], 77.0);
        let page = page(&report_with(1000, 10));
        assert!(page.contains("data-js-errors=\"0\"") && page.contains("window.onerror"));
        assert!(!page.contains("http://") || !page.contains("src=\"http"));
    }
}

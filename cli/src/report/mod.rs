//! The flight report: any log (ULog, DataFlash `.bin`, SPEC §10 CSV; one
//! or three IMUs) replayed through the UKF monitor (one per IMU, when the
//! log has aiding) and, for three IMUs, the parity monitor and the
//! PX4-like / ArduPilot-like baselines, drawn as one self-contained HTML
//! page ([`html`]) and standalone SVGs ([`svg`]).
//!
//! This module holds what is plotted; [`ukf`] and [`parity`] fill it from
//! the replays of `eval`, [`verdict`] says what the monitors concluded.

use serde::Serialize;

pub mod decimate;
pub mod html;
pub mod load;
pub mod parity;
pub mod svg;
pub mod ukf;
pub mod verdict;

/// Colours of the x, y, z axes (matplotlib's tab10, as the gallery).
pub const AXIS_COLORS: [&str; 3] = ["#d62728", "#2ca02c", "#1f77b4"];
/// Colours of IMU 0, 1, 2 where the three are drawn together.
pub const IMU_COLORS: [&str; 3] = ["#1f77b4", "#ff7f0e", "#9467bd"];

/// How a series is stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stroke {
    /// Solid line (min/max envelope per pixel column).
    Solid,
    /// Dashed (bounds such as ±3σ).
    Dashed,
}

/// One time series of a plot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// CSS colour.
    pub color: String,
    /// Stroke.
    pub stroke: Stroke,
    /// Sample times, s (ascending).
    pub t: Vec<f64>,
    /// Values in the plot's unit (NaN = gap).
    pub y: Vec<f64>,
}

impl Series {
    /// An empty series.
    pub fn new(name: impl Into<String>, color: &str, stroke: Stroke) -> Self {
        Self {
            name: name.into(),
            color: color.into(),
            stroke,
            t: Vec::new(),
            y: Vec::new(),
        }
    }

    /// Appends one sample.
    pub fn push(&mut self, t: f64, y: f64) {
        self.t.push(t);
        self.y.push(y);
    }
}

/// A time interval with a label (flag, alarm, status, phase).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Interval {
    /// Start, s.
    pub start_s: f64,
    /// End, s (the last sample in the state).
    pub end_s: f64,
    /// What held.
    pub label: String,
    /// CSS colour.
    pub color: String,
}

/// A vertical marker (isolation, first detection).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Marker {
    /// Time, s.
    pub t_s: f64,
    /// Text.
    pub label: String,
    /// CSS colour.
    pub color: String,
}

/// A horizontal line (threshold).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HLine {
    /// Value in the plot's unit.
    pub y: f64,
    /// Text.
    pub label: String,
}

/// One strip of flag bands above a plot (one per channel).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Strip {
    /// Strip name (channel).
    pub name: String,
    /// Intervals drawn in it.
    pub intervals: Vec<Interval>,
}

/// One plot: series against time, with threshold lines, markers and flag
/// strips.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plot {
    /// Identifier (file name of its SVG, HTML id).
    pub id: String,
    /// Title.
    pub title: String,
    /// Unit of the y axis.
    pub unit: String,
    /// Series.
    pub series: Vec<Series>,
    /// Threshold lines.
    pub hlines: Vec<HLine>,
    /// Vertical markers.
    pub markers: Vec<Marker>,
    /// Flag strips above the plot area.
    pub strips: Vec<Strip>,
}

impl Plot {
    /// An empty plot.
    pub fn new(id: impl Into<String>, title: impl Into<String>, unit: impl Into<String>) -> Self {
        Self {
            id: id.into(),
            title: title.into(),
            unit: unit.into(),
            series: Vec::new(),
            hlines: Vec::new(),
            markers: Vec::new(),
            strips: Vec::new(),
        }
    }

    /// Samples over all series.
    pub fn samples(&self) -> usize {
        self.series.iter().map(|s| s.t.len()).sum()
    }
}

/// The status timeline: one lane per monitor, sensor or baseline.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Timeline {
    /// Lanes, top to bottom.
    pub lanes: Vec<Strip>,
}

/// Builds [`Interval`]s from a per-sample state: consecutive samples with
/// the same `Some(label)` form one interval.
#[derive(Debug, Default)]
pub struct Runs {
    open: Option<Interval>,
    done: Vec<Interval>,
}

impl Runs {
    /// The state at `t` (`None`: nothing to draw).
    pub fn see(&mut self, t: f64, state: Option<(&str, &str)>) {
        match (&mut self.open, state) {
            (Some(o), Some((label, _))) if o.label == label => o.end_s = t,
            (open, state) => {
                if let Some(o) = open.take() {
                    self.done.push(o);
                }
                *open = state.map(|(label, color)| Interval {
                    start_s: t,
                    end_s: t,
                    label: label.into(),
                    color: color.into(),
                });
            }
        }
    }

    /// The intervals seen.
    pub fn finish(mut self) -> Vec<Interval> {
        if let Some(o) = self.open.take() {
            self.done.push(o);
        }
        self.done
    }
}

/// Everything the page shows.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct FlightReport {
    /// The log's file name.
    pub source: String,
    /// One line each: what was read and run.
    pub notes: Vec<String>,
    /// First and last time, s.
    pub span_s: (f64, f64),
    /// IMUs in the log.
    pub imus: usize,
    /// The verdict table.
    pub verdicts: Vec<verdict::Verdict>,
    /// The plots, top to bottom.
    pub plots: Vec<Plot>,
    /// Health statuses over time.
    pub timeline: Timeline,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_merge_equal_states_and_split_on_change() {
        let mut r = Runs::default();
        for (t, s) in [
            (0.0, None),
            (1.0, Some(("a", "red"))),
            (2.0, Some(("a", "red"))),
            (3.0, Some(("b", "blue"))),
            (4.0, None),
            (5.0, Some(("a", "red"))),
        ] {
            r.see(t, s);
        }
        let v = r.finish();
        let got: Vec<(f64, f64, &str)> = v
            .iter()
            .map(|i| (i.start_s, i.end_s, i.label.as_str()))
            .collect();
        assert_eq!(got, [(1.0, 2.0, "a"), (3.0, 3.0, "b"), (5.0, 5.0, "a")]);
    }
}

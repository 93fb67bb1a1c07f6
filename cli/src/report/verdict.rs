//! The verdict table at the top of the report: for each IMU channel and
//! each monitor, healthy / faulty / not judged, since when and why.

use serde::Serialize;

/// What a monitor concluded about one channel over the whole log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum State {
    /// Monitored and never flagged.
    Healthy,
    /// Flagged, isolated or failed at least once.
    Faulty,
    /// The monitor could not judge it (no aiding, too few IMUs, never out
    /// of training, or no aiding observes the channel).
    NotJudged,
}

impl State {
    /// Text of the table cell.
    pub fn text(self) -> &'static str {
        match self {
            Self::Healthy => "healthy",
            Self::Faulty => "faulty",
            Self::NotJudged => "not judged",
        }
    }
}

/// One row of the verdict table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// IMU index.
    pub imu: usize,
    /// Channel: `ax`, `ay`, `az`, `gx`, `gy`, `gz` (the SPEC §10 column names).
    pub channel: String,
    /// `ukf` (innovation monitor) or `parity` (redundant IMUs).
    pub monitor: String,
    /// The conclusion.
    pub state: State,
    /// Healthy: monitored from; faulty: first flagged; not judged: none.
    pub since_s: Option<f64>,
    /// Why, in one sentence with units.
    pub why: String,
}

/// Channel names of the table, in the order `[ax … gz]`.
pub const CHANNELS: [&str; 6] = ["ax", "ay", "az", "gx", "gy", "gz"];

/// Six "not judged" rows for IMU `imu` and `monitor`, all with `why`.
pub fn not_judged(imu: usize, monitor: &str, why: &str) -> Vec<Verdict> {
    CHANNELS
        .iter()
        .map(|c| Verdict {
            imu,
            channel: (*c).into(),
            monitor: monitor.into(),
            state: State::NotJudged,
            since_s: None,
            why: why.into(),
        })
        .collect()
}

/// Counts per state, for the headline.
pub fn counts(v: &[Verdict]) -> [usize; 3] {
    let n = |s: State| v.iter().filter(|x| x.state == s).count();
    [n(State::Healthy), n(State::Faulty), n(State::NotJudged)]
}

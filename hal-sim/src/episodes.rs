//! Fault-episode campaigns (issue 15): one run holds a step and a ramp on
//! every one of the six channels, in random order and sign, separated by
//! healthy stretches, so a single run measures detection, delay *and* what
//! the monitor does after each fault clears (the false-alarm cascades a
//! one-fault-per-run campaign cannot see).
//!
//! Episode `k` of a run: onset after a healthy gap drawn uniformly in
//! `[gap_s.0, gap_s.1]`, length `len_s`. A step (\[UKF\] E1) has size `a`, a
//! ramp (E2) grows at `b` from onset. An episode counts as detected when its
//! channel is flagged with the fault's sign while it is active; its delay is
//! from onset to that flag. After it clears, `settle_s` is allowed for the
//! windows to flush; every rising edge of "any channel flagged" from then
//! until the next onset is a *post-clear* false-alarm event.

use imu_fdi::monitor::Phase;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::fault::{FaultKind, FaultRow};
use crate::runner::Trace;
use crate::scenario::Scenario;

/// How episodes are laid out in a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodePlan {
    /// First onset not before this time, s (after converging and learning).
    pub first_onset_s: f64,
    /// Healthy gap before each episode, uniform in `[lo, hi]`, s.
    pub gap_s: (f64, f64),
    /// Episode length, s.
    pub len_s: f64,
    /// Allowed settle after a fault clears, s.
    pub settle_s: f64,
}

impl Default for EpisodePlan {
    /// 12 episodes of 8 s from 20 s, gaps of 15–25 s, 5 s settle (the
    /// issue's allowance): ≈ 360 s per run.
    fn default() -> Self {
        Self {
            first_onset_s: 20.0,
            gap_s: (15.0, 25.0),
            len_s: 8.0,
            settle_s: 5.0,
        }
    }
}

/// `base` with its fault table replaced by a step and a ramp on every
/// channel (12 rows), random order and signs from `seed`; the duration is
/// set to end one gap after the last episode.
pub fn episode_scenario(base: &Scenario, seed: u64, plan: &EpisodePlan) -> Scenario {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6570_6973);
    let mut order: [(usize, FaultKind); 12] =
        core::array::from_fn(|k| (k % 6, if k < 6 { FaultKind::E1 } else { FaultKind::E2 }));
    // Fisher–Yates.
    for i in (1..order.len()).rev() {
        let j = rng.random_range(0..=i);
        order.swap(i, j);
    }
    let mut scn = base.clone();
    scn.faults.clear();
    let mut t = plan.first_onset_s - plan.gap_s.0;
    for (channel, kind) in order {
        t += rng.random_range(plan.gap_s.0..=plan.gap_s.1);
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let _ = scn.faults.push(FaultRow {
            channel,
            start: t,
            end: t + plan.len_s,
            kind,
            sign,
        });
        t += plan.len_s;
    }
    scn.duration_s = t + plan.gap_s.1;
    scn
}

/// What one episode gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeOutcome {
    /// The injected fault.
    pub fault: FaultRow,
    /// Onset to the first flag of the right channel and sign, s.
    pub delay_s: Option<f64>,
    /// Rising edges of "any channel flagged" inside the settle allowance.
    pub settle_events: usize,
    /// Rising edges from the end of the settle allowance to the next onset
    /// (or the end of the run).
    pub post_clear_events: usize,
    /// Healthy monitored time counted for `post_clear_events`, s.
    pub post_clear_s: f64,
}

/// Scores every episode of a run (`trace.scenario` as built by
/// [`episode_scenario`]).
pub fn score(trace: &Trace, plan: &EpisodePlan) -> Vec<EpisodeOutcome> {
    let faults = &trace.scenario.faults;
    let flagged = |r: &crate::runner::TraceRow| {
        r.phase == Phase::Monitoring && r.flag.iter().any(|f| f.is_some_and(|v| v != 0))
    };
    let mut out = Vec::with_capacity(faults.len());
    for (k, f) in faults.iter().enumerate() {
        let next = faults
            .get(k + 1)
            .map_or(trace.scenario.duration_s, |n| n.start);
        let settled = f.end + plan.settle_s;
        let mut o = EpisodeOutcome {
            fault: *f,
            delay_s: None,
            settle_events: 0,
            post_clear_events: 0,
            post_clear_s: 0.0,
        };
        let mut prev = false;
        let mut last_t = None;
        for r in trace.rows.iter().filter(|r| r.t >= f.start && r.t < next) {
            let now = flagged(r);
            if f.active(r.t) {
                let want = if f.sign > 0.0 { 1 } else { -1 };
                if o.delay_s.is_none() && r.flag.get(f.channel).copied().flatten() == Some(want) {
                    o.delay_s = Some(r.t - f.start);
                }
            } else if r.t < settled {
                o.settle_events += usize::from(now && !prev);
            } else {
                // A flag still up from the settle time counts once more
                // here: the monitor had not returned to nominal.
                let edge = now && (!prev || last_t.is_none_or(|t: f64| t < settled));
                o.post_clear_events += usize::from(edge);
                if let Some(t0) = last_t.filter(|t: &f64| *t >= settled) {
                    o.post_clear_s += r.t - t0;
                }
            }
            prev = now;
            last_t = Some(r.t);
        }
        out.push(o);
    }
    out
}

/// Totals over episodes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EpisodeTotals {
    /// Episodes run.
    pub episodes: usize,
    /// Of those, detected.
    pub detected: usize,
    /// Median delay of the detected steps, s (NaN if none).
    pub step_delay_median_s: f64,
    /// Largest delay of the detected steps, s.
    pub step_delay_max_s: f64,
    /// Median delay of the detected accelerometer / gyro steps, s.
    pub step_delay_median_by_kind_s: [f64; 2],
    /// Median delay of the detected ramps, s.
    pub ramp_delay_median_s: f64,
    /// Flag rising edges inside the settle allowances.
    pub settle_events: usize,
    /// Post-clear false-alarm events.
    pub post_clear_events: usize,
    /// Healthy time after the settle allowances, s.
    pub post_clear_s: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

impl EpisodeTotals {
    /// Sums `outcomes`.
    pub fn of(outcomes: &[EpisodeOutcome]) -> Self {
        let delays_on = |k: FaultKind, chans: core::ops::Range<usize>| -> Vec<f64> {
            outcomes
                .iter()
                .filter(|o| o.fault.kind == k && chans.contains(&o.fault.channel))
                .filter_map(|o| o.delay_s)
                .collect()
        };
        let delays = |k: FaultKind| delays_on(k, 0..6);
        let steps = delays(FaultKind::E1);
        Self {
            episodes: outcomes.len(),
            detected: outcomes.iter().filter(|o| o.delay_s.is_some()).count(),
            step_delay_max_s: steps.iter().copied().fold(0.0, f64::max),
            step_delay_median_s: median(steps),
            step_delay_median_by_kind_s: [
                median(delays_on(FaultKind::E1, 0..3)),
                median(delays_on(FaultKind::E1, 3..6)),
            ],
            ramp_delay_median_s: median(delays(FaultKind::E2)),
            settle_events: outcomes.iter().map(|o| o.settle_events).sum(),
            post_clear_events: outcomes.iter().map(|o| o.post_clear_events).sum(),
            post_clear_s: outcomes.iter().map(|o| o.post_clear_s).sum(),
        }
    }

    /// One line: `detected d/n, step delay median/max, ramp median, settle
    /// and post-clear events`.
    pub fn line(&self) -> String {
        format!(
            "episodes {}/{} detected ({:.1} %), step delay median {:.2} s (accel {:.2} s, gyro {:.2} s, max {:.2} s), ramp delay median {:.2} s, flag events within settle {}, post-clear false-alarm events {} in {:.2} h",
            self.detected,
            self.episodes,
            100.0 * self.detected as f64 / self.episodes.max(1) as f64,
            self.step_delay_median_s,
            self.step_delay_median_by_kind_s[0],
            self.step_delay_median_by_kind_s[1],
            self.step_delay_max_s,
            self.ramp_delay_median_s,
            self.settle_events,
            self.post_clear_events,
            self.post_clear_s / 3600.0
        )
    }
}

//! Re-admission of a sensor isolated by the multi-scale tests, once its
//! error has decayed ("never stuck": a shock or a bus hiccup that passes
//! the hardware checks must not cost the board its redundancy for good).
//!
//! **The statistic.** At the isolation the full set's parity space and
//! multi-scale tests — the relative calibration, the block and window
//! covariances, the vibration law and the thresholds, all learned on the
//! healthy flight before it — are kept as a *shadow*, their window emptied
//! (it held the fault). Every block the shadow is fed the full set's block
//! means (the isolated sensor's samples go on being read and checked, never
//! fused) and decides exactly as the monitor would with the sensor back:
//! the same GLR scores against the same thresholds, so a score below
//! threshold on every window length is the tests' own "consistent", at
//! their false-alarm probability, with no margin set by hand. Its alarms
//! act on nothing but the probation.
//!
//! The shadow learns under the tests' own gate (a block is learned only
//! after a whole longest window of decisions below `learn_below` of their
//! thresholds, `multiscale::staged`), as the monitor does for the sensors
//! in the set: a fault large enough to be detected holds its scores above
//! the gate and is never learned, while the calibration keeps tracking the
//! slow relative drift. Frozen at the isolation instead, it aged: on
//! log171 (training from 100 s) a 15-s 0.5 m/s² a_z step isolated at
//! 197.5 s was re-admitted at 232.4 s with a 35-s-old calibration that
//! alarmed on IMU2 a_z at 237.7 s, two new false alarms in the 0.5 m/s²
//! table (493/0 → 491/2); learning, 493/0.
//!
//! **The rule.** Decisions count once every window length has a score (the
//! longest window, 10 s by default, filled with blocks after the
//! isolation). The sensor is re-admitted after `2 × longest` consecutive
//! such decisions (20 s by default) with every score, on every window length
//! and every sensor hypothesis, and the gross test, below its threshold —
//! two disjoint longest windows judged quiet, so an error that comes back
//! within a longest window is seen by every window length before the
//! sensor is; any decision above threshold, or a sample of the sensor
//! missing or unusable, restarts the count. A sensor
//! isolated again after a re-admission has its probation doubled each time;
//! at its [`MAX_ISOLATIONS`]-th isolation it stays out until reset
//! (an intermittent sensor: the alarm chatter is bounded to that many
//! isolations).
//!
//! **Re-admission** restores the shadow as the monitor's tests: the full
//! space and its learning (not retrained), with the window of the probation
//! blocks, so the tests go on exactly where the shadow's decisions were.
//! What the reduced set learned meanwhile is dropped.
//!
//! **Limits.** One sensor is judged at a time: a second isolation, or a
//! hardware failure of any sensor, while one is out ends its judging (the
//! shadow's space holds the sensor that just left), and it stays isolated
//! until reset. Isolations by an external verdict (the rest check) and the
//! white-noise tests' isolations stay latched until reset. Hardware
//! failures keep their latch-until-reset policy, also when they occur on a
//! sensor under judgement.

use nalgebra::{SVector, Vector3};

use crate::math::Real;

use super::super::multiscale::{Multiscale, Outcome, REGRESSORS};
use super::super::ParitySpace;
use super::flight::BlockSums;
use super::{ParityMonitor, Reconfig};

/// Parity isolations of one sensor after which it is no longer judged for
/// re-admission (it stays out until reset).
pub const MAX_ISOLATIONS: u8 = 3;

/// The full set's tests, kept at an isolation, judging the isolated
/// sensor.
#[derive(Debug, Clone)]
pub(super) struct Shadow<T: Real, const N: usize, const W: usize> {
    /// The sensor judged.
    sensor: usize,
    /// The full set's parity space.
    space: ParitySpace<T, N>,
    /// Its tests (alarms act only on the probation).
    ms: Multiscale<T, N, W>,
    /// Block before (`p̄`, `x̄`, per-sensor variance) and the fused mean
    /// before it, in the full space (the centred-difference regressor).
    prev: Option<(SVector<T, N>, Vector3<T>, SVector<T, N>)>,
    prev2: Option<Vector3<T>>,
    /// A sample of the sensor was unusable in the block being accumulated.
    pub(super) gap: bool,
    /// Consecutive counting decisions below threshold.
    quiet: u32,
    /// Decisions the probation needs.
    needed: u32,
}

/// Re-admission state of the monitor.
#[derive(Debug, Clone)]
pub(super) struct Readmission<T: Real, const N: usize, const W: usize> {
    pub(super) shadow: Option<Shadow<T, N, W>>,
    /// Parity isolations of each sensor since reset.
    isolations: [u8; N],
}

impl<T: Real, const N: usize, const W: usize> Default for Readmission<T, N, W> {
    fn default() -> Self {
        Self {
            shadow: None,
            isolations: [0; N],
        }
    }
}

impl<T: Real, const N: usize, const W: usize> Readmission<T, N, W> {
    /// The sensor judged, if any.
    pub(super) fn sensor(&self) -> Option<usize> {
        self.shadow.as_ref().map(|s| s.sensor)
    }
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// Called before sensor `k` is excluded by the multi-scale tests: keeps
    /// the full set's tests to judge it (unless it reached
    /// [`MAX_ISOLATIONS`]). Another sensor judged meanwhile stays out.
    pub(super) fn start_shadow(&mut self, k: usize) {
        self.drop_shadow();
        let Some(count) = self.readmission.isolations.get_mut(k) else {
            return;
        };
        *count = count.saturating_add(1);
        let count = *count;
        let Some(ms) = self.ms.as_ref().filter(|_| self.ms_trained) else {
            return;
        };
        if count >= MAX_ISOLATIONS {
            return;
        }
        let mut ms = *ms;
        ms.cancel();
        ms.clear_window();
        let needed = (2 * u32::from(ms.longest())) << count.saturating_sub(1);
        self.readmission.shadow = Some(Shadow {
            sensor: k,
            space: self.space,
            ms,
            prev: self.ms_prev,
            prev2: self.ms_prev2,
            gap: false,
            quiet: 0,
            needed,
        });
    }

    /// Ends the judging of the sensor under probation (it stays isolated).
    pub(super) fn drop_shadow(&mut self) {
        if let Some(sh) = self.readmission.shadow.take() {
            if let Some(h) = self.health.get_mut(sh.sensor) {
                h.set_probation(false);
            }
        }
    }

    /// A complete block (`mean`: the sensors' block means, `e` their
    /// variances) into the shadow: finishes its previous decision and
    /// starts this block's predecessor, as the monitor does.
    pub(super) fn shadow_block(&mut self, mean: &SVector<T, N>, e: &SVector<T, N>) {
        let Some(sh) = self.readmission.shadow.as_mut() else {
            return;
        };
        let failed = self.health.get(sh.sensor).and_then(|h| h.failure());
        if !failed.is_some_and(|s| s.is_parity_out()) {
            // A hardware failure latched over the isolation (or the
            // sensor is back by another way): no more judging.
            self.readmission.shadow = None;
            return;
        }
        if sh.ms.pending().is_some() {
            let o = sh.ms.finish(sh.space.v(), sh.space.active());
            self.shadow_outcome(o);
        }
        let Some(sh) = self.readmission.shadow.as_mut() else {
            return;
        };
        if core::mem::take(&mut sh.gap) {
            // The block lacks samples of the sensor: not judged, and the
            // probation starts again.
            sh.quiet = 0;
            sh.prev = None;
            sh.prev2 = None;
            if let Some(h) = self.health.get_mut(sh.sensor) {
                h.set_probation(false);
            }
            return;
        }
        let (p, x) = (sh.space.v() * mean, sh.space.lsq() * mean);
        if let (Some((p_prev, x_prev, e_prev)), Some(x_before)) = (sh.prev, sh.prev2) {
            let dx = (x - x_before) * T::lit(0.5);
            let phi: SVector<T, REGRESSORS> = sh.ms.regressor(&x_prev, &dx, &e_prev);
            let level = e_prev.sum().max(T::zero()).sqrt();
            sh.ms.begin(&p_prev, &phi, level, None);
        }
        sh.prev2 = sh.prev.map(|(_, x, _)| x);
        sh.prev = Some((p, x, *e));
    }

    /// One stage of the shadow's decision in work; a re-admission when
    /// its probation is complete and the monitor is between stages.
    /// Out of line: most steps have no shadow.
    #[inline(never)]
    pub(super) fn shadow_step(&mut self) {
        let Some(sh) = self.readmission.shadow.as_mut() else {
            return;
        };
        if sh.ms.pending().is_some() {
            let o = sh.ms.advance(sh.space.v(), sh.space.active());
            self.shadow_outcome(o);
        }
        let ready = self
            .readmission
            .shadow
            .as_ref()
            .is_some_and(|sh| sh.quiet >= sh.needed);
        let idle = self.configured() && self.ms.as_ref().is_none_or(|ms| ms.pending().is_none());
        if ready && idle {
            self.readmit();
        }
    }

    /// Applies a shadow decision to the probation count.
    fn shadow_outcome(&mut self, o: Outcome<T>) {
        let Some(sh) = self.readmission.shadow.as_mut() else {
            return;
        };
        let quiet = match o {
            Outcome::Busy | Outcome::Trained(_) => return,
            // Decisions count once every window length has a score.
            Outcome::Decided(Some(d)) if !sh.ms.windows_full() => {
                if d.ratio <= T::one() {
                    return;
                }
                false
            }
            Outcome::Decided(Some(d)) => d.ratio <= T::one(),
            Outcome::Decided(None) => false,
        };
        sh.quiet = if quiet { sh.quiet.saturating_add(1) } else { 0 };
        if let Some(h) = self.health.get_mut(sh.sensor) {
            h.set_probation(sh.quiet > 0);
        }
    }

    /// Puts the judged sensor back into the set with the shadow's tests.
    fn readmit(&mut self) {
        let Some(sh) = self.readmission.shadow.take() else {
            return;
        };
        let k = sh.sensor;
        if !self.health.get_mut(k).is_some_and(|h| h.readmit()) {
            return;
        }
        if let Some(r) = self.removed.get_mut(k) {
            *r = false;
        }
        self.ms = Some(sh.ms);
        self.reconfig = Reconfig::Idle;
        self.space = sh.space;
        self.ms_prev = sh.prev;
        self.ms_prev2 = sh.prev2;
        // The block being accumulated, into the full space (its sums are
        // linear in the samples, which include the sensor's).
        let block = self.ms_block;
        if let Some(m0) = block.m0() {
            let sum_m = m0 * T::lit(f64::from(block.len())) + block.m_sum();
            self.ms_block = block.with_projection(self.space.v() * sum_m, self.space.lsq() * sum_m);
        } else {
            self.ms_block = BlockSums::default();
        }
        self.ms_hold = 0;
        self.ms_above = 0;
        self.suspect_run = (None, 0);
        self.last.readmitted = Some(k);
    }
}

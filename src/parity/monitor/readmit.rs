//! Re-admission of a sensor isolated by the multi-scale tests once its
//! error has decayed, or excluded by a hardware failure once its output is
//! back ("never stuck": a shock or a bus hiccup must not cost the board its
//! redundancy for good).
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
//! The calibration it starts from is not the current one but the one of
//! one to two longest windows before the isolation (`Multiscale` keeps one
//! every longest window): a fault's first blocks are decided before any
//! score rises and are learned into the current calibration. On log171 a
//! 1-s 5 m/s² glitch learned that way hid the next glitches on the same
//! sensor after its re-admission (never alarmed, where a fresh monitor
//! isolates them); from the older calibration they are isolated as by a
//! fresh monitor (`cli/tests/parity_log171.rs`).
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
//! **Hardware failures** (issue 14, "never stuck"): a sensor whose
//! hardware check latched (frozen, silent, invalid output, railed) is
//! judged the same way once its output is good again
//! (`SensorHealth::resume`): the shadow is kept when it is excluded, its
//! blocks are not judged while the failure lasts, and from the first good
//! sample it is out of the set as an isolation, on probation and
//! re-admitted as above. The sensors that failed in the same period (a
//! frozen or silent IMU fails on all its axes at once) are judged and
//! re-admitted together, each with its own isolation count. On log171 an
//! IMU frozen for 15 s, or silent for 3 s, is back 29.5 s after its output
//! (`cli/tests/parity_hardware_log171.rs`); one that stays frozen stays out.
//!
//! **Limits.** One group is judged at a time: a second isolation, or a
//! hardware failure of another sensor, while some are out ends their
//! judging (the shadow's space holds the sensor that just left), and they
//! stay out until reset. Isolations by an external verdict (the rest
//! check) and the white-noise tests' isolations and hardware failures stay
//! latched until reset.

use nalgebra::{SVector, Vector3};

use crate::math::Real;

use super::super::multiscale::{Outcome, REGRESSORS};
use super::super::{ParitySpace, SensorHealth, SensorStatus};
use super::flight::BlockSums;
use super::{ParityMonitor, Reconfig};

/// Parity isolations of one sensor after which it is no longer judged for
/// re-admission (it stays out until reset).
pub const MAX_ISOLATIONS: u8 = 3;

/// Re-admission state of the monitor: the full set's tests kept at an
/// isolation (the shadow), judging the isolated sensor.
///
/// The shadow's tests are the idle slot of the monitor's `TestSlots`,
/// always there and written in place (the monitor's learning copied into
/// it at the isolation; made the live slot at the re-admission, nothing
/// moved): a `Multiscale` moved through an `Option` on the stack is
/// ≈ 20 KB per copy on the M4F.
#[derive(Debug, Clone)]
pub(super) struct Readmission<T: Real, const N: usize> {
    /// The sensors judged, one bit each (none: no shadow; the fields below
    /// are unused): the isolated one, or those whose hardware checks failed
    /// in the same period (one IMU's axes), judged and re-admitted
    /// together. A mask, not `[bool; N]`: a pass over N flags every step
    /// cost the M4F ≈ 50 instructions per step. Sensors from the 33rd on
    /// are never judged (they stay out until reset).
    judged: u32,
    /// The full set's parity space (its tests, the shadow slot, act only
    /// on the probation).
    space: ParitySpace<T, N>,
    /// The monitor's learning is still to be copied into the shadow: at the
    /// reconfiguration stage after the reduced space (`Reconfig::Shadow`),
    /// not in the isolating step (≈ 3.5 KB with nine sensors, which took
    /// that step over its budget). Until the learning is carried into the
    /// new space nothing else writes it, so the copy is the same.
    copy: bool,
    /// Block before (`p̄`, `x̄`, per-sensor variance) and the fused mean
    /// before it, in the full space (the centred-difference regressor).
    prev: Option<(SVector<T, N>, Vector3<T>, SVector<T, N>)>,
    prev2: Option<Vector3<T>>,
    /// A sample of the sensor was unusable in the block being accumulated.
    gap: bool,
    /// Consecutive counting decisions below threshold.
    quiet: u32,
    /// Decisions the probation needs.
    needed: u32,
    /// Parity isolations of each sensor since reset.
    isolations: [u8; N],
}

impl<T: Real, const N: usize> Readmission<T, N> {
    /// No sensor judged; `space` only fills the idle storage.
    pub(super) fn new(space: ParitySpace<T, N>) -> Self {
        Self {
            judged: 0,
            space,
            copy: false,
            prev: None,
            prev2: None,
            gap: false,
            quiet: 0,
            needed: 0,
            isolations: [0; N],
        }
    }

    /// Some sensor is judged.
    pub(super) fn judging(&self) -> bool {
        self.judged != 0
    }

    /// Times sensor `k` left the set (parity isolations and hardware
    /// failures) since reset; [`MAX_ISOLATIONS`] ends its way back.
    pub(super) fn times_out(&self, k: usize) -> u8 {
        self.isolations.get(k).copied().unwrap_or(u8::MAX)
    }

    /// Sensor `k` is judged.
    pub(super) fn judges(&self, k: usize) -> bool {
        bit(k) & self.judged != 0
    }

    /// The sensors judged.
    fn judged(&self) -> impl Iterator<Item = usize> {
        sensors(self.judged)
    }

    /// The monitor's learning is still to be copied into the shadow.
    pub(super) fn copy_pending(&self) -> bool {
        self.copy
    }
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// Called before sensor `k` is excluded by the multi-scale tests: keeps
    /// the full set's tests to judge it (unless it reached
    /// [`MAX_ISOLATIONS`]). Another sensor judged meanwhile stays out.
    /// What the isolation's reconfiguration resets (the space, the blocks
    /// before) is kept now; the learning is copied at the reconfiguration
    /// stage after the reduced space ([`copy_shadow`](Self::copy_shadow)).
    pub(super) fn start_shadow(&mut self, k: usize) {
        // A reconfiguration still in progress ends first: its own copy
        // stage must not take this isolation's.
        self.advance_reconfig(true);
        self.drop_shadow();
        let Some(count) = self.readmission.isolations.get_mut(k) else {
            return;
        };
        *count = count.saturating_add(1);
        let count = *count;
        let r = &mut self.readmission;
        let Some(ms) = self.ms.live().filter(|_| self.ms_trained) else {
            return;
        };
        if count >= MAX_ISOLATIONS {
            return;
        }
        r.copy = true;
        r.needed = (2 * u32::from(ms.longest())) << count.saturating_sub(1);
        r.judged = bit(k);
        r.space = self.space;
        r.prev = self.ms_prev;
        r.prev2 = self.ms_prev2;
        r.gap = false;
        r.quiet = 0;
    }

    /// Excludes the sensors whose hardware checks failed this period;
    /// with the multi-scale tests they are judged together for
    /// re-admission once their output is good again, as after a parity
    /// isolation (a frozen or silent IMU fails on all its axes at once).
    /// Out of line: rare.
    #[inline(never)]
    pub(super) fn exclude_failed(&mut self, failed: &[bool; N]) {
        let mut first = true;
        for k in (0..N).filter(|k| failed.get(*k) == Some(&true)) {
            if self.ms.is_some() {
                if first {
                    self.start_shadow(k);
                } else {
                    self.judge_also(k);
                }
            }
            first = false;
        }
        for k in (0..N).filter(|k| failed.get(*k) == Some(&true)) {
            self.exclude(k);
        }
    }

    /// Adds sensor `k` to the sensors judged by a shadow started in this
    /// period (its learning not yet copied: still the full set's), with its
    /// own isolation count.
    fn judge_also(&mut self, k: usize) {
        let longest = self.ms.live().map_or(0, |ms| u32::from(ms.longest()));
        let r = &mut self.readmission;
        let Some(count) = r.isolations.get_mut(k) else {
            return;
        };
        *count = count.saturating_add(1);
        if !r.copy || *count >= MAX_ISOLATIONS {
            return;
        }
        r.judged |= bit(k);
        r.needed = r.needed.max((2 * longest) << count.saturating_sub(1));
    }

    /// The monitor's learning into the shadow, if still to be copied: a
    /// reconfiguration stage of its own, before the learning is carried
    /// into the reduced space. Out of line: inlined into the
    /// reconfiguration stages, it cost each of them ≈ 60 instructions.
    #[inline(never)]
    pub(super) fn copy_shadow(&mut self) {
        let r = &mut self.readmission;
        if !core::mem::take(&mut r.copy) || !r.judging() {
            return;
        }
        if let Some((ms, shadow)) = self.ms.split_mut() {
            shadow.copy_learning_from(ms);
        }
    }

    /// Ends the judging of the sensors under probation (they stay out).
    pub(super) fn drop_shadow(&mut self) {
        self.readmission.copy = false;
        for k in sensors(core::mem::take(&mut self.readmission.judged)) {
            if let Some(h) = self.health.get_mut(k) {
                h.set_probation(false);
            }
        }
    }

    /// A complete block (`mean`: the sensors' block means, `e` their
    /// variances) into the shadow: finishes its previous decision and
    /// starts this block's predecessor, as the monitor does.
    pub(super) fn shadow_block(&mut self, mean: &SVector<T, N>, e: &SVector<T, N>) {
        if !self.readmission.judging() {
            return;
        }
        let failures = self
            .readmission
            .judged()
            .map(|k| self.health.get(k).and_then(|h| h.failure()));
        let (mut back, mut hardware) = (false, false);
        for f in failures {
            back |= f.is_none();
            hardware |= f.is_some_and(|s| !s.is_parity_out());
        }
        if back {
            self.drop_shadow();
            return;
        }
        if hardware {
            // A hardware failure (at the exclusion or latched over the
            // isolation): the block is not judged, the probation starts
            // again once the output is good (`SensorHealth::resume`).
            self.readmission.gap = true;
        }
        // A block closed before the copy stage (it runs first, then the
        // learning is carried: the copy is still the isolation's).
        self.copy_shadow();
        let Some(sh) = self.ms.shadow_mut() else {
            return;
        };
        let r = &mut self.readmission;
        if sh.pending().is_some() {
            let o = sh.finish(r.space.v(), r.space.active());
            self.shadow_outcome(o);
        }
        let r = &mut self.readmission;
        if core::mem::take(&mut r.gap) {
            // The block lacks samples of the sensor: not judged, and the
            // probation starts again.
            r.quiet = 0;
            r.prev = None;
            r.prev2 = None;
            self.set_probation(false);
            return;
        }
        let (p, x) = (r.space.v() * mean, r.space.lsq() * mean);
        if let (Some((p_prev, x_prev, e_prev)), Some(x_before), Some(sh)) =
            (r.prev, r.prev2, self.ms.shadow_mut())
        {
            let dx = (x - x_before) * T::lit(0.5);
            let phi: SVector<T, REGRESSORS> = sh.regressor(&x_prev, &dx, &e_prev);
            let level = e_prev.sum().max(T::zero()).sqrt();
            sh.begin(&p_prev, &phi, level, None);
        }
        r.prev2 = r.prev.map(|(_, x, _)| x);
        r.prev = Some((p, x, *e));
    }

    /// One stage of the shadow's decision in work; a re-admission when
    /// its probation is complete and the monitor is between stages.
    /// The judged sensor's sample (read and checked, never fused) goes
    /// into `m` for the block sums; an unusable one marks the block.
    /// Out of line: most steps have no shadow.
    #[inline(never)]
    pub(super) fn shadow_step(&mut self, m: &mut SVector<T, N>) {
        for k in sensors(self.readmission.judged) {
            // A hardware failure whose output is good again: judged from
            // this sample on.
            if let Some(h) = self.health.get_mut(k) {
                h.resume();
            }
            match (
                self.health.get(k).and_then(SensorHealth::out_sample),
                m.get_mut(k),
            ) {
                (Some(v), Some(slot)) => *slot = v,
                _ => self.readmission.gap = true,
            }
        }
        let r = &mut self.readmission;
        // Before the copy the shadow's tests are stale; the copy has
        // nothing in work.
        if let Some(sh) = self.ms.shadow_mut() {
            if !r.copy && sh.pending().is_some() {
                let o = sh.advance(r.space.v(), r.space.active());
                self.shadow_outcome(o);
            }
        }
        let r = &self.readmission;
        let ready = r.judging() && r.quiet >= r.needed;
        let idle = self.configured() && self.ms.live().is_none_or(|ms| ms.pending().is_none());
        if ready && idle {
            self.readmit();
        }
    }

    /// Applies a shadow decision to the probation count.
    fn shadow_outcome(&mut self, o: Outcome<T>) {
        let full = self.ms.shadow().is_some_and(|ms| ms.windows_full());
        let r = &mut self.readmission;
        if !r.judging() {
            return;
        }
        let quiet = match o {
            Outcome::Busy | Outcome::Trained(_) => return,
            // Decisions count once every window length has a score.
            Outcome::Decided(Some(d)) if !full => {
                if d.ratio <= T::one() {
                    return;
                }
                false
            }
            Outcome::Decided(Some(d)) => d.ratio <= T::one(),
            Outcome::Decided(None) => false,
        };
        r.quiet = if quiet { r.quiet.saturating_add(1) } else { 0 };
        let on = r.quiet > 0;
        self.set_probation(on);
    }

    /// The judged sensors on probation (`true`) or back to isolated.
    fn set_probation(&mut self, on: bool) {
        for k in sensors(self.readmission.judged) {
            if let Some(h) = self.health.get_mut(k) {
                h.set_probation(on);
            }
        }
    }

    /// Puts the judged sensor back into the set with the shadow's tests
    /// (their slot made the live one, nothing moved; the reduced set's
    /// tests are dropped).
    fn readmit(&mut self) {
        let r = &self.readmission;
        let out = r.judged().all(|k| {
            self.health
                .get(k)
                .and_then(SensorHealth::failure)
                .is_some_and(SensorStatus::is_parity_out)
        });
        let first = r.judged().next();
        let judged = core::mem::take(&mut self.readmission.judged);
        if !out || !self.ms.is_some() {
            return;
        }
        for k in sensors(judged) {
            if let (Some(h), Some(r)) = (self.health.get_mut(k), self.removed.get_mut(k)) {
                h.readmit();
                *r = false;
            }
        }
        self.ms.flip();
        self.reconfig = Reconfig::Idle;
        self.space = self.readmission.space;
        self.ms_prev = self.readmission.prev;
        self.ms_prev2 = self.readmission.prev2;
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
        self.last.readmitted = first;
    }
}

/// Marks sensor `k` in a set of sensors.
pub(super) fn mark<const N: usize>(mask: &mut [bool; N], k: usize) {
    if let Some(b) = mask.get_mut(k) {
        *b = true;
    }
}

/// Sensor `k`'s bit in a mask of judged sensors (none from the 33rd on).
fn bit(k: usize) -> u32 {
    u32::try_from(k)
        .ok()
        .and_then(|b| 1u32.checked_shl(b))
        .unwrap_or(0)
}

/// The sensors of a mask, lowest first.
fn sensors(mut mask: u32) -> impl Iterator<Item = usize> {
    core::iter::from_fn(move || {
        let k = usize::try_from(mask.trailing_zeros())
            .ok()
            .filter(|_| mask != 0)?;
        mask &= mask.wrapping_sub(1);
        Some(k)
    })
}

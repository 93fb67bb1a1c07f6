//! A sensor whose hardware check failed while the multi-scale tests were
//! still training, and whose output is good again, rejoins the set and
//! training starts over with it (issue 14, "never stuck"). While
//! monitoring, such a sensor is judged for re-admission against the full
//! set's tests (`readmit.rs`); during training there are no tests to judge
//! it by, so the only way back is to learn the full set again. Bounded as
//! the re-admissions are: the failures count towards
//! [`MAX_ISOLATIONS`](super::MAX_ISOLATIONS), and the sensor that reaches it
//! stays out (a sensor that keeps failing would otherwise restart
//! training for ever).

use crate::math::Real;

use super::super::multiscale::Multiscale;
use super::super::ParitySpace;
use super::flight::BlockSums;
use super::readmit::MAX_ISOLATIONS;
use super::{ParityMonitor, ParityPhase};

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// True while the multi-scale tests train with a sensor out of the set
    /// by a hardware failure (the only case [`retrain_if_resumed`] acts
    /// on): one comparison per step otherwise.
    ///
    /// [`retrain_if_resumed`]: Self::retrain_if_resumed
    #[inline]
    pub(super) fn training_without_some(&self) -> bool {
        self.ms.is_some()
            && !self.ms_trained
            && self.phase == ParityPhase::Training
            && self.removed.contains(&true)
    }

    /// Brings back, while training, every sensor whose hardware failure
    /// ended this period (its sample passed the checks) and that has not
    /// failed [`MAX_ISOLATIONS`] times, and restarts training on the set
    /// it makes. Out of line: rare.
    #[inline(never)]
    pub(super) fn retrain_if_resumed(&mut self) {
        if !self.configured() {
            // The failure's own reconfiguration first (next steps).
            return;
        }
        let mut back = false;
        for k in 0..N {
            let count = self.readmission.times_out(k);
            let (Some(h), Some(removed)) = (self.health.get_mut(k), self.removed.get_mut(k)) else {
                continue;
            };
            if *removed && count < MAX_ISOLATIONS && h.resume() && h.readmit() {
                *removed = false;
                back = true;
            }
        }
        if !back {
            return;
        }
        let active: [bool; N] =
            core::array::from_fn(|i| !self.removed.get(i).copied().unwrap_or(true));
        let Ok(space) = ParitySpace::new(self.space.geometry(), &active) else {
            return;
        };
        self.space = space;
        self.fusion = None;
        self.ms_block = BlockSums::default();
        self.ms_prev = None;
        self.ms_prev2 = None;
        self.ms_blocks = 0;
        self.ms_hold = 0;
        self.ms_above = 0;
        if let Some(ms) = self.ms.live_mut() {
            *ms = Multiscale::new(self.cfg.multiscale, self.space.dim(), ms.threshold_set());
        }
    }
}

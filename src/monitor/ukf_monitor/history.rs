//! The state history of the UKF monitor: one state per IMU period, kept
//! when aiding is fused at its own (configured or estimated) latency or the
//! heading offset is estimated, and shifted by every correction so that it
//! stays IMU propagation alone between any two of its states.

use super::{UkfMonitor, MAX_DELAY_STEPS};
use crate::math::{wrap_pi, Real};
use crate::model::{StateVec, ROLL};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The state history serves a configured or estimated aiding latency,
    /// the velocity's own latency and the heading-offset estimate.
    pub(super) fn keeps_history(&self) -> bool {
        self.delay_steps > 0
            || self.velocity_delay_steps.is_some()
            || self.delay_on()
            || self.heading_on()
    }

    /// The online aiding-delay estimate runs: configured, and compiled in
    /// (feature `aiding-estimators`; without it the estimators' code is
    /// dead and left out of the image, ≈ 9 KB of flash on the M4F).
    pub(super) fn delay_on(&self) -> bool {
        cfg!(feature = "aiding-estimators") && self.cfg.estimate_aiding_delay
    }

    /// The tracking fault estimate is configured and compiled in (feature
    /// `fault-tracking`; see [`delay_on`](Self::delay_on)).
    pub(super) fn tracking_on(&self) -> bool {
        cfg!(feature = "fault-tracking") && self.cfg.fault_psd.is_some()
    }

    /// The aiding is M1 (DVL + compass, `h` affine in the state): configured,
    /// or the only kind compiled in (without the feature `m2-aiding` M2's
    /// update and estimate are dead and left out of the image, ≈ 9 KB).
    pub(super) fn m1(&self) -> bool {
        !cfg!(feature = "m2-aiding") || self.meas.is_affine()
    }

    /// The heading-offset estimate runs (see [`delay_on`](Self::delay_on)).
    pub(super) fn heading_on(&self) -> bool {
        cfg!(feature = "aiding-estimators") && self.cfg.estimate_heading_offset
    }

    #[inline(never)] // keeps the copy of the history off `update`'s frame
    pub(super) fn shift_history(&mut self, x_prior: &StateVec<T>) {
        let mut dx = self.ukf.state() - x_prior;
        for v in dx.iter_mut().skip(ROLL) {
            *v = wrap_pi(*v);
        }
        let mut shifted = heapless::HistoryBuf::<StateVec<T>, { MAX_DELAY_STEPS + 1 }>::new();
        for s in self.history.oldest_ordered() {
            let mut n = s + dx;
            for v in n.iter_mut().skip(ROLL) {
                *v = wrap_pi(*v);
            }
            shifted.write(n);
        }
        self.history = shifted;
    }
}

//! Isolation on a verdict reached outside the parity tests (the rest
//! check of `parity::rest`): the same status, exclusion and
//! reconfiguration as an isolation by the tests.

use crate::math::Real;

use super::{ParityMonitor, ParityPhase};

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// Isolates sensor `k` on an external verdict (e.g.
    /// [`RestCheck`](crate::parity::RestCheck)): its status is latched as
    /// [`ParityIsolated`](crate::parity::SensorStatus::ParityIsolated) until
    /// [`reset`](Self::reset), and it leaves the set as after an isolation
    /// by the tests. In training the reduced set trains again from the
    /// start (the sensor's readings leave the calibration); in monitoring
    /// the learning is carried into the reduced space. Call it between
    /// steps; the next step's report shows the status (its `isolated` is
    /// for the tests' own isolations). Returns false, doing nothing, when
    /// `k` is out of the set already, cannot be told apart from the
    /// others, or there is no parity space left.
    pub fn isolate_external(&mut self, k: usize) -> bool {
        if !matches!(
            self.phase,
            ParityPhase::Training | ParityPhase::Calibrating | ParityPhase::Monitoring
        ) || self.removed.get(k).copied().unwrap_or(true)
            || !self.space.isolable(k)
        {
            return false;
        }
        if let Some(h) = self.health.get_mut(k) {
            h.isolate();
        }
        if self.ms.is_some() && self.ms_trained && self.configured() {
            self.exclude_between_blocks(k);
        } else {
            self.exclude(k);
        }
        self.suspect_run = (None, 0);
        true
    }
}

//! The IMU back after a gap (`ImuGap`, `input.rs`; the two-stage filter
//! does not predict over a long period, so its state stands still through
//! it): as in the innovation monitor (`ukf_monitor/imu_gap.rs`), no new
//! fault for `converge_s`, the block tests' windows cleared, and each triad
//! re-aligned to the first aiding epoch that has it complete, its channels'
//! fault estimates restarted at the nominal bias.

use nalgebra::Vector3;

use super::super::realign::gap_realignment;
use super::OtsukfMonitor;
use crate::math::Real;
use crate::model::{Measurement, ROLL};
use crate::monitor::Phase;

impl<T: Real> OtsukfMonitor<T> {
    /// Holds the decisions and marks both triads for re-alignment. Out of
    /// line: rare.
    #[inline(never)]
    pub(super) fn hold_after_gap(&mut self) {
        if !matches!(self.phase, Phase::Learning | Phase::Monitoring) {
            return;
        }
        self.blocks_clear();
        self.holdoff = self.holdoff.max(self.cfg.base.converge_s);
        self.gap_realign = [true; 2];
    }

    /// The triads still to re-align after a gap, from this epoch's aiding
    /// when complete in it; the aiding left to fuse (without the re-aligned
    /// channels) when one was.
    pub(super) fn realign_after_gap(
        &mut self,
        aiding: &Measurement<T>,
        omega: &Vector3<T>,
    ) -> Option<Measurement<T>> {
        let x = self.filter.state();
        let g = gap_realignment(&self.model, &self.meas, &x, aiding, omega, self.gap_realign)?;
        self.gap_realign = g.pending;
        self.apply_realignment(g.state, &g.reset);
        // Through a freeze the fault estimate followed the stand-in
        // sample's mismatch with the aiding: the re-aligned triad's
        // channels restart at the nominal bias (as `realign_ended`).
        let done = |i: usize| g.reset.get(i).copied().unwrap_or(false);
        let restart: [bool; 6] = core::array::from_fn(|j| done(if j < 3 { 0 } else { ROLL }));
        self.filter.reset_faults(&restart, &self.nominal);
        Some(g.rest)
    }
}

//! The IMU back after a gap (`ImuGap`, `input.rs`): samples missing beyond
//! the prediction's cap, invalid or frozen for longer than five nominal
//! periods. The state has missed that motion (on log171, 2 s of IMU rows cut
//! in a turn left the yaw tens of degrees off, pulled back by the 10° attitude
//! aiding over seconds and flagged as a g_z fault), and the windows of the
//! statistics and block tests span samples never integrated. So the
//! statistics are held for `converge_s` with their windows cleared, as after
//! an aiding loss, and each triad is re-aligned to the first aiding epoch
//! that has it complete, as the re-alignment of `realign.rs` does — whatever
//! its innovation: the gap, not the aiding, is what is known to be wrong.

use nalgebra::Vector3;

use super::super::realign::gap_realignment;
use super::UkfMonitor;
use crate::math::Real;
use crate::model::Measurement;
use crate::monitor::Phase;

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// Holds the statistics and marks both triads for re-alignment. Out of
    /// line: rare.
    #[inline(never)]
    pub(super) fn hold_after_gap(&mut self) {
        if !matches!(self.phase, Phase::Learning | Phase::Monitoring) {
            return;
        }
        for w in self.windows.iter_mut() {
            w.clear();
        }
        self.att_rate_clear();
        self.vel_inc_clear();
        self.stats_holdoff = self.stats_holdoff.max(self.cfg.converge_s);
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
        let x = *self.ukf.state();
        let g = gap_realignment(&self.model, &self.meas, &x, aiding, omega, self.gap_realign)?;
        self.gap_realign = g.pending;
        self.apply_realignment(g.state, &g.reset);
        Some(g.rest)
    }
}

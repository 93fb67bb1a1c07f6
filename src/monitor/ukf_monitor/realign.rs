//! Re-alignment to the aiding after a jump the outlier gate cannot follow
//! (a GNSS or DVL glitch), or when the attitude has reached the Euler
//! singularity: the triad is re-initialised instead of fused (the shared
//! rules are in `monitor/realign.rs`).

use super::*;
use crate::monitor::realign::{
    realign_due, realigned_state, reset_covariance, returned, returned_beyond, singular_recoverable,
};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The outlier gate rejects an aiding channel at most
    /// `gate_max_rejections` times in a row, then fuses it (a persistent
    /// innovation is what an IMU fault looks like). An innovation beyond
    /// `realign_innovation` at that point is not a fault the filter can
    /// follow but a jump of the aiding: the channel's triad (body velocity or
    /// attitude) is re-initialised from this epoch's aiding with the initial
    /// covariance (cross terms zeroed, so the covariance stays positive
    /// definite) and withdrawn from the update instead of being fused. The
    /// statistics restart: windows cleared, decisions reset, a hold-off of
    /// `converge_s` while the filter settles. Only for a channel fused within
    /// `aiding_timeout_s`: aiding that first arrives or returns after a
    /// loss is fused, unless its innovation is beyond `realign_innovation`:
    /// then it is re-aligned the same way. Returns the aiding left to
    /// fuse and whether anything was re-aligned. A triad that is not complete
    /// in this epoch cannot be re-aligned: its outlying channel is withheld
    /// until it is.
    pub(super) fn realign_outliers(
        &mut self,
        aiding: &Measurement<T>,
        omega: &Vector3<T>,
    ) -> (Measurement<T>, bool) {
        let mut out = *aiding;
        let predicted = self.meas.predict(self.ukf.state(), omega);
        let mut due = realign_due(
            aiding,
            &predicted,
            &self.cfg.realign_innovation,
            &self.rejection_run,
            &self.since_fused,
            u16::from(self.cfg.gate_max_rejections),
            self.cfg.aiding_timeout_s,
        );
        // Aiding back after a loss, with the dead-reckoned state further off
        // than `realign_innovation`: re-aligned too (issue 16). Not while
        // converging from the first alignment, which the aiding just set.
        if self.phase != Phase::Converging {
            let back = returned_beyond(
                aiding,
                &predicted,
                &self.cfg.realign_innovation,
                &self.since_fused,
                self.cfg.aiding_timeout_s,
            );
            for (d, b) in due.iter_mut().zip(back.iter()) {
                *d |= *b;
            }
        }
        if !due.iter().any(|d| *d) {
            return (out, false);
        }
        let vel_due = due.iter().take(3).any(|d| *d);
        let att_due = due.iter().skip(ROLL).any(|d| *d);
        let (x, reset) = realigned_state(
            &self.model,
            &self.meas,
            self.ukf.state(),
            aiding,
            omega,
            att_due,
            vel_due,
        );
        // Neither fused nor (when it could not be re-aligned) forgotten: an
        // outlying channel counts as one more rejection.
        for ((a, d), run) in out
            .available
            .iter_mut()
            .zip(due.iter())
            .zip(self.rejection_run.iter_mut())
        {
            if *d {
                *a = false;
                *run = run.saturating_add(1);
            }
        }
        if !reset.iter().any(|r| *r) {
            return (out, false);
        }
        // The re-aligned triads are not fused in this epoch.
        for (a, r) in out.available.iter_mut().zip(reset.iter()) {
            if *r {
                *a = false;
            }
        }
        self.apply_realignment(x, &reset);
        (out, true)
    }

    /// Aiding back after a loss (a channel silent beyond `aiding_timeout_s`
    /// that was fused before): the dead-reckoned state and its covariance
    /// have grown over the gap, and the first innovations after it measure
    /// that growth, not the IMU. The statistics are held for `converge_s`
    /// (windows cleared, nothing recorded, the nominal bias not adapted:
    /// `after_update`) while the filter re-converges; then the windows refill
    /// on healthy data before the channels are judged again (issue 16).
    pub(super) fn hold_after_loss(&mut self, aiding: &Measurement<T>) {
        if self.phase == Phase::Converging {
            return;
        }
        let timeout = self.cfg.aiding_timeout_s;
        let back = aiding
            .available
            .iter()
            .zip(self.since_fused.iter())
            .any(|(a, s)| *a && returned(*s, timeout));
        if back {
            for w in self.windows.iter_mut() {
                w.clear();
            }
            self.stats_holdoff = self.stats_holdoff.max(self.cfg.converge_s);
        }
    }

    /// At the Euler singularity (the prediction cannot run, `pitch_singular`)
    /// the attitude — and the velocity when it arrived — is re-initialised
    /// from an aiding epoch whose attitude is away from it (a loop or a
    /// tumble has gone through ±90°), with the same restart of the
    /// statistics as a re-alignment. True when it was.
    pub(super) fn recover_singular(&mut self, aiding: &Measurement<T>, omega: &Vector3<T>) -> bool {
        if !singular_recoverable(&self.model, aiding) {
            return false;
        }
        let (x, reset) = realigned_state(
            &self.model,
            &self.meas,
            self.ukf.state(),
            aiding,
            omega,
            true,
            true,
        );
        if !reset.iter().skip(ROLL).all(|r| *r) {
            return false;
        }
        self.apply_realignment(x, &reset);
        true
    }

    /// Re-initialises the `reset` states to `x` with their initial
    /// covariance, and restarts what depends on the state's history.
    fn apply_realignment(&mut self, x: StateVec<T>, reset: &[bool; NX]) {
        let p = reset_covariance(self.ukf.covariance(), reset, &self.cfg.initial_sigma);
        for (i, r) in reset.iter().enumerate() {
            if *r {
                // The re-aligned state no longer depends on the fault history.
                self.sensitivity.row_mut(i).fill(T::zero());
            }
        }
        self.tracker.forget_states(reset);
        self.reset_filter(x, p);
        // The state history (aiding latency) follows the re-aligned state.
        if self.delay_steps > 0 {
            let mut h = heapless::HistoryBuf::<StateVec<T>, { MAX_DELAY_STEPS + 1 }>::new();
            for _ in 0..self.history.len() {
                h.write(x);
            }
            self.history = h;
        }
        for w in self.windows.iter_mut() {
            w.clear();
        }
        self.att_rate_clear();
        self.vel_inc_clear();
        self.persistence.reset();
        self.stats_holdoff = self.stats_holdoff.max(self.cfg.converge_s);
    }
}

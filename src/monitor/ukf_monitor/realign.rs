//! Re-alignment to the aiding after a jump the outlier gate cannot follow
//! (a GNSS or DVL glitch), or when the attitude has reached the Euler
//! singularity: the triad is re-initialised instead of fused (the shared
//! rules are in `monitor/realign.rs`).

use super::*;
use crate::monitor::realign::{
    realign_due, realigned_state, reset_covariance, returned, returned_beyond, singular_recoverable,
};
use crate::monitor::ChannelState;

/// The fault size the end-of-fault rule tests a flag against: the
/// channel's estimate `f` now, or the estimate `raised` the flag was raised
/// with when that is larger in the same sign. A block test's estimate is
/// the mean of the window that flags, and a short glitch's mean falls as
/// longer windows take over the flag (log171, 5 m/s² for 1 s on a_x:
/// raised at 2.17 m/s² by the 2-s window, held at 0.41 by the 10-s one
/// until it had flushed, 10.1 s after the glitch), below what the shortest
/// window can contradict; a fault still present keeps the size it was
/// raised at, so that window's rule (its threshold deviation, the test's
/// per-decision probability under that fault) holds for it as well.
#[cfg(any(feature = "attitude-rate-test", feature = "velocity-increment-test"))]
pub(super) fn flag_reference<T: Real>(f: T, raised: Option<T>) -> T {
    match raised {
        Some(r) if r * f > T::zero() && r.abs() > f.abs() => r,
        _ => f,
    }
}

/// A block test is compiled in: without one (the MCU images) nothing can
/// tell that a fault has ended, and the flag ages are not kept.
const BLOCK_TESTS: bool =
    cfg!(feature = "attitude-rate-test") || cfg!(feature = "velocity-increment-test");

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
        // The jump detector names the triad that went off: a velocity
        // alone means an accelerometer (or GNSS) error, and a gyro flag
        // that follows is its attitude residue, not a gyro fault that
        // taints the velocity (`velocity_tainted`).
        self.velocity_jumped =
            reset.iter().take(3).any(|r| *r) && !reset.iter().skip(ROLL).any(|r| *r);
        // Judged before the re-alignment clears `velocity_tainted`.
        let regrow = self.regrowth_opens(&reset);
        self.apply_realignment(x, &reset);
        self.regrowth_open(regrow);
        (out, true)
    }

    /// A flag whose fault has ended (issue 15): a large short glitch
    /// integrates into the filter's attitude (gyro) or velocity
    /// (accelerometer) an error the aiding then pulls back only at the
    /// filter's gain (log171, 20 °/s for 3 s on z: ≈ 0.6 rad of yaw against
    /// a 10° yaw σ, flagged 8.5 s after the glitch), and the innovation
    /// test flags that residue as a fault still present. When the rate
    /// block test's newest shortest window, lying within the flag (flagged
    /// for that window and one block), contradicts the channel's estimate
    /// (the rule with which the test withdraws a longer window's verdict:
    /// under a fault still present, its per-decision probability), the
    /// fault is over: the triad it corrupted is
    /// re-aligned to this epoch's aiding as after an aiding jump, and the
    /// statistics restart. True when re-aligned. The rates the
    /// re-alignment needs (from `imu`, `in_range`) are computed only then:
    /// this runs at every aiding update.
    pub(super) fn realign_ended(
        &mut self,
        aiding: &Measurement<T>,
        in_range: bool,
        imu: &ImuVec<T>,
    ) -> bool {
        if !BLOCK_TESTS || self.phase != Phase::Monitoring {
            return false;
        }
        // Only channels still flagged after this epoch's decision.
        let mut flagged_for = self.flagged_for;
        for (a, s) in flagged_for.iter_mut().zip(self.report.status.iter()) {
            if !matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative) {
                *a = T::zero();
            }
        }
        let gyro = self.att_rate_ended(&flagged_for, &self.flag_raised_at);
        let acc = self.vel_inc_ended(&flagged_for, &self.flag_raised_at);
        let ended: [bool; NZ] = core::array::from_fn(|j| {
            let e = if j < 3 { acc.get(j) } else { gyro.get(j - 3) };
            e.copied().unwrap_or(false)
        });
        // The restart clears every channel's statistics: not while a flag
        // that has not ended would be lost with them (log171, a 20-s 20 °/s
        // step on y with an a_z flag it caused: the a_z flag ended, the
        // step's flag went with it 2 s before the step did).
        let still = self.report.status.iter().zip(ended.iter()).any(|(s, e)| {
            matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative) && !*e
        });
        // A velocity propagated through a gyro fault's attitude error
        // (`velocity_tainted`) is re-aligned with the attitude once every
        // gyro is judged healthy again (both carry the fault's residue), or
        // with the attitude when the gyro fault is found ended. Not while a
        // gyro is not judged: a manoeuvre the UKF's test does not cover
        // says nothing of the fault's end (log171, 20 °/s for 5 s on x at
        // 140 s: re-aligned at 143.1 s otherwise, the last 1.9 s unflagged).
        let gyro_gone = self.velocity_tainted
            && self
                .report
                .status
                .iter()
                .skip(3)
                .all(|s| matches!(s, ChannelState::Healthy));
        let att = ended.iter().skip(3).any(|e| *e) || gyro_gone;
        let vel = ended.iter().take(3).any(|e| *e) || (self.velocity_tainted && att);
        if still || (!att && !vel) {
            return false;
        }
        // The attitude as the update fuses it (learnt heading offset off).
        let corrected;
        let aiding = if self.heading_on() {
            corrected = self.correct_heading(aiding);
            &corrected
        } else {
            aiding
        };
        let omega = lever_arm_rates(in_range, &(*imu - self.removed_bias()));
        let (x, reset) = realigned_state(
            &self.model,
            &self.meas,
            self.ukf.state(),
            aiding,
            &omega,
            att,
            vel,
        );
        if !reset.iter().any(|r| *r) {
            return false;
        }
        self.apply_realignment(x, &reset);
        true
    }

    /// Ages the flags of the report by `dt`: how long each channel has
    /// been flagged (0 when it is not), and the estimate each flag was
    /// raised with (the report's, at the decision that raised it).
    pub(super) fn age_flags(&mut self, dt: T) {
        if !BLOCK_TESTS {
            return;
        }
        for (((a, r), s), f) in self
            .flagged_for
            .iter_mut()
            .zip(self.flag_raised_at.iter_mut())
            .zip(self.report.status.iter())
            .zip(self.report.fault_estimate.iter())
        {
            if matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative) {
                if *a <= T::zero() {
                    *r = *f;
                }
                *a += dt;
            } else {
                *a = T::zero();
                *r = T::zero();
            }
        }
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
    pub(super) fn apply_realignment(&mut self, x: StateVec<T>, reset: &[bool; NX]) {
        let p = reset_covariance(self.ukf.covariance(), reset, &self.cfg.initial_sigma);
        for (i, r) in reset.iter().enumerate() {
            if *r {
                // The re-aligned state no longer depends on the fault history.
                self.sensitivity.row_mut(i).fill(T::zero());
            }
        }
        self.tracker.forget_states(reset);
        // Any re-alignment closes a regrowth episode; only the jump rule's
        // opens one (`realign_outliers`): after the ended-fault rule's the
        // fault was just found over.
        self.regrowth_close();
        if reset.iter().take(3).any(|r| *r) {
            self.velocity_tainted = false;
        }
        self.reset_filter(x, p);
        self.history_fresh = 0;
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

//! Re-alignment of the two-stage monitor to its aiding: after a jump the
//! gate cannot follow, and at the Euler singularity. The rules are the
//! innovation monitor's (`monitor/realign.rs`); here they act on the full
//! state `x̂ = x̄ + V f̂` while the fault estimate `f̂` and its covariance
//! are kept: a glitch of the aiding says nothing about the IMU.

use nalgebra::Vector3;

use super::OtsukfMonitor;
use crate::math::Real;
use crate::model::{Measurement, StateVec, NX, ROLL};
use crate::monitor::realign::{
    realign_due, realigned_state, reset_covariance, singular_recoverable,
};

impl<T: Real> OtsukfMonitor<T> {
    /// The aiding left to fuse after re-aligning the triads whose channels
    /// were rejected `gate_max_rejections` times in a row and are still
    /// beyond `realign_innovation`, and whether anything was re-aligned
    /// (see [`UkfMonitor`](crate::monitor::UkfMonitor)'s rule, SPEC §8a).
    pub(super) fn realign_outliers(
        &mut self,
        aiding: &Measurement<T>,
        omega: &Vector3<T>,
    ) -> (Measurement<T>, bool) {
        let b = self.cfg.base;
        let mut out = *aiding;
        let x = self.filter.state();
        let predicted = self.meas.predict(&x, omega);
        let due = realign_due(
            aiding,
            &predicted,
            &b.realign_innovation,
            &self.track.rejection_run,
            &self.track.since_fused,
            u16::from(b.gate_max_rejections),
            b.aiding_timeout_s,
        );
        if !due.iter().any(|d| *d) {
            return (out, false);
        }
        let vel_due = due.iter().take(3).any(|d| *d);
        let att_due = due.iter().skip(ROLL).any(|d| *d);
        let (x_new, reset) =
            realigned_state(&self.model, &self.meas, &x, aiding, omega, att_due, vel_due);
        for (i, (a, d)) in out.available.iter_mut().zip(due.iter()).enumerate() {
            if *d {
                *a = false;
                self.track.withheld(i);
            }
        }
        if !reset.iter().any(|r| *r) {
            return (out, false);
        }
        for (a, r) in out.available.iter_mut().zip(reset.iter()) {
            if *r {
                *a = false;
            }
        }
        self.apply_realignment(x_new, &reset);
        (out, true)
    }

    /// A flag whose fault has ended (issue 15): the fault estimate tracked
    /// a large short glitch with a lag, so the attitude (gyro) or velocity
    /// (accelerometer) integrated part of it, and after the glitch `f̂`
    /// comes back only as that error is pulled out (log171, 20 °/s for 5 s
    /// on x: flagged 10 s after the glitch). When a block test's newest
    /// shortest window contradicts a flagged channel's `f̂ − b` (under a
    /// fault still present, the test's per-decision probability), the
    /// fault is over: the triad it corrupted is re-aligned to this
    /// epoch's aiding, the fault estimates of that triad's channels
    /// restart at the nominal bias with their initial variance, and their
    /// flags clear (no new flag for `converge_s`). True when re-aligned.
    pub(super) fn realign_ended(&mut self, aiding: &Measurement<T>, omega: &Vector3<T>) -> bool {
        let ended = self.blocks_ended();
        let vel = ended.iter().take(3).any(|e| *e);
        let att = ended.iter().skip(3).any(|e| *e);
        // Not while a flag that has not ended is up (as the innovation
        // monitor's rule: the re-alignment's hold-off and the block tests'
        // restart would go with it).
        let still = self
            .latched
            .iter()
            .zip(ended.iter())
            .any(|(l, e)| *l != 0 && !*e);
        if still || (!vel && !att) {
            return false;
        }
        let x = self.filter.state();
        let (x_new, reset) = realigned_state(&self.model, &self.meas, &x, aiding, omega, att, vel);
        if !reset.iter().any(|r| *r) {
            return false;
        }
        self.apply_realignment(x_new, &reset);
        // The channels whose state triad was re-aligned: accelerometers
        // with the velocity, gyros with the attitude.
        let restart: [bool; 6] = core::array::from_fn(|j| {
            let triad = if j < 3 { 0 } else { ROLL };
            reset.get(triad).copied().unwrap_or(false)
        });
        self.filter.reset_faults(&restart, &self.nominal);
        for (l, r) in self.latched.iter_mut().zip(restart.iter()) {
            if *r {
                *l = 0;
            }
        }
        self.blocks_clear();
        true
    }

    /// At the Euler singularity, the attitude (and velocity, when it
    /// arrived) from an aiding epoch away from it; true when re-aligned.
    pub(super) fn recover_singular(&mut self, aiding: &Measurement<T>, omega: &Vector3<T>) -> bool {
        let x = self.filter.state();
        if !singular_recoverable(&self.model, aiding) {
            return false;
        }
        let (x_new, reset) =
            realigned_state(&self.model, &self.meas, &x, aiding, omega, true, true);
        if !reset.iter().skip(ROLL).all(|r| *r) {
            return false;
        }
        self.apply_realignment(x_new, &reset);
        true
    }

    /// The `reset` states at `x` with their initial covariance, the others
    /// keeping their total covariance `P̄ + V P^f Vᵀ`; the fault estimate
    /// and `P^f` unchanged; decisions held for `converge_s`.
    pub(super) fn apply_realignment(&mut self, x: StateVec<T>, reset: &[bool; NX]) {
        let b = self.cfg.base;
        let p = reset_covariance(&self.filter.state_covariance(), reset, &b.initial_sigma);
        self.filter.reset_state(x, p);
        self.holdoff = self.holdoff.max(b.converge_s);
    }
}

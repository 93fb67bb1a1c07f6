//! Re-alignment to the aiding after a jump the outlier gate cannot follow
//! (a GNSS or DVL glitch): the triad is re-initialised instead of fused.

use super::*;

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
    /// loss is fused as before. Returns the aiding left to
    /// fuse and whether anything was re-aligned. A triad that is not complete
    /// in this epoch cannot be re-aligned: its outlying channel is withheld
    /// until it is.
    pub(super) fn realign_outliers(
        &mut self,
        aiding: &Measurement<T>,
        omega: &Vector3<T>,
    ) -> (Measurement<T>, bool) {
        let mut out = *aiding;
        let limit = u16::from(self.cfg.gate_max_rejections);
        let predicted = self.meas.predict(self.ukf.state(), omega);
        let mut due = [false; NZ];
        for (i, d) in due.iter_mut().enumerate() {
            let (Some(a), Some(z), Some(zp), Some(bound), Some(run), Some(fused)) = (
                aiding.available.get(i),
                aiding.z.get(i),
                predicted.get(i),
                self.cfg.realign_innovation.get(i),
                self.rejection_run.get(i),
                self.since_fused.get(i),
            ) else {
                continue;
            };
            // Only a jump of a channel in use: aiding that returns (or first
            // arrives) after more than `aiding_timeout_s` is fused as before.
            let recent = *fused <= self.cfg.aiding_timeout_s;
            let mut innovation = *z - *zp;
            if i >= ROLL {
                innovation = wrap_pi(innovation);
            }
            *d = *a
                && recent
                && *run >= limit
                && (!innovation.finite() || innovation.abs() > *bound);
        }
        if !due.iter().any(|d| *d) {
            return (out, false);
        }
        let vel_due = due.iter().take(3).any(|d| *d);
        let att_due = due.iter().skip(ROLL).any(|d| *d);
        let complete = |r: core::ops::Range<usize>| {
            aiding
                .available
                .get(r)
                .is_some_and(|a| a.iter().all(|v| *v))
        };
        let mut x = *self.ukf.state();
        let mut reset = [false; NX];
        if att_due && complete(ROLL..NZ) {
            let mut xa = x;
            xa.fixed_rows_mut::<3>(ROLL)
                .copy_from(&aiding.z.fixed_rows::<3>(ROLL));
            if self.model.check_attitude(&xa).is_ok() {
                x = xa;
                for r in reset.iter_mut().skip(ROLL) {
                    *r = true;
                }
            }
        }
        if vel_due && complete(0..3) {
            let v: Vector3<T> = aiding.z.fixed_rows::<3>(0).into_owned();
            let v_imu = self.meas.velocity_to_body(&x, &v) - omega.cross(&self.meas.lever_arm);
            if v_imu.iter().all(|c| c.finite()) {
                x.fixed_rows_mut::<3>(0).copy_from(&v_imu);
                for r in reset.iter_mut().take(3) {
                    *r = true;
                }
            }
        }
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
        let mut p = *self.ukf.covariance();
        for (i, ri) in reset.iter().enumerate() {
            for (j, rj) in reset.iter().enumerate() {
                if *ri || *rj {
                    if let Some(v) = p.get_mut((i, j)) {
                        *v = T::zero();
                    }
                }
            }
            if *ri {
                let s = self.cfg.initial_sigma.get(i).copied().unwrap_or(T::one());
                if let Some(v) = p.get_mut((i, i)) {
                    *v = s * s;
                }
                // The re-aligned state no longer depends on the fault history.
                self.sensitivity.row_mut(i).fill(T::zero());
            }
        }
        self.ukf.reset(x, p);
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
        self.persistence.reset();
        self.stats_holdoff = self.stats_holdoff.max(self.cfg.converge_s);
        (out, true)
    }
}

//! The step's report, written in place: the monitor's state, statuses and
//! corrected sample (`compose`), and the tracking fault estimate of a
//! staged aiding epoch (`track_epoch`).

use super::UkfMonitor;
use crate::filter::ChannelDiag;
use crate::math::Real;
use crate::model::{ImuVec, NZ};
use crate::monitor::{ChannelState, Health, Phase};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// Runs the tracker's aiding epoch staged by the last update (the
    /// sensitivity is still that update's `X⁺`, `Φ` still the epoch's) and
    /// shows its estimate on the channels that epoch's report monitored.
    #[inline(never)] // own stack frame and one copy (issue 17)
    pub(super) fn track_epoch(&mut self) {
        let Some(psd) = self.cfg.fault_psd else {
            return;
        };
        self.tracker.run_epoch(&psd, &self.sensitivity);
        let (f, sd) = self.tracker.estimate();
        let mask = self.tracker.mask();
        for (((o, s), (fv, sv)), m) in self
            .report
            .fault_estimate
            .iter_mut()
            .zip(self.report.detail.fault_sigma.iter_mut())
            .zip(f.iter().zip(sd.iter()))
            .zip(mask.iter())
        {
            *o = if *m { *fv } else { T::zero() };
            *s = if *m { *sv } else { T::zero() };
        }
    }

    /// Writes this step's report into `self.report` in place (no copy of
    /// the ≈ 340-byte report through a return value, issue 17).
    #[inline(never)] // own stack frame and one copy (issue 17)
    pub(super) fn compose(&mut self, imu: &ImuVec<T>, health: Health, updated: bool) {
        let r = &mut self.report;
        // Only `update` writes the diagnostics, and only on a step that
        // reports `updated`: after a step without one they are still the
        // defaults this clears them to (a predict-only step skips the
        // 120-byte store, issue 17).
        let diag_stale = r.updated;
        r.phase = self.phase;
        if self.phase != Phase::Monitoring {
            r.status = [ChannelState::NotMonitored; NZ];
        }
        r.health = health;
        r.updated = updated;
        r.state = *self.ukf.state();
        r.state_sigma = self
            .ukf
            .covariance()
            .diagonal()
            .map(|v| v.fmax(T::zero()).sqrt_fast());
        r.nominal_bias = self.nominal_bias;
        let mut corrected = imu - self.nominal_bias;
        for ((c, s), f) in corrected
            .iter_mut()
            .zip(r.status.iter())
            .zip(r.fault_estimate.iter())
        {
            if matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative) {
                *c -= *f;
            }
        }
        r.corrected_imu = corrected;
        r.detail.covariance_resets = self.ukf.covariance_resets();
        r.detail.innovation_inflation = self.inflation;
        if !updated && diag_stale {
            r.detail.diag = [ChannelDiag::default(); NZ];
        }
    }
}

//! The monitoring half of the UKF innovation monitor, run after each aiding
//! update: nominal-bias learning and drift tracking, the windowed t-tests,
//! the decision rule and the fault estimates.

use super::{UkfMonitor, MAX_NOMINAL_BIAS_FACTOR};
use crate::detect::{
    estimate_as_written, estimate_corrected, test_flags, window_evidence, DecisionRule, Statistic,
    WindowEvidence,
};
use crate::math::Real;
use crate::model::{ImuVec, NZ};
use crate::monitor::{ChannelState, Health, Phase};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// Row scale that turns a raw innovation into a window sample.
    fn window_scale(&self) -> ImuVec<T> {
        match self.cfg.statistic {
            Statistic::Raw => ImuVec::from_element(T::one()),
            Statistic::Whitened | Statistic::Normalized => {
                self.latest_variance.map(|v| T::one() / v.sqrt_fast())
            }
        }
    }

    #[inline(never)] // own stack frame and one copy (issue 17)
    pub(super) fn after_update(&mut self, health: &Health) {
        let dt_learn = self.phase_time - self.learn_clock;
        self.learn_clock = self.phase_time;
        // Instant estimate from the latest innovation of every channel; only
        // computed when the learner or the drift tracker will use it.
        let instant = |s: &Self| {
            let w = s.latest_variance.map(|v| T::one() / v);
            estimate_corrected(&s.signature, &w, &s.latest_innovation, &[true; NZ])
        };
        match self.phase {
            Phase::Learning => {
                if let Some(f) = instant(self) {
                    let k = (dt_learn / self.cfg.learn_tau_s).min(T::one());
                    self.nominal_bias += f * k;
                }
            }
            Phase::Monitoring => {
                self.detect(health);
                let quiet = self.report.status.iter().all(|s| {
                    !matches!(s, ChannelState::FaultNegative | ChannelState::FaultPositive)
                }) && self
                    .report
                    .detail
                    .t_statistic
                    .iter()
                    .all(|t| t.abs() < self.t_threshold() * T::lit(0.5));
                let estimate = if quiet { instant(self) } else { None };
                if let Some(f) = estimate {
                    let k = dt_learn / self.cfg.drift_tau_s;
                    for ((b, df), lim) in self
                        .nominal_bias
                        .iter_mut()
                        .zip(f.iter())
                        .zip(self.cfg.drift_rate_limit.iter())
                    {
                        let step = *df * k;
                        let cap = *lim * dt_learn;
                        *b += step.max(-cap).min(cap);
                    }
                }
            }
            _ => {}
        }
        let cap = T::lit(MAX_NOMINAL_BIAS_FACTOR);
        for (b, m) in self.nominal_bias.iter_mut().zip(self.cfg.min_fault.iter()) {
            *b = b.max(-*m * cap).min(*m * cap);
        }
    }

    fn detect(&mut self, _health: &Health) {
        let threshold = self.t_threshold();
        let WindowEvidence {
            full,
            tstat,
            rbar,
            weight,
        } = window_evidence(&self.windows, self.cfg.statistic, self.cfg.outlier_k);
        let flags = test_flags(&tstat, threshold);
        let scale = self.window_scale();
        let mut m_eff = self.signature;
        for (i, s) in scale.iter().enumerate() {
            let row = m_eff.row(i) * *s;
            m_eff.set_row(i, &row);
        }
        let rule = DecisionRule {
            detector: self.cfg.detector,
            paper_inv: self.paper_inv.as_ref(),
            min_fault: &self.cfg.min_fault,
            threshold_fraction: self.cfg.threshold_fraction,
            sign_deadband: self.cfg.sign_deadband,
            glr_threshold: self.cfg.glr_threshold,
            glr_relative: self.cfg.glr_relative,
        };
        let decision = rule.decide(&m_eff, &flags, &rbar, &weight);
        let monitored = self.monitored(&full);
        let mut masked = decision;
        for (d, m) in masked.iter_mut().zip(monitored.iter()) {
            if !*m {
                *d = 0;
            }
        }
        let out = self.persistence.update(&masked);
        // Estimates from the window means.
        let est =
            estimate_corrected(&m_eff, &weight, &rbar, &monitored).unwrap_or_else(ImuVec::zeros);
        let raw_mean = rbar.component_div(&scale.map(|s| if s > T::zero() { s } else { T::one() }));
        let mut as_written =
            estimate_as_written(&self.last_h, &self.last_input_b, self.last_dt, &raw_mean)
                .unwrap_or_else(ImuVec::zeros);
        for (v, m) in as_written.iter_mut().zip(monitored.iter()) {
            if !*m {
                *v = T::zero();
            }
        }
        for ((st, mon), o) in self
            .report
            .status
            .iter_mut()
            .zip(monitored.iter())
            .zip(out.iter())
        {
            *st = if !*mon {
                ChannelState::NotMonitored
            } else {
                match *o {
                    1 => ChannelState::FaultPositive,
                    -1 => ChannelState::FaultNegative,
                    _ => ChannelState::Healthy,
                }
            };
        }
        self.report.detail.t_statistic = tstat;
        self.report.detail.innovation_flags = flags;
        self.report.fault_estimate = est;
        self.report.detail.fault_estimate_as_written = as_written;
    }

    /// IMU channel j is monitored when the innovation channels carrying its
    /// signature have full windows: the velocity triad for accelerometers,
    /// the attitude triad for gyros.
    fn monitored(&self, full: &[bool; NZ]) -> [bool; NZ] {
        let vel = full.iter().take(3).all(|f| *f);
        let att = full.iter().skip(3).all(|f| *f);
        [vel, vel, vel, att, att, att]
    }
}

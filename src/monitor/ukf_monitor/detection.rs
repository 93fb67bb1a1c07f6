//! The monitoring half of the UKF innovation monitor, run after each aiding
//! update: nominal-bias learning and drift tracking, the windowed t-tests,
//! the decision rule and the fault estimates.

use super::UkfMonitor;
use crate::detect::{
    estimate_as_written_blocks, estimate_as_written_identity, estimate_corrected, test_flags,
    window_evidence, DecisionRule, Statistic, WindowEvidence,
};
use crate::math::{keep_rolled, rolled, rolled_mut, Real};
use crate::model::{ImuVec, Measurement, NZ};
use crate::monitor::{ChannelState, Health, Phase};

/// The inflation `n` learnt windows with t² summing to `s` prove: the
/// one-sided 97.7 % lower bound of their mean over the white value
/// (`white`: its mean and sd), clamped to `[1, max]`; 1 with fewer than
/// two windows' worth (see `freeze_inflation`).
pub(super) fn inflation_factor<T: Real, const W: usize>(s: T, n: T, white: (T, T), max: T) -> T {
    let (mean, sd) = white;
    let w = T::lit(W as f64);
    if n >= T::lit(2.0) * w {
        let lower = s / n - T::lit(2.0) * sd / (n / w).sqrt_fast();
        (lower / mean).max(T::one()).min(max)
    } else {
        T::one()
    }
}

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// Row scale that turns a raw innovation into a window sample.
    fn window_scale(&self) -> ImuVec<T> {
        match self.statistic() {
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
        // Instant estimate from the latest innovation of every channel
        // (`instant_estimate`); only computed when the learner, the drift
        // tracker or the power-up check will use it.
        let instant = |s: &Self| s.instant_estimate();
        // Nothing is learned while the statistics are held (a bad sample, a
        // re-alignment, aiding back after a loss): the innovations then
        // measure the filter's re-convergence, and `dt_learn` may span a
        // whole gap (issue 16: after 180 s without aiding the first update
        // moved the nominal bias by 0.9 × its innovation-mapped estimate).
        let held = self.stats_holdoff > T::zero();
        match self.phase {
            Phase::Learning => {
                self.learn_inflation();
                self.track_inflation(T::one());
                if let Some(f) = if held { None } else { instant(self) } {
                    // Before the bound: what the learner would hold without
                    // it (`power_up.rs`), once it has converged.
                    let learnt = self.phase_time - self.cfg.converge_s;
                    let second_half = learnt >= self.cfg.learn_s * T::lit(0.5);
                    self.power_up.learn(&(self.nominal_bias + f), second_half);
                    let k = (dt_learn / self.cfg.learn_tau_s).min(T::one());
                    self.nominal_bias += f * k;
                }
            }
            Phase::Monitoring => {
                let covered = self.covered();
                if covered {
                    self.inflation_at_motion();
                    self.detect(health);
                } else {
                    self.not_judged();
                }
                // Each test's view of the other triad (`withhold_coupled_flags`).
                let accel_fault = self.vel_inc_sees_fault();
                self.att_rate_apply(accel_fault);
                let tainted = self.velocity_tainted();
                let gyro_fault = self.att_rate_sees_fault();
                self.vel_inc_apply(tainted, gyro_fault);
                self.regrowth_apply();
                let f = if self.power_up.any() && !held {
                    instant(self)
                } else {
                    None
                };
                self.power_up_apply(f, dt_learn);
                // Not while the gyro/attitude test sees something either: a
                // slow bias under its threshold is not absorbed.
                let quiet = covered
                    && self.att_rate_quiet()
                    && self.vel_inc_quiet()
                    && self.report.status.iter().all(|s| {
                        !matches!(s, ChannelState::FaultNegative | ChannelState::FaultPositive)
                    })
                    && self
                        .report
                        .detail
                        .t_statistic
                        .iter()
                        .all(|t| t.abs() < self.t_threshold() * T::lit(0.5));
                let estimate = if quiet && !held { instant(self) } else { None };
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
                        *b += step.fmax(-cap).fmin(cap);
                    }
                }
                // The inflation learns from quiet judged epochs and from
                // those too active to be judged (`inflation_cover.rs`).
                if !held && (quiet || !covered) && self.tracking_inflation() {
                    let keep = T::one() - dt_learn / self.cfg.inflation_memory_s;
                    self.track_inflation(keep.max(T::zero()));
                }
            }
            _ => {}
        }
        let cap = self.nominal_bias_bound();
        for (b, m) in self.nominal_bias.iter_mut().zip(cap.iter()) {
            *b = b.fmax(-*m).fmin(*m);
        }
    }

    /// The instant estimate from the latest innovation of every channel.
    /// Not the horizontal accelerometers' from an epoch an unresolved
    /// heading offset may have contaminated (`heading.rs`). Out of line:
    /// three call sites (flash on the M4F).
    #[inline(never)]
    fn instant_estimate(&self) -> Option<ImuVec<T>> {
        let w = self.latest_variance.map(|v| T::one() / v);
        let f = estimate_corrected(&self.signature, &w, &self.latest_innovation, &[true; NZ]);
        if self.heading_on() && self.heading.contaminated {
            f.map(|mut f| {
                for v in f.iter_mut().take(2) {
                    *v = T::zero();
                }
                f
            })
        } else {
            f
        }
    }

    /// A bias beyond the turn-on bound found at monitoring start
    /// (`power_up.rs`): followed while flagged (over half a learning
    /// phase), reported where the other tests find the channel healthy or
    /// cannot judge it.
    /// `instant`: this epoch's instant estimate (`None`: held). Out of
    /// line: it acts only after a power-up fault (flash on the M4F).
    #[inline(never)]
    fn power_up_apply(&mut self, instant: Option<ImuVec<T>>, dt_learn: T) {
        if !self.power_up.any() {
            return;
        }
        let bound = self.nominal_bias_bound();
        let smallest = self.cfg.min_fault * self.cfg.threshold_fraction;
        if let Some(f) = instant {
            let span = (self.cfg.learn_s * T::lit(0.5)).fmax(T::lit(1e-3));
            let k = (dt_learn / span).fmin(T::one());
            let removed = self.removed_bias();
            self.power_up.track(&(removed + f), k, &bound, &smallest);
        }
        self.power_up.apply(
            &mut self.report.status,
            &mut self.report.fault_estimate,
            &bound,
        );
    }

    fn detect(&mut self, _health: &Health) {
        let threshold = self.t_threshold();
        let WindowEvidence {
            full,
            tstat,
            rbar,
            weight,
        } = window_evidence(&self.windows, self.statistic(), self.cfg.outlier_k);
        // The learned inflation: the test and the GLR weigh each window mean
        // by the spread it has on this vehicle's healthy data.
        let mut tstat = tstat;
        let mut weight = weight;
        for ((t, w), c) in tstat
            .iter_mut()
            .zip(weight.iter_mut())
            .zip(self.inflation.iter())
        {
            *t /= c.sqrt_fast();
            *w /= *c;
        }
        let flags = test_flags(&tstat, threshold);
        let scale = self.window_scale();
        // Built scaled, not copied and then scaled row by row (issue 17).
        let m_eff = self
            .signature
            .map_with_location(|i, _, v| v * scale.get(i).copied().unwrap_or_else(T::one));
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
        let mut monitored = self.monitored(&full);
        // An epoch an unresolved heading offset may have contaminated
        // beyond half the smallest fault (`heading.rs`): the horizontal
        // accelerometers cannot be judged from it, and the report says so.
        if self.heading_on() && self.heading.contaminated {
            for m in monitored.iter_mut().take(2) {
                *m = false;
            }
        }
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
        // H B is block upper triangular (M1's H the identity, M2's and B of
        // the model's block form): the elimination without its operations
        // on the zero blocks, and for M1 on the identity (the same values,
        // issue 17).
        let b = self.last_input_b();
        let as_written = if self.m1() {
            estimate_as_written_identity(&b, self.last_dt, &raw_mean)
        } else {
            estimate_as_written_blocks(&self.last_h, &b, self.last_dt, &raw_mean)
        };
        let mut as_written = as_written.unwrap_or_else(ImuVec::zeros);
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
        self.report.detail.fault_estimate_window = est;
        self.report.fault_estimate = est;
        if self.tracker.active {
            // This epoch's estimate is shown by the next step
            // (`track_epoch`); until then the last one.
            self.tracker.set_mask(monitored);
            let (f, sd) = self.tracker.estimate();
            let masked = |v: &ImuVec<T>| {
                let mut v = *v;
                for (x, m) in v.iter_mut().zip(monitored.iter()) {
                    if !*m {
                        *x = T::zero();
                    }
                }
                v
            };
            self.report.fault_estimate = masked(&f);
            self.report.detail.fault_sigma = masked(&sd);
        }
        self.report.detail.fault_estimate_as_written = as_written;
    }

    /// Accumulates each full window's t² during learning, clipped at 10²
    /// so one glitch (a 60 ms spike, an aiding jump) moves the mean by at
    /// most 100/n.
    fn learn_inflation(&mut self) {
        if self.cfg.max_innovation_inflation <= T::one() {
            return;
        }
        let ev = window_evidence(&self.windows, self.statistic(), self.cfg.outlier_k);
        let clip = T::lit(100.0);
        // Only with `max_innovation_inflation` > 1, in learning: rolled.
        for (((s, n), t), full) in rolled_mut(&mut self.inflation_sum)
            .iter_mut()
            .zip(rolled_mut(&mut self.inflation_n).iter_mut())
            .zip(rolled(&ev.tstat))
            .zip(rolled(&ev.full))
        {
            keep_rolled();
            if *full {
                *s += (*t * *t).min(clip);
                *n += T::one();
            }
        }
    }

    /// Whether the inflation follows the flight (configured and compiled in).
    fn tracking_inflation(&self) -> bool {
        cfg!(feature = "inflation-tracking")
            && self.cfg.inflation_memory_s > T::zero()
            && self.cfg.max_innovation_inflation > T::one()
    }

    /// After a fused aiding epoch: its attitude gives the window's motion
    /// (`inflation_cover.rs`).
    pub(super) fn cover_epoch(&mut self, _aiding: &Measurement<T>) {
        #[cfg(feature = "inflation-tracking")]
        if self.tracking_inflation() {
            let att = core::array::from_fn(|i| {
                let k = 3 + i;
                let on = _aiding.available.get(k).copied().unwrap_or(false);
                _aiding.z.get(k).copied().filter(|_| on)
            });
            self.cover.observe_attitude(att, self.phase_time, W);
        }
    }

    /// The learnt inflation covers this window's motion (always, without
    /// tracking); if so, the factors in use are the ones learnt at it.
    pub(in crate::monitor::ukf_monitor) fn covered(&self) -> bool {
        #[cfg(feature = "inflation-tracking")]
        if self.tracking_inflation() {
            return self.cover.covered(T::lit(2.0 * W as f64));
        }
        true
    }

    /// Sets the factors in use to the ones learnt at this window's motion.
    fn inflation_at_motion(&mut self) {
        #[cfg(feature = "inflation-tracking")]
        if self.tracking_inflation() {
            if let Some(white) = self.white_t2() {
                let max = self.cfg.max_innovation_inflation;
                for (c, f) in self.inflation.iter_mut().enumerate() {
                    let (s, n) = self.cover.tail(c);
                    *f = inflation_factor::<T, W>(s, n, white, max);
                }
            }
        }
    }

    /// An epoch the UKF's test does not judge: every channel not monitored
    /// (a block test may still flag it), no run carried over.
    fn not_judged(&mut self) {
        for s in self.report.status.iter_mut() {
            *s = ChannelState::NotMonitored;
        }
        self.report.fault_estimate = ImuVec::zeros();
        self.report.detail.fault_estimate_window = ImuVec::zeros();
        self.persistence.reset();
    }

    /// Learns this epoch's full windows' t² at the window's motion, with
    /// the memory's factor `keep` (1: no forgetting, in learning).
    fn track_inflation(&mut self, _keep: T) {
        #[cfg(feature = "inflation-tracking")]
        if self.tracking_inflation() {
            let ev = window_evidence(&self.windows, self.statistic(), self.cfg.outlier_k);
            let mut t2 = [None; NZ];
            for ((o, t), full) in t2.iter_mut().zip(ev.tstat.iter()).zip(ev.full.iter()) {
                if *full {
                    *o = Some(*t * *t);
                }
            }
            self.cover.learn(&t2, _keep);
        }
    }

    /// At the end of learning: inflation = what the data prove of mean t²
    /// over its white-noise value. For ν = W − 1 the white t has
    /// `E[t²] = ν/(ν−2)` and `Var[t²] = 3ν²/((ν−2)(ν−4)) − E[t²]²` (normal:
    /// 1 and 2); the learning gave `n` overlapping windows, i.e. about
    /// `n/W` independent ones. The factor is the one-sided 97.7 % lower
    /// bound `(mean − 2·sd/√(n/W)) / E[t²]`, clamped to
    /// `[1, max_innovation_inflation]`: sampling noise of a short learning
    /// phase on white data gives 1, not a desensitised test. Channels with
    /// fewer than 2·W windows keep 1.
    pub(super) fn freeze_inflation(&mut self) {
        let Some(white) = self.white_t2() else {
            return;
        };
        let max = self.cfg.max_innovation_inflation;
        // Once per learning phase: rolled.
        for ((c, s), n) in rolled_mut(&mut self.inflation)
            .iter_mut()
            .zip(rolled(&self.inflation_sum))
            .zip(rolled(&self.inflation_n))
        {
            *c = inflation_factor::<T, W>(*s, *n, white, max);
        }
    }

    /// Mean and standard deviation of a white window t² (`None`: the
    /// statistic has no finite variance at this window length).
    pub(super) fn white_t2(&self) -> Option<(T, T)> {
        let nu = W.saturating_sub(1) as f64;
        let (white, var) = match self.statistic() {
            Statistic::Normalized => (1.0, 2.0),
            _ if nu > 4.0 => {
                let e2 = nu / (nu - 2.0);
                (e2, 3.0 * nu * nu / ((nu - 2.0) * (nu - 4.0)) - e2 * e2)
            }
            _ => return None,
        };
        Some((T::lit(white), T::lit(var).sqrt_fast()))
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

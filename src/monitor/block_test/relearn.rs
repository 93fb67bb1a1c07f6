//! Statistics learnt afresh when the residual the test sees changes its
//! definition (the velocity test's GNSS lag switches, issue 15).
//!
//! **Why.** The offset, block and window variances, lag-1 correlation,
//! motion law and motion cover describe the residual they were learnt on.
//! At another lag the residual is another one: on log171 (learning from
//! 80 s) the lag is 0 until 105 s, and the take-off's blocks at lag 0
//! spread 0.35–0.85 m/s² per axis (the `τ·Δa` misfit) against 0.17–0.21
//! in flight at the 0.3 s used from 122 s. Kept, they set the thresholds
//! of the whole flight (a 0.5 m/s² step at 150 s stayed below them on
//! three IMU axes).
//!
//! **How.** At a switch a second test starts learning from nothing on
//! the new lag's blocks, gated by the judging test's decisions (a block
//! the latter would not learn is not learnt here either), while the
//! judging test goes on with the old statistics: no blind time. Once the
//! fresh statistics meet the condition under which a channel judges at
//! all (the offset rests on two longest windows of blocks, on every
//! channel) they replace the old ones; each length then judges once its
//! own degrees of freedom allow (`min_dof`), so the Student-t threshold
//! carries the smaller sample. A further switch before then starts the
//! fresh statistics again.

use super::*;

impl<T: Real> BlockTest<T> {
    /// An empty test with this one's per-decision probability.
    pub fn fresh(&self) -> Self {
        Self::new(self.alpha)
    }

    /// The ratios recorded for the newest block (its decisions and the
    /// monitor's flags): the gate of a test learning alongside.
    pub fn newest_ratio(&self) -> Option<Vector3<T>> {
        self.slot(0).and_then(|i| self.ratio_at.get(i)).copied()
    }

    /// Every channel's offset rests on two longest windows of learnt
    /// blocks (the condition for judging at all).
    pub fn learnt_enough(&self, cfg: &BlockTestConfig<T>) -> bool {
        let need = T::lit(2.0 * f64::from(cfg.lengths[NL - 1]));
        self.n_b.iter().all(|n| *n >= need)
    }

    /// Takes over what `fresh` learnt (offset, variances, correlation,
    /// motion law and cover); the blocks kept and the decisions stay.
    pub fn adopt_learnt(&mut self, fresh: &Self) {
        self.n_b = fresh.n_b;
        self.s1 = fresh.s1;
        self.s2 = fresh.s2;
        self.n11 = fresh.n11;
        self.s11 = fresh.s11;
        self.prev = fresh.prev;
        self.q_w = fresh.q_w;
        self.n_w = fresh.n_w;
        self.motion_var = fresh.motion_var;
        self.motion_hist = fresh.motion_hist;
        // The cached thresholds belong to the old degrees of freedom.
        self.quantile = [[(T::zero(), T::zero()); 3]; NL];
        self.detail.offset = fresh.detail.offset;
        self.detail.reddening = fresh.detail.reddening;
        self.detail.dof = fresh.detail.dof;
    }
}

//! The block variance as a function of motion.
//!
//! **Why.** A block mean's spread is not the same in a turn as in
//! straight flight: the attitude aiding's error turns the specific force
//! (velocity-increment test) and a lag misfit leaves `τ·Δa`, both growing
//! with the acceleration. On log171 (1-s blocks at the 0.3-s lag, first
//! differences of the block estimates) the spread is 0.09–0.18 m/s² in
//! the calmest third of the blocks and 0.34–0.49 m/s² in the most active
//! third, on every IMU and axis. One variance for all blocks then sets the
//! threshold of a calm window by the turns (a 0.5 m/s² step after the
//! turn at 136–147 s stayed at 0.8–1.0 of its threshold) and that of a
//! turn by the calm (ratios 0.6–0.8 fault-free at the turn's end).
//!
//! **Model.** Per channel, the learnt blocks' squared deviation from the
//! learnt offset is regressed on the block's motion measure:
//! `E[d²] = a + c·m`, `c ≥ 0`, with the learning's own forgetting and
//! gating (a fault is never learnt). A window's variance is then the white
//! one scaled by the mean, over its blocks, of `h(m) = (a + c·m)/(a + c·m̄)`
//! (`m̄` the learnt blocks' mean motion, where `h = 1`); the reddening is
//! learnt on window means divided by the same factor, so it stays the
//! correlation's share alone. Guards: `a` is at least a tenth of the
//! variance at `m̄` (a spread at rest ten times below the flight's mean
//! is not believed on a few dozen blocks), and the factor is 1 until two
//! longest windows of blocks have been learnt.

use super::*;

/// The smallest intercept, as a fraction of the variance at the mean
/// motion (module notes).
const MIN_INTERCEPT: f64 = 0.1;

impl<T: Real> BlockTest<T> {
    /// Adds a learnt block of channel `c` (deviation `d` from the learnt
    /// offset, motion `m`) to the regression, forgetting with `keep`.
    pub(super) fn learn_motion_variance(&mut self, c: usize, d: T, m: T, keep: T) {
        // A non-finite sample would hold the sums at NaN for good.
        if !(d.finite() && m.finite()) {
            return;
        }
        let d2 = d * d;
        let terms = [T::one(), m, m * m, d2, d2 * m];
        for (acc, x) in self.motion_var.iter_mut().zip(terms.iter()) {
            if let Some(a) = acc.get_mut(c) {
                *a = *a * keep + *x;
            }
        }
    }

    /// The relative variance `h(m)` of a block of channel `c` at motion
    /// `m` (1 before the regression rests on two longest windows of
    /// blocks, `longest`).
    pub(super) fn motion_factor(&self, c: usize, m: T, longest: usize) -> T {
        let get = |i: usize| {
            self.motion_var
                .get(i)
                .and_then(|v| v.get(c))
                .copied()
                .unwrap_or_else(T::zero)
        };
        let n = get(0);
        if n < T::lit(2.0 * longest as f64) {
            return T::one();
        }
        let mean_m = get(1) / n;
        let var_m = get(2) / n - mean_m * mean_m;
        let mean_d2 = get(3) / n;
        if var_m <= T::zero() || mean_d2 <= T::zero() {
            return T::one();
        }
        let slope = ((get(4) / n - mean_m * mean_d2) / var_m).fmax(T::zero());
        let a = (mean_d2 - slope * mean_m).fmax(T::lit(MIN_INTERCEPT) * mean_d2);
        let v = a + slope * mean_m;
        if v <= T::zero() {
            return T::one();
        }
        let h = (a + slope * m) / v;
        if h.finite() {
            h
        } else {
            T::one()
        }
    }

    /// The mean motion factor of channel `c` over the window of `len`
    /// blocks ending `age` blocks before the newest: `h` is linear in the
    /// motion, so its mean over the blocks is its value at their mean
    /// motion (one evaluation per window, not one per block).
    pub(super) fn window_factor(&self, c: usize, age: usize, len: usize, longest: usize) -> T {
        self.mean_motion(age, len)
            .map_or_else(T::one, |m| self.motion_factor(c, m, longest))
    }
}

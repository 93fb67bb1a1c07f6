//! The OTSUKF monitor's learned measurement-noise inflation (issue 15).
//!
//! Real aiding errors (GNSS velocity, an autopilot's attitude) are larger
//! than their nominal σ and time-correlated: the fault filter then trusts
//! each epoch too much, `f̂` wanders further than `P^f` says, and the
//! `k_on·σ_f` test fires on healthy data. During learning this measures, per
//! aiding component, the spread of the filter's own innovation `r^f` over
//! the variance it predicts (`A_ii`), on means over blocks of consecutive
//! epochs, so correlation over a block counts as well as a too-small σ. At
//! monitoring start the factor is frozen and multiplies that component's
//! `R`, so the gains and `P^f` describe the errors the flight really has.

use crate::math::{keep_rolled, rolled, rolled_mut, Real};
use crate::model::NZ;

/// Per aiding component: block sums, the accumulated block statistics and
/// the frozen factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Inflation<T> {
    /// Sum of the normalised innovations `r^f/√A` in the current block.
    block_sum: [T; NZ],
    /// Epochs in the current block.
    block_n: [u16; NZ],
    /// Sum of the completed blocks' `(Σ r^f/√A)² / len`.
    sum: [T; NZ],
    /// Completed blocks.
    n: [T; NZ],
    /// The factor in force (1 until frozen).
    factor: [T; NZ],
}

impl<T: Real> Inflation<T> {
    /// Nothing learned, factor 1.
    pub(super) fn new() -> Self {
        Self {
            block_sum: [T::zero(); NZ],
            block_n: [0; NZ],
            sum: [T::zero(); NZ],
            n: [T::zero(); NZ],
            factor: [T::one(); NZ],
        }
    }

    /// The factor per aiding component (`R` multiplier).
    pub(super) fn factor(&self) -> &[T; NZ] {
        &self.factor
    }

    /// One fused epoch of component `i` during learning: innovation `rf`,
    /// predicted variance `a`. A block of `len` epochs contributes
    /// `(Σ rf/√a)² / len`, clipped at 10² so one glitch (an aiding jump)
    /// moves the mean by at most 100/n; white data with the right variance
    /// give 1 on average whatever `len`.
    pub(super) fn observe(&mut self, i: usize, rf: T, a: T, len: u16) {
        let (Some(bs), Some(bn), Some(s), Some(n)) = (
            self.block_sum.get_mut(i),
            self.block_n.get_mut(i),
            self.sum.get_mut(i),
            self.n.get_mut(i),
        ) else {
            return;
        };
        if !(a > T::zero() && rf.finite()) {
            return;
        }
        *bs += rf / a.sqrt_fast();
        *bn += 1;
        if *bn >= len.max(1) {
            let l = T::lit(f64::from(*bn));
            *s += (*bs * *bs / l).min(T::lit(100.0));
            *n += T::one();
            *bs = T::zero();
            *bn = 0;
        }
    }

    /// A step the statistics may not take (a health flag, a hold-off, a
    /// rejected epoch): the partial blocks are dropped, so a block is always
    /// a run of consecutive healthy epochs.
    pub(super) fn break_blocks(&mut self) {
        self.block_sum = [T::zero(); NZ];
        self.block_n = [0; NZ];
    }

    /// Learning starts (again): everything learned so far is dropped.
    pub(super) fn reset(&mut self) {
        *self = Self::new();
    }

    /// At monitoring start: the factor is what the data prove of the mean
    /// block statistic over its white-noise value 1 (a block mean of
    /// normal errors gives χ²₁: variance 2), i.e. the one-sided 97.7 %
    /// lower bound `mean − 2·√(2/n)`, clamped to `[1, max]`: sampling noise
    /// of a short learning phase on consistent data gives 1, and a fault
    /// present during learning cannot switch detection off. Fewer than 4
    /// blocks: 1.
    pub(super) fn freeze(&mut self, max: T) {
        // Once per learning phase: rolled.
        for ((c, s), n) in rolled_mut(&mut self.factor)
            .iter_mut()
            .zip(rolled(&self.sum))
            .zip(rolled(&self.n))
        {
            keep_rolled();
            *c = if *n >= T::lit(4.0) {
                let lower = *s / *n - T::lit(2.0) * (T::lit(2.0) / *n).sqrt_fast();
                lower.max(T::one()).min(max.max(T::one()))
            } else {
                T::one()
            };
        }
    }
}

#[cfg(all(
    test,
    any(feature = "attitude-rate-test", feature = "velocity-increment-test")
))]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
    use super::*;
    use crate::monitor::block_test::test_noise::Noise;

    /// The factor learnt on component 0 from `n` innovations made by
    /// `gen`, each with predicted variance 1, in blocks of `len`.
    fn learn(n: usize, len: u16, max: f64, mut gen: impl FnMut() -> f64) -> f64 {
        let mut inf = Inflation::<f64>::new();
        for _ in 0..n {
            inf.observe(0, gen(), 1.0, len);
        }
        inf.freeze(max);
        inf.factor()[0]
    }

    #[test]
    fn consistent_innovations_learn_no_inflation() {
        let mut g = Noise(7);
        assert_eq!(learn(2000, 10, 25.0, || g.gauss()), 1.0);
    }

    #[test]
    fn innovations_three_times_too_large_learn_their_variance() {
        let mut g = Noise(11);
        let c = learn(2000, 10, 25.0, || 3.0 * g.gauss());
        assert!((7.0..9.5).contains(&c), "{c}");
        // Bounded: a fault during learning cannot switch detection off.
        let mut g = Noise(11);
        assert_eq!(learn(2000, 10, 4.0, || 3.0 * g.gauss()), 4.0);
    }

    /// Unit-variance AR(1) errors (φ = 0.9): each epoch looks consistent,
    /// a block mean does not; only the blocks see it.
    #[test]
    fn time_correlation_shows_over_blocks_only() {
        let ar = |seed: u64| {
            let mut g = Noise(seed);
            let mut x = 0.0;
            move || {
                x = 0.9 * x + (1.0f64 - 0.81).sqrt() * g.gauss();
                x
            }
        };
        let per_epoch = learn(4000, 1, 25.0, ar(3));
        let blocks = learn(4000, 10, 25.0, ar(3));
        assert!(per_epoch < 1.2, "{per_epoch}");
        assert!(blocks > 3.0, "{blocks}");
    }

    #[test]
    fn broken_blocks_and_short_learning_keep_one() {
        let mut inf = Inflation::<f64>::new();
        // 30 large epochs, the block broken every 9: no block completes.
        for k in 0..30 {
            if k % 9 == 8 {
                inf.break_blocks();
            }
            inf.observe(0, 5.0, 1.0, 10);
        }
        inf.freeze(25.0);
        assert_eq!(inf.factor()[0], 1.0);
    }
}

//! The tail of the window deviations the flight shows: each length's
//! learnt excess kurtosis and the Cornish–Fisher widening of the
//! threshold it calls for.
//!
//! **Why.** The threshold is the Student-t quantile of the design
//! per-decision probability: it allows for the learnt variance's own
//! uncertainty, but takes the standardized window deviations to be
//! Gaussian. On log171 they are not: the velocity test's 2/5/10-s windows
//! (UKF, fault-free, starts 60–100 s) crossed their thresholds 15 times
//! where ≈ 4.4 were expected at the design rate — a heavier tail than a
//! Gaussian's, which sharpening the learnt variance only makes worse.
//!
//! **What.** The windows' squared standardized deviations `e = d²/h`
//! (as `q_w` learns them, learn.rs) and their squares are summed with
//! the same gating and forgetting, once the offset rests on two longest
//! windows of blocks (the condition for judging: before it the offset
//! moves, and windows measured about an unsettled one — a 60-s weave
//! with Gaussian noise: excess kurtosis beyond 8 — say nothing of the
//! tail); the sample excess kurtosis is `κ̂ = n·Σe²/(Σe)² − 3`. Like the reddening factor it is a posterior: a
//! Gaussian prior (`κ = 0`) worth `prior_windows` windows, updated by the
//! `1.5·n/L` independent windows the overlapping ones count (Meketon &
//! Schmeiser 1984): a few windows cannot claim a tail. The threshold is
//! then widened by the fourth-order Cornish–Fisher expansion of the
//! quantile with that kurtosis and no skew (Cornish & Fisher 1937; the
//! "modified VaR" of Zangari 1996 and Favre & Galeano 2002):
//! `z_κ = z + κ(z³ − 3z)/24`, i.e. the t threshold times
//! `1 + κ(z² − 3)/24` at the normal quantile `z` of the design
//! probability. `κ` is kept within `[0, 8]`, where that expansion is
//! monotone — a bijection onto the quantiles (Maillard 2012, zero skew):
//! a thinner tail than a Gaussian's never narrows the threshold (the
//! t quantile already allows for the estimate), and beyond 8 the
//! expansion is no quantile at all.

use nalgebra::Vector3;

use super::*;

/// Upper bound of the excess kurtosis where the zero-skew Cornish–Fisher
/// expansion is monotone (Maillard 2012).
const CF_MAX_KURTOSIS: f64 = 8.0;

/// Per channel, one length's learnt tail sums: weight, `Σe` and `Σe²` of
/// the squared standardized window deviations `e`.
#[derive(Debug, Clone, Copy)]
pub(super) struct TailSums<T> {
    n: Vector3<T>,
    s1: Vector3<T>,
    s2: Vector3<T>,
}

impl<T: Real> Default for TailSums<T> {
    fn default() -> Self {
        Self {
            n: Vector3::zeros(),
            s1: Vector3::zeros(),
            s2: Vector3::zeros(),
        }
    }
}

impl<T: Real> TailSums<T> {
    /// Learns one window's squared standardized deviation `e` on channel
    /// `c`, forgetting with `keep`.
    pub(super) fn learn(&mut self, c: usize, e: T, keep: T) {
        if let (Some(n), Some(s1), Some(s2)) =
            (self.n.get_mut(c), self.s1.get_mut(c), self.s2.get_mut(c))
        {
            *n = *n * keep + T::one();
            *s1 = *s1 * keep + e;
            *s2 = *s2 * keep + e * e;
        }
    }

    /// The sample excess kurtosis of channel `c` and its weight in
    /// windows (`None` before two windows).
    fn kurtosis(&self, c: usize) -> Option<(T, T)> {
        let (n, s1, s2) = (*self.n.get(c)?, *self.s1.get(c)?, *self.s2.get(c)?);
        (n > T::one() && s1 > T::zero()).then(|| (n * s2 / (s1 * s1) - T::lit(3.0), n))
    }
}

impl<T: Real> BlockTest<T> {
    /// The posterior excess kurtosis of length `k`'s standardized window
    /// deviations on channel `c` (module notes; 0 before two windows).
    pub(super) fn window_kurtosis(&self, cfg: &BlockTestConfig<T>, k: usize, c: usize) -> T {
        let (Some(len), Some((kappa, n))) = (
            cfg.lengths.get(k),
            self.tail.get(k).and_then(|t| t.kurtosis(c)),
        ) else {
            return T::zero();
        };
        let n_eff = n * T::lit(OBM_DOF) / T::lit(f64::from(*len));
        let post = n_eff * kappa / (cfg.prior_windows + n_eff);
        post.fmax(T::zero()).fmin(T::lit(CF_MAX_KURTOSIS))
    }

    /// The Cornish–Fisher factor widening length `k`'s threshold on
    /// channel `c` for the learnt kurtosis: `1 + κ(z² − 3)/24`.
    pub(super) fn tail_factor(&self, cfg: &BlockTestConfig<T>, k: usize, c: usize) -> T {
        let z2 = self.z_design * self.z_design;
        T::one() + self.window_kurtosis(cfg, k, c) * (z2 - T::lit(3.0)) / T::lit(24.0)
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_noise::Noise;
    use super::*;

    /// The learnt kurtosis of `count` deviations drawn by `draw`.
    fn learnt(mut draw: impl FnMut() -> f64, count: usize) -> f64 {
        let mut t = TailSums::<f64>::default();
        for _ in 0..count {
            let d = draw();
            t.learn(0, d * d, 1.0);
        }
        t.kurtosis(0).map_or(f64::NAN, |(k, _)| k)
    }

    #[test]
    fn the_learnt_kurtosis_is_the_deviations_excess_kurtosis() {
        let mut n = Noise(7);
        // Gaussian: 0 (sd of the estimate at 20,000 samples: 0.035).
        let gauss = learnt(|| n.gauss(), 20_000);
        assert!(gauss.abs() < 0.15, "gaussian {gauss}");
        // A scale mixture (sd 1 or 3, equally likely): E d⁴ / (E d²)² =
        // 3·(1 + 81)/2 / 25 = 4.92, excess 1.92.
        let mut k = 0u32;
        let mix = learnt(
            || {
                k += 1;
                n.gauss() * if k.is_multiple_of(2) { 1.0 } else { 3.0 }
            },
            20_000,
        );
        assert!((mix - 1.92).abs() < 0.3, "mixture {mix}");
    }
}

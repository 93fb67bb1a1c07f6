//! How the parity residual's variance follows the vibration the IMUs see.
//!
//! On log171 the residual left after the relative calibration is far from
//! homoscedastic: blocks in the quietest tenth of the flight (by the
//! sensors' own within-block spread) carry about 0.4 of the average
//! residual energy, blocks in the loudest tenth 3.6 (gyro; accelerometer
//! 0.6 and 2.7). One covariance for the whole flight is then too wide in
//! calm flight (lost sensitivity) and too narrow in vibration bursts (the
//! heavy tails that made the false alarms of the realistic profile: the
//! kurtosis of the 2.5-s window means is 7.0 for the gyros, 4.8 for the
//! accelerometers). Dividing each block residual by `√ŝ(x)`, with `ŝ`
//! the residual energy predicted from the block's vibration level `x`,
//! brings those kurtoses to 4.8 and 3.4; the window tests, their learned
//! covariances and thresholds then run on the standardised residuals.
//!
//! `ŝ(x) = a + c x` is fitted by least squares to the block energies
//! `rᵀ Σ_b⁻¹ r / dim` — first on the training blocks, then, like the
//! covariances, with an exponential memory on the blocks the tests judged
//! quiet. A bias fault does not change the within-block spread, so the
//! model cannot absorb one; the fitted energy is clipped so a single wild
//! block cannot tilt it, and `ŝ` is bounded to a decade either side of the
//! flight's average so no block is trusted or discounted without limit.

use crate::math::Real;

/// Largest block energy (in units of the average) one block contributes
/// to the fit: χ²(dim)/dim beyond 30 is never noise for dim ≥ 2.
const ENERGY_CLIP: f64 = 30.0;
/// Bounds of `ŝ` relative to the flight's average residual energy.
const SCALE_MIN: f64 = 0.1;
/// See [`SCALE_MIN`].
const SCALE_MAX: f64 = 10.0;

/// Exponentially weighted moments of (vibration level `x`, block energy
/// `m`) and the line `ŝ(x) = a + c x` they give.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct VibrationScale<T> {
    /// Weighted means of `x`, `x²`, `m` and `x m`.
    mx: T,
    mxx: T,
    mm: T,
    mxm: T,
    /// Fitted intercept and slope.
    a: T,
    c: T,
}

impl<T: Real> Default for VibrationScale<T> {
    /// `ŝ ≡ 1`: no standardisation until something is learned.
    fn default() -> Self {
        Self {
            mx: T::zero(),
            mxx: T::zero(),
            mm: T::one(),
            mxm: T::zero(),
            a: T::one(),
            c: T::zero(),
        }
    }
}

impl<T: Real> VibrationScale<T> {
    /// The predicted relative residual energy at vibration level `x`.
    pub(super) fn predict(&self, x: T) -> T {
        let s = self.a + self.c * x;
        if !s.finite() {
            return T::one();
        }
        s.max(T::lit(SCALE_MIN)).min(T::lit(SCALE_MAX))
    }

    /// Fits the line to training blocks `(x, m)` from scratch.
    pub(super) fn fit<I: Iterator<Item = (T, T)> + Clone>(&mut self, blocks: I) {
        let n = blocks.clone().count();
        if n < 2 {
            *self = Self::default();
            return;
        }
        let w = T::one() / T::lit(n as f64);
        // Clip relative to the plain mean energy of the training blocks.
        let mean = blocks
            .clone()
            .filter(|(x, m)| x.finite() && m.finite())
            .fold(T::zero(), |acc, (_, m)| acc + m * w);
        let clip = T::lit(ENERGY_CLIP) * mean.max(T::lit(1e-6));
        *self = Self {
            mx: T::zero(),
            mxx: T::zero(),
            mm: T::zero(),
            mxm: T::zero(),
            ..Self::default()
        };
        for (x, m) in blocks {
            self.accumulate(x, m, w, clip);
        }
        self.solve();
    }

    /// Adds one quiet block with weight `w` (the covariances' EWMA weight)
    /// and refits.
    pub(super) fn learn(&mut self, x: T, m: T, w: T) {
        let keep = T::one() - w;
        self.mx *= keep;
        self.mxx *= keep;
        self.mm *= keep;
        self.mxm *= keep;
        let clip = T::lit(ENERGY_CLIP) * self.mm.max(T::lit(1e-6));
        self.accumulate(x, m, w, clip);
        self.solve();
    }

    /// One block's moments with weight `w`, its energy clipped to `clip`.
    fn accumulate(&mut self, x: T, m: T, w: T, clip: T) {
        if !(x.finite() && m.finite()) {
            return;
        }
        let m = m.max(T::zero()).min(clip);
        self.mx += w * x;
        self.mxx += w * x * x;
        self.mm += w * m;
        self.mxm += w * x * m;
    }

    /// Least squares of `m` on `[1, x]` from the moments; a flat line when
    /// the levels do not vary (then `ŝ` is the mean energy).
    fn solve(&mut self) {
        let var = self.mxx - self.mx * self.mx;
        let cov = self.mxm - self.mx * self.mm;
        // Relative floor: levels that vary by less than a millionth of
        // their size carry no slope information.
        let floor = T::lit(1e-6) * self.mxx.abs() + T::lit(1e-30);
        let c = if var > floor { cov / var } else { T::zero() };
        let a = self.mm - c * self.mx;
        if a.finite() && c.finite() {
            self.a = a;
            self.c = c;
        }
    }

    /// Mean predicted energy over the fitted levels (≈ 1 after training).
    #[cfg(test)]
    pub(super) fn mean_energy(&self) -> T {
        self.mm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_linear_energy_law_and_bounds_it() {
        // Energies exactly 0.5 + 2x on levels 0..1: the fit is exact.
        let blocks = (0..50).map(|i| {
            let x = f64::from(i) / 49.0;
            (x, 0.5 + 2.0 * x)
        });
        let mut s = VibrationScale::<f64>::default();
        s.fit(blocks);
        assert!((s.predict(0.0) - 0.5).abs() < 1e-9);
        assert!((s.predict(1.0) - 2.5).abs() < 1e-9);
        assert!((s.mean_energy() - 1.5).abs() < 1e-9);
        // Far outside the levels seen: bounded to a decade.
        assert_eq!(s.predict(100.0), SCALE_MAX);
        assert_eq!(s.predict(-100.0), SCALE_MIN);
    }

    #[test]
    fn constant_levels_give_the_mean_energy() {
        let mut s = VibrationScale::<f64>::default();
        s.fit((0..20).map(|i| (3.0, if i % 2 == 0 { 0.8 } else { 1.2 })));
        assert!((s.predict(3.0) - 1.0).abs() < 1e-9);
        assert!((s.predict(7.0) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn one_wild_block_moves_the_fit_by_a_bounded_amount() {
        let mut s = VibrationScale::<f64>::default();
        s.fit((0..100).map(|i| (f64::from(i % 10), 1.0)));
        s.learn(5.0, 1e9, 0.01);
        // Clipped to 30× the mean energy: the mean moves by at most 0.3.
        assert!(s.predict(5.0) < 1.35, "{}", s.predict(5.0));
        s.learn(f64::NAN, 1.0, 0.01);
        assert!(s.predict(5.0).is_finite());
    }
}

use crate::math::Real;

/// Scaled sigma-point parameters (Van der Merwe): `λ = α²(n+κ) − n`.
///
/// The default `α = 1, β = 2, κ = 0` gives `λ = 0`, so `W₀ᵐ = 0`,
/// `W₀ᶜ = 2` and every other weight `1/(2n)`: all weights are O(1) and the
/// sigma offsets are `√n·σ`, far from the `f32` rounding step of a 200 m/s
/// state. A tiny α (1e-3, common in textbooks) makes `W₀` ≈ −1e6 and the
/// weighted sums cancel catastrophically in `f32`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SigmaParams {
    /// Spread α (> 0).
    pub alpha: f64,
    /// Prior-distribution parameter β (2 is optimal for Gaussians).
    pub beta: f64,
    /// Secondary scaling κ.
    pub kappa: f64,
}

impl Default for SigmaParams {
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 2.0,
            kappa: 0.0,
        }
    }
}

/// Weights of the `S = 2n + 1` sigma points and the spread factor `√(n+λ)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SigmaWeights<T, const S: usize> {
    /// Mean weights.
    pub wm: [T; S],
    /// Covariance weights.
    pub wc: [T; S],
    /// `√(n + λ)`.
    pub gamma: T,
}

impl<T: Real, const S: usize> SigmaWeights<T, S> {
    /// Weights for `n = (S − 1)/2` states. Returns `None` for parameters that
    /// give `n + λ ≤ 0` (no real sigma spread).
    pub fn new(p: &SigmaParams) -> Option<Self> {
        let n = ((S - 1) / 2) as f64;
        let lambda = p.alpha * p.alpha * (n + p.kappa) - n;
        let c = n + lambda;
        if c.is_nan() || c <= 0.0 || p.alpha.is_nan() || p.alpha <= 0.0 {
            return None;
        }
        let wi = 1.0 / (2.0 * c);
        let mut wm = [T::lit(wi); S];
        let mut wc = [T::lit(wi); S];
        if let (Some(m0), Some(c0)) = (wm.first_mut(), wc.first_mut()) {
            *m0 = T::lit(lambda / c);
            *c0 = T::lit(lambda / c + 1.0 - p.alpha * p.alpha + p.beta);
        }
        Some(Self {
            wm,
            wc,
            gamma: T::lit(libm::sqrt(c)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_weights_sum_to_one() {
        let w = SigmaWeights::<f64, 13>::new(&SigmaParams::default()).unwrap();
        assert!((w.wm.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(w.wc[0], 2.0);
        assert!((w.gamma - 6f64.sqrt()).abs() < 1e-15);
        let bad = SigmaParams {
            alpha: 0.1,
            beta: 2.0,
            kappa: -7.0,
        };
        assert!(SigmaWeights::<f64, 13>::new(&bad).is_none());
    }
}

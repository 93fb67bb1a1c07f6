use super::WindowStats;
use crate::math::Real;
use crate::stats::{student_t_upper_quantile, StatsError};

/// `T = √n · mean / s`. A window with zero spread and non-zero mean (a frozen
/// aiding sensor, or quantised data) returns ±`T::max_value()`-like large
/// values rather than infinity; zero spread and zero mean returns 0.
pub fn t_statistic<T: Real>(s: &WindowStats<T>) -> T {
    let sqrt_n = T::lit(s.n as f64).sqrt_fast();
    if s.std > T::zero() {
        sqrt_n * s.mean / s.std
    } else if s.mean == T::zero() {
        T::zero()
    } else {
        let big = T::lit(1e30);
        if s.mean > T::zero() {
            big
        } else {
            -big
        }
    }
}

/// The windowed one-sample t-test of \[UKF\] §3 with its quantile computed at
/// configuration time.
///
/// `alpha` is the probability of one tail: the two-sided test (a flag of
/// either sign) has size `2α` per window under the fault-free hypothesis of
/// independent Gaussian innovations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TTest<T> {
    /// Per-tail significance level.
    pub alpha: f64,
    /// Window length the quantile was computed for.
    pub n: usize,
    /// The critical value `t_α(n − 1)`.
    pub threshold: T,
}

impl<T: Real> TTest<T> {
    /// Computes `t_α(n − 1)` for a window of `n` samples.
    pub fn new(alpha: f64, n: usize) -> Result<Self, StatsError> {
        if n < 3 {
            return Err(StatsError::DegreesOfFreedom);
        }
        let t = student_t_upper_quantile(alpha, (n - 1) as f64)?;
        Ok(Self {
            alpha,
            n,
            threshold: T::lit(t),
        })
    }

    /// −1, 0 or +1: the sign of a significant window mean.
    pub fn flag(&self, stat: T) -> i8 {
        if stat >= self.threshold {
            1
        } else if stat <= -self.threshold {
            -1
        } else {
            0
        }
    }
}

//! χ² tail and quantile for integer degrees of freedom (closed forms), and
//! the CUSUM threshold for a target in-control run length.

use super::StatsError;

/// Upper tail `P(χ²_ν > x)` for integer `ν ≥ 1`, from the closed forms
/// (even ν: Poisson sum; odd ν: normal tail plus a finite series).
pub fn chi_square_upper_tail(x: f64, nu: u32) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 || nu == 0 {
        return 1.0;
    }
    let half = 0.5 * x;
    if nu.is_multiple_of(2) {
        let mut term = 1.0;
        let mut sum = 1.0;
        for i in 1..nu / 2 {
            term *= half / f64::from(i);
            sum += term;
        }
        (libm::exp(-half) * sum).min(1.0)
    } else {
        let r = libm::sqrt(x);
        let tail = libm::erfc(r / core::f64::consts::SQRT_2);
        let pdf = libm::exp(-half) / libm::sqrt(2.0 * core::f64::consts::PI);
        let mut term = r;
        let mut sum = 0.0;
        for k in 1..=(nu - 1) / 2 {
            if k > 1 {
                term *= x / f64::from(2 * k - 1);
            }
            sum += term;
        }
        (tail + 2.0 * pdf * sum).min(1.0)
    }
}

/// `x` with `P(χ²_ν > x) = alpha`, by bisection on the log tail.
pub fn chi_square_upper_quantile(alpha: f64, nu: u32) -> Result<f64, StatsError> {
    if alpha.is_nan() || alpha <= 0.0 || alpha >= 1.0 {
        return Err(StatsError::Probability);
    }
    if nu == 0 {
        return Err(StatsError::DegreesOfFreedom);
    }
    let (mut lo, mut hi) = (0.0_f64, 10.0_f64);
    while chi_square_upper_tail(hi, nu) > alpha {
        hi *= 2.0;
        if hi > 1e6 {
            return Err(StatsError::Probability);
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if libm::log(chi_square_upper_tail(mid, nu)) > libm::log(alpha) {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-12 * hi {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Siegmund's approximation of the average run length of a one-sided CUSUM
/// `g ← max(0, g + s − κ)`, alarm at `g > h`, for `s ~ N(μ, 1)`.
pub fn cusum_run_length(mu: f64, kappa: f64, h: f64) -> f64 {
    let delta = mu - kappa;
    let b = h + 1.166;
    if libm::fabs(delta) < 1e-9 {
        return b * b;
    }
    (libm::exp(-2.0 * delta * b) + 2.0 * delta * b - 1.0) / (2.0 * delta * delta)
}

/// CUSUM threshold `h` whose in-control run length (μ = 0) is `arl0`
/// decisions, for reference value `κ > 0`.
///
/// Siegmund's ARL0 is `(eʸ − y − 1)/(2κ²)` with `y = 2κ(h + 1.166)`, so
/// `y` solves the convex `eʸ − y − 1 = 2κ²·ARL0`. Newton's method from
/// the upper bound `ln(1 + c) + 1` decreases monotonically onto the root in
/// a handful of steps (a few `exp` calls: cheap enough to rederive the
/// thresholds when the sensor set changes in flight).
pub fn cusum_threshold(kappa: f64, arl0: f64) -> Result<f64, StatsError> {
    if kappa.is_nan() || kappa <= 0.0 || arl0.is_nan() || arl0 <= 1.0 {
        return Err(StatsError::Probability);
    }
    let c = 2.0 * kappa * kappa * arl0;
    if !c.is_finite() {
        return Err(StatsError::Probability);
    }
    let mut y = libm::log1p(c) + 1.0;
    for _ in 0..60 {
        let e = libm::exp(y);
        let step = (e - y - 1.0 - c) / (e - 1.0);
        y -= step;
        if step.abs() <= 1e-12 * y {
            break;
        }
    }
    Ok((y / (2.0 * kappa) - 1.166).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi_square_quantiles_match_tables() {
        // Standard table values (e.g. NIST/SEMATECH e-Handbook, table 1.3.6.7.4).
        let table = [
            (0.05, 1, 3.841),
            (0.01, 2, 9.210),
            (0.001, 3, 16.266),
            (0.05, 4, 9.488),
            (0.001, 5, 20.515),
            (0.01, 6, 16.812),
        ];
        for (alpha, nu, want) in table {
            let x = chi_square_upper_quantile(alpha, nu).unwrap();
            assert!(
                (x - want).abs() < 2e-3,
                "χ²({nu}) at {alpha}: {x} vs {want}"
            );
        }
        assert!(chi_square_upper_quantile(0.0, 3).is_err());
        assert!(chi_square_upper_quantile(0.1, 0).is_err());
    }

    #[test]
    fn cusum_threshold_inverts_the_run_length() {
        let h = cusum_threshold(0.5, 1e5).unwrap();
        assert!((cusum_run_length(0.0, 0.5, h) / 1e5 - 1.0).abs() < 1e-9);
        for (kappa, arl0) in [(0.01, 1e9), (0.3, 50.0), (3.0, 1e12), (0.05, 2.0)] {
            let h = cusum_threshold(kappa, arl0).unwrap();
            let arl = cusum_run_length(0.0, kappa, h);
            assert!(
                (arl / arl0 - 1.0).abs() < 1e-9 || h == 0.0,
                "{kappa} {arl0}: {arl}"
            );
        }
        // Montgomery's table: κ = 0.5, h = 5 gives ARL0 ≈ 930 (Siegmund 938).
        assert!((cusum_run_length(0.0, 0.5, 5.0) - 938.0).abs() < 10.0);
        // ...and a 1σ shift is caught in ≈ 10 decisions.
        assert!((cusum_run_length(1.0, 0.5, 5.0) - 10.4).abs() < 0.5);
    }
}

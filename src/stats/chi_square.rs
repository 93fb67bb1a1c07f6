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

/// `x` with `P(χ²_ν > x) = alpha`.
///
/// Newton's method on `ln P(χ²_ν > x) − ln α` (derivative `−pdf/tail`)
/// from the Wilson–Hilferty cube-root approximation
/// `ν·(1 − 2/(9ν) + z·√(2/(9ν)))³` (Johnson, Kotz & Balakrishnan,
/// *Continuous Univariate Distributions* vol. 1, §18.8), safeguarded by
/// bisection on the bracket the iterates build: a handful of evaluations of
/// the closed-form tail where a bisection to 1e-12 took about forty (on the
/// M4F's software `f64`, the cone-array parity configuration went from
/// 2.6 M instructions to the figure in `docs/performance.md`).
pub fn chi_square_upper_quantile(alpha: f64, nu: u32) -> Result<f64, StatsError> {
    if alpha.is_nan() || alpha <= 0.0 || alpha >= 1.0 {
        return Err(StatsError::Probability);
    }
    if nu == 0 {
        return Err(StatsError::DegreesOfFreedom);
    }
    let k = f64::from(nu);
    // ln of the density's constant, 2^{−ν/2}/Γ(ν/2): once, not per step.
    let ln_c = -0.5 * k * core::f64::consts::LN_2 - libm::lgamma(0.5 * k);
    let ln_pdf = |x: f64| ln_c + (0.5 * k - 1.0) * libm::log(x) - 0.5 * x;
    let z = if alpha <= 0.5 {
        super::normal_upper_quantile(alpha)?
    } else {
        -super::normal_upper_quantile(1.0 - alpha)?
    };
    let s = 2.0 / (9.0 * k);
    let wh = 1.0 - s + z * libm::sqrt(s);
    let mut x = if wh > 0.0 { k * wh * wh * wh } else { 0.5 * k };
    let ln_alpha = libm::log(alpha);
    let (mut lo, mut hi) = (0.0_f64, f64::INFINITY);
    for _ in 0..200 {
        let tail = chi_square_upper_tail(x, nu);
        let g = libm::log(tail) - ln_alpha;
        if g > 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let step = g * tail / libm::exp(ln_pdf(x));
        // Quadratic convergence: a step of relative size 1e-8 leaves an
        // error of order 1e-16. (Tested before the bracket: at the root the
        // rounded `g` may already have closed the bracket onto `x`.)
        if step.abs() <= 1e-8 * x {
            return Ok(x + step);
        }
        let mut next = x + step;
        if !(next > lo && next < hi && next.is_finite()) {
            next = if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                2.0 * x.max(1.0)
            };
        }
        if next > 1e6 {
            return Err(StatsError::Probability);
        }
        if hi.is_finite() && hi - lo <= 1e-13 * hi {
            return Ok(next);
        }
        x = next;
    }
    Ok(x)
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

    /// The bisection this crate used before the Newton iteration (kept as
    /// the reference the faster root finder must reproduce).
    fn bisection(alpha: f64, nu: u32) -> f64 {
        let (mut lo, mut hi) = (0.0_f64, 10.0_f64);
        while chi_square_upper_tail(hi, nu) > alpha {
            hi *= 2.0;
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
        0.5 * (lo + hi)
    }

    #[test]
    fn chi_square_quantiles_match_high_precision_and_the_bisection() {
        // mpmath, 40 digits: gammainc(ν/2, x/2, ∞, regularized) = α.
        let reference = [
            (1e-9, 1, 37.324_893_051_362_33),
            (1e-9, 2, 41.446_531_673_892_82),
            (1e-9, 3, 44.841_275_330_562_4),
            (1e-9, 4, 47.879_455_731_147_95),
            (1e-9, 5, 50.692_193_701_543_03),
            (1e-9, 8, 58.307_613_127_485_63),
            (1e-6, 1, 23.928_126_976_934_83),
            (1e-6, 5, 35.888_186_879_672_87),
            (1e-3, 3, 16.266_236_196_238_13),
        ];
        for (alpha, nu, want) in reference {
            let x = chi_square_upper_quantile(alpha, nu).unwrap();
            assert!(
                (x / want - 1.0).abs() < 1e-12,
                "χ²({nu}) at {alpha}: {x} vs {want}"
            );
        }
        let mut worst = 0.0_f64;
        for nu in 1..=40 {
            let mut alpha = 0.9;
            while alpha > 1e-14 {
                let x = chi_square_upper_quantile(alpha, nu).unwrap();
                let b = bisection(alpha, nu);
                worst = worst.max((x / b - 1.0).abs());
                let back = chi_square_upper_tail(x, nu);
                assert!((back / alpha - 1.0).abs() < 1e-11, "{nu} {alpha}: {back}");
                alpha *= 0.13;
            }
        }
        assert!(
            worst < 1e-11,
            "worst relative difference to the bisection {worst:e}"
        );
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

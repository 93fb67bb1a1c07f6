//! 95 % confidence intervals for campaign tables.

use imu_fdi::stats::chi_square_upper_quantile;

/// z for a two-sided 95 % interval.
const Z95: f64 = 1.959_963_984_540_054;

/// Wilson score interval for `k` successes in `n` trials.
pub fn wilson_ci(k: u64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let z2 = Z95 * Z95;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = Z95 * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / (1.0 + z2 / n);
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Exact (Garwood) interval for a Poisson count `k`.
pub fn poisson_ci(k: u64) -> (f64, f64) {
    let lower = if k == 0 {
        0.0
    } else {
        chi_square_upper_quantile(0.975, (2 * k) as u32).map_or(f64::NAN, |x| x / 2.0)
    };
    let upper = chi_square_upper_quantile(0.025, (2 * k + 2) as u32).map_or(f64::NAN, |x| x / 2.0);
    (lower, upper)
}

/// Mean with a normal 95 % interval (mean, low, high); NaNs when empty.
pub fn mean_ci(v: &[f64]) -> (f64, f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    if v.len() < 2 {
        return (mean, mean, mean);
    }
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    let half = Z95 * (var / n).sqrt();
    (mean, mean - half, mean + half)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_match_textbook_values() {
        // Wilson 95 % for 8/10: [0.490, 0.943] (Newcombe 1998, table I).
        let (lo, hi) = wilson_ci(8, 10);
        assert!(
            (lo - 0.490).abs() < 1e-3 && (hi - 0.943).abs() < 1e-3,
            "{lo} {hi}"
        );
        // Garwood: k = 0 → [0, 3.689]; k = 5 → [1.623, 11.668].
        let (lo, hi) = poisson_ci(0);
        assert!(lo == 0.0 && (hi - 3.689).abs() < 1e-3, "{hi}");
        let (lo, hi) = poisson_ci(5);
        assert!(
            (lo - 1.623).abs() < 1e-3 && (hi - 11.668).abs() < 1e-3,
            "{lo} {hi}"
        );
        let (m, lo, hi) = mean_ci(&[1.0, 2.0, 3.0, 4.0]);
        assert!(
            (m - 2.5).abs() < 1e-12
                && (hi - m - Z95 * (5.0f64 / 12.0).sqrt()).abs() < 1e-12
                && lo < m
        );
    }
}

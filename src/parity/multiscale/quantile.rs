//! A closed-form Student-t quantile for thresholds that change with the
//! degrees of freedom while the covariances learn (no root search per
//! block on the MCU).

use crate::math::Real;

/// Upper quantile of Student's t with `nu` degrees of freedom from the
/// normal quantile `z` at the same probability: the Cornish–Fisher
/// expansion to `ν⁻⁴` (Abramowitz & Stegun 26.7.5).
pub(super) fn student_t_cornish_fisher<T: Real>(z: T, nu: T) -> T {
    let z2 = z * z;
    let z3 = z2 * z;
    let z5 = z3 * z2;
    let z7 = z5 * z2;
    let z9 = z7 * z2;
    let g1 = (z3 + z) / T::lit(4.0);
    let g2 = (T::lit(5.0) * z5 + T::lit(16.0) * z3 + T::lit(3.0) * z) / T::lit(96.0);
    let g3 = (T::lit(3.0) * z7 + T::lit(19.0) * z5 + T::lit(17.0) * z3 - T::lit(15.0) * z)
        / T::lit(384.0);
    let g4 = (T::lit(79.0) * z9 + T::lit(776.0) * z7 + T::lit(1482.0) * z5
        - T::lit(1920.0) * z3
        - T::lit(945.0) * z)
        / T::lit(92160.0);
    let u = T::one() / nu;
    z + u * (g1 + u * (g2 + u * (g3 + u * g4)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::{normal_upper_quantile, student_t_upper_quantile};

    #[test]
    fn matches_the_exact_quantile_where_it_is_used() {
        for alpha in [5e-7, 5e-6, 5e-4] {
            let z = normal_upper_quantile(alpha).unwrap();
            for nu in [12.0, 16.0, 24.0, 39.0, 48.0, 96.0, 500.0] {
                let exact = student_t_upper_quantile(alpha, nu).unwrap();
                let cf = student_t_cornish_fisher(z, nu);
                assert!(
                    (cf / exact - 1.0).abs() < 5e-3,
                    "{alpha} {nu}: {cf} vs {exact}"
                );
                // f32 on the target: same to 1e-5.
                let cf32 = student_t_cornish_fisher(z as f32, nu as f32);
                assert!((f64::from(cf32) / cf - 1.0).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn is_the_normal_quantile_in_the_limit() {
        let z = normal_upper_quantile(1e-6).unwrap();
        assert!((student_t_cornish_fisher(z, 1e9) - z).abs() < 1e-6);
    }
}

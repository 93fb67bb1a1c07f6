//! `f32` sine and cosine without `f64` arithmetic.
//!
//! Cody–Waite reduction by π/2 with a three-part constant, then the Cephes
//! single-precision minimax polynomials on [−π/4, π/4]. Maximum error against
//! `f64` is below 2e-7 for |x| ≤ 1e4 (tested); beyond that (never reached by
//! attitude angles, which are wrapped) an integer Payne–Hanek reduction
//! takes over, so no software-`f64` trigonometry is linked.

use super::Real;

const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
// π/2 split so that k·PIO2_1 and k·PIO2_2 are exact in f32 for |k| < 2^11.
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_513e-4;
const PIO2_3: f32 = 7.549_79e-8;
const REDUCTION_LIMIT: f32 = 1.0e4;

/// Returns `(sin x, cos x)` in single precision. NaN or infinite input gives NaN.
///
/// Not inlined: one copy instead of one per call site (≈ 0.8 KB of flash
/// on the MCU) for a call's few instructions.
#[inline(never)]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    let (k, y) = if x.abs() > REDUCTION_LIMIT {
        reduce_large(x)
    } else {
        let kf = x * FRAC_2_PI;
        // Round to nearest without libm: the cast truncates toward zero.
        let k = if kf >= 0.0 {
            (kf + 0.5) as i32
        } else {
            (kf - 0.5) as i32
        };
        let kr = k as f32;
        (k, ((x - kr * PIO2_1) - kr * PIO2_2) - kr * PIO2_3)
    };
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

/// 2/π to 256 bits, most significant word first (bit 1 of the fraction is
/// the top bit of the first word).
const TWO_OVER_PI: [u32; 8] = [
    0xA2F9_836E,
    0x4E44_1529,
    0xFC27_57D1,
    0xF534_DDC0,
    0xDB62_9599,
    0x3C43_9041,
    0xFE51_63AB,
    0xDEBB_C561,
];

/// Bit `i` (1-based, `2^-i`) of 2/π; zero outside the table.
fn two_over_pi_bit(i: i32) -> u128 {
    if i < 1 {
        return 0;
    }
    let i = (i - 1) as usize;
    TWO_OVER_PI
        .get(i / 32)
        .map_or(0, |w| u128::from((w >> (31 - i % 32)) & 1))
}

/// Payne–Hanek reduction of a large finite `x` (|x| ≥ 2¹³) by π/2 in
/// integer arithmetic: `(k mod 4, y)` with `x = k·π/2 + y`, |y| ≤ π/4.
/// Never reached by wrapped attitude angles; it replaces a software-`f64`
/// fallback (libm `rem_pio2`, ≈ 6 KB of flash) with a few hundred bytes.
#[cold]
#[inline(never)]
fn reduce_large(x: f32) -> (i32, f32) {
    let bits = x.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32;
    let m = u128::from((bits & 0x007f_ffff) | 0x0080_0000);
    // |x| = m·2^e; bits of 2/π from 2^(1−e) up contribute multiples of 4.
    let e = exp - 150;
    let start = e - 1;
    let mut window = 0u128;
    for j in 0..96 {
        window = (window << 1) | two_over_pi_bit(start + j);
    }
    // |x|·2/π = m·window·2^-94 (mod 4).
    let p = m * window;
    let frac_bits = 94;
    let mut q = ((p >> frac_bits) & 3) as i32;
    let mut f = (p & ((1u128 << frac_bits) - 1)) as i128;
    if f >= 1i128 << (frac_bits - 1) {
        f -= 1i128 << frac_bits;
        q += 1;
    }
    // f·2^-94 ∈ [−½, ½): keep 54 fractional bits, then scale by π/2.
    let v = (f >> (frac_bits - 54)) as i64;
    let y = v as f32 * (1.0 / (1u64 << 54) as f32) * core::f32::consts::FRAC_PI_2;
    if x < 0.0 {
        (-q, -y)
    } else {
        (q, y)
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
    fn large_arguments_reduce_exactly() {
        let mut worst = 0.0f64;
        for x in [
            1.0e4_f32, -1.0e4, 1.2345e4, 3.0e5, -7.77e6, 1.0e6, 1.0e9, 3.4e38, -2.5e20,
        ] {
            let (s, c) = sin_cos_f32(x);
            let xd = f64::from(x);
            worst = worst
                .max((f64::from(s) - libm::sin(xd)).abs())
                .max((f64::from(c) - libm::cos(xd)).abs());
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
// The negated compare is the point: NaN must fail the range test too.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn shift_sin_cos<T: Real>(s: T, c: T, d: T) -> Option<(T, T)> {
    // `|d| ≤ small` fails for NaN and ±∞ as well: one FPU compare for the
    // range and the finiteness (issue 17).
    if !(d.abs() <= T::small_angle()) {
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

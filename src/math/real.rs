use nalgebra::RealField;

/// The floating-point type a filter runs in.
///
/// `f32` is what the MCU runs; `f64` is the reference the `f32` build is
/// checked against. Beyond nalgebra's [`RealField`] it fixes *which*
/// implementation of the hot transcendental functions is used, because on a
/// Cortex-M4F `libm::sinf` computes in software `f64` (≈ 1,200 instructions)
/// while [`sin_cos_f32`](crate::math::sin_cos_f32) needs a few dozen.
pub trait Real: RealField + Copy + Default + core::fmt::Debug {
    /// Converts an `f64` constant (rounding for `f32`).
    fn lit(x: f64) -> Self;
    /// Widens to `f64` (exact for both implementations).
    fn to_f64(self) -> f64;
    /// Sine and cosine together; accurate to about one unit in the last place.
    fn sin_cos_fast(self) -> (Self, Self);
    /// Square root used by the filters' Cholesky factorisations.
    fn sqrt_fast(self) -> Self;
    /// True when the value is neither NaN nor infinite.
    fn finite(self) -> bool;
    /// Largest angle step `d` for which the series of
    /// [`shift_sin_cos`](crate::math::shift_sin_cos) (truncation `d⁶/720`)
    /// stays below this type's rounding error.
    fn small_angle() -> Self;
    /// The larger of `self` and `other` with C's `fmaxf` semantics: `other`
    /// when `self` is below it or NaN, else `self`. For `f32` this is the
    /// comparison the `fmaxf` that `f32::max` calls on the Cortex-M4F
    /// performs (FPv4 has no `vmaxnm`), inline: the call and its frame
    /// cost ≈ 10 instructions each, six to a dozen times a step (issue 17).
    /// For `f64` it is `f64::max`.
    fn fmax(self, other: Self) -> Self;
    /// The smaller of `self` and `other` with C's `fminf` semantics: `self`
    /// when it is below `other` or `other` is NaN, else `other`; inline
    /// for `f32` as [`fmax`](Self::fmax). For `f64` it is `f64::min`.
    fn fmin(self, other: Self) -> Self;
}

impl Real for f64 {
    #[inline]
    fn lit(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn sin_cos_fast(self) -> (Self, Self) {
        (libm::sin(self), libm::cos(self))
    }
    #[inline]
    fn sqrt_fast(self) -> Self {
        libm::sqrt(self)
    }
    #[inline]
    fn finite(self) -> bool {
        self.is_finite()
    }
    #[inline]
    fn small_angle() -> Self {
        // 0.005⁶/720 = 2e-17, below 2⁻⁵³.
        0.005
    }
    #[inline]
    fn fmax(self, other: Self) -> Self {
        self.max(other)
    }
    #[inline]
    fn fmin(self, other: Self) -> Self {
        self.min(other)
    }
}

impl Real for f32 {
    #[inline]
    fn lit(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn sin_cos_fast(self) -> (Self, Self) {
        super::sin_cos_f32(self)
    }
    #[inline]
    fn sqrt_fast(self) -> Self {
        super::sqrt_f32(self)
    }
    /// `|x| < ∞`: false for NaN and ±∞ like `is_finite`, but one FPU
    /// compare (`vabs`, `vcmp`) where `is_finite` moves the bits to a core
    /// register and tests the exponent (≈ 8 instructions on the
    /// Cortex-M4F; issue 17). Same answer for every input (tested).
    #[inline]
    fn finite(self) -> bool {
        self.abs() < f32::INFINITY
    }
    #[inline]
    fn small_angle() -> Self {
        // 0.1⁶/720 = 1.4e-9, below half an ulp of 1 (6e-8).
        0.1
    }
    #[inline]
    fn fmax(self, other: Self) -> Self {
        if self < other || self.is_nan() {
            other
        } else {
            self
        }
    }
    #[inline]
    fn fmin(self, other: Self) -> Self {
        if self < other || other.is_nan() {
            self
        } else {
            other
        }
    }
}

/// True when no element is NaN or infinite.
///
/// `x·0` is ±0 for every finite `x` and NaN for ±∞ and NaN, and a NaN
/// survives every sum, so the sum of `x·0` is zero exactly when all are
/// finite: one multiply and one add per element, without the compare and
/// branch per element of `iter().all(finite)` (the filters check 42 values
/// per step; issue 17). Same answer for every input (tested).
pub(crate) fn all_finite<T: Real>(v: &[T]) -> bool {
    let mut acc = T::zero();
    for x in v {
        acc += *x * T::zero();
    }
    acc == T::zero()
}

#[cfg(test)]
mod all_finite_tests {
    use super::all_finite;

    #[test]
    fn agrees_with_the_element_test() {
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            -3.0e38,
            f32::MAX,
            f32::MIN_POSITIVE,
            1e-45,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for a in specials {
            for b in specials {
                for c in specials {
                    let v = [a, b, c];
                    assert_eq!(all_finite(&v), v.iter().all(|x| x.is_finite()), "{v:?}");
                    let w = [f64::from(a), f64::from(b), f64::from(c)];
                    assert_eq!(all_finite(&w), w.iter().all(|x| x.is_finite()), "{w:?}");
                }
            }
        }
        assert!(all_finite::<f32>(&[]));
        for x in specials {
            assert_eq!(crate::math::Real::finite(x), x.is_finite(), "{x}");
        }
        // `fmax`/`fmin` are libm's `fmaxf`/`fminf` (what `f32::max`/`min`
        // call on the M4F) bit for bit, NaN for NaN.
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let more = [2.5f32, -2.5, 1e-38, -1e-38];
        for a in specials.iter().chain(more.iter()) {
            for b in specials.iter().chain(more.iter()) {
                let (a, b) = (*a, *b);
                let (m, n) = (crate::math::Real::fmax(a, b), crate::math::Real::fmin(a, b));
                assert!(same(m, libm::fmaxf(a, b)), "fmax({a}, {b}) = {m}");
                assert!(same(n, libm::fminf(a, b)), "fmin({a}, {b}) = {n}");
                if !(a == 0.0 && b == 0.0) {
                    assert!(same(m, a.max(b)), "fmax({a}, {b}) = {m}");
                    assert!(same(n, a.min(b)), "fmin({a}, {b}) = {n}");
                }
            }
        }
        // Every exponent and both signs, with a few mantissas.
        for bits in (0u32..=u32::MAX).step_by(65_521) {
            let x = f32::from_bits(bits);
            assert_eq!(crate::math::Real::finite(x), x.is_finite(), "{bits:#x}");
        }
    }
}

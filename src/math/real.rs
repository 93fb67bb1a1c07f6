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
        libm::sqrtf(self)
    }
    #[inline]
    fn finite(self) -> bool {
        self.is_finite()
    }
}

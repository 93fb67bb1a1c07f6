use super::Real;

/// 2π split as an exactly representable head (few mantissa bits, so `k·HEAD`
/// is exact for |k| < 2¹⁶ in `f32`) plus a tail, so that wrapping does not
/// add the `f32` rounding error of 2π (1.7e-7 rad) every time a sigma point
/// crosses ±π — which, near a heading of ±π, would bias the filter's mean by
/// that amount every step.
const TWO_PI_HEAD: f64 = 6.281_25;
const TWO_PI_TAIL: f64 = core::f64::consts::TAU - TWO_PI_HEAD;

/// Wraps an angle to (−π, π]. Non-finite input is returned unchanged so that
/// the caller's NaN check still sees it.
///
/// Only the range test is inlined: the reduction is rare (an angle crossing
/// ±π) and, inlined at each of the filter's dozens of call sites, cost
/// kilobytes of flash on the MCU (issue 17).
#[inline]
pub fn wrap_pi<T: Real>(a: T) -> T {
    let pi = T::pi();
    // Fast path first (the common case; NaN fails the comparison).
    if a > -pi && a <= pi {
        return a;
    }
    wrap_pi_reduce(a)
}

/// The reduction of [`wrap_pi`] for an angle outside (−π, π].
#[inline(never)]
fn wrap_pi_reduce<T: Real>(a: T) -> T {
    let pi = T::pi();
    if !a.finite() {
        return a;
    }
    let turns = (a / T::two_pi()).round();
    let mut w = (a - turns * T::lit(TWO_PI_HEAD)) - turns * T::lit(TWO_PI_TAIL);
    if w > pi {
        w = (w - T::lit(TWO_PI_HEAD)) - T::lit(TWO_PI_TAIL);
    } else if w <= -pi {
        w = (w + T::lit(TWO_PI_HEAD)) + T::lit(TWO_PI_TAIL);
    }
    w
}

/// [`wrap_pi`] for plain `f64` values (host tools, metrics).
#[inline]
pub fn wrap_pi_f64(a: f64) -> f64 {
    wrap_pi::<f64>(a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;

    #[test]
    fn wraps_into_half_open_interval() {
        assert_eq!(wrap_pi(PI), PI);
        assert!((wrap_pi(-PI) - PI).abs() < 1e-15);
        assert!((wrap_pi(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((wrap_pi(-7.0 * PI / 2.0) - PI / 2.0).abs() < 1e-12);
        assert!((wrap_pi(101.0_f64) - (101.0 - 32.0 * PI)).abs() < 1e-12);
        assert!(wrap_pi(f64::NAN).is_nan());
    }
}

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
    if !a.finite() {
        return a;
    }
    // One turn off (a sigma point or a step just across ±π, the usual
    // case): `turns = ±1` exactly, so the same two subtractions as below
    // without the division and rounding.
    let two_pi = T::two_pi();
    if a > T::zero() && a <= two_pi {
        return finish_wrap((a - T::lit(TWO_PI_HEAD)) - T::lit(TWO_PI_TAIL));
    }
    if a < T::zero() && a >= -two_pi {
        return finish_wrap((a + T::lit(TWO_PI_HEAD)) + T::lit(TWO_PI_TAIL));
    }
    let turns = (a / two_pi).round();
    finish_wrap((a - turns * T::lit(TWO_PI_HEAD)) - turns * T::lit(TWO_PI_TAIL))
}

/// The last correction of [`wrap_pi_reduce`]: the reduced angle may land a
/// rounding step outside (−π, π]. (One copy: three inlined ones cost flash
/// for a path that runs only when an angle crosses ±π.)
#[inline(never)]
fn finish_wrap<T: Real>(mut w: T) -> T {
    let pi = T::pi();
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

    /// The reduction as it was before the one-turn shortcut.
    fn by_turns<T: Real>(a: T) -> T {
        if (a > -T::pi() && a <= T::pi()) || !a.finite() {
            return a;
        }
        let turns = (a / T::two_pi()).round();
        finish_wrap((a - turns * T::lit(TWO_PI_HEAD)) - turns * T::lit(TWO_PI_TAIL))
    }

    #[test]
    fn one_turn_shortcut_is_bit_identical() {
        let mut n = 0;
        for k in -200_000..=200_000 {
            let a = k as f64 * 1.3e-4;
            assert_eq!(wrap_pi(a).to_bits(), by_turns(a).to_bits(), "{a}");
            let b = a as f32;
            assert_eq!(wrap_pi(b).to_bits(), by_turns(b).to_bits(), "{b}");
            n += 1;
        }
        // Around the edges of the shortcut, to the ulp.
        for edge in [PI, -PI, 2.0 * PI, -2.0 * PI] {
            let mut x = edge as f32;
            let mut y = edge;
            for _ in 0..64 {
                assert_eq!(wrap_pi(x).to_bits(), by_turns(x).to_bits(), "{x}");
                assert_eq!(wrap_pi(y).to_bits(), by_turns(y).to_bits(), "{y}");
                x = f32::from_bits(x.to_bits() + 1);
                y = f64::from_bits(y.to_bits() + 1);
            }
            let mut x = edge as f32;
            let mut y = edge;
            for _ in 0..64 {
                x = f32::from_bits(x.to_bits() - 1);
                y = f64::from_bits(y.to_bits() - 1);
                assert_eq!(wrap_pi(x).to_bits(), by_turns(x).to_bits(), "{x}");
                assert_eq!(wrap_pi(y).to_bits(), by_turns(y).to_bits(), "{y}");
            }
        }
        assert!(n > 400_000);
    }

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

use super::Real;

/// Wraps an angle to (−π, π]. Non-finite input is returned unchanged so that
/// the caller's NaN check still sees it.
#[inline]
pub fn wrap_pi<T: Real>(a: T) -> T {
    if !a.finite() {
        return a;
    }
    let pi = T::pi();
    let two_pi = T::two_pi();
    if a > -pi && a <= pi {
        return a;
    }
    let mut w = a % two_pi; // in (−2π, 2π)
    if w > pi {
        w -= two_pi;
    } else if w <= -pi {
        w += two_pi;
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

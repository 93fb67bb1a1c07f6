//! Rotations for the block tests: `exp` and `log` of SO(3) on
//! unit quaternions (exact at any angle, `log` by `atan2` so that small
//! angles keep their digits in `f32`), the inverse right Jacobian, and
//! ZYX Euler angles to a quaternion.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::math::Real;

/// `log(q)` as a rotation vector, by `atan2` (no `acos` near 1, which
/// loses half the digits of a small angle in `f32`).
#[cfg(feature = "attitude-rate-test")] // the gyro test's only
pub(crate) fn rotation_log<T: Real>(q: &UnitQuaternion<T>) -> Vector3<T> {
    let q = q.quaternion();
    // q and −q are the same rotation: take the short way.
    let (w, v) = if q.w < T::zero() {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let n = v.norm();
    if n <= T::zero() {
        return Vector3::zeros();
    }
    v * (T::lit(2.0) * n.atan2(w) / n)
}

/// `exp(θ)` of a rotation vector, exact for any angle.
pub(crate) fn rotation_exp<T: Real>(theta: &Vector3<T>) -> UnitQuaternion<T> {
    let a = theta.norm();
    let (s, c) = (a * T::lit(0.5)).sin_cos_fast();
    // sin(a/2)/a, by its series where a is tiny.
    let k = if a > T::lit(1e-4) {
        s / a
    } else {
        T::lit(0.5) - a * a / T::lit(48.0)
    };
    UnitQuaternion::new_unchecked(Quaternion::from_parts(c, theta * k))
}

/// `J_r(φ)⁻¹ v`, the inverse right Jacobian of SO(3): with `ΔR_g =
/// exp(φ + δ)` (a constant bias `δ/Δt` on a constant rate),
/// `log(exp(−φ) ΔR_g) = J_r(φ) δ + O(δ²)`, so this maps the residual back
/// to the bias exactly to first order at any rate (at 200 °/s over 0.1 s
/// `J_r` turns a bias by 10°).
#[cfg(feature = "attitude-rate-test")] // the gyro test's only
pub(crate) fn inverse_right_jacobian<T: Real>(phi: &Vector3<T>, v: &Vector3<T>) -> Vector3<T> {
    let th2 = phi.norm_squared();
    // 1/θ² − (1 + cos θ)/(2θ sin θ), by its series below 0.1 rad (the
    // closed form cancels there).
    let c = if th2 < T::lit(0.01) {
        T::lit(1.0 / 12.0) + th2 * (T::lit(1.0 / 720.0) + th2 * T::lit(1.0 / 30_240.0))
    } else {
        let th = th2.sqrt_fast();
        let (s, co) = th.sin_cos_fast();
        T::one() / th2 - (T::one() + co) / (T::lit(2.0) * th * s)
    };
    let pv = phi.cross(v);
    v + pv * T::lit(0.5) + phi.cross(&pv) * c
}

/// The body→NED rotation of ZYX Euler angles (roll, pitch, yaw).
pub(crate) fn from_euler<T: Real>(roll: T, pitch: T, yaw: T) -> UnitQuaternion<T> {
    let h = T::lit(0.5);
    let (sr, cr) = (roll * h).sin_cos_fast();
    let (sp, cp) = (pitch * h).sin_cos_fast();
    let (sy, cy) = (yaw * h).sin_cos_fast();
    UnitQuaternion::new_unchecked(Quaternion::new(
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ))
}

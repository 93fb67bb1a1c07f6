// Dense fixed-size kernel: every index below is a loop variable bounded by
// the matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

use super::{ImuVec, Mat6, StateVec, PITCH, ROLL, YAW};
use crate::math::{shift_sin_cos, wrap_pi, Real};

/// Why the model refused to evaluate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelError {
    /// |cos θ| fell below the configured limit: the Euler-angle model is
    /// singular near θ = ±90° and would produce huge rates or NaN.
    PitchSingularity,
    /// A state or input component was NaN or infinite.
    NonFinite,
}

/// Kinematics of a rigid vehicle with body-frame velocity and Euler attitude.
///
/// ```text
/// u̇ = v r − w q − g sinθ        + a_x
/// v̇ = −u r + w p + g cosθ sinφ  + a_y
/// ẇ = u q − v p + g cosθ cosφ   + a_z
/// φ̇ = p + (q sinφ + r cosφ) tanθ
/// θ̇ = q cosφ − r sinφ
/// ψ̇ = (q sinφ + r cosφ) / cosθ
/// ```
/// (\[UKF\] eq. (4) with its `a_zm` typo in the first line corrected.)
///
/// The discrete step is the explicit midpoint rule (RK2): the input is held
/// over the IMU period, and at 100 Hz with body rates below a few rad/s its
/// local error (O(dt³)) is orders of magnitude below the sensor noise, at half
/// the cost of RK4 on the MCU.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleModel<T> {
    /// Gravity magnitude, m/s².
    pub gravity: T,
    /// Smallest |cos θ| accepted (default 0.1, i.e. |θ| ≲ 84°).
    pub cos_pitch_min: T,
}

impl<T: Real> Default for VehicleModel<T> {
    fn default() -> Self {
        Self {
            gravity: T::lit(super::G0),
            cos_pitch_min: T::lit(0.1),
        }
    }
}

/// Sines and cosines of roll and pitch, evaluated once per attitude and
/// shared by the Jacobians of one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudeTrig<T> {
    sphi: T,
    cphi: T,
    sth: T,
    cth: T,
}

type Trig<T> = AttitudeTrig<T>;

impl<T: Real> VehicleModel<T> {
    fn trig(&self, x: &StateVec<T>) -> Result<Trig<T>, ModelError> {
        let (sphi, cphi) = x[ROLL].sin_cos_fast();
        let (sth, cth) = x[PITCH].sin_cos_fast();
        if !(sphi.finite() && sth.finite()) {
            return Err(ModelError::NonFinite);
        }
        if cth.abs() < self.cos_pitch_min {
            return Err(ModelError::PitchSingularity);
        }
        Ok(Trig {
            sphi,
            cphi,
            sth,
            cth,
        })
    }

    /// The attitude trigonometry of `x`, for [`jacobians`](Self::jacobians).
    pub fn attitude_trig(&self, x: &StateVec<T>) -> Result<AttitudeTrig<T>, ModelError> {
        self.trig(x)
    }

    /// Checks that an attitude is away from the Euler singularity.
    pub fn check_attitude(&self, x: &StateVec<T>) -> Result<(), ModelError> {
        self.trig(x).map(|_| ())
    }

    /// Continuous-time derivative `ẋ = f(x, u)`.
    pub fn derivative(&self, x: &StateVec<T>, u: &ImuVec<T>) -> Result<StateVec<T>, ModelError> {
        let t = self.trig(x)?;
        Ok(self.derivative_with(x, u, &t))
    }

    fn derivative_with(&self, x: &StateVec<T>, u: &ImuVec<T>, t: &Trig<T>) -> StateVec<T> {
        let g = self.gravity;
        let (vu, vv, vw) = (x[0], x[1], x[2]);
        let (p, q, r) = (u[3], u[4], u[5]);
        let qs_rc = q * t.sphi + r * t.cphi;
        StateVec::new(
            vv * r - vw * q - g * t.sth + u[0],
            -vu * r + vw * p + g * t.cth * t.sphi + u[1],
            vu * q - vv * p + g * t.cth * t.cphi + u[2],
            p + qs_rc * t.sth / t.cth,
            q * t.cphi - r * t.sphi,
            qs_rc / t.cth,
        )
    }

    /// One step of length `dt` (explicit midpoint), with roll and yaw wrapped
    /// to (−π, π].
    pub fn step(&self, x: &StateVec<T>, u: &ImuVec<T>, dt: T) -> Result<StateVec<T>, ModelError> {
        let t = self.trig(x)?;
        self.step_with(x, u, dt, &t)
    }

    /// [`step`](Self::step) of a state `x` near `near`, whose attitude
    /// trigonometry `t_near` is known ([`attitude_trig`](Self::attitude_trig)):
    /// the sines and cosines of `x`'s roll and pitch are shifted from
    /// `near`'s by the angle-addition formulas ([`shift_sin_cos`]) instead of
    /// evaluated — the sigma points of a predict are such states, a dozen
    /// instructions each instead of two range reductions and polynomials
    /// (issue 17). Equal to `step` to rounding; falls back to it when the
    /// difference is not small or the pitch nears the singularity.
    pub fn step_near(
        &self,
        x: &StateVec<T>,
        near: &StateVec<T>,
        t_near: &AttitudeTrig<T>,
        u: &ImuVec<T>,
        dt: T,
    ) -> Result<StateVec<T>, ModelError> {
        let t = match (
            shift_sin_cos(t_near.sphi, t_near.cphi, x[ROLL] - near[ROLL]),
            shift_sin_cos(t_near.sth, t_near.cth, x[PITCH] - near[PITCH]),
        ) {
            (Some((sphi, cphi)), Some((sth, cth)))
                if sphi.finite() && sth.finite() && cth.abs() >= self.cos_pitch_min =>
            {
                Trig {
                    sphi,
                    cphi,
                    sth,
                    cth,
                }
            }
            _ => self.trig(x)?,
        };
        self.step_with(x, u, dt, &t)
    }

    fn step_with(
        &self,
        x: &StateVec<T>,
        u: &ImuVec<T>,
        dt: T,
        t: &Trig<T>,
    ) -> Result<StateVec<T>, ModelError> {
        let t = *t;
        let k1 = self.derivative_with(x, u, &t);
        let h = dt * T::lit(0.5);
        let mid = x + k1 * h;
        // The midpoint attitude is a small step from x's: shift its sines and
        // cosines (≈ 100 fewer instructions per step on the Cortex-M4F than
        // evaluating them), unless the step is too large for the series.
        let tm = match (
            shift_sin_cos(t.sphi, t.cphi, k1[ROLL] * h),
            shift_sin_cos(t.sth, t.cth, k1[PITCH] * h),
        ) {
            (Some((sphi, cphi)), Some((sth, cth))) if cth.abs() >= self.cos_pitch_min => Trig {
                sphi,
                cphi,
                sth,
                cth,
            },
            _ => self.trig(&mid)?,
        };
        let k2 = self.derivative_with(&mid, u, &tm);
        let mut next = x + k2 * dt;
        next[ROLL] = wrap_pi(next[ROLL]);
        next[YAW] = wrap_pi(next[YAW]);
        if crate::math::all_finite(next.as_slice()) {
            Ok(next)
        } else {
            Err(ModelError::NonFinite)
        }
    }

    /// The states [`step`](Self::step) depends on nonlinearly come first in
    /// this order (roll, pitch), then those it is affine in (the body
    /// velocity, given the body rates, and the yaw, which enters only
    /// itself): the `order` of [`Ukf::predict_split`](crate::filter::Ukf::predict_split)
    /// with [`NONLINEAR_STATES`](Self::NONLINEAR_STATES) nonlinear states.
    pub const SPLIT_ORDER: [usize; 6] = [ROLL, PITCH, 0, 1, 2, YAW];
    /// How many leading states of [`SPLIT_ORDER`](Self::SPLIT_ORDER) enter
    /// the step nonlinearly.
    pub const NONLINEAR_STATES: usize = 2;

    /// `step(x + δ, u, dt) − step(x, u, dt)` for a deviation `δ` with zero
    /// roll and pitch, exactly (to rounding) for every `x`: the attitude
    /// rates depend on roll and pitch only, so the attitude path is
    /// unchanged and the yaw moves by `δψ`; the velocity equation is
    /// `v̇ = Ω v + g(φ, θ) + a` with `Ω = −[ω×]` set by the body rates, so
    /// the midpoint rule moves the velocity by `(I + Ω dt + Ω² dt²/2) δv`.
    pub fn step_deviation(&self, d: &StateVec<T>, u: &ImuVec<T>, dt: T) -> StateVec<T> {
        let (p, q, r) = (u[3], u[4], u[5]);
        let omega = |v: [T; 3]| {
            [
                v[1] * r - v[2] * q,
                v[2] * p - v[0] * r,
                v[0] * q - v[1] * p,
            ]
        };
        let h = dt * T::lit(0.5);
        let dv = [d[0], d[1], d[2]];
        let k1 = omega(dv);
        let k2 = omega([dv[0] + k1[0] * h, dv[1] + k1[1] * h, dv[2] + k1[2] * h]);
        let z = T::zero();
        StateVec::new(
            dv[0] + k2[0] * dt,
            dv[1] + k2[1] * dt,
            dv[2] + k2[2] * dt,
            z,
            z,
            d[YAW],
        )
    }

    /// State Jacobian `A = ∂f/∂x`.
    pub fn jacobian_state(&self, x: &StateVec<T>, u: &ImuVec<T>) -> Result<Mat6<T>, ModelError> {
        let t = self.trig(x)?;
        Ok(self.jacobian_state_with(u, &t))
    }

    /// Both Jacobians `(A, B)` from one evaluation of the attitude
    /// trigonometry.
    pub fn jacobians(
        &self,
        x: &StateVec<T>,
        u: &ImuVec<T>,
        t: &AttitudeTrig<T>,
    ) -> (Mat6<T>, Mat6<T>) {
        (
            self.jacobian_state_with(u, t),
            self.jacobian_input_with(x, t),
        )
    }

    fn jacobian_state_with(&self, u: &ImuVec<T>, t: &Trig<T>) -> Mat6<T> {
        let g = self.gravity;
        let (p, q, r) = (u[3], u[4], u[5]);
        let qs_rc = q * t.sphi + r * t.cphi;
        let qc_rs = q * t.cphi - r * t.sphi;
        let tan = t.sth / t.cth;
        let sec2 = T::one() / (t.cth * t.cth);
        let z = T::zero();
        #[rustfmt::skip]
        let a = Mat6::new(
            z,   r,   -q,  z,                      -g * t.cth,               z,
            -r,  z,   p,   g * t.cth * t.cphi,     -g * t.sth * t.sphi,      z,
            q,   -p,  z,   -g * t.cth * t.sphi,    -g * t.sth * t.cphi,      z,
            z,   z,   z,   qc_rs * tan,            qs_rc * sec2,             z,
            z,   z,   z,   -qs_rc,                 z,                        z,
            z,   z,   z,   qc_rs / t.cth,          qs_rc * t.sth * sec2,     z,
        );
        a
    }

    /// Input Jacobian `B = G = ∂f/∂u_m`; with the additive fault convention
    /// (`measured = true + f`) the fault-input matrix is `G_f = −B`.
    pub fn jacobian_input(&self, x: &StateVec<T>) -> Result<Mat6<T>, ModelError> {
        let t = self.trig(x)?;
        Ok(self.jacobian_input_with(x, &t))
    }

    /// [`jacobian_input`](Self::jacobian_input) at `x` with its attitude
    /// trigonometry `t` ([`attitude_trig`](Self::attitude_trig)) known: the
    /// same matrix as the second of [`jacobians`](Self::jacobians).
    pub(crate) fn jacobian_input_with(&self, x: &StateVec<T>, t: &Trig<T>) -> Mat6<T> {
        let (vu, vv, vw) = (x[0], x[1], x[2]);
        let tan = t.sth / t.cth;
        let o = T::one();
        let z = T::zero();
        #[rustfmt::skip]
        let b = Mat6::new(
            o, z, z, z,    -vw,             vv,
            z, o, z, vw,   z,               -vu,
            z, z, o, -vv,  vu,              z,
            z, z, z, o,    t.sphi * tan,    t.cphi * tan,
            z, z, z, z,    t.cphi,          -t.sphi,
            z, z, z, z,    t.sphi / t.cth,  t.cphi / t.cth,
        );
        b
    }

    /// `A X` for a state Jacobian `A` of this model (or a multiple of one),
    /// from its block structure `A = [Ω Γ; 0 Λ]`: the lower-left block is
    /// zero, `Ω = −[ω×]` is a cross-product matrix, and the third columns of
    /// `Γ` and `Λ` are zero (no derivative depends on the yaw). So 108
    /// multiply-adds instead of the 216 of the dense product (issue 17).
    /// Only those entries of `a` are read.
    pub fn mul_state_jacobian(a: &Mat6<T>, x: &Mat6<T>) -> Mat6<T> {
        // Ω = [w×] with w = (Ω₂₁, Ω₀₂, Ω₁₀).
        let (w0, w1, w2) = (a[(2, 1)], a[(0, 2)], a[(1, 0)]);
        let xa = x.fixed_view::<2, 6>(3, 0);
        let gx = a.fixed_view::<3, 2>(0, 3) * xa;
        let lx = a.fixed_view::<3, 2>(3, 3) * xa;
        let mut out = Mat6::zeros();
        for j in 0..6 {
            let (x0, x1, x2) = (x[(0, j)], x[(1, j)], x[(2, j)]);
            out[(0, j)] = w1 * x2 - w2 * x1 + gx[(0, j)];
            out[(1, j)] = w2 * x0 - w0 * x2 + gx[(1, j)];
            out[(2, j)] = w0 * x1 - w1 * x0 + gx[(2, j)];
            out[(3, j)] = lx[(0, j)];
            out[(4, j)] = lx[(1, j)];
            out[(5, j)] = lx[(2, j)];
        }
        out
    }

    /// Discrete transition matrix of one step, `Φ ≈ I + A dt + (A dt)²/2`.
    pub fn transition(&self, x: &StateVec<T>, u: &ImuVec<T>, dt: T) -> Result<Mat6<T>, ModelError> {
        let ad = self.jacobian_state(x, u)? * dt;
        Ok(Mat6::identity() + ad + ad * ad * T::lit(0.5))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn num_jac(
        m: &VehicleModel<f64>,
        x: &StateVec<f64>,
        u: &ImuVec<f64>,
        wrt_x: bool,
    ) -> Mat6<f64> {
        let mut j = Mat6::zeros();
        let h = 1e-6;
        for k in 0..6 {
            let (mut xp, mut xm, mut up, mut um) = (*x, *x, *u, *u);
            if wrt_x {
                xp[k] += h;
                xm[k] -= h;
            } else {
                up[k] += h;
                um[k] -= h;
            }
            let d = (m.derivative(&xp, &up).unwrap() - m.derivative(&xm, &um).unwrap()) / (2.0 * h);
            j.set_column(k, &d);
        }
        j
    }

    #[test]
    fn jacobians_match_finite_differences() {
        let m = VehicleModel::<f64>::default();
        let x = StateVec::new(2.0, 0.3, -0.2, 0.4, -0.3, 2.5);
        let u = ImuVec::new(0.5, -0.2, -9.5, 0.1, -0.2, 0.3);
        let a = m.jacobian_state(&x, &u).unwrap();
        let b = m.jacobian_input(&x).unwrap();
        assert!((a - num_jac(&m, &x, &u, true)).amax() < 1e-7);
        assert!((b - num_jac(&m, &x, &u, false)).amax() < 1e-7);
    }

    #[test]
    fn level_vehicle_at_rest_is_an_equilibrium() {
        let m = VehicleModel::<f64>::default();
        let x = StateVec::zeros();
        let u = ImuVec::new(0.0, 0.0, -super::super::G0, 0.0, 0.0, 0.0);
        assert!(m.derivative(&x, &u).unwrap().norm() < 1e-12);
    }

    #[test]
    fn singular_pitch_is_reported_not_nan() {
        let m = VehicleModel::<f32>::default();
        let x = StateVec::new(1.0, 0.0, 0.0, 0.0, core::f32::consts::FRAC_PI_2 - 1e-4, 0.0);
        assert_eq!(
            m.derivative(&x, &ImuVec::zeros()),
            Err(ModelError::PitchSingularity)
        );
        let n = StateVec::new(f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert_eq!(
            m.step(&n, &ImuVec::zeros(), 0.01),
            Err(ModelError::NonFinite)
        );
    }

    #[test]
    fn step_is_affine_in_velocity_and_yaw() {
        let m = VehicleModel::<f64>::default();
        let x = StateVec::new(2.0, 0.3, -0.2, 0.4, -0.3, 2.5);
        let u = ImuVec::new(0.5, -0.2, -9.5, 0.6, -0.8, 1.1);
        let y0 = m.step(&x, &u, 0.01).unwrap();
        for d in [
            StateVec::new(0.3, -0.2, 0.1, 0.0, 0.0, 0.05),
            StateVec::new(-5.0, 2.0, 7.0, 0.0, 0.0, -0.4),
        ] {
            let y = m.step(&(x + d), &u, 0.01).unwrap();
            let mut got = y - y0;
            got[YAW] = wrap_pi(got[YAW]);
            let want = m.step_deviation(&d, &u, 0.01);
            assert!((got - want).amax() < 1e-13, "{:e}", (got - want).amax());
        }
        for (i, s) in VehicleModel::<f64>::SPLIT_ORDER.iter().enumerate() {
            assert_eq!(
                i < VehicleModel::<f64>::NONLINEAR_STATES,
                [ROLL, PITCH].contains(s)
            );
        }
    }

    #[test]
    fn structured_jacobian_product_equals_the_dense_one() {
        let m = VehicleModel::<f64>::default();
        let x = StateVec::new(2.0, 0.3, -0.2, 0.4, -0.3, 2.5);
        let u = ImuVec::new(0.5, -0.2, -9.5, 0.6, -0.8, 1.1);
        let a = m.jacobian_state(&x, &u).unwrap();
        let y = Mat6::from_fn(|i, j| (i * 6 + j) as f64 * 0.1 - 1.7);
        let d = VehicleModel::mul_state_jacobian(&a, &y) - a * y;
        assert!(d.amax() < 1e-13, "{:e}", d.amax());
    }

    #[test]
    fn step_near_equals_step() {
        let m = VehicleModel::<f64>::default();
        let x = StateVec::new(2.0, 0.3, -0.2, 0.4, -0.3, 2.5);
        let u = ImuVec::new(0.5, -0.2, -9.5, 0.6, -0.8, 1.1);
        let t = m.attitude_trig(&x).unwrap();
        for d in [
            StateVec::zeros(),
            StateVec::new(0.3, -0.2, 0.1, 0.02, -0.03, 0.05),
            StateVec::new(0.0, 0.0, 0.0, 0.5, 0.4, 0.0),
        ] {
            for s in [x + d, x - d] {
                let got = m.step_near(&s, &x, &t, &u, 0.01).unwrap();
                let want = m.step(&s, &u, 0.01).unwrap();
                assert!((got - want).amax() < 1e-14, "{:e}", (got - want).amax());
            }
        }
        // Near the singularity, and for non-finite states, the same errors.
        let s = StateVec::new(1.0, 0.0, 0.0, 0.0, 1.5, 0.0);
        let near = StateVec::new(1.0, 0.0, 0.0, 0.0, 1.45, 0.0);
        let tn = m.attitude_trig(&near).unwrap();
        assert_eq!(
            m.step_near(&s, &near, &tn, &u, 0.01),
            Err(ModelError::PitchSingularity)
        );
        let n = StateVec::new(0.0, 0.0, 0.0, f64::NAN, 0.0, 0.0);
        assert_eq!(
            m.step_near(&n, &x, &t, &u, 0.01),
            Err(ModelError::NonFinite)
        );
    }

    #[test]
    fn step_wraps_yaw() {
        let m = VehicleModel::<f64>::default();
        let x = StateVec::new(0.0, 0.0, 0.0, 0.0, 0.0, core::f64::consts::PI - 0.005);
        let u = ImuVec::new(0.0, 0.0, -super::super::G0, 0.0, 0.0, 1.0);
        let n = m.step(&x, &u, 0.01).unwrap();
        assert!(n[YAW] < -3.0);
    }
}

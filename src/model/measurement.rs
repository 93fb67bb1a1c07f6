// Dense fixed-size kernel: every index below is a loop variable bounded by
// the matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

use nalgebra::{Matrix3, Vector3};

use super::{Mat6, MeasVec, StateVec, NZ, PITCH, ROLL, YAW};
use crate::math::Real;

/// Which aiding sensors provide the measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AidingKind {
    /// M1 (AUV, \[UKF\]): DVL body-frame velocity + compass/AHRS attitude,
    /// `z = [u, v, w, φ, θ, ψ]`.
    DvlCompass,
    /// M2 (aircraft, \[OTS\]): GNSS NED velocity + GNSS attitude,
    /// `z = [R_nb·v_body; φ; θ; ψ]`.
    GnssAttitude,
}

/// No lever arm: the velocity sensor sits at the IMU.
pub const LEVER_ARM_NONE: [f64; 3] = [0.0; 3];

/// The aiding measurement model `z = h(x) + ν`.
///
/// Measurement channels are `[vel_0, vel_1, vel_2, φ, θ, ψ]`; the velocity
/// triad is body-frame (M1) or NED (M2). The velocity is that of the sensor,
/// `v + ω×r` with `r` the lever arm from the IMU to the DVL or antenna
/// (body axes, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasurementModel<T> {
    /// M1 or M2.
    pub kind: AidingKind,
    /// Lever arm from the IMU to the velocity sensor, body axes, m.
    pub lever_arm: Vector3<T>,
}

/// One aiding epoch: values plus which channels are present.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement<T> {
    /// Measured values in channel order (ignored where not `available`).
    pub z: MeasVec<T>,
    /// Which channels this epoch carries (velocity only, attitude only, …).
    pub available: [bool; NZ],
}

impl<T: Real> Measurement<T> {
    /// An epoch with no channel present.
    pub fn none() -> Self {
        Self {
            z: MeasVec::zeros(),
            available: [false; NZ],
        }
    }
    /// True when at least one channel is present.
    pub fn any(&self) -> bool {
        self.available.iter().any(|a| *a)
    }
}

/// Body→NED rotation for ZYX Euler angles, plus the three elementary factors
/// (`R = Rz(ψ) Ry(θ) Rx(φ)`) used for the Jacobian.
fn rotations<T: Real>(x: &StateVec<T>) -> (Matrix3<T>, Matrix3<T>, Matrix3<T>) {
    let (sp, cp) = x[ROLL].sin_cos_fast();
    let (st, ct) = x[PITCH].sin_cos_fast();
    let (sy, cy) = x[YAW].sin_cos_fast();
    let z = T::zero();
    let o = T::one();
    let rx = Matrix3::new(o, z, z, z, cp, -sp, z, sp, cp);
    let ry = Matrix3::new(ct, z, st, z, o, z, -st, z, ct);
    let rz = Matrix3::new(cy, -sy, z, sy, cy, z, z, z, o);
    (rx, ry, rz)
}

impl<T: Real> MeasurementModel<T> {
    /// A model without lever arm.
    pub fn new(kind: AidingKind) -> Self {
        Self {
            kind,
            lever_arm: Vector3::zeros(),
        }
    }

    /// True when `h` is affine in the state (M1: `h(x) = x + c`), so the
    /// filter may use the exact closed-form update.
    pub fn is_affine(&self) -> bool {
        matches!(self.kind, AidingKind::DvlCompass)
    }

    /// The states `h` depends on nonlinearly come first in this order, then
    /// those it is affine in, with the Jacobian as coefficient: `(order,
    /// nonlinear)` for the split sigma-point update. M2 is affine in the
    /// body velocity given the attitude (`R(φ, θ, ψ)·v`); M1 in everything.
    pub fn split(&self) -> ([usize; NZ], usize) {
        match self.kind {
            AidingKind::DvlCompass => ([0, 1, 2, ROLL, PITCH, YAW], 0),
            AidingKind::GnssAttitude => ([ROLL, PITCH, YAW, 0, 1, 2], 3),
        }
    }

    /// `h(x)` given the body rate `omega` (for the lever-arm term).
    pub fn predict(&self, x: &StateVec<T>, omega: &Vector3<T>) -> MeasVec<T> {
        let v_sensor = Vector3::new(x[0], x[1], x[2]) + omega.cross(&self.lever_arm);
        let v = match self.kind {
            AidingKind::DvlCompass => v_sensor,
            AidingKind::GnssAttitude => {
                let (rx, ry, rz) = rotations(x);
                rz * (ry * (rx * v_sensor))
            }
        };
        MeasVec::new(v[0], v[1], v[2], x[ROLL], x[PITCH], x[YAW])
    }

    /// Rotates a measured sensor velocity into body axes using the attitude
    /// in `x` (identity for M1, `R_nbᵀ v` for M2): used for alignment.
    pub fn velocity_to_body(&self, x: &StateVec<T>, v: &Vector3<T>) -> Vector3<T> {
        match self.kind {
            AidingKind::DvlCompass => *v,
            AidingKind::GnssAttitude => {
                let (rx, ry, rz) = rotations(x);
                (rz * ry * rx).transpose() * v
            }
        }
    }

    /// Measurement Jacobian `H = ∂h/∂x` at `x`.
    pub fn jacobian(&self, x: &StateVec<T>, omega: &Vector3<T>) -> Mat6<T> {
        let mut h = Mat6::identity();
        if let AidingKind::GnssAttitude = self.kind {
            let (rx, ry, rz) = rotations(x);
            let vb = Vector3::new(x[0], x[1], x[2]) + omega.cross(&self.lever_arm);
            let r = rz * ry * rx;
            let ex = Vector3::x();
            let ey = Vector3::y();
            let ez = Vector3::z();
            // dRx/dφ = Rx [e_x]×, and likewise for the other two factors.
            let d_phi = r * ex.cross(&vb);
            let d_theta = rz * (ry * ey.cross(&(rx * vb)));
            let d_psi = rz * ez.cross(&(ry * (rx * vb)));
            for i in 0..3 {
                for j in 0..3 {
                    h[(i, j)] = r[(i, j)];
                }
                h[(i, ROLL)] = d_phi[i];
                h[(i, PITCH)] = d_theta[i];
                h[(i, YAW)] = d_psi[i];
            }
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gnss_jacobian_matches_finite_differences() {
        let mut m = MeasurementModel::<f64>::new(AidingKind::GnssAttitude);
        m.lever_arm = Vector3::new(0.3, -0.1, 0.2);
        let x = StateVec::new(20.0, 1.0, -0.5, 0.3, -0.2, 2.0);
        let w = Vector3::new(0.1, 0.2, -0.3);
        let h = m.jacobian(&x, &w);
        for k in 0..6 {
            let (mut xp, mut xm) = (x, x);
            xp[k] += 1e-6;
            xm[k] -= 1e-6;
            let d = (m.predict(&xp, &w) - m.predict(&xm, &w)) / 2e-6;
            assert!((d - h.column(k)).amax() < 1e-6, "column {k}");
        }
    }

    #[test]
    fn level_north_flight_reads_forward_speed_as_north() {
        let m = MeasurementModel::<f64>::new(AidingKind::GnssAttitude);
        let x = StateVec::new(20.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let z = m.predict(&x, &Vector3::zeros());
        assert!((z[0] - 20.0).abs() < 1e-12 && z[1].abs() < 1e-12);
        let x = StateVec::new(20.0, 0.0, 0.0, 0.0, 0.0, core::f64::consts::FRAC_PI_2);
        let z = m.predict(&x, &Vector3::zeros());
        assert!((z[1] - 20.0).abs() < 1e-12, "east when heading 90°");
    }
}

use super::{ImuVec, Mat6, StateVec, VehicleModel};
use crate::math::{symmetrize, Real};
use crate::model::ModelError;

/// IMU white-noise power spectral densities used as filter process noise.
///
/// Units are PSDs: (m/s²)²/Hz for the accelerometers, (rad/s)²/Hz for the
/// gyros — i.e. the square of a datasheet noise density. A per-sample variance
/// σ² at sample period dt converts as `PSD = σ²·dt`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuNoisePsd<T> {
    /// Per-channel PSD in channel order `[a_x, a_y, a_z, p, q, r]`.
    pub psd: ImuVec<T>,
}

impl<T: Real> ImuNoisePsd<T> {
    /// Same PSD on the three accelerometer and on the three gyro channels.
    pub fn uniform(accel: T, gyro: T) -> Self {
        Self {
            psd: ImuVec::new(accel, accel, accel, gyro, gyro, gyro),
        }
    }
}

/// Discrete process noise of one step (\[OTS\] eq. (13)).
///
/// `Q̄ = G q Gᵀ`, `M₁ = Q̄`, `M₂ = A M₁ + (A M₁)ᵀ`,
/// `Q = M₁ dt + M₂ dt²/2` — the series truncated after i = 2: at 100 Hz the
/// third term is below 1e-3 of the first for body rates < 3 rad/s.
pub fn discrete_process_noise<T: Real>(
    model: &VehicleModel<T>,
    x: &StateVec<T>,
    u: &ImuVec<T>,
    noise: &ImuNoisePsd<T>,
    dt: T,
) -> Result<Mat6<T>, ModelError> {
    let g = model.jacobian_input(x)?;
    let a = model.jacobian_state(x, u)?;
    Ok(discrete_process_noise_from(&a, &g, noise, dt))
}

/// [`discrete_process_noise`] from Jacobians the caller already has
/// (`a = ∂f/∂x`, `g = ∂f/∂u`), so a filter step evaluates them once.
pub fn discrete_process_noise_from<T: Real>(
    a: &Mat6<T>,
    g: &Mat6<T>,
    noise: &ImuNoisePsd<T>,
    dt: T,
) -> Mat6<T> {
    // G·diag(q) scales the columns of G.
    let mut gq = *g;
    for (mut col, q) in gq.column_iter_mut().zip(noise.psd.iter()) {
        col *= *q;
    }
    let m1 = gq * g.transpose();
    let am1 = a * m1;
    let m2 = am1 + am1.transpose();
    let mut q = m1 * dt + m2 * (dt * dt * T::lit(0.5));
    symmetrize(&mut q);
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_axis_random_walk_matches_closed_form() {
        // At rest and level, an accelerometer PSD q gives velocity variance q·dt.
        let m = VehicleModel::<f64>::default();
        let x = StateVec::zeros();
        let u = ImuVec::new(0.0, 0.0, -super::super::super::model::G0, 0.0, 0.0, 0.0);
        let n = ImuNoisePsd::uniform(1e-4, 0.0);
        let q = discrete_process_noise(&m, &x, &u, &n, 0.01).unwrap();
        assert!((q[(0, 0)] - 1e-6).abs() < 1e-15);
        // The gyro PSD couples into velocity through gravity at second order.
        let n = ImuNoisePsd::uniform(0.0, 1e-6);
        let q = discrete_process_noise(&m, &x, &u, &n, 0.01).unwrap();
        assert!((q[(3, 3)] - 1e-8).abs() < 1e-18);
        assert!((q[(1, 3)] - 0.5 * 9.80665 * 1e-6 * 1e-4).abs() < 1e-15);
    }
}

use nalgebra::Matrix3;

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

/// [`discrete_process_noise_from`] for the Jacobians of [`VehicleModel`],
/// using their block structure (3×3 blocks, `v` velocity, `a` attitude):
///
/// ```text
/// G = [ I  S ]      A = [ Ω  Γ ]
///     [ 0  E ]          [ 0  Λ ]
/// ```
///
/// `S = [c×]` (`c` the body velocity) and `Ω = [w×]` (`w = −ω`) are
/// cross-product matrices, and the third columns of `Γ` and `Λ` are zero
/// (the yaw enters no derivative). So `M₁ = G q Gᵀ` and `N = A M₁` need
/// 186 multiply-adds instead of the 432 of two 6×6 products (issue 17: the
/// Jacobians are never multiplied as dense blocks), and `Q` is written
/// symmetric by construction. Only the entries named above are read; the
/// result equals the general form to rounding (tested).
pub fn discrete_process_noise_structured<T: Real>(
    a: &Mat6<T>,
    g: &Mat6<T>,
    noise: &ImuNoisePsd<T>,
    dt: T,
) -> Mat6<T> {
    let at = |m: &Mat6<T>, i: usize, j: usize| m.get((i, j)).copied().unwrap_or_else(T::zero);
    // The axes of the two cross-product blocks: [k×] has k = (K₂₁, K₀₂, K₁₀).
    let c = [at(g, 2, 4), at(g, 0, 5), at(g, 1, 3)];
    let w = [at(a, 2, 1), at(a, 0, 2), at(a, 1, 0)];
    let e: Matrix3<T> = g.fixed_view::<3, 3>(3, 3).into_owned();
    let gamma = a.fixed_view::<3, 2>(0, 3);
    let lambda = a.fixed_view::<3, 2>(3, 3);
    let qa = noise.psd.fixed_rows::<3>(0);
    let qg = noise.psd.fixed_rows::<3>(3);
    // D Sᵀ = (S D)ᵀ = −D S (S skew) and D Eᵀ, D = diag(q_g): scaled rows.
    let mut dst = Matrix3::<T>::zeros();
    let mut det = e.transpose();
    for (i, q) in qg.iter().enumerate() {
        let mut row = det.row_mut(i);
        row *= *q;
        // Row i of −D S: −q_i S_i·, S = [c×].
        let s_row = cross_row(&c, i);
        for (j, v) in s_row.iter().enumerate() {
            if let Some(d) = dst.get_mut((i, j)) {
                *d = -*v * *q;
            }
        }
    }
    let mut m_vv = cross_mul(&c, &dst);
    for (i, q) in qa.iter().enumerate() {
        if let Some(d) = m_vv.get_mut((i, i)) {
            *d += *q;
        }
    }
    let m_va = cross_mul(&c, &det);
    let m_aa = e * det;
    let m_av = m_va.transpose();
    let n_vv = cross_mul(&w, &m_vv) + gamma * m_av.fixed_rows::<2>(0);
    let n_va = cross_mul(&w, &m_va) + gamma * m_aa.fixed_rows::<2>(0);
    let n_av = lambda * m_av.fixed_rows::<2>(0);
    let n_aa = lambda * m_aa.fixed_rows::<2>(0);
    let h = dt * dt * T::lit(0.5);
    let mut q = Mat6::zeros();
    for j in 0..3 {
        for i in 0..3 {
            let (ij, ji) = ((i, j), (j, i));
            let get = |m: &Matrix3<T>, k: (usize, usize)| m.get(k).copied().unwrap_or_else(T::zero);
            let q_va = get(&m_va, ij) * dt + (get(&n_va, ij) + get(&n_av, ji)) * h;
            if let Some(v) = q.get_mut((i, 3 + j)) {
                *v = q_va;
            }
            if let Some(v) = q.get_mut((3 + j, i)) {
                *v = q_va;
            }
            if i >= j {
                // Both triangles from one sum: the blocks are symmetric.
                let q_vv = get(&m_vv, ij) * dt + (get(&n_vv, ij) + get(&n_vv, ji)) * h;
                let q_aa = get(&m_aa, ij) * dt + (get(&n_aa, ij) + get(&n_aa, ji)) * h;
                for (r, s, v) in [(i, j, q_vv), (3 + i, 3 + j, q_aa)] {
                    if let Some(o) = q.get_mut((r, s)) {
                        *o = v;
                    }
                    if let Some(o) = q.get_mut((s, r)) {
                        *o = v;
                    }
                }
            }
        }
    }
    q
}

/// Row `i` of the cross-product matrix `[k×]`.
fn cross_row<T: Real>(k: &[T; 3], i: usize) -> [T; 3] {
    let z = T::zero();
    let [k0, k1, k2] = *k;
    match i {
        0 => [z, -k2, k1],
        1 => [k2, z, -k0],
        _ => [-k1, k0, z],
    }
}

/// `[k×] X`: each column crossed with `k` (18 multiply-adds, not 27).
fn cross_mul<T: Real>(k: &[T; 3], x: &Matrix3<T>) -> Matrix3<T> {
    let [k0, k1, k2] = *k;
    let x = |i: usize, j: usize| x.get((i, j)).copied().unwrap_or_else(T::zero);
    Matrix3::from_fn(|i, j| match i {
        0 => k1 * x(2, j) - k2 * x(1, j),
        1 => k2 * x(0, j) - k0 * x(2, j),
        _ => k0 * x(1, j) - k1 * x(0, j),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn structured_form_equals_the_general_one() {
        let m = VehicleModel::<f64>::default();
        let noise = ImuNoisePsd {
            psd: ImuVec::new(6e-5, 7e-5, 8e-5, 2e-7, 3e-7, 4e-7),
        };
        for (x, u) in [
            (
                StateVec::new(2.0, 0.3, -0.2, 0.4, -0.3, 2.5),
                ImuVec::new(0.5, -0.2, -9.5, 0.1, -0.2, 0.3),
            ),
            (
                StateVec::new(60.0, -1.0, 2.0, -1.0, 1.2, -3.0),
                ImuVec::new(3.0, 1.0, -12.0, 1.5, 0.8, -2.0),
            ),
        ] {
            let a = m.jacobian_state(&x, &u).unwrap();
            let g = m.jacobian_input(&x).unwrap();
            let general = discrete_process_noise_from(&a, &g, &noise, 0.01);
            let fast = discrete_process_noise_structured(&a, &g, &noise, 0.01);
            assert!(
                (general - fast).amax() < 1e-14 * general.amax(),
                "{:e}",
                (general - fast).amax()
            );
        }
    }

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

// Dense fixed-size kernel: every index below is a loop variable bounded by
// the matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

use crate::math::{cholesky, cholesky_solve_right, Real};
use crate::model::{ImuVec, Mat6};

/// \[UKF\] §4 as written: `f̂ = (H G_k)⁻¹ r̄` with `G_k = −B·dt` the fault-input
/// matrix of the current IMU step (SPEC §6). Because the filter's own
/// correction feeds back, the steady innovation of a constant fault is
/// `M f`, not `H G_k f`, so this over-estimates by roughly `T/(K·dt)`
/// (aiding interval T, gain K) — kept for comparison. `None` if `H B` is
/// singular.
pub fn estimate_as_written<T: Real>(
    h: &Mat6<T>,
    b: &Mat6<T>,
    dt: T,
    rbar: &ImuVec<T>,
) -> Option<ImuVec<T>> {
    let hg = h * b * (-dt);
    hg.try_inverse().map(|inv| inv * rbar)
}

/// The corrected mapping `f̂ = M⁺ r̄`, as weighted least squares with the
/// inverse variances `w` of the window means (0 for innovation channels not
/// monitored), solved only for the fault channels in `columns` (the others
/// come out as 0, as do faults that no monitored channel observes). `None`
/// when the normal matrix is singular.
pub fn estimate_corrected<T: Real>(
    m: &Mat6<T>,
    w: &ImuVec<T>,
    rbar: &ImuVec<T>,
    columns: &[bool; 6],
) -> Option<ImuVec<T>> {
    let mut normal = Mat6::<T>::zeros();
    let mut rhs = nalgebra::SMatrix::<T, 1, 6>::zeros();
    let mut observed = [false; 6];
    for a in 0..6 {
        for b in 0..6 {
            let mut s = T::zero();
            for i in 0..6 {
                s += m[(i, a)] * w[i] * m[(i, b)];
            }
            normal[(a, b)] = s;
        }
        let mut s = T::zero();
        for i in 0..6 {
            s += m[(i, a)] * w[i] * rbar[i];
        }
        rhs[a] = s;
    }
    // A column no monitored channel sees has a zero diagonal: decouple it.
    let mut max_diag = T::zero();
    for a in 0..6 {
        max_diag = max_diag.max(normal[(a, a)]);
    }
    for (a, obs) in observed.iter_mut().enumerate() {
        *obs = columns.get(a).copied().unwrap_or(false) && normal[(a, a)] > max_diag * T::lit(1e-9);
        if !*obs {
            for b in 0..6 {
                normal[(a, b)] = T::zero();
                normal[(b, a)] = T::zero();
            }
            normal[(a, a)] = T::one();
            rhs[a] = T::zero();
        }
    }
    let l = cholesky(&normal).ok()?;
    Some(cholesky_solve_right(&l, &rhs).transpose())
}

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
    // M1's H is the identity: skip the product.
    let hg = if crate::math::is_identity(h) {
        b * (-dt)
    } else {
        h * b * (-dt)
    };
    solve_pivoted(hg, *rbar)
}

/// Solves `A x = b` by Gaussian elimination with partial pivoting, in place
/// on copies (a fixed 6×6 kernel: about 70 % of the instructions of nalgebra's
/// generic LU on the Cortex-M4F). `None` when a pivot is zero or the result
/// is not finite.
fn solve_pivoted<T: Real>(mut a: Mat6<T>, mut b: ImuVec<T>) -> Option<ImuVec<T>> {
    for k in 0..6 {
        let mut p = k;
        let mut best = a[(k, k)].abs();
        for i in (k + 1)..6 {
            let v = a[(i, k)].abs();
            if v > best {
                best = v;
                p = i;
            }
        }
        if best <= T::zero() || !best.finite() {
            return None;
        }
        if p != k {
            a.swap_rows(p, k);
            b.swap_rows(p, k);
        }
        let inv = T::one() / a[(k, k)];
        for i in (k + 1)..6 {
            let f = a[(i, k)] * inv;
            for j in (k + 1)..6 {
                let akj = a[(k, j)];
                a[(i, j)] -= f * akj;
            }
            let bk = b[k];
            b[i] -= f * bk;
        }
    }
    for k in (0..6).rev() {
        let mut s = b[k];
        for j in (k + 1)..6 {
            s -= a[(k, j)] * b[j];
        }
        b[k] = s / a[(k, k)];
    }
    b.iter().all(|v| v.finite()).then_some(b)
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
    // Normal equations Mᵀ W M f = Mᵀ W r̄, with W M formed once.
    let mut wm = *m;
    for (mut row, wi) in wm.row_iter_mut().zip(w.iter()) {
        row *= *wi;
    }
    // Mᵀ W M is symmetric and `cholesky` reads its lower triangle only.
    let mut normal = Mat6::<T>::zeros();
    for b in 0..6 {
        for a in b..6 {
            normal[(a, b)] = m.column(a).dot(&wm.column(b));
        }
    }
    let mut rhs = rbar.tr_mul(&wm);
    let mut observed = [false; 6];
    // A column no monitored channel sees has a zero diagonal: decouple it.
    let mut max_diag = T::zero();
    for a in 0..6 {
        max_diag = max_diag.fmax(normal[(a, a)]);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pivoted_solve_matches_the_inverse() {
        // A zero leading pivot forces a row swap.
        let a = Mat6::<f64>::from_fn(|i, j| {
            if i == 0 && j == 0 {
                0.0
            } else {
                ((i * 7 + j * 3) % 5) as f64 - 2.0 + if i == j { 6.0 } else { 0.0 }
            }
        });
        let b = ImuVec::new(1.0, -2.0, 0.5, 3.0, -1.0, 0.25);
        let x = solve_pivoted(a, b).unwrap();
        assert!((a * x - b).amax() < 1e-13);
        assert!((x - a.try_inverse().unwrap() * b).amax() < 1e-13);
        assert!(solve_pivoted(Mat6::<f64>::zeros(), b).is_none());
    }
}

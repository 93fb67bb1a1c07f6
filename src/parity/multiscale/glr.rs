//! The generalised likelihood ratio of single-sensor bias hypotheses in
//! parity space, and the small covariance helpers it needs.

use nalgebra::{SMatrix, SVector};

use crate::math::{cholesky_solve_right, Real};

/// `dᵀ A⁻¹ d` from the Cholesky factor `L` of `A`.
pub(super) fn mahalanobis2<T: Real, const N: usize>(l: &SMatrix<T, N, N>, d: &SVector<T, N>) -> T {
    let y = cholesky_solve_right(l, &d.transpose());
    y.dot(&d.transpose())
}

/// The covariance restricted to the first `dim` coordinates, with identity
/// beyond so the fixed-size factorisation is full rank.
pub(super) fn pad<T: Real, const N: usize>(a: &SMatrix<T, N, N>, dim: usize) -> SMatrix<T, N, N> {
    SMatrix::<T, N, N>::from_fn(|i, j| {
        if i < dim && j < dim {
            // Symmetrised: EWMA updates keep it so only up to rounding.
            let aij = a.get((i, j)).copied().unwrap_or(T::zero());
            let aji = a.get((j, i)).copied().unwrap_or(T::zero());
            (aij + aji) * T::lit(0.5)
        } else if i == j {
            T::one()
        } else {
            T::zero()
        }
    })
}

/// Best single-sensor hypothesis `(k, score, bias)` for the parity residual
/// `r` with covariance factor `l`, and the runner-up's score.
pub(super) fn best_two<T: Real, const N: usize>(
    l: &SMatrix<T, N, N>,
    v: &SMatrix<T, N, N>,
    r: &SVector<T, N>,
    active: &[bool; N],
) -> (Option<(usize, T, T)>, T) {
    // a_k = Σ⁻¹ v_k for every column at once: rows of Vᵀ Σ⁻¹.
    let a = cholesky_solve_right(l, &v.transpose());
    let z = a * r;
    let mut best: Option<(usize, T, T)> = None;
    let mut second = T::zero();
    for k in 0..N {
        if !active.get(k).copied().unwrap_or(false) {
            continue;
        }
        let q = a.row(k).dot(&v.column(k).transpose());
        if q.partial_cmp(&T::lit(1e-12)) != Some(core::cmp::Ordering::Greater) {
            continue;
        }
        let zk = z.get(k).copied().unwrap_or(T::zero());
        let score = zk * zk / q;
        match best {
            Some((_, s, _)) if score <= s => second = second.max(score),
            _ => {
                if let Some((_, s, _)) = best {
                    second = second.max(s);
                }
                best = Some((k, score, zk / q));
            }
        }
    }
    (best, second)
}

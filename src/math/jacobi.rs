// Dense fixed-size kernel: every index is a loop variable bounded by the
// matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

//! Eigen-decomposition of a small symmetric matrix by cyclic Jacobi
//! rotations: a few dozen lines, no allocation, any const size (nalgebra's
//! `SymmetricEigen` needs type-level `N − 1`, which generic code cannot name).

use nalgebra::{SMatrix, SVector};

use super::Real;

/// Sweeps after which the iteration stops even if not converged (cyclic
/// Jacobi converges quadratically; 6×6 needs ~6 sweeps in `f64`).
const MAX_SWEEPS: usize = 30;

/// Eigenvalues (descending) and eigenvectors (columns, same order) of the
/// symmetric matrix `a` (lower triangle read). Returns `None` when `a`
/// holds a non-finite value.
pub fn symmetric_eigen<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
) -> Option<(SVector<T, N>, SMatrix<T, N, N>)> {
    let mut m = SMatrix::<T, N, N>::from_fn(|i, j| if i >= j { a[(i, j)] } else { a[(j, i)] });
    if !m.iter().all(|x| x.finite()) {
        return None;
    }
    let mut v = SMatrix::<T, N, N>::identity();
    let scale = m.norm_squared();
    for _ in 0..MAX_SWEEPS {
        let mut off = T::zero();
        for p in 0..N {
            for q in p + 1..N {
                off += m[(p, q)] * m[(p, q)];
            }
        }
        if off <= T::default_epsilon() * T::default_epsilon() * scale {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                let apq = m[(p, q)];
                if apq == T::zero() {
                    continue;
                }
                let tau = (m[(q, q)] - m[(p, p)]) / (apq + apq);
                let t = tau.signum() / (tau.abs() + (T::one() + tau * tau).sqrt());
                let t = if tau == T::zero() { T::one() } else { t };
                let c = T::one() / (T::one() + t * t).sqrt();
                let s = t * c;
                for k in 0..N {
                    let (mkp, mkq) = (m[(k, p)], m[(k, q)]);
                    m[(k, p)] = c * mkp - s * mkq;
                    m[(k, q)] = s * mkp + c * mkq;
                }
                for k in 0..N {
                    let (mpk, mqk) = (m[(p, k)], m[(q, k)]);
                    m[(p, k)] = c * mpk - s * mqk;
                    m[(q, k)] = s * mpk + c * mqk;
                }
                for k in 0..N {
                    let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
                    v[(k, p)] = c * vkp - s * vkq;
                    v[(k, q)] = s * vkp + c * vkq;
                }
            }
        }
    }
    // Selection sort, descending: N ≤ 9 here.
    let mut values = m.diagonal();
    for i in 0..N {
        let mut best = i;
        for j in i + 1..N {
            if values[j] > values[best] {
                best = j;
            }
        }
        if best != i {
            values.swap_rows(i, best);
            v.swap_columns(i, best);
        }
    }
    Some((values, v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reconstructs_a_random_symmetric_matrix() {
        let b = SMatrix::<f64, 6, 6>::from_fn(|i, j| ((i * 7 + j * 3) as f64 * 0.61).sin());
        let a = b * b.transpose();
        let (values, vectors) = symmetric_eigen(&a).unwrap();
        let rebuilt = vectors * SMatrix::from_diagonal(&values) * vectors.transpose();
        assert!((rebuilt - a).amax() < 1e-12);
        assert!((vectors.transpose() * vectors - SMatrix::<f64, 6, 6>::identity()).amax() < 1e-12);
        assert!(values.as_slice().windows(2).all(|w| w[0] >= w[1]));
    }

    #[test]
    fn f32_agrees_with_f64_on_a_diagonal_dominant_case() {
        let a64 = SMatrix::<f64, 3, 3>::new(4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 1.0);
        let (v64, _) = symmetric_eigen(&a64).unwrap();
        let (v32, _) = symmetric_eigen(&a64.cast::<f32>()).unwrap();
        assert!((v64.cast::<f32>() - v32).amax() < 1e-5);
        assert!(symmetric_eigen(&SMatrix::<f64, 2, 2>::new(f64::NAN, 0.0, 0.0, 1.0)).is_none());
    }
}

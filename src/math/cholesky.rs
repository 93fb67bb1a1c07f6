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

/// Lower Cholesky factor `L` with `A = L Lᵀ` (upper triangle of `L` zero).
///
/// Only the lower triangle of `a` is read. Returns
/// [`LinalgError::NotPositiveDefinite`] (with the failing pivot) instead of
/// producing NaN.
///
/// This is nalgebra's left-looking column algorithm (column `j` loses
/// `l_jk ·` column `k` for every `k < j`, as an `axpy` on column views, then
/// is scaled by its pivot) with one change: the pivot's square root is
/// [`Real::sqrt_fast`] — the FPU's `vsqrt` on the Cortex-M4F — where
/// `nalgebra::Cholesky` calls software `libm::sqrtf` (61 instructions each).
/// The views' ranges are bounded by the loop indices (`k < j < N`), so
/// nalgebra's range assertions cannot fire.
pub fn cholesky<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
) -> Result<SMatrix<T, N, N>, LinalgError> {
    let mut l = *a;
    for j in 0..N {
        for k in 0..j {
            let factor = -l[(j, k)];
            let (mut col_j, col_k) = l.columns_range_pair_mut(j, k);
            col_j
                .rows_range_mut(j..)
                .axpy(factor, &col_k.rows_range(j..), T::one());
        }
        let d = l[(j, j)];
        if d <= T::zero() || !d.finite() {
            return Err(LinalgError::NotPositiveDefinite(j));
        }
        let s = d.sqrt_fast();
        l[(j, j)] = s;
        let inv = T::one() / s;
        l.view_range_mut(j + 1.., j).scale_mut(inv);
    }
    l.fill_upper_triangle(T::zero(), 1);
    Ok(l)
}

/// Adds `w·d·dᵀ` to the lower triangle of `p` (the upper triangle is left
/// alone; see [`mirror_lower`]). Half the work of a full outer product.
pub fn add_outer_lower<T: Real, const N: usize>(
    p: &mut SMatrix<T, N, N>,
    d: &nalgebra::SVector<T, N>,
    w: T,
) {
    let ds = d.as_slice();
    for (j, (col, dj)) in p
        .as_mut_slice()
        .chunks_exact_mut(N)
        .zip(ds.iter())
        .enumerate()
    {
        let wd = w * *dj;
        let (Some(dst), Some(src)) = (col.get_mut(j..), ds.get(j..)) else {
            continue;
        };
        for (c, di) in dst.iter_mut().zip(src.iter()) {
            *c += wd * *di;
        }
    }
}

/// Copies the lower triangle of `p` onto its upper triangle.
pub fn mirror_lower<T: Real, const N: usize>(p: &mut SMatrix<T, N, N>) {
    for j in 0..N {
        for i in (j + 1)..N {
            p[(j, i)] = p[(i, j)];
        }
    }
}

/// `dst` = `p` with its lower triangle mirrored onto the upper: the same
/// values as [`mirror_lower`] on `p` followed by a copy into `dst`, in one
/// pass (21 loads, 36 stores for 6×6 instead of 30 + 72; issue 17).
pub(crate) fn mirror_lower_into<T: Real, const N: usize>(
    p: &SMatrix<T, N, N>,
    dst: &mut SMatrix<T, N, N>,
) {
    for j in 0..N {
        for i in j..N {
            let v = p[(i, j)];
            dst[(i, j)] = v;
            dst[(j, i)] = v;
        }
    }
}

/// True when every entry of the lower triangle (diagonal included) is
/// finite: after [`mirror_lower`] the same answer as
/// [`all_finite`](super::all_finite) over the whole matrix, on 21 values
/// instead of 36 for 6×6 (issue 17). Same sum of `x·0` as `all_finite`.
pub(crate) fn lower_finite<T: Real, const N: usize>(p: &SMatrix<T, N, N>) -> bool {
    let mut acc = T::zero();
    for j in 0..N {
        for i in j..N {
            acc += p[(i, j)] * T::zero();
        }
    }
    acc == T::zero()
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

/// `x −= g · y`, or `x −= g · x` when `y` is `None`, column by column in
/// place: the values of `x -= g * y` (nalgebra's product sums `g_ik y_kj`
/// over `k` in the same order; unit test) without the product's temporary
/// and its copy (issue 17: the sensitivity's `(I − K H) X` at each update).
pub(crate) fn sub_product<T: Real, const N: usize>(
    x: &mut SMatrix<T, N, N>,
    g: &SMatrix<T, N, N>,
    y: Option<&SMatrix<T, N, N>>,
) {
    for j in 0..N {
        // Column j of the product reads column j of `y` only: with `y = x`
        // it is read before being overwritten.
        let col: [T; N] = core::array::from_fn(|k| match y {
            Some(y) => y[(k, j)],
            None => x[(k, j)],
        });
        for i in 0..N {
            let mut s = g[(i, 0)] * col[0];
            for k in 1..N {
                s += g[(i, k)] * col[k];
            }
            x[(i, j)] -= s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    #[test]
    fn mirror_into_and_lower_finite_match_mirror_and_all_finite() {
        let mut p = nalgebra::Matrix4::<f32>::from_fn(|i, j| (i * 4 + j) as f32 * 0.37 - 2.0);
        let mut dst = nalgebra::Matrix4::<f32>::from_element(9.0);
        mirror_lower_into(&p, &mut dst);
        let mut whole = p;
        mirror_lower(&mut whole);
        assert_eq!(dst, whole);
        assert!(lower_finite(&p));
        // Non-finite values above the diagonal are overwritten by the mirror.
        p[(0, 3)] = f32::NAN;
        p[(1, 2)] = f32::INFINITY;
        assert!(lower_finite(&p));
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for (i, j) in [(0, 0), (3, 0), (2, 1), (3, 3)] {
                let mut q = p;
                q[(i, j)] = bad;
                let mut m = q;
                mirror_lower(&mut m);
                assert!(!lower_finite(&q));
                assert_eq!(lower_finite(&q), crate::math::all_finite(m.as_slice()));
            }
        }
    }

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
        // A 6×6 with every entry coupled, and an upper triangle that must be ignored.
        let b = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, j| {
            1.0 / (1.0 + i as f64 + j as f64) + if i == j { 1.0 } else { 0.0 }
        });
        let mut junk = b;
        junk[(0, 5)] = 1e6;
        let l = cholesky(&junk).unwrap();
        assert!((l - cholesky_reference(&b).unwrap()).amax() < 1e-15);
        assert!((l * l.transpose() - b).amax() < 1e-14);
        for i in 0..6 {
            for j in (i + 1)..6 {
                assert_eq!(l[(i, j)], 0.0, "upper ({i},{j})");
            }
        }
    }

    #[test]
    fn lower_outer_product_and_mirror_match_the_full_product() {
        let d = nalgebra::Vector4::new(1.0, -2.0, 0.5, 3.0);
        let mut p = nalgebra::Matrix4::<f64>::identity();
        add_outer_lower(&mut p, &d, 0.25);
        mirror_lower(&mut p);
        let full = nalgebra::Matrix4::<f64>::identity() + d * d.transpose() * 0.25;
        assert!((p - full).amax() < 1e-15);
    }

    #[test]
    fn pivot_of_the_failure_is_named() {
        let mut a = nalgebra::SMatrix::<f64, 6, 6>::identity();
        a[(3, 3)] = -1.0;
        assert_eq!(cholesky(&a), Err(LinalgError::NotPositiveDefinite(3)));
        a[(3, 3)] = f64::INFINITY;
        assert_eq!(cholesky(&a), Err(LinalgError::NotPositiveDefinite(3)));
    }

    #[test]
    fn indefinite_is_an_error() {
        let a = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert_eq!(cholesky(&a), Err(LinalgError::NotPositiveDefinite(1)));
        let n = Matrix3::from_diagonal_element(f64::NAN);
        assert_eq!(cholesky(&n), Err(LinalgError::NotPositiveDefinite(0)));
    }

    #[test]
    fn sub_product_matches_nalgebra() {
        let g = SMatrix::<f32, 6, 6>::from_fn(|i, j| ((i * 7 + j * 3) % 11) as f32 * 0.37 - 1.9);
        let y =
            SMatrix::<f32, 6, 6>::from_fn(|i, j| ((i * 5 + j * 13) % 7) as f32 * 1.3e-3 - 0.004);
        let x0 = SMatrix::<f32, 6, 6>::from_fn(|i, j| ((i + 2 * j) % 5) as f32 * 0.11 + 0.01);
        let mut x = x0;
        sub_product(&mut x, &g, Some(&y));
        assert_eq!(x, x0 - g * y);
        let mut x = y;
        sub_product(&mut x, &g, None);
        assert_eq!(x, y - g * y);
    }
}

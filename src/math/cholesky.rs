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
/// `l_jk ·` column `k` for every `k < j`, then is scaled by its pivot) with
/// two changes: the pivot's square root is [`Real::sqrt_fast`] — the FPU's
/// `vsqrt` on the Cortex-M4F — where `nalgebra::Cholesky` calls software
/// `libm::sqrtf` (61 instructions each); and the loops run over the
/// column-major array itself instead of nalgebra's column views, whose range
/// checks and strided `axpy` kept the 6×6 factor at 462 instructions on the
/// M4F (issue 17). Every entry sees the same operations in the same order as
/// the view-based version (`y + (−l_jk)·x` is `y − l_jk·x` to the bit), so
/// the factor is bit-identical to it (tested).
pub fn cholesky<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
) -> Result<SMatrix<T, N, N>, LinalgError> {
    let mut l = *a;
    let c = &mut l.data.0; // the columns
    if N == 6 {
        // Literal column indices: after inlining every loop bound is a
        // constant, so the 6×6 factor is straight-line code (the filters'
        // size; a loop over `j` is not unrolled by the compiler).
        factor_column(c, 0)?;
        factor_column(c, 1)?;
        factor_column(c, 2)?;
        factor_column(c, 3)?;
        factor_column(c, 4)?;
        factor_column(c, 5)?;
    } else {
        for j in 0..N {
            factor_column(c, j)?;
        }
    }
    // The upper triangle: zero (it held `a`'s).
    for (j, col) in c.iter_mut().enumerate() {
        for v in col.iter_mut().take(j) {
            *v = T::zero();
        }
    }
    Ok(l)
}

/// Column `j` of the left-looking factorisation, columns `0..j` being
/// final: `l_ij −= l_jk l_ik` for `k < j`, then the pivot's root and the
/// scaling by its reciprocal. `j < N` (every caller).
#[inline(always)]
fn factor_column<T: Real, const N: usize>(
    c: &mut [[T; N]; N],
    j: usize,
) -> Result<(), LinalgError> {
    for k in 0..j {
        let f = c[k][j];
        for i in j..N {
            let y = c[j][i] - f * c[k][i];
            c[j][i] = y;
        }
    }
    let d = c[j][j];
    // `0 < d < ∞` is `d > 0 && finite(d)` (NaN fails both compares) in two
    // FPU compares instead of an integer test of the bits.
    if !(d > T::zero() && d < T::lit(f64::INFINITY)) {
        return Err(LinalgError::NotPositiveDefinite(j));
    }
    let s = d.sqrt_fast();
    c[j][j] = s;
    let inv = T::one() / s;
    for i in (j + 1)..N {
        let y = c[j][i] * inv;
        c[j][i] = y;
    }
    Ok(())
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

    /// The former view-based loop (nalgebra `axpy` on column views).
    fn cholesky_views<T: Real, const N: usize>(a: &SMatrix<T, N, N>) -> Option<SMatrix<T, N, N>> {
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
                return None;
            }
            let s = d.sqrt_fast();
            l[(j, j)] = s;
            let inv = T::one() / s;
            l.view_range_mut(j + 1.., j).scale_mut(inv);
        }
        l.fill_upper_triangle(T::zero(), 1);
        Some(l)
    }

    #[test]
    fn array_loop_is_bit_identical_to_the_view_based_one() {
        // Random SPD 6×6 (f32 and f64): B Bᵀ + εI from a fixed LCG.
        let mut seed = 0x2545_f491_u64;
        let mut next = || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            ((seed >> 33) as f64 / (1u64 << 31) as f64) - 0.5
        };
        for trial in 0..200 {
            let b = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|_, _| next());
            let eps = if trial % 2 == 0 { 1e-3 } else { 1e-9 };
            let a = b * b.transpose() + nalgebra::SMatrix::<f64, 6, 6>::identity() * eps;
            let a32 = a.map(|v| v as f32);
            assert_eq!(cholesky(&a).ok(), cholesky_views(&a), "f64 trial {trial}");
            assert_eq!(
                cholesky(&a32).ok(),
                cholesky_views(&a32),
                "f32 trial {trial}"
            );
            let (x, y) = (cholesky(&a32).ok(), cholesky_views(&a32));
            if let (Some(x), Some(y)) = (x, y) {
                for (p, q) in x.iter().zip(y.iter()) {
                    assert_eq!(p.to_bits(), q.to_bits(), "f32 trial {trial}");
                }
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
}

// Dense fixed-size kernel: every index below is a loop variable bounded by
// the matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

use crate::math::{cholesky, cholesky_solve_right, Real};
use nalgebra::{SMatrix, SVector};

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

/// [`estimate_as_written`] for M2's `H = [R D; 0 I]` and the vehicle
/// model's `B = [I S; 0 E]` (`VehicleModel::jacobian_input_with`): `H B` is
/// block upper triangular, its lower-left 3×3 block exactly zero, so the
/// pivoted elimination never moves a pivot across the two blocks nor
/// eliminates below the first, and is done without those operations on
/// known zeros (`solve_pivoted_blocks`). The result equals
/// [`estimate_as_written`] (a zero's sign aside: unit test), and the
/// general 6×6 elimination is not in the monitor's code (issue 17). The
/// lower-left blocks of `h` and `b` are taken to be zero.
pub(crate) fn estimate_as_written_blocks<T: Real>(
    h: &Mat6<T>,
    b: &Mat6<T>,
    dt: T,
    rbar: &ImuVec<T>,
) -> Option<ImuVec<T>> {
    solve_pivoted_blocks::<T, 6, 3>(h * b * (-dt), *rbar)
}

/// [`estimate_as_written`] for `H = I` (M1) and an input Jacobian of the
/// vehicle model's block form `B = [I S; 0 E]` (upper-left block the
/// identity, lower-left zero: `VehicleModel::jacobian_input_with`). The
/// pivoted elimination of `−B·dt` is the same, less its operations on those
/// known zeros: no pivot moves in the first three columns (the entries below
/// the diagonal are zero), their elimination multiplies by zero, so only the
/// lower-right block is eliminated and the first three unknowns are
/// back-substituted through `S`. The result equals
/// [`estimate_as_written`]`(I, B, dt, r̄)` (a zero's sign aside: unit test),
/// in ≈ 150 instructions on the Cortex-M4F where the 6×6 took ≈ 1,150 (S2
/// trace, issue 17). Only the diagonal of the upper-left block and the two
/// right-hand blocks of `b` are read.
pub(crate) fn estimate_as_written_identity<T: Real>(
    b: &Mat6<T>,
    dt: T,
    rbar: &ImuVec<T>,
) -> Option<ImuVec<T>> {
    let nd = -dt;
    let usable = |p: T| p.abs() > T::zero() && p.abs().finite();
    let d = [b[(0, 0)] * nd, b[(1, 1)] * nd, b[(2, 2)] * nd];
    if !d.iter().all(|p| usable(*p)) {
        return None;
    }
    // The lower-right block, pivoted as `solve_pivoted` does (the same
    // kernel at 3×3).
    let y = nalgebra::Vector3::new(rbar[3], rbar[4], rbar[5]);
    let a = nalgebra::Matrix3::<T>::from_fn(|i, j| b[(3 + i, 3 + j)] * nd);
    let y = solve_pivoted_blocks::<T, 3, 3>(a, y)?;
    // The first three rows: diagonal `−dt`, coupled to the last three by `S`.
    let mut x = ImuVec::zeros();
    for (k, dk) in d.iter().enumerate() {
        let mut s = rbar[k];
        for j in 0..3 {
            s -= (b[(k, 3 + j)] * nd) * y[j];
        }
        x[k] = s / *dk;
    }
    x.fixed_rows_mut::<3>(3).copy_from(&y);
    x.iter().all(|v| v.finite()).then_some(x)
}

/// Solves `A x = b` by Gaussian elimination with partial pivoting, in place
/// on copies (a fixed 6×6 kernel: about 70 % of the instructions of nalgebra's
/// generic LU on the Cortex-M4F). `None` when a pivot is zero or the result
/// is not finite.
fn solve_pivoted<T: Real>(a: Mat6<T>, b: ImuVec<T>) -> Option<ImuVec<T>> {
    solve_pivoted_blocks::<T, 6, 6>(a, b)
}

/// [`solve_pivoted`] for an `A` whose rows from `SPLIT` on are zero in the
/// columns before `SPLIT` (block upper triangular; those entries are not
/// read): the pivot of a column before `SPLIT` is searched, and rows are
/// eliminated, only among the rows before `SPLIT` — the rows below would
/// never win the search and are eliminated with a zero multiplier, so the
/// values are those of [`solve_pivoted`] (a zero's sign aside). `SPLIT = 6`
/// is the general elimination; `D` is the size (6 here, 3 for the lower-right
/// block of [`estimate_as_written_identity`]).
fn solve_pivoted_blocks<T: Real, const D: usize, const SPLIT: usize>(
    mut a: SMatrix<T, D, D>,
    mut b: SVector<T, D>,
) -> Option<SVector<T, D>> {
    for k in 0..D {
        let end = if k < SPLIT { SPLIT.min(D) } else { D };
        let mut p = k;
        let mut best = a[(k, k)].abs();
        for i in (k + 1)..end {
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
        for i in (k + 1)..end {
            let f = a[(i, k)] * inv;
            for j in (k + 1)..D {
                let akj = a[(k, j)];
                a[(i, j)] -= f * akj;
            }
            let bk = b[k];
            b[i] -= f * bk;
        }
    }
    for k in (0..D).rev() {
        let mut s = b[k];
        for j in (k + 1)..D {
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
    // Built scaled, not copied and then scaled row by row (issue 17).
    let wm = m.map_with_location(|i, _, v| v * w.get(i).copied().unwrap_or_else(T::zero));
    // Mᵀ W M is symmetric and `cholesky` reads its lower triangle only.
    // Built in one pass, not zeroed first (issue 17).
    let mut normal = Mat6::<T>::from_fn(|a, b| {
        if a >= b {
            m.column(a).dot(&wm.column(b))
        } else {
            T::zero()
        }
    });
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

    #[test]
    fn block_form_solve_equals_the_pivoted_one() {
        // B = [I S; 0 E] as the vehicle model builds it and H = I or M2's
        // [R D; 0 I], over attitudes that make either block pivot, and
        // degenerate cases.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let id = Mat6::<f32>::identity();
        for case in 0..2000 {
            let (phi, theta) = (next() * 3.1, next() * 1.5);
            let (vu, vv, vw) = (next() * 20.0, next() * 5.0, next() * 2.0);
            let (sp, cp, st, ct) = (phi.sin(), phi.cos(), theta.sin(), theta.cos());
            #[rustfmt::skip]
            let b = Mat6::<f64>::new(
                1.0, 0.0, 0.0, 0.0, -vw, vv,
                0.0, 1.0, 0.0, vw, 0.0, -vu,
                0.0, 0.0, 1.0, -vv, vu, 0.0,
                0.0, 0.0, 0.0, 1.0, sp * st / ct, cp * st / ct,
                0.0, 0.0, 0.0, 0.0, cp, -sp,
                0.0, 0.0, 0.0, 0.0, sp / ct, cp / ct,
            )
            .cast::<f32>();
            let rot = nalgebra::Rotation3::from_euler_angles(phi, theta, next() * 3.1);
            let mut h2 = Mat6::<f64>::identity();
            h2.fixed_view_mut::<3, 3>(0, 0).copy_from(rot.matrix());
            h2.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&nalgebra::Matrix3::from_fn(|_, _| next() * 10.0));
            let h2 = h2.cast::<f32>();
            let r = ImuVec::<f64>::from_fn(|_, _| next() * 1e-2).cast::<f32>();
            let dt = if case == 7 { 0.0 } else { 0.01f32 };
            let r = if case == 9 {
                ImuVec::repeat(f32::NAN)
            } else {
                r
            };
            let x = estimate_as_written_identity(&b, dt, &r);
            assert_eq!(x, estimate_as_written(&id, &b, dt, &r), "case {case}");
            let x2 = estimate_as_written_blocks(&h2, &b, dt, &r);
            assert_eq!(x2, estimate_as_written(&h2, &b, dt, &r), "M2 case {case}");
            if case != 7 && case != 9 {
                assert!(x.is_some() && x2.is_some());
            }
        }
        // The identity input Jacobian (before the first predict).
        let r = ImuVec::<f64>::new(0.1, -0.2, 0.3, -0.4, 0.5, -0.6);
        assert_eq!(
            estimate_as_written_identity(&Mat6::identity(), 0.01, &r),
            estimate_as_written(&Mat6::identity(), &Mat6::identity(), 0.01, &r)
        );
    }
}

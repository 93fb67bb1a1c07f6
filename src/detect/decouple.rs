// Dense fixed-size kernel: every index below is a loop variable bounded by
// the matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

use crate::math::Real;
use crate::model::{ImuVec, Mat6};

/// \[UKF\] §3.2 sign matrix as printed: rows innovations `[r_u … r_ψ]`,
/// columns faults `[f_ax … f_r]` (det = −2).
#[rustfmt::skip]
pub const PAPER_MATRIX_AS_PRINTED: [[i8; 6]; 6] = [
    [ 1,  0,  0,  0,  1, -1],
    [ 0, -1,  0, -1,  0,  1],
    [ 0,  0, -1,  1, -1,  0],
    [ 0,  0,  0, -1, -1, -1],
    [ 0,  0,  0,  0, -1,  1],
    [ 0,  0,  0,  0, -1, -1],
];

/// The same matrix with the erratum of SPEC §5: entry (r_u, f_ax) is −1
/// (a positive accelerometer fault makes the filter over-predict velocity,
/// so the innovation is negative); det = +2.
#[rustfmt::skip]
pub const PAPER_MATRIX_CORRECTED: [[i8; 6]; 6] = [
    [-1,  0,  0,  0,  1, -1],
    [ 0, -1,  0, -1,  0,  1],
    [ 0,  0, -1,  1, -1,  0],
    [ 0,  0,  0, -1, -1, -1],
    [ 0,  0,  0,  0, -1,  1],
    [ 0,  0,  0,  0, -1, -1],
];

/// A sign table as a matrix.
pub fn paper_matrix<T: Real>(table: &[[i8; 6]; 6]) -> Mat6<T> {
    let mut c = Mat6::zeros();
    for (i, row) in table.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            c[(i, j)] = T::lit(f64::from(*v));
        }
    }
    c
}

/// The run-time decoupling matrix: the sign pattern of the closed-loop
/// signature matrix `M` (SPEC §5), with a dead-band.
///
/// Columns are first scaled by `fault_scale` (the minimum fault of interest
/// per channel, so accelerometer and gyro columns are comparable), rows by
/// `innovation_sigma` (so that the comparison is in units of innovation
/// noise); then entries below `deadband` × the largest entry of their row
/// become 0, e.g. the `v·r` and `w·q` couplings when v, w ≈ 0.
pub fn runtime_sign_matrix<T: Real>(
    m: &Mat6<T>,
    fault_scale: &ImuVec<T>,
    innovation_sigma: &ImuVec<T>,
    deadband: T,
) -> Mat6<T> {
    let mut c = Mat6::zeros();
    for i in 0..6 {
        let mut scaled = [T::zero(); 6];
        let mut row_max = T::zero();
        for (j, s) in scaled.iter_mut().enumerate() {
            let sig = innovation_sigma[i];
            let v = if sig > T::zero() {
                m[(i, j)] * fault_scale[j] / sig
            } else {
                T::zero()
            };
            *s = v;
            row_max = row_max.max(v.abs());
        }
        for (j, s) in scaled.iter().enumerate() {
            if row_max > T::zero() && s.abs() >= deadband * row_max {
                c[(i, j)] = if *s > T::zero() { T::one() } else { -T::one() };
            }
        }
    }
    c
}

/// `F′ = C⁻¹ · flag`, reduced to fault signs: entries with |F′| ≥ 1 (to
/// round-off) become ±1, fractions become 0 — the paper's rule. Returns
/// `None` when `c_inv` is `None` (singular C) and also reports whether any
/// fraction was discarded (the flag pattern was not a combination of whole
/// columns, e.g. partial or simultaneous faults).
pub fn decouple_flags<T: Real>(c_inv: &Mat6<T>, flags: &[i8; 6]) -> ([i8; 6], bool) {
    let mut f = ImuVec::<T>::zeros();
    for (v, fl) in f.iter_mut().zip(flags.iter()) {
        *v = T::lit(f64::from(*fl));
    }
    let fp = c_inv * f;
    let mut out = [0i8; 6];
    let mut fractional = false;
    let tol = T::lit(1e-3);
    for (o, v) in out.iter_mut().zip(fp.iter()) {
        let a = v.abs();
        if a >= T::one() - tol {
            *o = if *v > T::zero() { 1 } else { -1 };
            if (a - a.round()).abs() > tol {
                fractional = true;
            }
        } else if a > tol {
            fractional = true;
        }
    }
    (out, fractional)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn determinants_match_the_spec() {
        let p: Mat6<f64> = paper_matrix(&PAPER_MATRIX_AS_PRINTED);
        let c: Mat6<f64> = paper_matrix(&PAPER_MATRIX_CORRECTED);
        assert!((p.determinant() + 2.0).abs() < 1e-12);
        assert!((c.determinant() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn single_column_patterns_decouple_exactly() {
        let c: Mat6<f64> = paper_matrix(&PAPER_MATRIX_CORRECTED);
        let ci = c.try_inverse().unwrap();
        for j in 0..6 {
            for sign in [-1i8, 1] {
                let mut flags = [0i8; 6];
                for (i, fl) in flags.iter_mut().enumerate() {
                    *fl = (PAPER_MATRIX_CORRECTED[i][j]) * sign;
                }
                let (f, frac) = decouple_flags(&ci, &flags);
                let mut expect = [0i8; 6];
                expect[j] = sign;
                assert_eq!(f, expect);
                assert!(!frac);
            }
        }
    }
}

//! Small dense kernels for the multi-scale tests on the leading `dim`
//! coordinates only (issue 14).
//!
//! The covariances of the tests are `N × N` with the identity beyond the
//! parity dimension (`pad`), and parity vectors are zero there, so every
//! factorisation and solve can stop at `dim` (6 of 9 for three triads:
//! a third of the Cholesky work). The kernels walk nalgebra's column-major
//! storage with iterators — no bounds-checked indexing in the loops — and
//! use forward substitution only where a quadratic form is all that is
//! needed (`dᵀ A⁻¹ d = ‖L⁻¹ d‖²`), half the work of a full solve.

use nalgebra::{SMatrix, SVector};

use crate::math::Real;

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

/// The [`cholesky_dim`] factor of a covariance that changes only on
/// learned blocks, in training and in a reconfiguration, kept between its
/// changes: the block stages read the block covariance's and two window
/// covariances' factors on every block, and refactorising an unchanged
/// matrix gives the same bits (the factorisation is deterministic).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct CachedFactor<T: Real, const N: usize> {
    /// Factorised in place (no 324-byte copy of a returned factor); `None`
    /// until first used (nothing to set up in the configuration).
    factor: Option<SMatrix<T, N, N>>,
    /// The factorisation succeeded.
    ok: bool,
    /// `factor` and `ok` are those of the matrix as it is now.
    current: bool,
}

impl<T: Real, const N: usize> CachedFactor<T, N> {
    /// No factor yet: the first [`get`](Self::get) computes it.
    pub(super) fn stale() -> Self {
        Self {
            factor: None,
            ok: false,
            current: false,
        }
    }

    /// The matrix (or the dimension) changed: factorise again on next use.
    pub(super) fn invalidate(&mut self) {
        self.current = false;
    }

    /// The factor of `a` on its leading `dim` coordinates, computed only
    /// when stale; `a` and `dim` must be those the cache was kept for
    /// (every change to them calls [`invalidate`](Self::invalidate)).
    pub(super) fn get(&mut self, a: &SMatrix<T, N, N>, dim: usize) -> Option<&SMatrix<T, N, N>> {
        if !self.current {
            let f = self.factor.get_or_insert_with(SMatrix::zeros);
            self.ok = cholesky_dim_in(f, a, dim).is_some();
            self.current = true;
        }
        self.factor.as_ref().filter(|_| self.ok)
    }
}

/// Cholesky factor `L` (lower) of the leading `dim × dim` block of `a`
/// (lower triangle read), identity beyond; `None` when that block is not
/// positive definite or not finite. The column operations and their order
/// are those of `crate::math::cholesky`.
pub(super) fn cholesky_dim<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
    dim: usize,
) -> Option<SMatrix<T, N, N>> {
    let mut l = SMatrix::<T, N, N>::identity();
    cholesky_dim_in(&mut l, a, dim)?;
    Some(l)
}

/// [`cholesky_dim`] into `l`'s storage (overwritten; on `None` it holds no
/// factor).
pub(super) fn cholesky_dim_in<T: Real, const N: usize>(
    l: &mut SMatrix<T, N, N>,
    a: &SMatrix<T, N, N>,
    dim: usize,
) -> Option<()> {
    let dim = dim.min(N);
    // Not `fill_with_identity`: nalgebra's element iterator costs ≈ 3,000
    // instructions for 9×9 on the M4F.
    *l = SMatrix::identity();
    for (j, (dst, src)) in l
        .as_mut_slice()
        .chunks_exact_mut(N)
        .zip(a.as_slice().chunks_exact(N))
        .enumerate()
        .take(dim)
    {
        for (d, s) in dst.iter_mut().zip(src.iter()).take(dim).skip(j) {
            *d = *s;
        }
    }
    factor_lower(l, dim)
}

/// [`cholesky_dim`] of `a + b w` into `l`'s leading `dim` block (its lower
/// triangle; every other entry of `l` is left as it was: nothing that
/// reads this factor reads them), the sum formed on the lower triangle it
/// reads only, straight into the factor's storage (the scale tests' `cov +
/// block_cov × w` as whole 9×9 products and sums, then copied into the
/// factor, cost ≈ 3 × 81 flops and moves more per window length). Each
/// entry is `a_ij + b_ij × w`, the operations of the matrix expression.
pub(super) fn cholesky_dim_sum<T: Real, const N: usize>(
    l: &mut SMatrix<T, N, N>,
    a: &SMatrix<T, N, N>,
    b: &SMatrix<T, N, N>,
    w: T,
    dim: usize,
) -> Option<()> {
    let dim = dim.min(N);
    for (j, ((dst, sa), sb)) in l
        .as_mut_slice()
        .chunks_exact_mut(N)
        .zip(a.as_slice().chunks_exact(N))
        .zip(b.as_slice().chunks_exact(N))
        .enumerate()
        .take(dim)
    {
        for ((d, x), y) in dst
            .iter_mut()
            .zip(sa.iter())
            .zip(sb.iter())
            .take(dim)
            .skip(j)
        {
            *d = *x + *y * w;
        }
    }
    factor_lower(l, dim)
}

/// Factorises in place the lower triangle of the leading `dim` block of
/// `l` (identity beyond); `None` when it is not positive definite.
pub(super) fn factor_lower<T: Real, const N: usize>(
    l: &mut SMatrix<T, N, N>,
    dim: usize,
) -> Option<()> {
    // The parity dimensions of up to nine sensors and the calibration's
    // size with their loops at a compile-time dimension (see
    // `factor_lower_d`), anything else at run time.
    match dim.min(N) {
        2 => factor_lower_d::<T, N, 2>(l),
        3 => factor_lower_d::<T, N, 3>(l),
        4 => factor_lower_d::<T, N, 4>(l),
        5 => factor_lower_d::<T, N, 5>(l),
        6 => factor_lower_d::<T, N, 6>(l),
        16 => factor_lower_d::<T, N, 16>(l),
        d => factor_lower_dyn(l, d),
    }
}

/// [`factor_lower`] at a dimension `D` known at compile time: the same
/// column operations in the same order (issue 14: the run-time loops cost
/// ≈ 2,500 instructions for the calibration's 16×16 on the M4F).
fn factor_lower_d<T: Real, const N: usize, const D: usize>(l: &mut SMatrix<T, N, N>) -> Option<()> {
    let s = l.as_mut_slice();
    for j in 0..D {
        for k in 0..j {
            let f = *s.get(k * N + j)?;
            for i in j..D {
                let x = *s.get(k * N + i)?;
                let d = s.get_mut(j * N + i)?;
                *d -= f * x;
            }
        }
        let d = s.get_mut(j * N + j)?;
        if !(*d > T::zero() && d.finite()) {
            return None;
        }
        let root = d.sqrt_fast();
        *d = root;
        let inv = T::one() / root;
        for i in j + 1..D {
            let x = s.get_mut(j * N + i)?;
            *x *= inv;
        }
    }
    Some(())
}

/// [`factor_lower`] at a run-time dimension.
fn factor_lower_dyn<T: Real, const N: usize>(l: &mut SMatrix<T, N, N>, dim: usize) -> Option<()> {
    let s = l.as_mut_slice();
    for j in 0..dim {
        let (done, rest) = s.split_at_mut(j * N);
        let col_j = rest.get_mut(j..dim)?;
        for col_k in done.chunks_exact(N) {
            let f = *col_k.get(j)?;
            for (d, x) in col_j.iter_mut().zip(col_k.get(j..dim)?.iter()) {
                *d -= f * *x;
            }
        }
        let (d, below) = col_j.split_first_mut()?;
        if !(*d > T::zero() && d.finite()) {
            return None;
        }
        let root = d.sqrt_fast();
        *d = root;
        let inv = T::one() / root;
        for x in below.iter_mut() {
            *x *= inv;
        }
    }
    Some(())
}

/// `b ← L⁻¹ b` on the first `dim` entries (forward substitution).
pub(super) fn forward<T: Real, const N: usize>(l: &SMatrix<T, N, N>, b: &mut [T], dim: usize) {
    let dim = dim.min(N);
    for (j, col) in l.as_slice().chunks_exact(N).enumerate().take(dim) {
        let (head, tail) = b.split_at_mut((j + 1).min(b.len()));
        let (Some(yj), Some(ljj), Some(below)) = (head.last_mut(), col.get(j), col.get(j + 1..dim))
        else {
            return;
        };
        *yj /= *ljj;
        let y = *yj;
        for (bi, lij) in tail.iter_mut().zip(below.iter()) {
            *bi -= *lij * y;
        }
    }
}

/// `L⁻¹ b` on the first `D` entries of `b`, for a dimension known at
/// compile time (issue 14: the loops unroll and `y` stays in registers; the
/// run-time `dim` kernels cost ≈ 7–11 instructions per multiply-add on
/// the M4F). Row by row, `yᵢ = (bᵢ − lᵢ₀ y₀ − lᵢ₁ y₁ − …) / lᵢᵢ` with the
/// subtractions in column order: each `yᵢ` gets the operations, in order,
/// that [`forward`]'s column sweep applies to `bᵢ`, so the bits are its.
pub(super) fn forward_d<T: Real, const N: usize, const D: usize>(
    l: &SMatrix<T, N, N>,
    b: &[T],
) -> [T; D] {
    let ls = l.as_slice();
    let mut y = [T::zero(); D];
    for i in 0..D {
        let mut s = b.get(i).copied().unwrap_or(T::zero());
        // Over all `D` columns with the test inside, not `0..i`: the loop's
        // trip count is then fixed and the compiler unrolls it (the 16×16
        // sweeps ≈ 1,200 → ≈ 900 instructions on the M4F).
        for j in 0..D {
            if j < i {
                let lij = ls.get(j * N + i).copied().unwrap_or(T::zero());
                s -= lij * y.get(j).copied().unwrap_or(T::zero());
            }
        }
        if let Some(yi) = y.get_mut(i) {
            *yi = s / ls.get(i * N + i).copied().unwrap_or(T::one());
        }
    }
    y
}

/// [`backward`] on `D` entries known at compile time (see [`forward_d`]):
/// the same dot products, summed in the same order.
pub(super) fn backward_d<T: Real, const N: usize, const D: usize>(
    l: &SMatrix<T, N, N>,
    x: &mut [T; D],
) {
    let ls = l.as_slice();
    for i in (0..D).rev() {
        let mut s = T::zero();
        // A fixed trip count, as in `forward_d`.
        for j in 0..D {
            if j > i {
                let lji = ls.get(i * N + j).copied().unwrap_or(T::zero());
                s += lji * x.get(j).copied().unwrap_or(T::zero());
            }
        }
        if let Some(xi) = x.get_mut(i) {
            *xi = (*xi - s) / ls.get(i * N + i).copied().unwrap_or(T::one());
        }
    }
}

/// `b ← L⁻ᵀ b` on the first `dim` entries (backward substitution).
#[cfg(test)]
pub(super) fn backward<T: Real, const N: usize>(l: &SMatrix<T, N, N>, b: &mut [T], dim: usize) {
    let dim = dim.min(N);
    for (i, col) in l.as_slice().chunks_exact(N).enumerate().take(dim).rev() {
        let (head, tail) = b.split_at_mut((i + 1).min(b.len()));
        let (Some(xi), Some(lii), Some(below)) = (head.last_mut(), col.get(i), col.get(i + 1..dim))
        else {
            return;
        };
        let s = dot(below, tail);
        *xi = (*xi - s) / *lii;
    }
}

/// `Σ aᵢ bᵢ` over the shorter of the two.
pub(super) fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    a.iter()
        .zip(b.iter())
        .fold(T::zero(), |acc, (x, y)| acc + *x * *y)
}

/// `dᵀ A⁻¹ d = ‖L⁻¹ d‖²` on the first `dim` coordinates.
pub(super) fn quad_form<T: Real, const N: usize>(
    l: &SMatrix<T, N, N>,
    d: &SVector<T, N>,
    dim: usize,
) -> T {
    let mut y = *d;
    forward(l, y.as_mut_slice(), dim);
    let y = y.as_slice().get(..dim.min(N)).unwrap_or(&[]);
    dot(y, y)
}

/// Best single-sensor hypothesis `(k, score, bias)` for the parity residual
/// `r` with covariance factor `l` on the first `dim` coordinates, and the
/// runner-up's score: `z_k = v_kᵀ Σ⁻¹ r = (L⁻¹v_k)·(L⁻¹r)`,
/// `q_k = ‖L⁻¹ v_k‖²`, score `z_k²/q_k`, bias `z_k/q_k`.
pub(super) fn best_two<T: Real, const N: usize>(
    l: &SMatrix<T, N, N>,
    v: &SMatrix<T, N, N>,
    r: &SVector<T, N>,
    active: &[bool; N],
    dim: usize,
) -> (Option<(usize, T, T)>, T) {
    // The parity dimensions of up to nine sensors with their loops unrolled
    // (see `forward_d`), the rest at run time.
    match dim.min(N) {
        1 => best_two_d::<T, N, 1>(l, v, r, active),
        2 => best_two_d::<T, N, 2>(l, v, r, active),
        3 => best_two_d::<T, N, 3>(l, v, r, active),
        4 => best_two_d::<T, N, 4>(l, v, r, active),
        5 => best_two_d::<T, N, 5>(l, v, r, active),
        6 => best_two_d::<T, N, 6>(l, v, r, active),
        d => best_two_dyn(l, v, r, active, d),
    }
}

/// One hypothesis' score against the best two so far (`best`, `second`).
fn rank<T: Real>(best: &mut Option<(usize, T, T)>, second: &mut T, k: usize, q: T, zk: T) {
    if q.partial_cmp(&T::lit(1e-12)) != Some(core::cmp::Ordering::Greater) {
        return;
    }
    let score = zk * zk / q;
    match *best {
        Some((_, sc, _)) if score <= sc => *second = second.max(score),
        _ => {
            if let Some((_, sc, _)) = *best {
                *second = second.max(sc);
            }
            *best = Some((k, score, zk / q));
        }
    }
}

/// [`best_two`] for a parity dimension `D` known at compile time: the
/// same operations in the same order, without the per-hypothesis copies
/// of the `v` column (a `memclr` and a `memcpy` call each, ≈ 90
/// instructions per hypothesis on the M4F).
fn best_two_d<T: Real, const N: usize, const D: usize>(
    l: &SMatrix<T, N, N>,
    v: &SMatrix<T, N, N>,
    r: &SVector<T, N>,
    active: &[bool; N],
) -> (Option<(usize, T, T)>, T) {
    let s: [T; D] = forward_d::<T, N, D>(l, r.as_slice());
    let mut best: Option<(usize, T, T)> = None;
    let mut second = T::zero();
    for (k, (col, on)) in v.as_slice().chunks_exact(N).zip(active.iter()).enumerate() {
        if !on {
            continue;
        }
        let u: [T; D] = forward_d::<T, N, D>(l, col);
        rank(&mut best, &mut second, k, dot(&u, &u), dot(&u, &s));
    }
    (best, second)
}

/// [`best_two`] at a run-time dimension.
fn best_two_dyn<T: Real, const N: usize>(
    l: &SMatrix<T, N, N>,
    v: &SMatrix<T, N, N>,
    r: &SVector<T, N>,
    active: &[bool; N],
    dim: usize,
) -> (Option<(usize, T, T)>, T) {
    let dim = dim.min(N);
    let mut s = *r;
    forward(l, s.as_mut_slice(), dim);
    let s = s.as_slice().get(..dim).unwrap_or(&[]);
    let mut best: Option<(usize, T, T)> = None;
    let mut second = T::zero();
    for (k, (col, on)) in v.as_slice().chunks_exact(N).zip(active.iter()).enumerate() {
        if !on {
            continue;
        }
        let mut u = [T::zero(); N];
        for (d, x) in u.iter_mut().zip(col.iter()).take(dim) {
            *d = *x;
        }
        forward(l, &mut u, dim);
        let u = u.get(..dim).unwrap_or(&[]);
        rank(&mut best, &mut second, k, dot(u, u), dot(u, s));
    }
    (best, second)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::cholesky;

    /// A 9×9 covariance padded beyond `dim` = 6, as the tests hold them.
    fn padded() -> SMatrix<f64, 9, 9> {
        let b = SMatrix::<f64, 9, 9>::from_fn(|i, j| ((i * 7 + j * 3) % 5) as f64 - 2.0);
        let a = b * b.transpose() + SMatrix::identity() * 3.0;
        SMatrix::from_fn(|i, j| {
            if i < 6 && j < 6 {
                a[(i, j)]
            } else if i == j {
                1.0
            } else {
                0.0
            }
        })
    }

    #[test]
    fn factor_and_solves_match_the_full_size_ones() {
        let a = padded();
        let l = cholesky_dim(&a, 6).unwrap();
        let full = cholesky(&a).unwrap();
        assert!((l - full).abs().max() < 1e-12, "{l} vs {full}");
        // Solve A x = b both ways.
        let b = SVector::<f64, 9>::from_fn(|i, _| if i < 6 { i as f64 - 2.5 } else { 0.0 });
        let mut x = b;
        forward(&l, x.as_mut_slice(), 6);
        backward(&l, x.as_mut_slice(), 6);
        assert!((a * x - b).norm() < 1e-10);
        let q = quad_form(&l, &b, 6);
        let want = b.dot(&(a.try_inverse().unwrap() * b));
        assert!((q - want).abs() < 1e-10 * want);
        // Not positive definite: refused.
        let mut bad = a;
        bad[(2, 2)] = -1.0;
        assert!(cholesky_dim(&bad, 6).is_none());
    }

    /// The fused sum and factor give the bits of the matrix expression
    /// factorised (`f32`, as on the target).
    #[test]
    fn the_fused_sum_factor_is_that_of_the_matrix_sum() {
        let a = padded().map(|x| x as f32);
        let b = padded().transpose().map(|x| (x * 0.37) as f32);
        let bits = |m: &SMatrix<f32, 9, 9>| m.map(f32::to_bits);
        for w in [0.0_f32, 0.013, 0.7, 3.1] {
            let mut fused = SMatrix::identity();
            cholesky_dim_sum(&mut fused, &a, &b, w, 6).unwrap();
            let plain = cholesky_dim(&(a + b * w), 6).unwrap();
            assert_eq!(bits(&fused), bits(&plain), "w {w}");
        }
        // Not positive definite: no factor, as for the plain sum.
        assert!(cholesky_dim_sum(&mut SMatrix::zeros(), &a, &b, -1e3, 6).is_none());
        assert!(cholesky_dim(&(a + b * -1e3), 6).is_none());
    }

    /// The unrolled kernels give the bits of the run-time ones (`f32`, as
    /// on the target): the forward and backward sweeps and the
    /// factorisation at the calibration's size, the factorisation at 6, and
    /// `best_two` at every parity dimension it unrolls.
    #[test]
    fn the_unrolled_kernels_are_bit_identical() {
        let bits = |x: &[f32]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        let a16 = SMatrix::<f64, 16, 16>::from_fn(|i, j| ((i * 5 + j * 11) % 7) as f64 - 3.0);
        let a16 = (a16 * a16.transpose() + SMatrix::identity() * 2.0).map(|x| x as f32);
        let l16 = cholesky_dim(&a16, 16).unwrap();
        let b16 = SVector::<f32, 16>::from_fn(|i, _| (i as f32 * 0.37).sin());
        let mut want = b16;
        forward(&l16, want.as_mut_slice(), 16);
        let mut got: [f32; 16] = forward_d::<f32, 16, 16>(&l16, b16.as_slice());
        assert_eq!(bits(&got), bits(want.as_slice()));
        backward(&l16, want.as_mut_slice(), 16);
        backward_d(&l16, &mut got);
        assert_eq!(bits(&got), bits(want.as_slice()));
        // The factorisation at 16 and at 6 (in a 9×9).
        // (`cholesky_dim` starts from the lower triangle, zero above.)
        let mut dyn16 =
            SMatrix::<f32, 16, 16>::from_fn(|i, j| if i >= j { a16[(i, j)] } else { 0.0 });
        factor_lower_dyn(&mut dyn16, 16).unwrap();
        assert_eq!(bits(l16.as_slice()), bits(dyn16.as_slice()));
        let a9 = padded().map(|x| x as f32);
        let (mut d6, mut r6) = (a9, a9);
        factor_lower_d::<f32, 9, 6>(&mut d6).unwrap();
        factor_lower_dyn(&mut r6, 6).unwrap();
        assert_eq!(bits(d6.as_slice()), bits(r6.as_slice()));
        let v = SMatrix::<f32, 9, 9>::from_fn(|i, j| (((i + 2) * (j + 1)) % 7) as f32 - 3.1);
        let r = SVector::<f32, 9>::from_fn(|i, _| 0.3 * i as f32 - 1.1);
        let mut active = [true; 9];
        active[4] = false;
        for dim in 1..=9 {
            let a = padded().map(|x| x as f32);
            let a = SMatrix::<f32, 9, 9>::from_fn(|i, j| {
                if i < dim && j < dim {
                    a[(i, j)]
                } else if i == j {
                    1.0
                } else {
                    0.0
                }
            });
            let l = cholesky_dim(&a, dim).unwrap();
            let (got, got_second) = best_two(&l, &v, &r, &active, dim);
            let (want, want_second) = best_two_dyn(&l, &v, &r, &active, dim);
            let key =
                |b: Option<(usize, f32, f32)>| b.map(|(k, s, z)| (k, s.to_bits(), z.to_bits()));
            assert_eq!(key(got), key(want), "dim {dim}");
            assert_eq!(got_second.to_bits(), want_second.to_bits(), "dim {dim}");
        }
    }

    #[test]
    fn best_two_matches_the_closed_form() {
        let a = padded();
        let l = cholesky_dim(&a, 6).unwrap();
        let v = SMatrix::<f64, 9, 9>::from_fn(|i, j| {
            if i < 6 {
                (((i + 2) * (j + 1)) % 7) as f64 - 3.0
            } else {
                0.0
            }
        });
        let r = SVector::<f64, 9>::from_fn(|i, _| if i < 6 { 0.3 * i as f64 - 1.0 } else { 0.0 });
        let inv = a.try_inverse().unwrap();
        let mut active = [true; 9];
        active[4] = false;
        let scores: Vec<(usize, f64, f64)> = (0..9)
            .filter(|k| active[*k])
            .map(|k| {
                let vk = v.column(k);
                let z = vk.dot(&(inv * r));
                let q = vk.dot(&(inv * vk));
                (k, z * z / q, z / q)
            })
            .collect();
        let best = scores
            .iter()
            .cloned()
            .fold(scores[0], |b, s| if s.1 > b.1 { s } else { b });
        let second = scores
            .iter()
            .filter(|s| s.0 != best.0)
            .map(|s| s.1)
            .fold(0.0, f64::max);
        let (got, got_second) = best_two(&l, &v, &r, &active, 6);
        let got = got.unwrap();
        assert_eq!(got.0, best.0);
        assert!((got.1 - best.1).abs() < 1e-9 * best.1);
        assert!((got.2 - best.2).abs() < 1e-9 * best.2.abs().max(1.0));
        assert!((got_second - second).abs() < 1e-9 * second.max(1.0));
    }
}

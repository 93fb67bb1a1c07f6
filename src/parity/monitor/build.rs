//! Building the white-noise tests of a parity space from a learned
//! baseline in bounded stages (issue 17): the covariance's factor, the
//! projections and the PCA basis in one stage, then each sensor's CUSUM
//! threshold in two (a software-`f64` root search on the M4F). The monitor
//! runs one stage per step at the end of training and after an isolation or
//! a failure (`reconfig.rs`), so no step carries the whole build.

use nalgebra::SMatrix;

use crate::math::{cholesky, cholesky_solve_right, symmetric_eigen, Real};

use super::super::config::ParityConfig;
use super::super::space::ParitySpace;
use super::super::training::Baseline;
use super::white::Tests;

/// Stages of [`build_stage`] at most: the covariance's factor, the
/// projections and the PCA basis, then the CUSUM threshold of each sensor
/// that has one in two stages (a software-`f64` root search each on the
/// M4F).
pub(super) const fn build_stages(n: usize) -> usize {
    1 + 2 * n
}

impl<T: Real, const N: usize> Tests<T, N> {
    /// Tests of `baseline` not built yet (see [`build_stage`]).
    pub(super) fn new(baseline: Baseline<T, N>) -> Self {
        Self {
            baseline,
            cov_inv: SMatrix::zeros(),
            a: SMatrix::zeros(),
            q: [T::zero(); N],
            glt_threshold: T::zero(),
            pca_basis: SMatrix::zeros(),
            pca_var: [T::zero(); 2],
            pca_threshold: T::zero(),
            kappa: [T::zero(); N],
            cusum_h: [T::zero(); N],
        }
    }
}

/// Runs stage `stage` (of [`build_stages`]`(N)`) of building every
/// threshold and projection of `space` from `t.baseline` (issue 17:
/// bounded cost per stage, so the monitor runs one per step). `None`: the baseline gives
/// no tests.
pub(super) fn build_stage<T: Real, const N: usize>(
    t: &mut Tests<T, N>,
    stage: usize,
    newton: &mut Newton,
    space: &ParitySpace<T, N>,
    cfg: &ParityConfig<T>,
    scales: &[T; 3],
    chi2: &[T; N],
) -> Option<usize> {
    if stage == 0 {
        projections(t, space, cfg, scales, chi2)?;
        pca(t, space, cfg, scales, chi2)?;
        return Some(next_cusum(t, 0));
    }
    let (k, second) = ((stage - 1) / 2, (stage - 1) % 2 == 1);
    cusum(t, k, second, newton, cfg, scales)?;
    Some(if second {
        next_cusum(t, k + 1)
    } else {
        stage + 1
    })
}

/// First stage of the CUSUM of the first sensor from `from` on that has
/// one (`q_k > 0`), or [`build_stages`]`(N)` when none is left.
fn next_cusum<T: Real, const N: usize>(t: &Tests<T, N>, from: usize) -> usize {
    (from..N)
        .find(|k| t.q.get(*k).is_some_and(|q| *q > T::zero()))
        .map_or(build_stages(N), |k| 1 + 2 * k)
}

/// `Σ_b⁻¹`, `a_k = Σ_b⁻¹ v_k`, `q_k` and the GLT threshold.
fn projections<T: Real, const N: usize>(
    t: &mut Tests<T, N>,
    space: &ParitySpace<T, N>,
    cfg: &ParityConfig<T>,
    scales: &[T; 3],
    chi2: &[T; N],
) -> Option<()> {
    let dim = space.dim();
    if dim == 0 {
        return None;
    }
    let block_cov = &t.baseline.block_cov;
    // Pad the unused block with identity so the factorisation is full rank.
    let l = cholesky(&padded(block_cov, dim, T::one())).ok()?;
    let mut cov_inv = cholesky_solve_right(&l, &SMatrix::<T, N, N>::identity());
    let mut a = cholesky_solve_right(&l, &space.v().transpose()).transpose();
    for i in dim..N {
        cov_inv.row_mut(i).fill(T::zero());
        cov_inv.column_mut(i).fill(T::zero());
        a.row_mut(i).fill(T::zero());
    }
    t.q = core::array::from_fn(|k| {
        if space.detectable(k) {
            space.v().column(k).dot(&a.column(k))
        } else {
            T::zero()
        }
    });
    t.cov_inv = cov_inv;
    t.a = a;
    t.glt_threshold = *chi2.get(dim)? * cfg.threshold_margin * scales[0];
    Some(())
}

/// The PCA pattern test's basis, variances and threshold.
fn pca<T: Real, const N: usize>(
    t: &mut Tests<T, N>,
    space: &ParitySpace<T, N>,
    cfg: &ParityConfig<T>,
    scales: &[T; 3],
    chi2: &[T; N],
) -> Option<()> {
    let dim = space.dim();
    let block_cov = &t.baseline.block_cov;
    // Pad with zeros: the unused directions get eigenvalue 0 and sort last.
    let (values, vectors) = symmetric_eigen(&padded(block_cov, dim, T::zero()))?;
    let pca_dims = dim.min(2);
    for c in 0..pca_dims {
        t.pca_basis.set_column(c, &vectors.column(c));
        if let Some(v) = t.pca_var.get_mut(c) {
            *v = values.get(c).copied().unwrap_or(T::zero());
        }
    }
    t.pca_threshold = *chi2.get(pca_dims)? * cfg.threshold_margin * scales[1];
    Some(())
}

/// The parity block covariance's leading `dim × dim` block, with `diagonal`
/// on the rest of the diagonal and zeros elsewhere.
fn padded<T: Real, const N: usize>(
    block_cov: &SMatrix<T, N, N>,
    dim: usize,
    diagonal: T,
) -> SMatrix<T, N, N> {
    SMatrix::<T, N, N>::from_fn(|i, j| {
        if i < dim && j < dim {
            at(block_cov, i, j)
        } else if i == j {
            diagonal
        } else {
            T::zero()
        }
    })
}

/// Newton iterations of the CUSUM threshold's root search in the first of
/// a sensor's two stages (software `f64` `exp` on the M4F: about 3 k
/// instructions each).
const NEWTON_SPLIT: u8 = 3;
/// Iterations at most (those of [`cusum_threshold`](crate::stats::cusum_threshold)).
const NEWTON_MAX: u8 = 60;
/// Marks a converged search.
const NEWTON_DONE: u8 = u8::MAX;

/// The root search of Siegmund's ARL approximation, as
/// [`cusum_threshold`](crate::stats::cusum_threshold) runs it, resumable: `y` the iterate, `.1` the
/// iterations done ([`NEWTON_DONE`] once converged).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Newton(f64, u8);

impl Newton {
    /// Before the first iteration.
    pub(super) const START: Self = Self(0.0, 0);

    /// Starts the search for `c = 2κ²·ARL₀` (`None`: bad inputs).
    fn begin(kappa: f64, arl0: f64) -> Option<(Self, f64)> {
        if kappa.is_nan() || kappa <= 0.0 || arl0.is_nan() || arl0 <= 1.0 {
            return None;
        }
        let c = 2.0 * kappa * kappa * arl0;
        if !c.is_finite() {
            return None;
        }
        Some((Self(libm::log1p(c) + 1.0, 0), c))
    }

    /// Iterates until `until` iterations are done or it converges.
    fn run(&mut self, c: f64, until: u8) {
        while self.1 < until.min(NEWTON_MAX) {
            let e = libm::exp(self.0);
            let step = (e - self.0 - 1.0 - c) / (e - 1.0);
            self.0 -= step;
            self.1 += 1;
            if step.abs() <= 1e-12 * self.0 {
                self.1 = NEWTON_DONE;
            }
        }
    }
}

/// Sensor `k`'s CUSUM reference and threshold, in two stages (`second`):
/// the first iterations of the threshold's root search, then the rest —
/// the same iterations as [`cusum_threshold`](crate::stats::cusum_threshold).
fn cusum<T: Real, const N: usize>(
    t: &mut Tests<T, N>,
    k: usize,
    second: bool,
    newton: &mut Newton,
    cfg: &ParityConfig<T>,
    scales: &[T; 3],
) -> Option<()> {
    let (Some(&qk), Some(kk), Some(hk)) = (t.q.get(k), t.kappa.get_mut(k), t.cusum_h.get_mut(k))
    else {
        return Some(());
    };
    if qk <= T::zero() {
        return Some(());
    }
    // A bias b on sensor k shifts the standardised projection by b·√q_k.
    let shift = (cfg.cusum_bias * qk.sqrt()).to_f64();
    let kappa_k = 0.5 * shift;
    let (start, c) = Newton::begin(kappa_k, cfg.cusum_arl0)?;
    if !second {
        *newton = start;
        newton.run(c, NEWTON_SPLIT);
        return Some(());
    }
    newton.run(c, NEWTON_MAX);
    let h = (newton.0 / (2.0 * kappa_k) - 1.166).max(0.0);
    *kk = T::lit(kappa_k);
    *hk = T::lit(h) * cfg.threshold_margin * scales[2];
    Some(())
}

fn at<T: Real, const N: usize>(m: &SMatrix<T, N, N>, i: usize, j: usize) -> T {
    m.get((i, j)).copied().unwrap_or(T::zero())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::cusum_threshold;

    #[test]
    fn the_split_root_search_gives_the_thresholds_of_cusum_threshold() {
        for kappa in [1e-3, 0.01, 0.05, 0.2, 0.5, 1.0, 3.0] {
            for arl0 in [10.0, 1e4, 1e9] {
                let want = cusum_threshold(kappa, arl0).unwrap();
                let (mut n, c) = Newton::begin(kappa, arl0).unwrap();
                n.run(c, NEWTON_SPLIT);
                n.run(c, NEWTON_MAX);
                let got = (n.0 / (2.0 * kappa) - 1.166).max(0.0);
                assert_eq!(got.to_bits(), want.to_bits(), "κ {kappa} ARL₀ {arl0}");
            }
        }
        assert!(Newton::begin(0.0, 1e9).is_none());
        assert!(Newton::begin(0.1, 1.0).is_none());
    }
}

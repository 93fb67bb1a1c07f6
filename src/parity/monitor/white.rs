//! The monitor's white-noise tests (SPEC §7, [PAR]): training of offset,
//! leakage and noise, threshold calibration, the PCA pattern, windowed χ²
//! (GLT) and per-sensor CUSUM tests, and isolation by fault direction.

use nalgebra::{SMatrix, SVector, Vector3};

use crate::math::{cholesky, cholesky_solve_right, symmetric_eigen, Real};

use super::super::config::{ParityConfig, ParityDetector};
use super::super::space::ParitySpace;
use super::super::training::{Baseline, Trainer};
use super::{DetectorFlags, ParityMonitor, ParityPhase, ParityReport};

/// Blocks a CUSUM alarm takes at most to clear once the bias is gone
/// (5 s with the default 0.1-s blocks).
const CUSUM_CLEAR_BLOCKS: f64 = 50.0;

/// Derived per-space quantities (recomputed on reconfiguration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Tests<T: Real, const N: usize> {
    pub(super) baseline: Baseline<T, N>,
    /// `Σ_b⁻¹` (identity block beyond `dim`, then zeroed).
    pub(super) cov_inv: SMatrix<T, N, N>,
    /// Column k: `a_k = Σ_b⁻¹ v_k`.
    pub(super) a: SMatrix<T, N, N>,
    /// `q_k = v_kᵀ Σ_b⁻¹ v_k`.
    pub(super) q: [T; N],
    pub(super) glt_threshold: T,
    pub(super) pca_basis: SMatrix<T, N, 2>,
    pub(super) pca_var: [T; 2],
    pub(super) pca_threshold: T,
    pub(super) kappa: [T; N],
    pub(super) cusum_h: [T; N],
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    pub(super) fn train(&mut self, p: &SVector<T, N>, x: &Vector3<T>) {
        self.trainer.add(p, x);
        if !self.trainer.done() {
            return;
        }
        // All at once (the lead-in's calibration starts on the next sample;
        // only a reconfiguration in flight is built one stage per step).
        match self
            .trainer
            .finish()
            .and_then(|b| derive_tests(&self.space, b, &self.cfg, &self.scales, &self.chi2))
        {
            Some(t) => {
                self.tests = Some(t);
                self.phase = if self.cfg.calibrate_samples > 0 {
                    ParityPhase::Calibrating
                } else {
                    ParityPhase::Monitoring
                };
            }
            // Non-finite training data: train again rather than test with it.
            None => {
                self.trainer =
                    Trainer::new(self.cfg.train_samples, self.cfg.block_len, self.cfg.ridge)
            }
        }
    }

    pub(super) fn monitor(
        &mut self,
        p: &SVector<T, N>,
        x: &Vector3<T>,
        report: &mut ParityReport<T, N>,
    ) {
        let Some(t) = self.tests else {
            return;
        };
        let r = p - t.baseline.leak * x - t.baseline.offset;
        self.block += r;
        self.block_n = self.block_n.saturating_add(1);
        if self.block_n < self.cfg.block_len {
            return;
        }
        let b = self.block / T::lit(f64::from(self.cfg.block_len));
        self.block = SVector::zeros();
        self.block_n = 0;
        if let Some(slot) = self.window.get_mut(self.head) {
            *slot = b;
        }
        let k_win = self.cfg.window_blocks;
        self.head = (self.head + 1) % k_win;
        self.filled = (self.filled + 1).min(k_win);
        report.decision = true;

        // CUSUMs: per sensor direction, on the standardised block projection.
        let mut cusum_ratio = T::zero();
        let mut cusum_arg = None;
        for k in 0..N {
            let (Some(&q), Some(&kappa), Some(&h)) = (t.q.get(k), t.kappa.get(k), t.cusum_h.get(k))
            else {
                continue;
            };
            if q <= T::zero() || h <= T::zero() {
                continue;
            }
            let s = t.a.column(k).dot(&b) / q.sqrt();
            let (Some(gp), Some(gn)) = (self.cusum_pos.get_mut(k), self.cusum_neg.get_mut(k))
            else {
                continue;
            };
            // Page's CUSUM, held below `h + κ·CUSUM_CLEAR_BLOCKS`: the alarm
            // is raised as before (at `h`), but once the bias is gone it
            // clears within that many blocks (it decays by ≈ κ per block)
            // instead of after as long as the excursion took to build —
            // minutes after a gross transient (issue 16, found by the
            // parity fuzz target).
            let cap = h + kappa * T::lit(CUSUM_CLEAR_BLOCKS);
            *gp = (*gp + s - kappa).max(T::zero()).min(cap);
            *gn = (*gn - s - kappa).max(T::zero()).min(cap);
            let ratio = gp.max(*gn) / h;
            if !ratio.finite() {
                *gp = T::zero();
                *gn = T::zero();
                continue;
            }
            if ratio > cusum_ratio {
                cusum_ratio = ratio;
                cusum_arg = Some(k);
            }
        }
        report.cusum_ratio = cusum_ratio;
        report.flags.cusum = cusum_ratio > T::one();

        // Window tests once the window is full.
        let mut mean = SVector::<T, N>::zeros();
        if self.filled >= k_win {
            for w in self.window.iter().take(k_win) {
                mean += w;
            }
            mean /= T::lit(k_win as f64);
            let kf = T::lit(k_win as f64);
            report.glt = kf * mean.dot(&(t.cov_inv * mean));
            report.flags.glt = report.glt > t.glt_threshold;
            let y = t.pca_basis.transpose() * mean;
            report.pattern = [y.x, y.y];
            let mut pca = T::zero();
            for (yi, vi) in y.iter().zip(t.pca_var.iter()) {
                if *vi > T::zero() {
                    pca += *yi * *yi / *vi;
                }
            }
            report.pca = kf * pca;
            report.flags.pca = report.pca > t.pca_threshold;
            if !report.glt.finite() || !report.pca.finite() {
                // Cannot happen with finite samples; never let NaN decide.
                report.flags.glt = false;
                report.flags.pca = false;
                self.filled = 0;
            }
            if let Some((ratio, arg)) = self.restart_after_gross(&t, report) {
                cusum_ratio = ratio;
                cusum_arg = arg;
            }
        }
        if self.phase == ParityPhase::Calibrating {
            self.calibrate(&t, &b, report);
            return;
        }
        let fault = match self.cfg.detector {
            ParityDetector::Pca => report.flags.pca,
            ParityDetector::Glt => report.flags.glt,
            ParityDetector::Cusum => report.flags.cusum,
            ParityDetector::GltOrCusum => report.flags.glt || report.flags.cusum,
            // Decided per block in `multiscale_block`.
            ParityDetector::Multiscale => return,
        };
        report.fault = fault;

        // Isolation: the direction that explains the window mean best (or,
        // before the window fills, the CUSUM that fired).
        let basis = if self.filled >= k_win { mean } else { b };
        let (suspect, bias) = isolate(&t, &basis, self.space.active());
        report.suspect = if self.filled >= k_win {
            suspect
        } else {
            cusum_arg.or(suspect)
        };
        report.bias_estimate = bias;

        if !fault {
            self.suspect_run = (None, 0);
            let quiet = report.glt < t.glt_threshold * T::lit(0.5) && cusum_ratio < T::lit(0.5);
            if quiet && self.cfg.drift_blocks > T::one() {
                // Follow slow bias drift (within the bias-instability spec).
                let gain = T::one() / self.cfg.drift_blocks;
                if let Some(tests) = self.tests.as_mut() {
                    tests.baseline.offset += b * gain;
                }
            }
            return;
        }
        let Some(k) = report.suspect else {
            return;
        };
        if !self.space.isolable(k) {
            // Detect-only geometry (e.g. two aligned triads): say so by not
            // isolating; `fault` stays raised.
            self.suspect_run = (None, 0);
            return;
        }
        if self.vote_to_isolate(k, report) {
            report.flags = DetectorFlags::default();
        }
    }

    /// After a gross bias (one the window test flags) has gone — the window
    /// test back below half its threshold — the CUSUM excess above `h` it
    /// built says nothing about what is left, and is cut to what
    /// `window_blocks` blocks of the smallest bias the CUSUMs are tuned to
    /// (`2κ`) would add: `h + window_blocks · κ`. Issue 16, found by the
    /// parity fuzz target in a detect-only space: with the excess at the cap
    /// (`h + 50 κ`), the offset the drift tracker could not follow during
    /// the alarm (bias random walk, 0.33 block σ on a sensor with
    /// κ = 0.52) made the CUSUM decay by `κ − μ` instead of `κ` per block,
    /// and the alarm stood 11 s after valid input returned. A bias that
    /// stays keeps the CUSUM rising from there (the alarm stands); a bias
    /// that never reaches the window test's threshold is not affected. The
    /// CUSUM ratio and its argument, recomputed, when a restart happened.
    fn restart_after_gross(
        &mut self,
        t: &Tests<T, N>,
        report: &mut ParityReport<T, N>,
    ) -> Option<(T, Option<usize>)> {
        if report.flags.glt {
            self.cusum_gross = true;
            return None;
        }
        let quiet = report.glt.finite() && report.glt < t.glt_threshold * T::lit(0.5);
        if !self.cusum_gross || !quiet {
            return None;
        }
        self.cusum_gross = false;
        let blocks = T::lit(self.cfg.window_blocks as f64);
        let mut best = (T::zero(), None);
        for (k, ((gp, gn), (h, kappa))) in self
            .cusum_pos
            .iter_mut()
            .zip(self.cusum_neg.iter_mut())
            .zip(t.cusum_h.iter().zip(t.kappa.iter()))
            .enumerate()
        {
            if *h <= T::zero() {
                continue;
            }
            let limit = *h + *kappa * blocks;
            *gp = gp.min(limit);
            *gn = gn.min(limit);
            let ratio = gp.max(*gn) / *h;
            if ratio > best.0 {
                best = (ratio, Some(k));
            }
        }
        report.cusum_ratio = best.0;
        report.flags.cusum = best.0 > T::one();
        Some(best)
    }

    /// One calibration decision: records each statistic against its
    /// threshold, raises no alarm; at the end scales the thresholds.
    fn calibrate(
        &mut self,
        t: &Tests<T, N>,
        block: &SVector<T, N>,
        report: &mut ParityReport<T, N>,
    ) {
        let ratios = [
            report.glt / t.glt_threshold,
            if t.pca_threshold > T::zero() {
                report.pca / t.pca_threshold
            } else {
                T::zero()
            },
            report.cusum_ratio,
        ];
        for (p, r) in self.peaks.iter_mut().zip(ratios.iter()) {
            if r.finite() && *r > *p {
                *p = *r;
            }
        }
        report.flags = DetectorFlags::default();
        report.fault = false;
        // Follow drift during calibration too (the offset keeps learning).
        if self.cfg.drift_blocks > T::one() {
            let gain = T::one() / self.cfg.drift_blocks;
            if let Some(tests) = self.tests.as_mut() {
                tests.baseline.offset += block * gain;
            }
        }
        self.calibrated = self
            .calibrated
            .saturating_add(u32::from(self.cfg.block_len));
        if self.calibrated < self.cfg.calibrate_samples {
            return;
        }
        for (s, p) in self.scales.iter_mut().zip(self.peaks.iter()) {
            *s = (*p * T::lit(1.25)).max(T::one());
        }
        let baseline = self.tests.map(|t| t.baseline);
        self.tests = baseline
            .and_then(|b| derive_tests(&self.space, b, &self.cfg, &self.scales, &self.chi2));
        self.phase = if self.tests.is_some() {
            ParityPhase::Monitoring
        } else {
            ParityPhase::Lost
        };
        self.filled = 0;
        self.head = 0;
        self.cusum_pos = [T::zero(); N];
        self.cusum_neg = [T::zero(); N];
    }
}

/// Builds every threshold and projection for `space` from `baseline`, all
/// stages at once (end of training and of calibration).
pub(super) fn derive_tests<T: Real, const N: usize>(
    space: &ParitySpace<T, N>,
    baseline: Baseline<T, N>,
    cfg: &ParityConfig<T>,
    scales: &[T; 3],
    chi2: &[T; N],
) -> Option<Tests<T, N>> {
    let mut t = Tests::new(baseline);
    let mut newton = Newton::START;
    let mut stage = 0;
    while stage < build_stages(N) {
        stage = build_stage(&mut t, stage, &mut newton, space, cfg, scales, chi2)?;
    }
    Some(t)
}

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
    let padded = SMatrix::<T, N, N>::from_fn(|i, j| {
        if i < dim && j < dim {
            at(block_cov, i, j)
        } else if i == j {
            T::one()
        } else {
            T::zero()
        }
    });
    let l = cholesky(&padded).ok()?;
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
    let (values, vectors) = symmetric_eigen(&SMatrix::<T, N, N>::from_fn(|i, j| {
        if i < dim && j < dim {
            at(block_cov, i, j)
        } else {
            T::zero()
        }
    }))?;
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

/// Sensor maximising `(a_kᵀ r)² / q_k` and its bias estimate `a_kᵀ r / q_k`.
fn isolate<T: Real, const N: usize>(
    t: &Tests<T, N>,
    r: &SVector<T, N>,
    active: &[bool; N],
) -> (Option<usize>, T) {
    let mut best = (None, T::zero(), T::zero());
    for k in 0..N {
        let (Some(&q), Some(&a)) = (t.q.get(k), active.get(k)) else {
            continue;
        };
        if !a || q <= T::zero() {
            continue;
        }
        let z = t.a.column(k).dot(r);
        let score = z * z / q;
        if score > best.1 {
            best = (Some(k), score, z / q);
        }
    }
    (best.0, best.2)
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

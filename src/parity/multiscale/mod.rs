//! Parity tests for real flights: in-flight relative calibration, robust
//! (Huber-clipped) block residuals and a generalised likelihood test on
//! window means at several time scales, each with a covariance learned from
//! the data.
//!
//! Why not the white-noise χ² of SPEC §7 on raw samples: on a real board
//! (ArduPilot log171, three IMUs logged at 49 Hz) the per-sample residual
//! between IMUs is 1–12 °/s of vibration aliased by point sampling, strongly
//! time-correlated, and the IMUs differ by up to 14 % in scale and by a few
//! milliseconds in delay. What is left after a relative calibration is a
//! slowly wandering residual whose 10-s means stay within a few tenths of a
//! °/s. So this module
//! 1. averages samples into blocks (≈ 0.25 s) — the calibration then
//!    regresses on block means, where the vibration noise of the regressor
//!    is small (no errors-in-variables attenuation of the scale terms);
//! 2. learns, by recursive least squares with forgetting, the parity vector
//!    as `p̄ ≈ C φ`, `φ = [1, x̄ − x_ref, Δx̄, e − e_ref]`: offset (relative
//!    biases), motion leakage (relative scale and misalignment, `V(M−I)H` of
//!    SPEC §7), time skew (`Δx̄`, the centred block difference: a relative
//!    delay δ between IMUs leaves `−δ ẋ` in the parity vector) and
//!    vibration rectification (`e_k`, each sensor's variance within the
//!    block: an IMU's DC shift under vibration, the "accel-Z aliasing"
//!    ArduPilot warns of, grows with the vibration it sees through its own
//!    non-linearity and filter — on log171 it moves IMU2's a_z by 1.2 m/s²
//!    for seconds, and these regressors take the worst 2.5-s excursion of
//!    the a_z residuals from 1.2–1.7 to ≈ 0.3 m/s²); learning is frozen
//!    while any test is above a fraction of its threshold;
//! 3. clips each block residual to a Mahalanobis norm (Huber), so one
//!    violent manoeuvre cannot move a window mean by more than a bounded
//!    amount while a persistent bias passes unclipped;
//! 4. tests the window means over several lengths (default 2.5, 5, 10 s)
//!    with the GLR of a single-sensor bias, `max_k (v_kᵀ Σ⁻¹ r̄)² / v_kᵀ Σ⁻¹ v_k`,
//!    where Σ is *that window length's* covariance learned from the healthy
//!    flight (so time correlation is in it by construction) plus the
//!    calibration's own prediction uncertainty `φ̄ᵀ P φ̄ Σ_b`. Under no fault
//!    and a known Σ each score would be χ²(1); Σ is *estimated*, from a
//!    memory of `variance_blocks` blocks that holds only
//!    `variance_blocks / n` independent windows of length `n`, so the
//!    score is the square of a Student t with that many degrees of freedom
//!    and each length's threshold is that t quantile squared at the
//!    configured false-alarm probability (heavier tails for the long
//!    windows, whose covariance rests on fewer independent samples);
//! 5. names a sensor only when its hypothesis beats the runner-up by a
//!    likelihood-ratio margin: with a noisy third sensor two hypotheses can
//!    explain a window almost equally well, and naming the wrong one would
//!    remove a healthy sensor.

use nalgebra::{SMatrix, SVector, Vector3};

use crate::math::Real;
use crate::stats::{student_t_cornish_fisher, student_t_upper_quantile};

mod carry;
mod config;
mod energy_range;
mod lin;
mod scale;
mod staged;
mod training;

use carry::CalSnap;
pub use config::MultiscaleConfig;
use lin::{backward_d, best_two, dot, factor_lower, forward_d, CachedFactor};
use scale::VibrationScale;
pub use staged::{BlockStage, Outcome, STAGES};

/// Sensors whose own vibration energy is a regressor (the first nine).
pub const VIBRATION_REGRESSORS: usize = 9;
/// Regressors of the relative calibration:
/// `[1, x̄ − x_ref, Δx̄, e_0 − e_0,ref, …, e_8 − e_8,ref]`.
pub const REGRESSORS: usize = 7 + VIBRATION_REGRESSORS;
/// Number of window lengths tested.
pub const SCALES: usize = 3;
// `Multiscale::decided_set` holds one bit per window length.
const _: () = assert!(SCALES <= 8);
/// Parts of [`Multiscale::transform_part`]: the calibration and block
/// covariance, then two window covariances per part.
pub const TRANSFORM_PARTS: usize = 1 + SCALES.div_ceil(2);

type Phi<T> = SVector<T, REGRESSORS>;
/// Lowest and highest value of each vibration regressor learned.
type EnergyRange<T> = (
    SVector<T, VIBRATION_REGRESSORS>,
    SVector<T, VIBRATION_REGRESSORS>,
);
/// Index of the first vibration regressor in `φ`.
const FIRST_VIBRATION: usize = REGRESSORS - VIBRATION_REGRESSORS;
/// A window's mean residual, mean regressor and mean gain.
type WindowMean<T, const N: usize> = (SVector<T, N>, Phi<T>, T);

/// One decision of the multi-scale tests.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MultiscaleDecision<T> {
    /// Largest score ÷ threshold over sensors and window lengths (alarm
    /// above 1).
    pub ratio: T,
    /// Window length (index into `scales`) of that score.
    pub scale: usize,
    /// Sensor whose bias hypothesis explains that window best.
    pub suspect: Option<usize>,
    /// Its least-squares bias estimate (unit of the sensors).
    pub bias: T,
    /// Score margin of the suspect over the runner-up hypothesis (χ² units).
    pub margin: T,
    /// Sensor to isolate: the best hypothesis of the alarming window length
    /// where it beats the runner-up by the widest margin (longer windows
    /// average a noisy third sensor down and tell two candidates apart).
    pub isolate: Option<(usize, T)>,
    /// The calibration learned from this block (the covariances learn from
    /// the block leaving the 10-s ring at the same time, see `learn_below`).
    pub learning: bool,
    /// The alarm comes from the gross test (a fault far beyond any
    /// vibration excursion: raised at once, without confirmation).
    pub gross: bool,
}

/// Learning state of the tests in one parity space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Multiscale<T: Real, const N: usize, const W: usize> {
    cfg: MultiscaleConfig<T>,
    dim: usize,
    /// Information matrix of the RLS (`Σ λ^k φ φᵀ`).
    sxx: SMatrix<T, REGRESSORS, REGRESSORS>,
    /// Cross moments `Σ λ^k p̄ φᵀ`.
    spx: SMatrix<T, N, REGRESSORS>,
    /// Ridge (diagonal) added to `sxx` before solving.
    ridge: Phi<T>,
    /// References the motion and vibration regressors are centred on
    /// (first block).
    x_ref: Option<(Vector3<T>, SVector<T, VIBRATION_REGRESSORS>)>,
    /// Range of the vibration regressors (`e − e_ref`) the calibration has
    /// learned, lowest and highest (`None` before its first block); see
    /// [`within_learned_energy`](Self::within_learned_energy).
    energy_range: Option<EnergyRange<T>>,
    /// Block covariance of the residual (padded with identity beyond `dim`).
    block_cov: SMatrix<T, N, N>,
    /// Covariance of the window mean at each length.
    window_cov: [SMatrix<T, N, N>; SCALES],
    /// Vibration scale model `ŝ(x) = a + c x` of the block residual's
    /// variance against the block's vibration level `x` (see
    /// [`VibrationScale`]).
    scale: VibrationScale<T>,
    /// Clipped (standardised) residuals and regressors of the last `W`
    /// blocks.
    residuals: [SVector<T, N>; W],
    /// `1/√ŝ` of each stored block: a bias `b` shows in the standardised
    /// window mean as `b` times the mean of these.
    gains: [T; W],
    /// Vibration level of each stored block (the fit at the end of
    /// training needs them).
    levels: [T; W],
    /// The same residuals unclipped and not standardised (for the gross
    /// test).
    raw: [SVector<T, N>; W],
    /// Covariance updates so far (the EWMA weight is `1/min(updates,
    /// variance_blocks)`).
    updates: u32,
    regressors: [Phi<T>; W],
    /// Each stored block's vibration regressors were within the range the
    /// calibration had learned when it predicted the block (see
    /// [`raw_mean_learned`](Self::raw_mean_learned)).
    learned_range: [bool; W],
    /// Mahalanobis norms² of the stored blocks (block-covariance units,
    /// before clipping) and the window means their decisions saw: the
    /// covariances learn a block only once it leaves the ring, after every
    /// window containing it has been judged quiet (see `learn_quiet`).
    norms: [T; W],
    decided_means: [[SVector<T, N>; SCALES]; W],
    /// Bit `s` of a stored block's entry: window length `s` had a mean at
    /// its decision (as `[Option<SVector>; SCALES]` the ring took 440 more
    /// bytes with nine sensors, in each of the monitor's two test slots).
    decided_set: [u8; W],
    head: usize,
    filled: usize,
    /// Blocks since a score was last at or above the learning fraction.
    quiet_blocks: u32,
    /// The steady-state threshold of each window length (see
    /// [`thresholds`](Self::thresholds)).
    scale_h: [T; SCALES],
    /// Normal quantile at `false_alarm / 2`, for the thresholds of the
    /// first minutes (see [`early_threshold`](Self::early_threshold)); 0
    /// when it could not be computed (steady thresholds throughout).
    z: T,
    /// Residual blocks the training covariance rests on.
    trained_blocks: u32,
    /// The block in work, one stage per monitor step.
    work: staged::Work<T, N>,
    /// The work's calibration factor is that of the current `sxx + ridge`
    /// (nothing learned since it was computed): the next block reuses it
    /// instead of refactorising the same matrix (issue 14; bit-identical,
    /// the factorisation is deterministic).
    cal_current: bool,
    /// Factors of `block_cov`, of the shortest window's covariance (gross
    /// test) and of the longest's (offset check), kept while they are
    /// unchanged (see [`covariances_changed`](Self::covariances_changed)).
    block_factor: CachedFactor<T, N>,
    short_factor: CachedFactor<T, N>,
    long_factor: CachedFactor<T, N>,
    /// The calibration (`sxx`, `spx`) as it was one and two longest
    /// windows of decisions ago (`None`: not yet, or another space since),
    /// for [`copy_learning_from`](Self::copy_learning_from).
    cal_snaps: [Option<CalSnap<T, N>>; 2],
    /// Decisions since the newest snapshot.
    since_snap: u16,
}

impl<T: Real, const N: usize, const W: usize> Multiscale<T, N, W> {
    /// The threshold of each window length: the squared Student-t
    /// quantile at `cfg.false_alarm / 2` with `variance_blocks / length`
    /// degrees of freedom (software `f64`; once, at configuration). `None`
    /// when a quantile cannot be computed.
    pub fn thresholds(cfg: &MultiscaleConfig<T>) -> Option<[T; SCALES]> {
        let mut out = [T::zero(); SCALES];
        for (h, len) in out.iter_mut().zip(cfg.scales.iter()) {
            let nu = (cfg.variance_blocks.to_f64() / f64::from((*len).max(1))).max(2.0);
            let t = student_t_upper_quantile(cfg.false_alarm * 0.5, nu).ok()?;
            *h = T::lit(t * t);
        }
        Some(out)
    }

    /// Fresh tests for a parity space of dimension `dim` with the
    /// thresholds from [`thresholds`](Self::thresholds).
    pub fn new(cfg: MultiscaleConfig<T>, dim: usize, thresholds: [T; SCALES]) -> Self {
        let ridge = Phi::<T>::from_fn(|i, _| match i {
            0 => T::lit(1e-9),
            1..=3 => cfg.ridge_motion,
            4..=6 => cfg.ridge_skew,
            _ => cfg.ridge_vibration,
        });
        Self {
            cfg,
            dim,
            sxx: SMatrix::zeros(),
            spx: SMatrix::zeros(),
            ridge,
            x_ref: None,
            energy_range: None,
            block_cov: SMatrix::identity(),
            window_cov: [SMatrix::identity(); SCALES],
            scale: VibrationScale::default(),
            residuals: [SVector::zeros(); W],
            gains: [T::one(); W],
            levels: [T::zero(); W],
            raw: [SVector::zeros(); W],
            updates: 0,
            regressors: [Phi::zeros(); W],
            learned_range: [true; W],
            norms: [T::zero(); W],
            decided_means: [[SVector::zeros(); SCALES]; W],
            decided_set: [0; W],
            head: 0,
            filled: 0,
            quiet_blocks: 0,
            scale_h: thresholds,
            z: crate::stats::normal_upper_quantile(cfg.false_alarm * 0.5)
                .map(T::lit)
                .unwrap_or(T::zero()),
            trained_blocks: 0,
            work: staged::Work::default(),
            cal_current: false,
            block_factor: CachedFactor::stale(),
            short_factor: CachedFactor::stale(),
            long_factor: CachedFactor::stale(),
            cal_snaps: [None; 2],
            since_snap: 0,
        }
    }

    /// Every window length has a score: the ring holds the longest window.
    pub fn windows_full(&self) -> bool {
        self.filled >= usize::from(self.cfg.scales[SCALES - 1])
    }

    /// Longest window length, blocks.
    pub fn longest(&self) -> u16 {
        self.cfg.scales[SCALES - 1]
    }

    /// The threshold of each window length.
    pub fn threshold_set(&self) -> [T; SCALES] {
        self.scale_h
    }

    /// Regressor vector of a block with mean `x`, centred difference `dx`
    /// and per-sensor variances `e` (sensors beyond
    /// [`VIBRATION_REGRESSORS`] are left out).
    pub fn regressor(
        &mut self,
        x: &Vector3<T>,
        dx: &Vector3<T>,
        e: &SVector<T, N>,
    ) -> SVector<T, REGRESSORS> {
        let ev = SVector::<T, VIBRATION_REGRESSORS>::from_fn(|i, _| {
            if self.cfg.vibration {
                e.get(i).copied().unwrap_or(T::zero())
            } else {
                T::zero()
            }
        });
        let (x_ref, e_ref) = *self.x_ref.get_or_insert((*x, ev));
        let c = x - x_ref;
        let de = ev - e_ref;
        Phi::<T>::from_fn(|i, _| match i {
            0 => T::one(),
            1..=3 => c.get(i - 1).copied().unwrap_or(T::zero()),
            4..=6 => dx.get(i - 4).copied().unwrap_or(T::zero()),
            _ => de.get(i - 7).copied().unwrap_or(T::zero()),
        })
    }

    /// Adds one block to the calibration (training, or in flight while
    /// quiet); `forget` applies the RLS forgetting factor first.
    pub fn learn_calibration(&mut self, p: &SVector<T, N>, phi: &Phi<T>, forget: bool) {
        // `sxx` is symmetric: only its lower triangle is kept (the factor
        // reads no more); `spx` rows beyond `dim` are zero (so are `p`'s).
        // `sxx` changes: the factor kept in the work is stale.
        self.cal_current = false;
        self.widen_energy_range(phi);
        let lambda = T::one() - T::one() / self.cfg.calibration_blocks;
        let dim = self.dim.min(N);
        let phis = phi.as_slice();
        // The lower triangle over every row with the test inside (a fixed
        // trip count the compiler unrolls), `forget` decided once.
        for (j, (col, fj)) in self
            .sxx
            .as_mut_slice()
            .chunks_exact_mut(REGRESSORS)
            .zip(phis.iter())
            .enumerate()
        {
            if forget {
                for (i, (x, fi)) in col.iter_mut().zip(phis.iter()).enumerate() {
                    if i >= j {
                        *x = *x * lambda + *fi * *fj;
                    }
                }
            } else {
                for (i, (x, fi)) in col.iter_mut().zip(phis.iter()).enumerate() {
                    if i >= j {
                        *x += *fi * *fj;
                    }
                }
            }
        }
        for (col, fj) in self.spx.as_mut_slice().chunks_exact_mut(N).zip(phis.iter()) {
            for (x, pi) in col.iter_mut().zip(p.iter()).take(dim) {
                if forget {
                    *x *= lambda;
                }
                *x += *pi * *fj;
            }
        }
    }

    /// The calibration's Cholesky factor of `sxx + ridge` (the reference
    /// the in-place [`factor_calibration`](Self::factor_calibration) is
    /// checked against).
    #[cfg(test)]
    fn calibration_factor(&self) -> Option<SMatrix<T, REGRESSORS, REGRESSORS>> {
        let mut a = self.sxx;
        for (i, r) in self.ridge.iter().enumerate() {
            if let Some(d) = a.get_mut((i, i)) {
                *d += *r;
            }
        }
        lin::cholesky_dim(&a, REGRESSORS)
    }

    /// [`calibration_factor`](Self::calibration_factor)'s factor, computed
    /// in place in the work: the same entries (`sxx` lower triangle, the
    /// ridge added on the diagonal, zero above) and the same factorisation,
    /// without the 1 KB copies of `sxx`, of the factor returned and of its
    /// store into the work. On `None` the work holds no usable factor
    /// (`cal_current` stays false, nothing reads it before the next one).
    ///
    /// Only the lower triangle is written: the work's factor is zero above
    /// the diagonal from `Work::default` on, and nothing ever writes there
    /// (the factorisation and its solves read the lower triangle only), so
    /// the 120 zeros need not be stored again on every learned block.
    fn factor_calibration(&mut self) -> Option<()> {
        let l = self.work.cal.as_mut_slice();
        let (sxx, ridge) = (self.sxx.as_slice(), self.ridge.as_slice());
        for j in 0..REGRESSORS {
            let r = ridge.get(j).copied().unwrap_or(T::zero());
            for i in j..REGRESSORS {
                let at = j * REGRESSORS + i;
                let (Some(d), Some(x)) = (l.get_mut(at), sxx.get(at)) else {
                    return None;
                };
                *d = if i == j { *x + r } else { *x };
            }
        }
        factor_lower(&mut self.work.cal, REGRESSORS)
    }

    /// Prior residual `p̄ − C φ` of a block (before it is learned), with the
    /// calibration's Cholesky factor `l`; `None` when not finite.
    fn residual_with(
        &self,
        l: &SMatrix<T, REGRESSORS, REGRESSORS>,
        p: &SVector<T, N>,
        phi: &Phi<T>,
    ) -> Option<SVector<T, N>> {
        // `C φ = spx (sxx + ridge)⁻¹ φ`: one solve for the regressor, not
        // one per parity row for `C`.
        // The kernels at the calibration's fixed size (unrolled; the bits of
        // `forward` and `backward`).
        let mut w: [T; REGRESSORS] = forward_d::<T, REGRESSORS, REGRESSORS>(l, phi.as_slice());
        backward_d(l, &mut w);
        let mut r = *p;
        let dim = self.dim.min(N);
        for (col, wj) in self.spx.as_slice().chunks_exact(N).zip(w.iter()) {
            for (ri, c) in r.iter_mut().zip(col.iter()).take(dim) {
                *ri -= *c * *wj;
            }
        }
        r.iter().all(|x| x.finite()).then_some(r)
    }

    /// `φᵀ (sxx + ridge)⁻¹ φ`: the calibration's prediction variance of a
    /// (mean) regressor, in units of the block covariance.
    /// `l` is the factor of [`calibration_factor`](Self::calibration_factor),
    /// computed once per block by the caller (`None`: no prediction term).
    fn prediction_weight(l: Option<&SMatrix<T, REGRESSORS, REGRESSORS>>, phi: &Phi<T>) -> T {
        // ‖L⁻¹ φ‖² by forward substitution.
        l.map_or(T::zero(), |l| {
            let y: [T; REGRESSORS] = forward_d::<T, REGRESSORS, REGRESSORS>(l, phi.as_slice());
            dot(&y, &y)
        })
    }

    /// Pushes a clipped residual, the raw one and its regressor into the
    /// window.
    fn push(&mut self, r: &SVector<T, N>, raw: &SVector<T, N>, phi: &Phi<T>, gain: T, level: T) {
        if let Some(slot) = self.residuals.get_mut(self.head) {
            *slot = *r;
        }
        if let Some(slot) = self.gains.get_mut(self.head) {
            *slot = gain;
        }
        if let Some(slot) = self.levels.get_mut(self.head) {
            *slot = level;
        }
        if let Some(slot) = self.raw.get_mut(self.head) {
            *slot = *raw;
        }
        if let Some(slot) = self.regressors.get_mut(self.head) {
            *slot = *phi;
        }
        let within = self.within_learned_energy(phi);
        if let Some(slot) = self.learned_range.get_mut(self.head) {
            *slot = within;
        }
        self.head = (self.head + 1) % W.max(1);
        self.filled = (self.filled + 1).min(W);
    }

    /// Window means of residual, regressor and gain over each length
    /// (newest blocks) into the work, `None` for a length not yet filled.
    /// Written in place (returned by value they were a ≈ 330-byte copy) and
    /// the ring walked backwards without a `%` per block; the sums are
    /// the same, newest block first.
    fn fill_window_means(&mut self) {
        let mut sr = SVector::<T, N>::zeros();
        let mut sp = Phi::<T>::zeros();
        let mut sg = T::zero();
        let mut idx = self.head;
        let mut scale = 0;
        self.work.means = [None; SCALES];
        for n in 1..=self.filled {
            idx = if idx == 0 {
                W.saturating_sub(1)
            } else {
                idx - 1
            };
            if let (Some(r), Some(p)) = (self.residuals.get(idx), self.regressors.get(idx)) {
                sr += r;
                sp += p;
            }
            sg += self.gains.get(idx).copied().unwrap_or(T::one());
            while let Some(len) = self.cfg.scales.get(scale) {
                if usize::from(*len) != n {
                    break;
                }
                let k = T::lit(n as f64);
                if let Some(slot) = self.work.means.get_mut(scale) {
                    *slot = Some((sr / k, sp / k, sg / k));
                }
                scale += 1;
            }
        }
    }

    /// Mean of the newest `len` unclipped residuals, each times its own
    /// block's gain (standardised); `None` until `len` blocks are stored.
    fn raw_mean(&self, len: usize) -> Option<SVector<T, N>> {
        self.ring_mean(len, |idx| {
            let r = self.raw.get(idx)?;
            Some(self.gains.get(idx).map_or(*r, |g| r * *g))
        })
    }

    /// Mean of `value` over the newest `len` stored blocks (ring slots,
    /// newest first) where it gives one; `None` until `len` blocks are
    /// stored or when it gives none.
    fn ring_mean(
        &self,
        len: usize,
        value: impl Fn(usize) -> Option<SVector<T, N>>,
    ) -> Option<SVector<T, N>> {
        if len == 0 || self.filled < len {
            return None;
        }
        let mut s = SVector::<T, N>::zeros();
        let mut kept = 0usize;
        let mut idx = self.head;
        for _ in 0..len {
            idx = (idx + W - 1) % W.max(1);
            if let Some(r) = value(idx) {
                s += r;
                kept += 1;
            }
        }
        (kept > 0).then(|| s / T::lit(kept as f64))
    }

    /// Per-sensor relative bias the calibration has absorbed: the suspect
    /// with its GLR bias estimate, when it exceeds the offset limit (a fault
    /// present since power-up), and the runner-up margin. The offset is
    /// the (forgetting-weighted) mean parity vector of the learned blocks —
    /// the relative biases as the flight showed them on average — not the
    /// regression's intercept, which sits wherever the regressors are
    /// centred.
    pub fn offset_fault(
        &mut self,
        v: &SMatrix<T, N, N>,
        active: &[bool; N],
    ) -> Option<(usize, T, T)> {
        if !self.cfg.offset_limit.finite() {
            return None;
        }
        let count = self.sxx.get((0, 0)).copied().unwrap_or(T::zero());
        if count.partial_cmp(&T::one()) != Some(core::cmp::Ordering::Greater) {
            return None;
        }
        let offset: SVector<T, N> = self.spx.column(0) / count;
        // The offset is a long mean: its uncertainty is that of the longest
        // window, not of one block (the block covariance would make every
        // offset look insignificant next to the vibration).
        let l = self.long_factor.get(self.window_cov.last()?, self.dim)?;
        let (best, second) = best_two(l, v, &offset, active, self.dim);
        let (k, score, bias) = best?;
        let margin = score - second;
        (bias.abs() > self.cfg.offset_limit).then_some((k, bias, margin))
    }

    /// The threshold of a window of `len` blocks now: the squared t
    /// quantile with the degrees of freedom its covariance has so far — at
    /// most those of the training's block covariance it started from
    /// (`trained_blocks − 1`), plus one per `len` blocks learned since —
    /// capped at the steady state. Right after training the shortest
    /// window's threshold is about a quarter higher than in steady state
    /// (ν 39 instead of 96 for 10-block windows of a 30-s training); the
    /// longer windows, whose steady ν is lower, start at theirs (their
    /// covariances start conservatively at the shortest window's instead).
    /// The quantile is the Cornish–Fisher expansion of t in powers of 1/ν
    /// (Abramowitz & Stegun 26.7.5; within 0.5 % for ν ≥ 12), a few flops
    /// per block instead of a root search.
    fn early_threshold(&self, steady: T, len: u16) -> T {
        if self.z <= T::zero() {
            return steady;
        }
        let learned = self.updates.saturating_sub(self.trained_blocks);
        let nu = T::lit(f64::from(self.trained_blocks.saturating_sub(1)))
            + T::lit(f64::from(learned)) / T::lit(f64::from(len.max(1)));
        let t = student_t_cornish_fisher(self.z, nu.max(T::lit(8.0)));
        (t * t).max(steady)
    }

    /// `block_cov`, `window_cov` or `dim` changed: their kept factors are
    /// stale.
    fn covariances_changed(&mut self) {
        self.block_factor.invalidate();
        self.short_factor.invalidate();
        self.long_factor.invalidate();
    }

    /// Forgets the window (after a reconfiguration) and re-arms the quiet
    /// counter.
    pub fn clear_window(&mut self) {
        self.filled = 0;
        self.head = 0;
        self.quiet_blocks = 0;
    }
}

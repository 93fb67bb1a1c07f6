//! One block's work in stages, one stage per monitor step (issue 17).
//!
//! Closing a block used to cost ≈ 142 k instructions in one sample on the
//! Cortex-M4F (the calibration's 16×16 factorisation and solve, the Huber
//! clip, three window tests with their own factorisation, the gross test,
//! the learning, the offset check) while every other sample cost a few
//! hundred. The same arithmetic, in the same order, now runs one stage per
//! sample over the next block's first samples ([`BlockStage`], at most
//! [`STAGES`] of them), and the block's decision is applied when the last
//! stage runs: the decision values are those of the one-shot computation,
//! taken [`STAGES`] samples later at most (less than one block with the
//! default blocks of 0.25 s).

use nalgebra::{SMatrix, SVector};

use crate::math::Real;

use super::lin::{best_two, cholesky_dim_sum, quad_form};
use super::training::FINISH_PARTS;
use super::{Multiscale, MultiscaleDecision, Phi, WindowMean, REGRESSORS, SCALES};

/// Most stages one block takes (monitoring: factor, residual, window, three
/// window lengths, gross test, learning, offset check).
pub const STAGES: usize = 9;

/// The stage of a block's work the next monitor step runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BlockStage {
    /// Cholesky factor of the calibration's information matrix.
    Factor,
    /// The block's prior residual and its vibration standardisation.
    Residual,
    /// Huber clip, the residual into the window, the window means.
    Window,
    /// The GLR of one window length (index into `scales`).
    Scale(u8),
    /// The gross test on the shortest window, unclipped.
    Gross,
    /// Learning from a quiet block (calibration, covariances, vibration law).
    Learn,
    /// The fault-since-power-up check on the calibration's offset; the
    /// decision is complete after it.
    Offset,
    /// Training: the block's residual kept for the covariance.
    TrainResidual,
    /// A reconfiguration after an isolation or a failure (the reduced
    /// space, then the tests rebuilt or the learning carried into it; see
    /// [`reconfig_steps`](crate::parity::reconfig_steps)); its stage: 0
    /// the reduced space, then the following ones in order.
    Reconfigure(u8),
    /// Training: part of the end of training (vibration law, covariances;
    /// 14 of them).
    TrainFinish(u8),
}

/// What a finished job gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome<T> {
    /// Still working: the next step runs the next stage.
    Busy,
    /// A monitoring block decided (`None`: the calibration could not be
    /// solved, the block is skipped).
    Decided(Option<MultiscaleDecision<T>>),
    /// A training block learned; `Some(ok)` when training ended with it
    /// (`ok` false: degenerate data, train again).
    Trained(Option<bool>),
}

/// Intermediate results of the block in work.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Work<T: Real, const N: usize> {
    stage: Option<BlockStage>,
    /// A training block.
    training: bool,
    /// Training: end training after this block.
    finish: bool,
    p: SVector<T, N>,
    phi: Phi<T>,
    level: T,
    /// Factor of the calibration (`Factor` to `Scale`).
    pub(super) cal: SMatrix<T, REGRESSORS, REGRESSORS>,
    raw_r: SVector<T, N>,
    energy: T,
    norm2: T,
    clipped: SVector<T, N>,
    /// Window means (`Window` to `Scale`).
    pub(super) means: [Option<WindowMean<T, N>>; SCALES],
    best_ratio: T,
    isolate: Option<(usize, T)>,
    out: MultiscaleDecision<T>,
    /// End of training: mean of the standardised residuals and the sum
    /// of the correlation windows' norms.
    pub(super) train_mean: SVector<T, N>,
    pub(super) train_sum: T,
}

impl<T: Real, const N: usize> Default for Work<T, N> {
    fn default() -> Self {
        Self {
            stage: None,
            training: false,
            finish: false,
            p: SVector::zeros(),
            phi: Phi::zeros(),
            level: T::zero(),
            cal: SMatrix::zeros(),
            raw_r: SVector::zeros(),
            energy: T::one(),
            norm2: T::zero(),
            clipped: SVector::zeros(),
            means: [None; SCALES],
            best_ratio: T::zero(),
            isolate: None,
            out: MultiscaleDecision::default(),
            train_mean: SVector::zeros(),
            train_sum: T::zero(),
        }
    }
}

impl<T: Real, const N: usize, const W: usize> Multiscale<T, N, W> {
    /// Starts a monitoring block (`training` `None`) or a training block of
    /// the second part of training (`Some(finish)`: training ends with it
    /// when `finish`). Any job still in work is dropped: call
    /// [`finish`](Self::finish) first.
    pub fn begin(&mut self, p: &SVector<T, N>, phi: &Phi<T>, level: T, training: Option<bool>) {
        self.work = Work {
            stage: Some(BlockStage::Factor),
            training: training.is_some(),
            finish: training.unwrap_or(false),
            p: *p,
            phi: *phi,
            level,
            // The factor of the block before, reused while current.
            cal: self.work.cal,
            ..Work::default()
        };
    }

    /// The stage the next [`advance`](Self::advance) runs, `None` when idle.
    pub fn pending(&self) -> Option<BlockStage> {
        self.work.stage
    }

    /// Forgets the job in work (reconfiguration, retraining).
    pub fn cancel(&mut self) {
        self.work.stage = None;
    }

    /// Runs one stage of the job in work.
    pub fn advance(&mut self, v: &SMatrix<T, N, N>, active: &[bool; N]) -> Outcome<T> {
        let Some(stage) = self.work.stage else {
            return Outcome::Busy;
        };
        let next = match stage {
            // Not a stage of a block (the monitor runs those).
            BlockStage::Reconfigure(_) => return self.done(Outcome::Busy),
            BlockStage::Factor => match self.current_factor() {
                Some(()) => {
                    if self.work.training {
                        BlockStage::TrainResidual
                    } else {
                        BlockStage::Residual
                    }
                }
                None if self.work.training => {
                    // No residual from this block; it still trains the
                    // calibration.
                    return self.train_learned();
                }
                None => return self.done(Outcome::Decided(None)),
            },
            BlockStage::TrainResidual => {
                let (phi, level) = (self.work.phi, self.work.level);
                if let Some(r) = self.residual_with(&self.work.cal, &self.work.p, &phi) {
                    self.train_residual(&r, &phi, level);
                }
                return self.train_learned();
            }
            BlockStage::TrainFinish(part) => match self.finish_training_part(usize::from(part)) {
                Some(false) => BlockStage::TrainFinish(part.saturating_add(1)),
                Some(true) => return self.done(Outcome::Trained(Some(true))),
                None => return self.done(Outcome::Trained(Some(false))),
            },
            BlockStage::Residual => {
                let w = &self.work;
                let Some(raw_r) = self.residual_with(&w.cal, &w.p, &w.phi) else {
                    return self.done(Outcome::Decided(None));
                };
                // Standardised by the residual energy this vibration level
                // predicts (see `scale`): the tests below all run on it.
                self.work.energy = self.scale.predict(self.work.level);
                self.work.raw_r = raw_r;
                BlockStage::Window
            }
            BlockStage::Window => {
                let (raw_r, phi, level) = (self.work.raw_r, self.work.phi, self.work.level);
                let gain = T::one() / self.work.energy.sqrt();
                let r = raw_r * gain;
                let Some(lb) = self.block_factor.get(&self.block_cov, self.dim) else {
                    return self.done(Outcome::Decided(Some(MultiscaleDecision::default())));
                };
                // Huber: bound the block's Mahalanobis norm.
                let norm2 = quad_form(lb, &r, self.dim);
                let norm = norm2.sqrt();
                let bound = T::lit(self.dim as f64).sqrt() + self.cfg.huber;
                let clipped = if norm > bound && norm.finite() {
                    r * (bound / norm)
                } else {
                    r
                };
                self.push(&clipped, &raw_r, &phi, gain, level);
                self.fill_window_means();
                let newest = (self.head + W - 1) % W.max(1);
                if let Some(slot) = self.norms.get_mut(newest) {
                    *slot = norm2;
                }
                if let (Some(slot), Some(set)) = (
                    self.decided_means.get_mut(newest),
                    self.decided_set.get_mut(newest),
                ) {
                    *set = 0;
                    for (s, (d, m)) in slot.iter_mut().zip(self.work.means.iter()).enumerate() {
                        if let Some((rbar, _, _)) = m {
                            *d = *rbar;
                            *set |= 1 << s;
                        }
                    }
                }
                self.work.norm2 = norm2;
                self.work.clipped = clipped;
                BlockStage::Scale(0)
            }
            BlockStage::Scale(i) => {
                self.scale_test(usize::from(i), v, active);
                if usize::from(i) + 1 < SCALES {
                    BlockStage::Scale(i + 1)
                } else {
                    BlockStage::Gross
                }
            }
            BlockStage::Gross => {
                self.gross_test(v, active);
                let w = &mut self.work;
                w.out.isolate = w.isolate;
                if !w.best_ratio.finite() {
                    w.out.ratio = T::zero();
                    w.out.suspect = None;
                    // Never learn from a non-finite score.
                    BlockStage::Offset
                } else {
                    BlockStage::Learn
                }
            }
            BlockStage::Learn => {
                self.learn_quiet();
                self.snapshot_calibration();
                BlockStage::Offset
            }
            BlockStage::Offset => {
                let mut d = self.work.out;
                // A relative bias the calibration holds beyond the offset
                // limit is a fault present since power-up (or training).
                if d.ratio <= T::one() {
                    if let Some((k, bias, margin)) = self.offset_fault(v, active) {
                        d = MultiscaleDecision {
                            ratio: T::one() + T::lit(1e-3),
                            scale: 0,
                            suspect: Some(k),
                            bias,
                            margin,
                            isolate: Some((k, margin)),
                            learning: false,
                            gross: false,
                        };
                    }
                }
                return self.done(Outcome::Decided(Some(d)));
            }
        };
        self.work.stage = Some(next);
        Outcome::Busy
    }

    /// Runs the job in work to its end (a new block closed before it was
    /// done: blocks shorter than [`STAGES`] samples).
    pub fn finish(&mut self, v: &SMatrix<T, N, N>, active: &[bool; N]) -> Outcome<T> {
        for _ in 0..STAGES + FINISH_PARTS {
            match self.advance(v, active) {
                Outcome::Busy if self.work.stage.is_some() => {}
                o => return o,
            }
        }
        Outcome::Busy
    }

    /// Puts the calibration's factor of the current `sxx` into the work:
    /// kept from the block before when nothing was learned since (in
    /// monitoring, every block that is not quiet enough to learn), else
    /// factorised anew. `None` when it cannot be factorised.
    fn current_factor(&mut self) -> Option<()> {
        if !self.cal_current {
            self.factor_calibration()?;
            self.cal_current = true;
        }
        Some(())
    }

    fn done(&mut self, o: Outcome<T>) -> Outcome<T> {
        self.work.stage = None;
        o
    }

    /// A training block's calibration update; the end of training next
    /// when this was the last block.
    fn train_learned(&mut self) -> Outcome<T> {
        let (p, phi) = (self.work.p, self.work.phi);
        self.learn_calibration(&p, &phi, false);
        if self.work.finish {
            self.work.stage = Some(BlockStage::TrainFinish(0));
            return Outcome::Busy;
        }
        self.done(Outcome::Trained(None))
    }

    /// The GLR of window length `i` on the block in work.
    fn scale_test(&mut self, i: usize, v: &SMatrix<T, N, N>, active: &[bool; N]) {
        let (Some(Some((rbar, phibar, gbar))), Some(cov), Some(h_steady), Some(len)) = (
            self.work.means.get(i).copied(),
            self.window_cov.get(i),
            self.scale_h.get(i),
            self.cfg.scales.get(i),
        ) else {
            return;
        };
        let h = self.early_threshold(*h_steady, *len);
        let w = Self::prediction_weight(Some(&self.work.cal), &phibar);
        // `cov + block_cov × w`, symmetric as both terms are (`pad` keeps
        // them so).
        // Only the leading block's lower triangle is written, and read.
        let mut l = SMatrix::<T, N, N>::zeros();
        if cholesky_dim_sum(&mut l, cov, &self.block_cov, w, self.dim).is_none() {
            return;
        }
        let l = &l;
        let (best, second) = best_two(l, v, &rbar, active, self.dim);
        let Some((k, score, bias)) = best else {
            return;
        };
        let ratio = score / h;
        let mut margin = score - second;
        // Attribution of an alarm on a 5- or 10-s window may also use the
        // window's *unclipped* mean, when it names the same sensor. The
        // clip bounds what one block adds to a window, and it is what keeps
        // manoeuvre transients from raising alarms (the detection above
        // stays on clipped means); but it also shrinks a bias that is a few
        // block σ in the quiet directions — on log171 a 2 °/s x-gyro step
        // to 0.43–0.63 of its size — and the x hypotheses of IMU1 and IMU2
        // are so nearly opposite there (whitened cosine −0.95) that the
        // margin is a few percent of the score. Over ≥ 20 blocks one
        // block moves the unclipped mean by at most 1/20 of its size; the
        // 2.5-s window stays clipped (with it too, the realistic profile's
        // gyro step flights with a false alarm were 2/2/2/2 of 36 per size
        // instead of 1/1/2/1).
        if ratio > T::one() && i >= 1 {
            if let Some(u) = self.raw_mean(usize::from(*len)) {
                if let (Some((ku, su, _)), second_u) = best_two(l, v, &u, active, self.dim) {
                    if ku == k {
                        margin = margin.max(su - second_u);
                    }
                }
            }
        }
        let w = &mut self.work;
        if ratio > T::one() && w.isolate.is_none_or(|(_, m)| margin > m) {
            w.isolate = Some((k, margin));
        }
        if ratio > w.best_ratio || w.out.suspect.is_none() {
            w.best_ratio = ratio;
            w.out = MultiscaleDecision {
                ratio,
                scale: i,
                suspect: Some(k),
                // Back to sensor units: a bias b shows as b × mean gain.
                bias: bias / gbar.max(T::lit(1e-6)),
                margin,
                isolate: None,
                learning: false,
                gross: false,
            };
        }
    }

    /// Gross test: the shortest window unclipped, at `gross_factor` × the
    /// threshold.
    fn gross_test(&mut self, v: &SMatrix<T, N, N>, active: &[bool; N]) {
        let short = usize::from(self.cfg.scales[0]);
        let (Some(rbar), Some(cov)) = (self.raw_mean_learned(short), self.window_cov.first())
        else {
            return;
        };
        let Some(l) = self.short_factor.get(cov, self.dim) else {
            return;
        };
        let (best, second) = best_two(l, v, &rbar, active, self.dim);
        let Some((k, score, bias)) = best else {
            return;
        };
        let h0 = self.scale_h.first().copied().unwrap_or(T::lit(1e6));
        let ratio = score / (h0 * self.cfg.gross_factor);
        let w = &mut self.work;
        if ratio > T::one() && ratio > w.best_ratio {
            w.best_ratio = ratio;
            w.out.ratio = ratio;
            w.out.scale = 0;
            w.out.suspect = Some(k);
            w.out.bias = bias;
            w.out.margin = score - second;
            w.out.gross = true;
            w.isolate = Some((k, score - second));
        }
    }

    /// Learning from quiet decisions (every score below `learn_below` of
    /// its threshold for a whole longest window). The calibration learns
    /// the newest block: it must track the slow relative drift, and its
    /// 2-min memory takes in a fault's first blocks only slowly. The
    /// covariances and the vibration law learn a block only when it leaves
    /// the ring, after every window containing it (the longest is the
    /// ring) has been judged. Learning them from the newest block took in
    /// a fault's first blocks while its windows were still filling: on
    /// log171 a 1 °/s gyro step 25 s into monitoring (when the covariances
    /// still move by 1/100 per block) was learned into the window
    /// covariances for the whole 10 s after onset and never reached half
    /// the threshold. With the delay the gate no longer has to freeze a
    /// fault before it is visible, only to exclude what came near an
    /// alarm, so `learn_below` is near one (less censoring of the
    /// covariances, and a calibration that keeps learning through the
    /// first manoeuvres after training).
    fn learn_quiet(&mut self) {
        // Only what is used, not the whole work (1,632 bytes for nine
        // sensors: ≈ 430 instructions of `memcpy` on the M4F).
        let (best_ratio, p, phi) = (self.work.best_ratio, self.work.p, self.work.phi);
        if best_ratio < self.cfg.learn_below {
            self.quiet_blocks = self.quiet_blocks.saturating_add(1);
        } else {
            self.quiet_blocks = 0;
        }
        let longest = u32::from(self.cfg.scales[SCALES - 1]);
        if self.quiet_blocks <= longest {
            return;
        }
        self.work.out.learning = true;
        self.learn_calibration(&p, &phi, true);
        self.learn_oldest();
    }

    /// The covariances and the vibration law learn the oldest block of the
    /// full ring when every decision since it entered was quiet.
    fn learn_oldest(&mut self) {
        if self.filled < W || (self.quiet_blocks as usize) < W {
            return;
        }
        // After `push`, `head` is the oldest block's slot.
        let i = self.head;
        let (Some(r), Some(gain), Some(level), Some(norm2), Some(means), Some(set)) = (
            self.residuals.get(i).copied(),
            self.gains.get(i).copied(),
            self.levels.get(i).copied(),
            self.norms.get(i).copied(),
            self.decided_means.get(i).copied(),
            self.decided_set.get(i).copied(),
        ) else {
            return;
        };
        self.updates = self.updates.saturating_add(1);
        self.covariances_changed();
        let wt = T::one() / T::lit(f64::from(self.updates)).min(self.cfg.variance_blocks);
        ewma_outer_padded(&mut self.block_cov, &r, wt, self.dim);
        // The block's raw energy in block-covariance units (`gain` is
        // `1/√ŝ` of its standardisation).
        let dimf = T::lit(self.dim.max(1) as f64);
        let energy = T::one() / (gain * gain).max(T::lit(1e-12));
        self.scale.learn(level, energy * norm2 / dimf, wt);
        for (s, (cov, rbar)) in self.window_cov.iter_mut().zip(means.iter()).enumerate() {
            if set & (1 << s) != 0 {
                ewma_outer_padded(cov, rbar, wt, self.dim);
            }
        }
    }
}

/// `cov ← pad(cov (1 − wt) + r rᵀ wt, dim)` in place: the same operations
/// on the entries `pad` keeps (`r_i r_j` is the outer product's one
/// multiply; the symmetrisation `(a_ij + a_ji) / 2` as `pad` does it), none
/// on those it resets, and no 9×9 temporaries. Bit for bit the expression
/// (`tests.rs`); with four covariances learned per block, the expression
/// made the learning stage ≈ 10 k instructions on the M4F, so a monitor
/// and the re-admission shadow learning in the same step passed 20,000.
fn ewma_outer_padded<T: Real, const N: usize>(
    cov: &mut SMatrix<T, N, N>,
    r: &SVector<T, N>,
    wt: T,
    dim: usize,
) {
    let keep = T::one() - wt;
    for j in 0..N {
        for i in j..N {
            let v = if i < dim && j < dim {
                let (Some(ri), Some(rj), Some(cij), Some(cji)) =
                    (r.get(i), r.get(j), cov.get((i, j)), cov.get((j, i)))
                else {
                    return;
                };
                let uij = *cij * keep + *ri * *rj * wt;
                let uji = *cji * keep + *rj * *ri * wt;
                (uij + uji) * T::lit(0.5)
            } else if i == j {
                T::one()
            } else {
                T::zero()
            };
            if let Some(x) = cov.get_mut((i, j)) {
                *x = v;
            }
            if let Some(x) = cov.get_mut((j, i)) {
                *x = v;
            }
        }
    }
}

#[cfg(test)]
mod tests;

//! The monitor's path for real flights: samples into blocks, the block's
//! regressors (centred difference, per-sensor vibration), training and
//! decisions of the multi-scale tests, isolation by their verdict.

use nalgebra::{SVector, Vector3};

use crate::math::Real;

use super::super::multiscale::{BlockStage, Multiscale, Outcome, REGRESSORS};
use super::{reconfig, ParityMonitor};

/// Sums over the block being accumulated for the multi-scale tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct BlockSums<T: Real, const N: usize> {
    p: SVector<T, N>,
    x: Vector3<T>,
    /// First sample of the block, the sensors' sums are centred on.
    m0: Option<SVector<T, N>>,
    m: SVector<T, N>,
    mm: SVector<T, N>,
    n: u16,
}

impl<T: Real, const N: usize> Default for BlockSums<T, N> {
    fn default() -> Self {
        Self {
            p: SVector::zeros(),
            x: Vector3::zeros(),
            m0: None,
            m: SVector::zeros(),
            mm: SVector::zeros(),
            n: 0,
        }
    }
}

impl<T: Real, const N: usize> BlockSums<T, N> {
    /// First sample of the block (`None`: empty).
    pub(super) fn m0(&self) -> Option<SVector<T, N>> {
        self.m0
    }

    /// Samples in the block.
    pub(super) fn len(&self) -> u16 {
        self.n
    }

    /// `Σ (m − m₀)` over the block.
    pub(super) fn m_sum(&self) -> SVector<T, N> {
        self.m
    }

    /// The same sums with the parity and fused sums of another space.
    pub(super) fn with_projection(self, p: SVector<T, N>, x: Vector3<T>) -> Self {
        Self { p, x, ..self }
    }

    /// Adds one sample; the samples in the block now. Out of line: compiled
    /// into `step_ref` its sums cost ≈ 30 instructions more per sample on
    /// the M4F, by how much else was live in registers around them.
    #[inline(never)]
    fn add(&mut self, m: &SVector<T, N>, p: &SVector<T, N>, x: &Vector3<T>) -> u16 {
        // Centre the sensor sums on the block's first sample so the f32
        // variance is not the difference of two large numbers.
        let m0 = *self.m0.get_or_insert(*m);
        let dm = m - m0;
        self.p += p;
        self.x += x;
        self.m += dm;
        self.mm += dm.component_mul(&dm);
        self.n = self.n.saturating_add(1);
        self.n
    }
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// Accumulates one sample into the multi-scale block; a complete block
    /// starts the work on the one before it (whose centred difference is
    /// now known).
    pub(super) fn multiscale_sample(
        &mut self,
        m: &SVector<T, N>,
        p: &SVector<T, N>,
        x: &Vector3<T>,
    ) {
        if self.ms_block.add(m, p, x) >= self.cfg.block_len {
            self.close_block();
        }
    }

    /// [`multiscale_sample`](Self::multiscale_sample) when the block is
    /// complete (once per block: out of line, so the per-sample sums are
    /// compiled into `step_ref` without its register pressure).
    #[inline(never)]
    fn close_block(&mut self) {
        let b = &self.ms_block;
        let n = T::lit(f64::from(b.n));
        let (pb, xb) = (b.p / n, b.x / n);
        let mean = b.m / n;
        let eb = (b.mm / n - mean.component_mul(&mean)).map(|v| v.max(T::zero()));
        let full_mean = b.m0.map(|m0| m0 + mean);
        self.ms_block = BlockSums::default();
        if let Some(m) = full_mean.filter(|_| self.readmission.judging()) {
            // The parity-isolated sensor's shadow tests take the block too.
            self.shadow_block(&m, &eb);
        }
        // A reconfiguration still carrying the learning ends first.
        self.advance_reconfig(true);
        // Blocks shorter than the stages: the work in progress ends now.
        if self.ms.live().is_some_and(|ms| ms.pending().is_some()) && self.multiscale_advance(true)
        {
            // It reconfigured: this block is from the old space.
            return;
        }
        if let (Some((p_prev, x_prev, e_prev)), Some(x_before)) = (self.ms_prev, self.ms_prev2) {
            let dx = (xb - x_before) * T::lit(0.5);
            self.multiscale_block(&p_prev, &x_prev, &dx, &e_prev);
        }
        self.ms_prev2 = self.ms_prev.map(|(_, x, _)| x);
        self.ms_prev = Some((pb, xb, eb));
    }

    /// Starts one block through the multi-scale tests: training (first two
    /// thirds calibrate, at once; the last third measures the residual's
    /// covariance), or a decision, in stages.
    fn multiscale_block(
        &mut self,
        p: &SVector<T, N>,
        x: &Vector3<T>,
        dx: &Vector3<T>,
        e: &SVector<T, N>,
    ) {
        let train_blocks = (self.cfg.train_samples / u32::from(self.cfg.block_len.max(1))).max(12);
        let active = *self.space.active();
        let Some(ms) = self.ms.live_mut() else {
            return;
        };
        // Sensors out of the set may read anything: no vibration regressor.
        let e = SVector::<T, N>::from_fn(|i, _| {
            if active.get(i).copied().unwrap_or(false) {
                e.get(i).copied().unwrap_or(T::zero())
            } else {
                T::zero()
            }
        });
        let phi: SVector<T, REGRESSORS> = ms.regressor(x, dx, &e);
        // The block's vibration level: the RMS spread of the sensors within
        // it (what the residual's variance follows, see `multiscale::scale`).
        let level = e.sum().max(T::zero()).sqrt();
        if self.ms_trained {
            ms.begin(p, &phi, level, None);
            return;
        }
        self.ms_blocks = self.ms_blocks.saturating_add(1);
        if self.ms_blocks <= train_blocks * 2 / 3 {
            ms.learn_calibration(p, &phi, false);
            return;
        }
        ms.begin(p, &phi, level, Some(self.ms_blocks >= train_blocks));
    }

    /// Runs one stage of the block in work (`to_end`: all of them) and
    /// applies its outcome: the end of training, or the block's decision,
    /// with isolation after `isolate_after` agreeing decisions whose
    /// hypothesis beats the runner-up by the margin. True when it isolated
    /// a sensor (the set changed).
    ///
    /// The test for "no block in work" is inlined into the callers (most
    /// samples have none; the call and the body's set-up cost ≈ 44
    /// instructions per sample on the M4F, issue 14).
    #[inline]
    pub(super) fn multiscale_advance(&mut self, to_end: bool) -> bool {
        if !self.configured() || self.ms.live().is_none_or(|ms| ms.pending().is_none()) {
            return false;
        }
        self.run_multiscale_stage(to_end)
    }

    /// [`multiscale_advance`](Self::multiscale_advance) with a block in work.
    #[inline(never)]
    fn run_multiscale_stage(&mut self, to_end: bool) -> bool {
        let cfg = self.cfg.multiscale;
        let Some(ms) = self.ms.live_mut() else {
            return false;
        };
        let (v, active) = (self.space.v(), self.space.active());
        let outcome = if to_end {
            ms.finish(v, active)
        } else {
            ms.advance(v, active)
        };
        let d = match outcome {
            Outcome::Busy | Outcome::Trained(None) | Outcome::Decided(None) => return false,
            Outcome::Trained(Some(true)) => {
                self.ms_trained = true;
                return false;
            }
            Outcome::Trained(Some(false)) => {
                // Degenerate training data: start again.
                *ms = Multiscale::new(cfg, self.space.dim(), ms.threshold_set());
                self.ms_blocks = 0;
                return false;
            }
            Outcome::Decided(Some(d)) => d,
        };
        self.last.decision = true;
        self.last.multiscale = d;
        // The alarm is confirmed by `isolate_after` consecutive decisions
        // above threshold (the run isolation needs too), or at once by the
        // gross test. On a point-sampled board a vibration line that the
        // sampling folds to near 0 Hz swings the block means for a second or
        // two while the within-block spread collapses: on the realistic
        // profile such a swing crossed the 2.5-s threshold for one or two
        // decisions (11 of 12 runs above threshold in 10 fault-free hours),
        // while a bias holds its windows above threshold for as long as it
        // lasts. The confirmation costs a detection `isolate_after − 1`
        // blocks (0.5 s at the default 0.25-s blocks).
        let above = d.ratio > T::one();
        self.ms_above = if above {
            self.ms_above.saturating_add(1)
        } else {
            0
        };
        let confirmed = above && (d.gross || self.ms_above >= self.cfg.isolate_after.max(1));
        // The alarm holds for one shortest window after the last confirmed
        // decision: when a fault ends, the windows still hold its blocks for
        // up to the longest length, and a score hovering at the threshold
        // would otherwise flicker into new alarm events.
        self.ms_hold = if confirmed {
            cfg.scales[0]
        } else {
            self.ms_hold.saturating_sub(1)
        };
        self.last.fault = confirmed || self.ms_hold > 0;
        self.last.suspect = d.suspect;
        self.last.bias_estimate = d.bias;
        let candidate = d
            .isolate
            .filter(|(k, m)| above && *m >= cfg.isolation_margin && self.space.isolable(*k))
            .map(|(k, _)| k);
        let Some(k) = candidate else {
            if !above {
                self.suspect_run = (None, 0);
            }
            return false;
        };
        // Confirmation and isolation need the same run of decisions: the
        // period that isolates is then the alarm's first, and reports it.
        let isolated = self.vote_to_isolate(k);
        if isolated {
            self.last.fault = true;
        }
        isolated
    }

    /// Excludes sensor `k` isolated by a block's decision, taken some
    /// samples into the next block: as if it had been excluded when that
    /// block began, which is when the one-shot computation decided. The
    /// reduced space now (so the samples go on into the block), the
    /// partial block's sums moved into it, the learning carried over the
    /// next steps; the block before is kept only for its fused mean (it is
    /// the old space's), as before.
    pub(super) fn exclude_between_blocks(&mut self, k: usize) {
        let (prev, block) = (self.ms_prev, self.ms_block);
        self.exclude(k);
        self.advance_reconfig(false);
        if !self.configured()
            && !matches!(
                self.reconfig,
                reconfig::Reconfig::Transform(..) | reconfig::Reconfig::Shadow(_)
            )
        {
            return;
        }
        self.ms_prev = prev;
        self.ms_prev2 = None;
        if let Some(m0) = block.m0 {
            // Σ m = n m₀ + Σ (m − m₀); the sums are linear in it.
            let sum_m = m0 * T::lit(f64::from(block.n)) + block.m;
            self.ms_block = BlockSums {
                p: self.space.v() * sum_m,
                x: self.space.lsq() * sum_m,
                ..block
            };
        }
    }

    /// The stage of deferred work the next step runs: a reconfiguration
    /// after an isolation or a failure (both detectors), or the multi-scale
    /// block in work; `None` when there is none.
    pub fn pending_stage(&self) -> Option<BlockStage> {
        if !self.configured() {
            return Some(BlockStage::Reconfigure(self.reconfig_stage()));
        }
        self.ms.live().and_then(|ms| ms.pending())
    }
}

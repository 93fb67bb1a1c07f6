//! Reconfiguration after an isolation or a failure, in stages (issue 17):
//! the reduced parity space, then either the white-noise tests rebuilt
//! ([`build_stage`]) or the multi-scale tests' learning carried into the
//! new space (after an isolation judged for re-admission, first copied
//! into the shadow, `readmit.rs`), one stage per step, instead of all in
//! the step that isolated.
//! The tests are idle meanwhile (their window and CUSUMs restart after a
//! reconfiguration anyway) and fusion goes on; what the stages build is
//! what the one-shot reconfiguration built, in use at most
//! [`reconfig_steps`] steps later.
//!
//! The white-noise tests' first build, at the end of training, runs in the
//! same stages; there the samples go on into blocks against the learned
//! baseline, the phase stays `Training` until the tests are built, and a
//! block completed meanwhile is decided once they are (`white.rs`). The end
//! of calibration only scales the thresholds.

use nalgebra::SMatrix;

use crate::math::Real;

use super::super::multiscale::{Multiscale, TRANSFORM_PARTS};
use super::super::training::{Baseline, Trainer};
use super::build::{build_stage, build_stages, Newton};
use super::{ParityMonitor, ParityPhase};

/// Steps a reconfiguration takes at most with `N` sensors.
pub const fn reconfig_steps(n: usize) -> usize {
    let white = 1 + build_stages(n);
    // The space, the re-admission shadow's copy, the transform.
    let multiscale = 2 + TRANSFORM_PARTS;
    if white > multiscale {
        white
    } else {
        multiscale
    }
}

/// Reconfiguration in progress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Reconfig<T: Real, const N: usize> {
    /// None.
    Idle,
    /// The space without sensor `k` next.
    Space(usize),
    /// White-noise tests: build stage `.0` next (the tests in progress are
    /// in `tests`); `.1` the CUSUM threshold's root search in progress;
    /// `.2` the first build, at the end of training (samples go on into
    /// blocks; calibration or monitoring starts once built).
    Tests(usize, Newton, bool),
    /// Multi-scale tests, after an isolation to be judged for re-admission:
    /// the learning copied into the shadow (`readmit.rs`) before it is
    /// carried (`.0`: the old space's `V`, for `Transform` part 0).
    Shadow(SMatrix<T, N, N>),
    /// Multi-scale tests: part `.1` of carrying the learning through the
    /// transition `.0` (`p_new = c p`; in part 0 still the old space's `V`,
    /// from which the transition is formed).
    Transform(SMatrix<T, N, N>, usize),
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// The tests run on this step (no reconfiguration in progress).
    pub(super) fn configured(&self) -> bool {
        matches!(self.reconfig, Reconfig::Idle)
    }

    /// Index of the reconfiguration stage next (see
    /// [`BlockStage::Reconfigure`](crate::parity::BlockStage::Reconfigure)).
    pub(super) fn reconfig_stage(&self) -> u8 {
        let i = match self.reconfig {
            Reconfig::Idle | Reconfig::Space(_) => 0,
            Reconfig::Tests(stage, ..) => 1 + stage,
            Reconfig::Shadow(_) => 1,
            Reconfig::Transform(_, part) => 2 + part,
        };
        u8::try_from(i).unwrap_or(u8::MAX)
    }

    /// Samples go into the tests on this step: no reconfiguration in
    /// progress, or only the multi-scale learning being copied or carried (the
    /// samples accumulate in the new space meanwhile; a block closing
    /// finishes the carrying first).
    pub(super) fn accepts_samples(&self) -> bool {
        matches!(
            self.reconfig,
            Reconfig::Idle
                | Reconfig::Shadow(_)
                | Reconfig::Transform(..)
                | Reconfig::Tests(_, _, true)
        )
    }

    /// Runs one stage of the reconfiguration in progress (`to_end`: all).
    ///
    /// The test for "none in progress" is inlined into the callers: the
    /// stages' body sets up its frame (≈ 290 instructions on the M4F)
    /// before its first `match`, which every sample paid for nothing
    /// (issue 14).
    #[inline]
    pub(super) fn advance_reconfig(&mut self, to_end: bool) {
        if !matches!(self.reconfig, Reconfig::Idle) {
            self.run_reconfig(to_end);
        }
    }

    /// [`advance_reconfig`](Self::advance_reconfig) with a reconfiguration
    /// in progress.
    #[inline(never)]
    fn run_reconfig(&mut self, to_end: bool) {
        loop {
            match self.reconfig {
                Reconfig::Idle => return,
                Reconfig::Space(k) => {
                    self.reconfig = Reconfig::Idle;
                    self.reduce(k);
                }
                Reconfig::Tests(stage, newton, lead_in) => {
                    self.reconfig = Reconfig::Idle;
                    self.tests_stage(stage, newton, lead_in);
                }
                Reconfig::Shadow(m) => {
                    self.reconfig = Reconfig::Transform(m, 0);
                    self.copy_shadow();
                }
                Reconfig::Transform(m, part) => {
                    self.reconfig = Reconfig::Idle;
                    self.transform_stage(&m, part);
                }
            }
            if !to_end {
                return;
            }
        }
    }

    /// Part `part` of carrying the multi-scale learning into the new space
    /// (`m`: the transition, or in part 0 the old space's `V`).
    #[inline(never)]
    fn transform_stage(&mut self, m: &SMatrix<T, N, N>, part: usize) {
        // Part 0 holds the old space's `V`: the transition
        // `c = V_new V_oldᵀ` is formed here, not in the
        // (isolating) step that built the new space.
        let c = if part == 0 {
            self.space.v() * m.transpose()
        } else {
            *m
        };
        let dim = self.space.dim();
        if let Some(ms) = self.ms.live_mut() {
            ms.transform_part(&c, dim, part);
        }
        if part + 1 < TRANSFORM_PARTS {
            self.reconfig = Reconfig::Transform(c, part + 1);
        }
    }

    /// One stage of building the white-noise tests (`lead_in`: the first
    /// build, at the end of training). Out of line: the multi-scale
    /// monitor's steps never run it.
    #[inline(never)]
    fn tests_stage(&mut self, stage: usize, mut newton: Newton, lead_in: bool) {
        let built = self.tests.as_mut().and_then(|t| {
            let (cfg, space) = (&self.cfg, &self.space);
            build_stage(t, stage, &mut newton, space, cfg, &self.scales, &self.chi2)
        });
        match built {
            // Non-finite training data: train again rather
            // than test with it.
            None if lead_in => {
                self.tests = None;
                self.held = None;
                self.block = nalgebra::SVector::zeros();
                self.block_n = 0;
                self.trainer =
                    Trainer::new(self.cfg.train_samples, self.cfg.block_len, self.cfg.ridge);
            }
            None => {
                self.tests = None;
                self.phase = ParityPhase::Lost;
            }
            Some(next) if next < build_stages(N) => {
                self.reconfig = Reconfig::Tests(next, newton, lead_in);
            }
            Some(_) if lead_in => {
                self.phase = if self.cfg.calibrate_samples > 0 {
                    ParityPhase::Calibrating
                } else {
                    ParityPhase::Monitoring
                };
            }
            Some(_) => {}
        }
    }

    /// The space without sensor `k` (already marked removed), and what
    /// carries into it: the white-noise baseline through the transition
    /// (its tests rebuilt in the next stages), the multi-scale learning
    /// (carried in the next stages), or training restarted.
    fn reduce(&mut self, k: usize) {
        let Some(sub) = self.reduced_space(k) else {
            return;
        };
        if let Some(ms) = self.ms.live_mut() {
            if self.ms_trained {
                ms.cancel();
                let v = *self.space.v();
                self.reconfig = if self.readmission.copy_pending() {
                    Reconfig::Shadow(v)
                } else {
                    Reconfig::Transform(v, 0)
                };
            } else {
                // Failed while training: train the reduced set.
                *ms = Multiscale::new(self.cfg.multiscale, sub.dim(), ms.threshold_set());
                self.ms_blocks = 0;
            }
        }
        if let Some(t) = self.tests.as_mut() {
            let c = self.space.transition_to(&sub);
            t.baseline = Baseline {
                offset: c * t.baseline.offset,
                leak: c * t.baseline.leak,
                block_cov: c * t.baseline.block_cov * c.transpose(),
                correlation_factor: t.baseline.correlation_factor,
            };
            self.reconfig = Reconfig::Tests(0, Newton::START, false);
        } else if !self.ms.is_some() {
            // Failed during training: start training the reduced set.
            self.trainer = Trainer::new(self.cfg.train_samples, self.cfg.block_len, self.cfg.ridge);
        }
        self.space = sub;
    }
}

//! Reconfiguration of the white-noise tests after an isolation, in stages
//! (issue 17): the reduced parity space, then the tests rebuilt one stage
//! per step ([`TestsBuilder`]) instead of ≈ 168 k instructions in the step
//! that isolated. The tests are idle meanwhile (their window and CUSUMs
//! restart after a reconfiguration anyway), fusion goes on; the rebuilt
//! tests are those the one-shot reconfiguration gave, in use `N + 3`
//! steps later at most.

use crate::math::Real;

use super::super::training::Baseline;
use super::white::{Build, TestsBuilder};
use super::{ParityMonitor, ParityPhase};

/// Reconfiguration in progress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Reconfig<T: Real, const N: usize> {
    /// None.
    Idle,
    /// The space without sensor `k` next; `baseline` is the old space's.
    Space(usize, Baseline<T, N>),
    /// The tests of the new space, stage by stage.
    Tests(TestsBuilder<T, N>),
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// Starts reconfiguring the white-noise tests without sensor `k`
    /// (already marked removed); false when they are not running (training,
    /// multi-scale tests): the caller reconfigures at once.
    pub(super) fn stage_reconfig(&mut self, k: usize) -> bool {
        if self.ms.is_some() {
            return false;
        }
        let Some(t) = self.tests.take() else {
            return false;
        };
        self.reconfig = Reconfig::Space(k, t.baseline);
        true
    }

    /// Runs one stage of the reconfiguration in progress (`to_end`: all).
    pub(super) fn advance_reconfig(&mut self, to_end: bool) {
        loop {
            match self.reconfig {
                Reconfig::Idle => return,
                Reconfig::Space(k, baseline) => {
                    self.reconfig = Reconfig::Idle;
                    if let Some(sub) = self.reduced_space(k) {
                        let c = self.space.transition_to(&sub);
                        let b = Baseline {
                            offset: c * baseline.offset,
                            leak: c * baseline.leak,
                            block_cov: c * baseline.block_cov * c.transpose(),
                            correlation_factor: baseline.correlation_factor,
                        };
                        self.space = sub;
                        self.reconfig = Reconfig::Tests(TestsBuilder::new(b));
                    }
                }
                Reconfig::Tests(mut builder) => {
                    match builder.stage(&self.space, &self.cfg, &self.scales, &self.chi2) {
                        Build::Busy => self.reconfig = Reconfig::Tests(builder),
                        Build::Done(t) => {
                            self.reconfig = Reconfig::Idle;
                            self.tests = t;
                            if self.tests.is_none() {
                                self.phase = ParityPhase::Lost;
                            }
                        }
                    }
                }
            }
            if !to_end {
                return;
            }
        }
    }
}

//! The tracker without the feature `fault-tracking`: the same calls, no
//! state and no code on the monitor's step (the MCU images, issue 17).

use crate::filter::ChannelDiag;
use crate::math::Real;
use crate::model::{ImuVec, Mat6, NX, NZ};

/// Without the feature `fault-tracking`: an empty stand-in with the same
/// calls, so the monitor carries no tracker state (≈ 1 KB in f32).
#[derive(Debug, Clone)]
pub(in crate::monitor::ukf_monitor) struct FaultTracker<T> {
    /// Never set: the tracker does not run.
    pub active: bool,
    _t: core::marker::PhantomData<T>,
}

impl<T: Real> FaultTracker<T> {
    /// An inactive tracker.
    pub fn new() -> Self {
        Self {
            active: false,
            _t: core::marker::PhantomData,
        }
    }
    /// Never: no epoch is staged.
    pub fn pending(&self) -> bool {
        false
    }
    /// Does nothing.
    pub fn begin_epoch(&mut self, _x_prior: &Mat6<T>, _gate: T) {}
    /// Does nothing.
    pub fn observe_all(&mut self, _diag: &[ChannelDiag<T>; NZ], _inflation: &[T; NZ]) {}
    /// Does nothing.
    pub fn end_epoch(&mut self, _gain: &Mat6<T>, _h: Option<&Mat6<T>>) {}
    /// Does nothing.
    pub fn run_epoch(&mut self, _psd: &ImuVec<T>, _x_post: &Mat6<T>) {}
    /// Does nothing (the configuration is refused without the feature).
    pub fn start(&mut self, _sigma0: &ImuVec<T>, _x: &Mat6<T>) {}
    /// No estimate.
    pub fn estimate(&self) -> (ImuVec<T>, ImuVec<T>) {
        (ImuVec::zeros(), ImuVec::zeros())
    }
    /// Does nothing.
    pub fn set_mask(&mut self, _monitored: [bool; 6]) {}
    /// No channel.
    pub fn mask(&self) -> [bool; 6] {
        [false; 6]
    }
    /// Does nothing.
    pub fn forget_states(&mut self, _reset: &[bool; NX]) {}
    /// Does nothing.
    pub fn advance(&mut self, _a: &Mat6<T>, _dt: T) {}
}

//! The power-up check's stand-in when it is not compiled in (feature
//! `power-up-check` off, the MCU images): it learns nothing and flags
//! nothing. A bias beyond the turn-on bound is then reported by the
//! windowed tests alone, which needs the learnt inflation not to have
//! absorbed it: the presets' `max_innovation_inflation` of 1 keeps it out
//! (`tests/power_up_bias.rs`: 1.5 °/s flagged within 1 s of monitoring).

use core::marker::PhantomData;

use crate::math::Real;
use crate::model::ImuVec;
use crate::monitor::ChannelState;

/// Nothing (see the module notes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PowerUpCheck<T>(PhantomData<T>);

impl<T> Default for PowerUpCheck<T> {
    fn default() -> Self {
        Self(PhantomData)
    }
}

impl<T: Real> PowerUpCheck<T> {
    #[inline(always)]
    pub(super) fn learn(&mut self, _unbounded: &ImuVec<T>, _second_half: bool) {}
    #[inline(always)]
    pub(super) fn start(&mut self, _bound: &ImuVec<T>, _smallest: &ImuVec<T>) {}
    #[inline(always)]
    pub(super) fn any(&self) -> bool {
        false
    }
    #[inline(always)]
    pub(super) fn excess(&self) -> ImuVec<T> {
        ImuVec::zeros()
    }
    #[inline(always)]
    pub(super) fn track(&mut self, _u: &ImuVec<T>, _k: T, _b: &ImuVec<T>, _s: &ImuVec<T>) {}
    #[inline(always)]
    pub(super) fn apply(&self, _s: &mut [ChannelState; 6], _e: &mut ImuVec<T>, _b: &ImuVec<T>) {}
}

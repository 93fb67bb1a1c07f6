//! The accelerometer/GNSS-velocity consistency test's hooks when it is not
//! compiled in (feature `velocity-increment-test` off, the MCU images):
//! they do nothing, and a configuration asking for the test is refused
//! (`ConfigError::NotCompiled("velocity_increment")`).

use super::UkfMonitor;
use crate::math::Real;
use crate::model::{ImuVec, Measurement};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    #[inline(always)]
    pub(super) fn vel_inc_sample(&mut self, _imu: &ImuVec<T>, _dt: T, _usable: bool) {}
    #[inline(always)]
    pub(super) fn vel_inc_epoch(&mut self, _aiding: &Measurement<T>) {}
    #[inline(always)]
    pub(super) fn vel_inc_apply(&mut self, _tainted: bool, _elsewhere: bool) {}
    #[inline(always)]
    pub(super) fn vel_inc_sees_fault(&self) -> bool {
        false
    }
    #[inline(always)]
    pub(super) fn velocity_tainted(&mut self) -> bool {
        false
    }
    #[inline(always)]
    pub(super) fn vel_inc_quiet(&self) -> bool {
        true
    }
    #[inline(always)]
    pub(super) fn vel_inc_clear(&mut self) {}
    #[inline(always)]
    pub(super) fn vel_inc_reset(&mut self) {}
    #[inline(always)]
    pub(super) fn vel_inc_start(&mut self) {}
    #[inline(always)]
    pub(super) fn vel_inc_ended(&self, _flagged_for: &[T; 6], _raised_at: &[T; 6]) -> [bool; 3] {
        [false; 3]
    }
}

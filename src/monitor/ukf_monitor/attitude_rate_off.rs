//! The gyro/attitude-aiding consistency test's hooks when it is not
//! compiled in (feature `attitude-rate-test` off, the MCU images): they do
//! nothing, and a configuration asking for the test is refused
//! (`ConfigError::NotCompiled("attitude_rate")`).

use super::UkfMonitor;
use crate::math::Real;
use crate::model::{ImuVec, Measurement};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    #[inline(always)]
    pub(super) fn att_rate_sample(&mut self, _imu: &ImuVec<T>, _dt: T, _usable: bool) {}
    #[inline(always)]
    pub(super) fn att_rate_epoch(&mut self, _aiding: &Measurement<T>) {}
    #[inline(always)]
    pub(super) fn att_rate_apply(&mut self, _elsewhere: bool) {}
    #[inline(always)]
    pub(super) fn att_rate_sees_fault(&self) -> bool {
        false
    }
    #[inline(always)]
    pub(super) fn att_rate_quiet(&self) -> bool {
        true
    }
    #[inline(always)]
    pub(super) fn att_rate_clear(&mut self) {}
    #[inline(always)]
    pub(super) fn att_rate_reset(&mut self) {}
    #[inline(always)]
    pub(super) fn att_rate_start(&mut self) {}
    #[inline(always)]
    pub(super) fn att_rate_ended(&self, _flagged_for: &[T; 6], _raised_at: &[T; 6]) -> [bool; 3] {
        [false; 3]
    }
}

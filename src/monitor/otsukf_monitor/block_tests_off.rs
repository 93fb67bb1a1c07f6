//! Built without both block-test features: the hooks do nothing.

use super::OtsukfMonitor;
use crate::math::Real;
use crate::model::{ImuVec, Measurement, NZ};
use crate::monitor::{AttitudeRateDetail, OtsukfReport, VelocityIncrementDetail};

impl<T: Real> OtsukfMonitor<T> {
    /// The gyro/attitude-aiding test is not compiled in: `None`.
    pub fn attitude_rate_detail(&self) -> Option<AttitudeRateDetail<T>> {
        None
    }

    /// The accelerometer/GNSS-velocity test is not compiled in: `None`.
    pub fn velocity_increment_detail(&self) -> Option<(VelocityIncrementDetail<T>, T)> {
        None
    }

    pub(super) fn blocks_sample(&mut self, _imu: &ImuVec<T>, _dt: T, _usable: bool) {}

    pub(super) fn blocks_epoch(&mut self, _aiding: &Measurement<T>, _fused: &[bool; NZ]) {}

    pub(super) fn blocks_apply(&mut self, _r: &mut OtsukfReport<T>) {}

    pub(super) fn blocks_accel_unlearnt(&self) -> bool {
        false
    }

    pub(super) fn blocks_ended(&self) -> [bool; 6] {
        [false; 6]
    }

    pub(super) fn blocks_clear(&mut self) {}

    pub(super) fn blocks_reset(&mut self) {}

    pub(super) fn blocks_start(&mut self) {}
}

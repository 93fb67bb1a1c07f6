//! Built without `aiding-estimators`: the attitude aiding is fused on
//! arrival (`attitude_lag.rs`; the configuration refuses a latency).

use super::OtsukfMonitor;
use crate::math::Real;
use crate::model::{Measurement, StateVec};

impl<T: Real> OtsukfMonitor<T> {
    /// The attitude latency is not compiled in: `None`.
    pub fn attitude_lag_estimate(&self) -> Option<T> {
        None
    }

    #[cfg(feature = "attitude-rate-test")]
    pub(super) fn att_lag_steps(&self) -> usize {
        0
    }

    pub(super) fn att_lag_reset(&mut self) {}

    pub(super) fn att_lag_before(&self) -> Option<StateVec<T>> {
        None
    }

    pub(super) fn att_lag_period(
        &mut self,
        _before: &Option<StateVec<T>>,
        _propagated: bool,
        _dt: T,
    ) {
    }

    pub(super) fn att_lag_epoch(&mut self, _aiding: &Measurement<T>) {}

    pub(super) fn bring_attitude_forward(&self, aiding: &Measurement<T>) -> Measurement<T> {
        *aiding
    }
}

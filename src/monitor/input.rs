//! What every single-IMU monitor does before and around its filter, in one
//! place so the monitors cannot drift apart: the input checks (sample
//! within range, measured period, aiding channels with a finite value, the
//! gyro rates the lever-arm term may use) and the start-up phases
//! (aligning → converging → learning → monitoring, SPEC §8a).

use nalgebra::Vector3;

use super::Phase;
use crate::math::Real;
use crate::model::{ImuVec, Measurement, NZ};

/// Beyond this multiple of full scale a sample is not a measurement.
const RANGE_FACTOR: f64 = 1.5;
/// At or beyond this fraction of full scale a sample is clipping.
const SATURATION_FRACTION: f64 = 0.98;
/// A period longer than this many nominal periods is a gap.
const MAX_PERIOD_FACTOR: f64 = 5.0;

/// One channel's reading is finite and within 1.5× its full scale.
fn channel_in_range<T: Real>(v: T, full_scale: T) -> bool {
    v.finite() && v.abs() <= full_scale * T::lit(RANGE_FACTOR)
}

/// True when every channel is finite and within 1.5× its full scale.
pub(crate) fn in_range<T: Real>(imu: &ImuVec<T>, full_scale: &ImuVec<T>) -> bool {
    imu.iter()
        .zip(full_scale.iter())
        .all(|(v, fs)| channel_in_range(*v, *fs))
}

/// The sample that stands in for an unusable one: each channel that is
/// finite and within range as read, the others from `last` (the last good
/// sample). One bad cell (a NaN written by a logger, a corrupted register)
/// then leaves the five other channels real.
pub(crate) fn stand_in<T: Real>(
    imu: &ImuVec<T>,
    last: &ImuVec<T>,
    full_scale: &ImuVec<T>,
) -> ImuVec<T> {
    let mut out = *last;
    for ((o, v), fs) in out.iter_mut().zip(imu.iter()).zip(full_scale.iter()) {
        if channel_in_range(*v, *fs) {
            *o = *v;
        }
    }
    out
}

/// True when any channel is at or beyond 98 % of its full scale.
pub(crate) fn saturated<T: Real>(imu: &ImuVec<T>, full_scale: &ImuVec<T>) -> bool {
    imu.iter()
        .zip(full_scale.iter())
        .any(|(v, fs)| v.abs() >= *fs * T::lit(SATURATION_FRACTION))
}

/// The measured period against the nominal one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Period<T> {
    /// Finite, positive and at most five nominal periods.
    Valid(T),
    /// Longer than five nominal periods (a gap): the cap.
    Long(T),
    /// Not finite, zero or negative.
    Invalid,
}

/// Classifies the measured `dt` against the nominal `period`.
pub(crate) fn check_period<T: Real>(dt: T, period: T) -> Period<T> {
    let max_dt = period * T::lit(MAX_PERIOD_FACTOR);
    if !(dt.finite() && dt > T::zero()) {
        Period::Invalid
    } else if dt > max_dt {
        Period::Long(max_dt)
    } else {
        Period::Valid(dt)
    }
}

/// The time an IMU gave its monitor's filter nothing to follow: periods
/// beyond what the prediction bridged (a dropout: the next sample carries
/// the time) and samples not usable (invalid, frozen), where the filter
/// dead-reckoned on the last good one. After a gap longer than five nominal
/// periods the state has missed that much motion, and the windows of the
/// statistics and block tests span samples that were never integrated: the
/// monitor holds its statistics as after an aiding loss, instead of
/// flagging what the gap did (on log171 2 s of IMU rows cut in flight
/// flagged a_x, g_y and g_z of every IMU for 3–6 s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct ImuGap<T> {
    missed: T,
}

impl<T: Real> ImuGap<T> {
    /// One period: `dt` measured, `bridged` the period the prediction
    /// used (`None`: not predicted), `usable` this sample. True when the
    /// IMU is back after a gap longer than five nominal `period`s.
    pub(crate) fn back_after_gap(
        &mut self,
        dt: T,
        bridged: Option<T>,
        usable: bool,
        period: T,
    ) -> bool {
        let dt = if dt.finite() && dt > T::zero() {
            dt
        } else {
            T::zero()
        };
        let followed = match bridged {
            Some(b) if usable => b,
            _ => T::zero(),
        };
        self.missed += (dt - followed).fmax(T::zero());
        if !usable {
            return false;
        }
        let gap = self.missed > period * T::lit(MAX_PERIOD_FACTOR);
        self.missed = T::zero();
        gap
    }

    /// This sample is unusable (`usable` false) and the run of unusable
    /// samples it belongs to is still short enough to bridge with a stand-in
    /// everywhere: at most five nominal `period`s missed, beyond which
    /// [`back_after_gap`](Self::back_after_gap) reports a gap when the IMU
    /// is back. Always false without the gap recovery (feature
    /// `imu-gap-recovery`), which is what ends a longer run.
    pub(crate) fn bridges(&self, usable: bool, period: T) -> bool {
        !usable
            && cfg!(feature = "imu-gap-recovery")
            && self.missed <= period * T::lit(MAX_PERIOD_FACTOR)
    }
}

/// The aiding channels that arrived with a finite value.
pub(crate) fn usable_aiding<T: Real>(aiding: &Measurement<T>) -> [bool; NZ] {
    let mut available = aiding.available;
    for (a, z) in available.iter_mut().zip(aiding.z.iter()) {
        *a = *a && z.finite();
    }
    available
}

/// The aiding with every channel outside its physical range withdrawn:
/// velocity components beyond `max_speed` (m/s), angles beyond ±π, anything
/// not finite. The flag says whether a present channel was withdrawn.
pub(crate) fn aiding_in_range<T: Real>(
    aiding: &Measurement<T>,
    max_speed: T,
) -> (Measurement<T>, bool) {
    let mut out = *aiding;
    let mut invalid = false;
    // Most IMU periods carry no aiding: nothing to withdraw, and the loop
    // below would still walk all six channels (≈ 120 instructions on the
    // Cortex-M4F per predict-only step, issue 17).
    if !aiding.any() {
        return (out, invalid);
    }
    for (i, (a, z)) in out.available.iter_mut().zip(aiding.z.iter()).enumerate() {
        if !*a {
            continue;
        }
        let limit = if i < 3 { max_speed } else { T::pi() };
        if !(z.finite() && z.abs() <= limit) {
            *a = false;
            invalid = true;
        }
    }
    (out, invalid)
}

/// The gyro rates of a (bias-corrected) sample for the lever-arm term; zero
/// for an invalid sample, which must not reach the state through it.
pub(crate) fn lever_arm_rates<T: Real>(in_range: bool, imu: &ImuVec<T>) -> Vector3<T> {
    if in_range {
        imu.fixed_rows::<3>(3).into_owned()
    } else {
        Vector3::zeros()
    }
}

/// The phase that follows `phase` after `time` in it since alignment:
/// learning once converged (`converge_s`), monitoring once learned
/// (`converge_s + learn_s`); `None` while it stays.
pub(crate) fn next_phase<T: Real>(
    phase: Phase,
    time: T,
    converge_s: T,
    learn_s: T,
) -> Option<Phase> {
    match phase {
        Phase::Converging if time >= converge_s => Some(Phase::Learning),
        Phase::Learning if time >= converge_s + learn_s => Some(Phase::Monitoring),
        _ => None,
    }
}

/// Consecutive identical in-range samples: a frozen output (SPEC §8a).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FrozenCheck<T> {
    prev: ImuVec<T>,
    count: u16,
}

impl<T: Real> FrozenCheck<T> {
    /// No sample seen.
    pub fn new() -> Self {
        Self {
            prev: ImuVec::zeros(),
            count: 0,
        }
    }

    /// Counts `imu` (when in range); true once `limit` repeats are reached.
    pub fn update(&mut self, imu: &ImuVec<T>, in_range: bool, limit: u16) -> bool {
        if in_range {
            if *imu == self.prev {
                self.count = self.count.saturating_add(1);
            } else {
                self.count = 0;
            }
            self.prev = *imu;
        }
        self.count >= limit
    }

    /// The last in-range sample.
    pub fn last(&self) -> &ImuVec<T> {
        &self.prev
    }
}

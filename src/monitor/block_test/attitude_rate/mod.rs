//! The gyro/attitude-aiding consistency test (issue 15,
//! `UkfMonitorConfig::attitude_rate`).
//!
//! **Why.** The ten-epoch innovation windows see a gyro bias `b` only
//! through the attitude innovations, whose per-epoch SNR is about
//! `b / σ` with σ the aliased vibration of one IMU sample (6–12 °/s on
//! log171): a 2 °/s step needs 5–10 s of evidence, which a 1-s window and
//! a learnt inflation built for it never collect. This test compares the
//! gyro with the attitude aiding directly, over seconds.
//!
//! **Residual.** Between two attitude-aiding epochs the raw gyro is
//! integrated as a quaternion, one exact rotation `exp(ω·dt)` per IMU
//! sample (rates reach 200 °/s in Acro: no small-angle shortcut across an
//! interval), giving the body rotation `ΔR_g`; the aiding gives
//! `ΔR_a = R_a(t₀)ᵀ R_a(t₁)`. The residual `log(ΔR_aᵀ ΔR_g)` (body axes,
//! logarithm by `atan2`, exact in `f32` for small angles), mapped by the
//! inverse right Jacobian of the gyro's rotation, is `b·Δt` to first order
//! in `b` at any rate, plus the aiding's error at `t₁` minus that at `t₀`. Summed
//! over a block or a window the aiding errors telescope (only the ends
//! remain) while a bias adds up, so the window mean is `b` plus the
//! gyro's own noise and `(e(t) − e(t−T))/T`. A constant heading offset of
//! the aiding cancels exactly in `ΔR_a`; a constant aiding lag leaves
//! only end terms, learnt with the variance. The raw gyro is used, not
//! the nominal-bias-corrected one, so that the UKF's drift tracker (gated
//! by the UKF's own test) cannot absorb a slow fault this test sees; the
//! offset is learnt here instead.
//!
//! **Blocks and windows.** Residuals are summed over blocks of `block_s`
//! (`Σ residual / Σ Δt`, rad/s); windows of `lengths` blocks slide by one
//! block and are judged at each block's end. An epoch whose attitude the
//! UKF did not fuse (its gate rejected it) is skipped and the gyro
//! integrated on to the next one; an interval longer than
//! `aiding_timeout_s`, an invalid IMU sample or held statistics drop the
//! interval.
//!
//!
//! The blocks are judged and learnt by the machinery both block tests
//! share (`block_test/`: learnt offset, variance and reddening, Student-t
//! thresholds, motion cover, gated learning, withdrawal), with the mean
//! squared rate as the motion measure. A flag is merged into the UKF's
//! report only on a gyro channel the UKF judges healthy; before this test
//! can judge it changes nothing (the UKF's test still decides, and
//! `NotMonitored` stays so).

use nalgebra::{UnitQuaternion, Vector3};

use heapless::Deque;

use super::rotation::{from_euler, inverse_right_jacobian, rotation_exp, rotation_log};
use super::{BlockTest, ChannelLimits, EpochContext, IntervalTest};
use crate::math::Real;
use crate::model::{ImuVec, Measurement};
use crate::monitor::ukf_monitor::MAX_DELAY_STEPS;
use crate::monitor::{AttitudeRateConfig, UkfMonitorConfig};

#[cfg(test)]
mod tests;

/// The test's state (see the module notes).
#[derive(Debug, Clone)]
pub(in crate::monitor) struct AttitudeRate<T> {
    /// The gyro rotation since the reference epoch, its time and
    /// `Σ |ω|² dt` over it.
    gyro: UnitQuaternion<T>,
    gyro_dt: T,
    gyro_motion: T,
    /// `Σ |ω|² dt` of the intervals in the open block.
    sum_motion: T,
    /// The aiding attitude the interval started from.
    reference: Option<UnitQuaternion<T>>,
    /// Sum of the residuals and of their intervals in the open block.
    sum: Vector3<T>,
    sum_dt: T,
    /// The last raw gyro samples (rate, period, usable), newest last, and
    /// the aiding latency in periods they are integrated at (see
    /// [`sample_delayed`](Self::sample_delayed)).
    past: Deque<(Vector3<T>, T, bool), { MAX_DELAY_STEPS + 1 }>,
    delay: usize,
    /// Blocks, windows, learning and decisions.
    pub(in crate::monitor) test: BlockTest<T>,
}

impl<T: Real> AttitudeRate<T> {
    /// An empty test with per-decision probability `alpha`.
    pub fn new(alpha: f64) -> Self {
        Self {
            gyro: UnitQuaternion::identity(),
            gyro_dt: T::zero(),
            gyro_motion: T::zero(),
            sum_motion: T::zero(),
            reference: None,
            sum: Vector3::zeros(),
            sum_dt: T::zero(),
            past: Deque::new(),
            delay: 0,
            test: BlockTest::new(alpha),
        }
    }

    /// One IMU sample when the aiding arrives `delay` IMU periods late
    /// (the UKF monitor's configured or estimated latency, at most
    /// [`MAX_DELAY_STEPS`]): an attitude epoch describes the body `delay`
    /// periods before it arrives, so the gyro is integrated that many
    /// periods late, and the interval between two epochs spans the same
    /// motion in both. Without it a lag leaves `(ω(t) − ω(t−T)) τ / T` in a
    /// window mean: 8 °/s over 2.5 s for a roll-rate change of 100 °/s at
    /// τ = 0.2 s (log171 with its attitude 0.2 s late: 5 flags of this test
    /// on healthy gyros with the latency estimated, none without the test).
    /// A change of `delay` drops the interval under way.
    pub fn sample_delayed(&mut self, imu: &ImuVec<T>, dt: T, live: bool, delay: usize) {
        let delay = delay.min(MAX_DELAY_STEPS);
        if delay == 0 && self.past.is_empty() {
            return IntervalTest::sample(self, imu, dt, live);
        }
        if delay != self.delay {
            self.delay = delay;
            self.invalidate();
        }
        if self.past.is_full() {
            self.past.pop_front();
        }
        let rate = imu.fixed_rows::<3>(3).into_owned();
        let _ = self.past.push_back((rate, dt, live));
        let then = self
            .past
            .len()
            .checked_sub(1 + delay)
            .and_then(|i| self.past.iter().nth(i))
            .copied();
        match then {
            Some((rate, dt, true)) if live => self.integrate(&rate, dt),
            _ => self.invalidate(),
        }
    }

    /// Starts afresh (learning restarted).
    pub fn reset(&mut self) {
        self.clear_windows();
        self.test.reset();
    }

    /// Forgets the interval, the open block, the block means and the
    /// decisions (a re-alignment): what was learnt is kept.
    pub fn clear_windows(&mut self) {
        self.invalidate();
        self.sum = Vector3::zeros();
        self.sum_dt = T::zero();
        self.sum_motion = T::zero();
        self.test.clear_windows();
    }

    /// Drops the interval under way: the next attitude epoch only sets the
    /// reference.
    pub fn invalidate(&mut self) {
        self.reference = None;
        self.gyro = UnitQuaternion::identity();
        self.gyro_dt = T::zero();
        self.gyro_motion = T::zero();
    }

    /// The test of a monitor configured with `cfg` (idle when it is off).
    pub fn for_config(cfg: &UkfMonitorConfig<T>) -> Self {
        Self::new(cfg.attitude_rate.map_or(0.0, |c| c.alpha()))
    }

    /// One IMU sample's rotation.
    pub fn integrate(&mut self, rate: &Vector3<T>, dt: T) {
        if self.reference.is_some() {
            self.gyro *= rotation_exp(&(rate * dt));
            self.gyro_dt += dt;
            self.gyro_motion += rate.norm_squared() * dt;
        }
    }

    /// An attitude-aiding epoch (ZYX Euler angles of body→NED), closing
    /// the interval; decides and learns when it closes a block. `limits`:
    /// the gyro channels' (largest offset, smallest deviation reported); `max_interval`: longer
    /// intervals are dropped; `external`: a UKF channel is flagged.
    pub fn epoch(
        &mut self,
        cfg: &AttitudeRateConfig<T>,
        euler: [T; 3],
        limits: &ChannelLimits<T>,
        max_interval: T,
        external: bool,
    ) {
        let [r, p, y] = euler;
        let aid = from_euler(r, p, y);
        self.test.mark_external(external);
        let interval = self.gyro_dt;
        if let Some(reference) = self.reference {
            if interval > T::zero() && interval <= max_interval {
                let d_aid = reference.inverse() * aid;
                let res = inverse_right_jacobian(
                    &rotation_log(&self.gyro),
                    &rotation_log(&(d_aid.inverse() * self.gyro)),
                );
                if res.iter().all(|v| v.finite()) {
                    self.sum += res;
                    self.sum_dt += interval;
                    self.sum_motion += self.gyro_motion;
                }
            }
        }
        self.reference = Some(aid);
        self.gyro = UnitQuaternion::identity();
        self.gyro_dt = T::zero();
        self.gyro_motion = T::zero();
        // The block closes at its length, within half an interval (ten
        // 0.1-s intervals sum to a hair under 1 s in floating point).
        if self.sum_dt > T::zero() && self.sum_dt >= cfg.block_s - interval * T::lit(0.5) {
            let mean = self.sum / self.sum_dt;
            let motion = self.sum_motion / self.sum_dt;
            self.sum = Vector3::zeros();
            self.sum_dt = T::zero();
            self.sum_motion = T::zero();
            self.test.close_block(cfg, mean, motion, limits);
        }
    }
}

impl<T: Real> IntervalTest<T> for AttitudeRate<T> {
    type Config = AttitudeRateConfig<T>;

    fn invalidate(&mut self) {
        AttitudeRate::invalidate(self);
    }

    fn integrate_sample(&mut self, imu: &ImuVec<T>, dt: T) {
        self.integrate(&imu.fixed_rows::<3>(3).into_owned(), dt);
    }

    /// An attitude the filter fused closes the interval
    /// ([`epoch`](AttitudeRate::epoch)); one it rejected is skipped (the
    /// gyro integrates on).
    fn close(&mut self, cfg: &Self::Config, aiding: &Measurement<T>, ctx: &EpochContext<T>) {
        if ctx.fused && aiding.available.iter().skip(3).all(|a| *a) {
            let att = aiding.z.fixed_rows::<3>(3);
            self.epoch(
                cfg,
                [att.x, att.y, att.z],
                &ctx.limits,
                ctx.timeout_s,
                ctx.external,
            );
        }
    }
}

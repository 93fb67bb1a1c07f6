//! The attitude aiding's latency in the OTSUKF monitor (issue 15): an
//! online estimate, and the late attitude brought to now.
//!
//! An attitude source (an external AHRS, a flight controller's own
//! estimator) reports each attitude some 0.1–0.3 s after the instant it
//! describes. Fused on arrival, the lag `τ` leaves `τ·ω` in the attitude
//! innovation, which the fault filter takes for a gyro bias in every turn
//! and the learned inflation for aiding noise (log171 with its attitude
//! 0.2 s late: pitch `R` inflated ×11, 1/13/7 fault-free flag events per
//! IMU). The OTSUKF has no state history to fuse against, so, as for the
//! GNSS velocity (`velocity_lag.rs`), the lag is moved to the measurement:
//! a ring keeps each IMU period's change of the Euler angles, and an
//! attitude that describes the vehicle `n` periods ago is brought to now by
//! adding the last `n` of them. The changes are those of the *raw* gyro
//! (the propagated change plus the gyro fault estimate's share): taken
//! with the corrected gyro, the compensation would move with `f̂` itself, a
//! feedback the fault filter does not model (as for the velocity).
//!
//! **Estimate** (`base.estimate_aiding_delay`): the principle of the
//! innovation monitor's (`ukf_monitor/delay.rs`). Levels cannot tell the
//! lags apart (fused at a wrong lag the filter drags its state after the
//! aiding), changes can: the ring holds IMU propagation only, no aiding
//! correction. At each attitude epoch the aiding's change since its
//! previous sample (`age` periods) is compared, for every lag `L`, with the
//! ring's change between `L + age` and `L` periods back. Summed over a
//! block of [`BLOCK_EPOCHS`] epochs, the mismatches telescope: the aiding
//! noise enters at the block's two ends only, a lag error as
//! `δ·(ω(t) − ω(t − block))`, and a constant gyro bias as a constant that
//! the spread ignores. The estimate is the lag whose block mismatches
//! spread least (normalised by the attitude σ) over the last
//! [`TAU_BLOCKS`] blocks, once the configured lag's spread exceeds the
//! least by the latter's own sampling error (measured on log171 on time
//! from 60 s, before the vehicle turns much: without that rule the
//! estimate wandered, learning restarted and monitoring began 20 s late).
//!
//! **Limits.** Lags from 0 to [`MAX_LAG`] IMU periods (0.32 s at 100 Hz,
//! the gyro/attitude block test's delay line), with aiding intervals up to
//! `LAG_RING − MAX_LAG` periods (longer ones are skipped). One latency for
//! the three attitude angles; the GNSS velocity's is `velocity_lag_s`. A
//! vehicle that does not rotate gives every lag the same spread: the
//! estimate is then arbitrary within the range, and harmless, since without
//! rotation the late attitude is the present one. Nothing is learnt while a
//! channel is flagged (a gyro fault changes the attitude's changes as a lag
//! would) nor before [`MIN_BLOCKS`] blocks (the configured
//! `aiding_delay_s` is used until then). While the estimate moves by
//! [`RELEARN_STEPS`] periods or more from the lag learning started at,
//! learning restarts (the nominal bias and the inflation absorbed the old
//! lag's innovations); once monitoring, a moved lag is applied without
//! relearning, as in the innovation monitor.

use nalgebra::Vector3;

use super::velocity_lag::LAG_RING;
use super::OtsukfMonitor;
use crate::math::{wrap_pi, Real};
use crate::model::{Measurement, StateVec, ROLL};
use crate::monitor::input::usable_aiding;
use crate::monitor::ukf_monitor::MAX_DELAY_STEPS;
use crate::monitor::Phase;

/// The longest lag estimated or compensated, IMU periods.
pub(super) const MAX_LAG: usize = MAX_DELAY_STEPS;
const LAGS: usize = MAX_LAG + 1;
/// Aiding epochs summed into one block (2 s at 10 Hz), as the innovation
/// monitor's estimate.
const BLOCK_EPOCHS: u16 = 20;
/// Blocks averaged per lag (60 s at 10 Hz).
const TAU_BLOCKS: f64 = 30.0;
/// Blocks before the estimate is used (6 s at 10 Hz).
const MIN_BLOCKS: f64 = 3.0;
/// A move of the estimate during learning that restarts it (the
/// innovation monitor's `DELAY_RELEARN_STEPS`).
const RELEARN_STEPS: usize = 3;
/// The attitude rows of the measurement.
const ATT: usize = 3;

/// The ring of per-period attitude changes, the lag in use and its
/// estimator.
#[derive(Debug, Clone)]
pub(super) struct AttitudeLag<T> {
    /// Per IMU period, the raw gyro's change of roll, pitch, yaw.
    ring: [Vector3<T>; LAG_RING],
    head: usize,
    filled: usize,
    /// The lag in use, IMU periods.
    pub(super) steps: usize,
    /// The lag learning started at.
    learned: usize,
    /// The configured lag, and whether the estimate has left it.
    configured: usize,
    left: bool,
    /// Per lag, the running mean and mean square of the normalised block
    /// mismatch of each angle, and this block's sum.
    mean: [Vector3<T>; LAGS],
    square: [Vector3<T>; LAGS],
    block: [Vector3<T>; LAGS],
    block_epochs: u16,
    blocks: T,
    /// The previous aiding attitude and IMU periods since it.
    prev: Option<(Vector3<T>, usize)>,
}

impl<T: Real> AttitudeLag<T> {
    /// Empty, compensating `steps` periods until an estimate exists.
    pub(super) fn new(steps: usize) -> Self {
        Self {
            ring: [Vector3::zeros(); LAG_RING],
            head: 0,
            filled: 0,
            steps,
            learned: steps,
            configured: steps,
            left: false,
            mean: [Vector3::zeros(); LAGS],
            square: [Vector3::zeros(); LAGS],
            block: [Vector3::zeros(); LAGS],
            block_epochs: 0,
            blocks: T::zero(),
            prev: None,
        }
    }

    /// One IMU period's attitude change (zero when not propagated).
    pub(super) fn push(&mut self, d: Vector3<T>) {
        if let Some(slot) = self.ring.get_mut(self.head) {
            *slot = d;
        }
        self.head = (self.head + 1) % LAG_RING;
        self.filled = (self.filled + 1).min(LAG_RING);
        if let Some((_, age)) = self.prev.as_mut() {
            *age = age.saturating_add(1);
        }
    }

    /// The change between `from + n` and `from` periods back; `None`
    /// until recorded.
    pub(super) fn over(&self, from: usize, n: usize) -> Option<Vector3<T>> {
        if from + n > self.filled {
            return None;
        }
        let mut sum = Vector3::zeros();
        for k in from + 1..=from + n {
            if let Some(v) = self.ring.get((self.head + LAG_RING - k) % LAG_RING) {
                sum += v;
            }
        }
        Some(sum)
    }

    /// Forgets the ring and the interval under way (alignment: the
    /// attitude jumps).
    pub(super) fn reset(&mut self) {
        self.filled = 0;
        self.prev = None;
        self.interrupt();
    }

    /// Drops the block under way and the previous aiding (a fault
    /// flagged): none of its data reaches the estimate.
    pub(super) fn interrupt(&mut self) {
        self.prev = None;
        self.block = [Vector3::zeros(); LAGS];
        self.block_epochs = 0;
    }

    /// One attitude epoch (`z` roll, pitch, yaw as it arrived; `sigma`
    /// their noise): adds each lag's mismatch to the block, and when the
    /// block closes, updates the estimate.
    pub(super) fn observe(&mut self, z: Vector3<T>, sigma: &Vector3<T>) {
        let Some((z0, age)) = self.prev.replace((z, 0)) else {
            return;
        };
        let dz = (z - z0).map(wrap_pi);
        if age == 0 || self.over(MAX_LAG, age).is_none() {
            return;
        }
        for lag in 0..LAGS {
            if let (Some(d), Some(acc)) = (self.over(lag, age), self.block.get_mut(lag)) {
                *acc += (dz - d).map(wrap_pi);
            }
        }
        self.block_epochs += 1;
        if self.block_epochs < BLOCK_EPOCHS {
            return;
        }
        // The spread of each lag's block mismatches about their mean
        // (a constant gyro bias adds a constant to every block).
        self.blocks += T::one();
        let k = T::one() / self.blocks.min(T::lit(TAU_BLOCKS));
        let mut best: Option<(usize, T)> = None;
        let mut configured = None;
        for (lag, ((acc, m), q)) in self
            .block
            .iter()
            .zip(self.mean.iter_mut())
            .zip(self.square.iter_mut())
            .enumerate()
        {
            let r = acc.component_div(sigma);
            *m += (r - *m) * k;
            *q += (r.component_mul(&r) - *q) * k;
            let spread = (*q - m.component_mul(m)).map(|v| v.max(T::zero())).sum();
            if lag == self.configured {
                configured = Some(spread);
            }
            if spread.finite() && best.is_none_or(|(_, b)| spread < b) {
                best = Some((lag, spread));
            }
        }
        self.block = [Vector3::zeros(); LAGS];
        self.block_epochs = 0;
        if self.blocks < T::lit(MIN_BLOCKS) {
            return;
        }
        let Some((lag, b)) = best else { return };
        // The configured lag is left only once its spread exceeds the
        // best's by that spread's own sampling error (a mean of `n`
        // squared, roughly normal mismatches: relative error `√(2/n)`): a
        // vehicle that hardly rotates gives every lag the same spread, and
        // an arbitrary pick would restart learning. After that, the least
        // spread (no margin between lags, whose spreads share their data).
        let n = self.blocks.min(T::lit(TAU_BLOCKS));
        let evident = configured.is_some_and(|c| c - b > b * (T::lit(2.0) / n).sqrt_fast());
        if self.left || evident {
            self.left = true;
            self.steps = lag;
        }
    }
}

impl<T: Real> OtsukfMonitor<T> {
    /// The attitude aiding's latency in use, s: `base.aiding_delay_s`, or
    /// with `base.estimate_aiding_delay` the current estimate (`None` when
    /// neither is set: fused on arrival).
    pub fn attitude_lag_estimate(&self) -> Option<T> {
        self.att_lag_on()
            .then(|| T::lit(self.att_lag.steps as f64) * self.cfg.base.imu_period)
    }

    /// The attitude latency is compensated or estimated.
    fn att_lag_on(&self) -> bool {
        self.cfg.base.estimate_aiding_delay || self.cfg.base.aiding_delay_s > T::zero()
    }

    /// Alignment: the attitude jumped, the ring restarts.
    pub(super) fn att_lag_reset(&mut self) {
        self.att_lag.reset();
    }

    /// The gyro/attitude block test's delay line, IMU periods.
    pub(super) fn att_lag_steps(&self) -> usize {
        self.att_lag.steps
    }

    /// The state before the prediction, when the latency is on (a 6×6
    /// product: not computed otherwise).
    pub(super) fn att_lag_before(&self) -> Option<StateVec<T>> {
        self.att_lag_on().then(|| self.filter.state())
    }

    /// After a period: its attitude change as the raw gyro gave it, the
    /// propagated change (`before` the state before the prediction) plus
    /// the gyro fault estimate's share `B·f̂·dt`.
    pub(super) fn att_lag_period(&mut self, before: &Option<StateVec<T>>, propagated: bool, dt: T) {
        let Some(before) = before else {
            return;
        };
        let after = self.filter.state();
        let d = match (propagated, self.model.jacobian_input(before)) {
            (true, Ok(b)) => {
                let back = b * self.filter.fault() * dt;
                Vector3::from_fn(|i, _| {
                    let j = ROLL + i;
                    let (Some(a), Some(p), Some(f)) = (after.get(j), before.get(j), back.get(j))
                    else {
                        return T::zero();
                    };
                    wrap_pi(*a - *p) + *f
                })
            }
            _ => Vector3::zeros(),
        };
        self.att_lag.push(d);
    }

    /// An epoch's attitude as it arrived into the estimator (when on); a
    /// moved estimate during learning restarts learning.
    pub(super) fn att_lag_epoch(&mut self, aiding: &Measurement<T>) {
        if !self.cfg.base.estimate_aiding_delay {
            return;
        }
        if self.phase == Phase::Monitoring && self.latched.iter().any(|l| *l != 0) {
            self.att_lag.interrupt();
            return;
        }
        let avail = usable_aiding(aiding);
        if avail.iter().skip(ATT).take(3).all(|a| *a) {
            let z = aiding.z.fixed_rows::<3>(ATT).into_owned();
            let s = self.cfg.base.meas_sigma.fixed_rows::<3>(ATT).into_owned();
            self.att_lag.observe(z, &s);
        }
        let lag = self.att_lag.steps;
        match self.phase {
            Phase::Converging | Phase::Aligning => self.att_lag.learned = lag,
            Phase::Learning if lag.abs_diff(self.att_lag.learned) >= RELEARN_STEPS => {
                // Through `advance_phase`: learning starts afresh.
                self.att_lag.learned = lag;
                self.phase = Phase::Converging;
                self.phase_time = self.cfg.base.converge_s;
            }
            _ => {}
        }
    }

    /// An attitude that describes the vehicle `steps` periods ago brought
    /// to now by the raw gyro's change since; not fused until that change
    /// is known.
    pub(super) fn bring_attitude_forward(&self, aiding: &Measurement<T>) -> Measurement<T> {
        let mut a = *aiding;
        let n = self.att_lag.steps;
        if !self.att_lag_on() || n == 0 {
            return a;
        }
        match self.att_lag.over(0, n) {
            Some(d) => {
                for (z, c) in a.z.iter_mut().skip(ATT).zip(d.iter()) {
                    *z = wrap_pi(*z + *c);
                }
            }
            None => {
                for v in a.available.iter_mut().skip(ATT) {
                    *v = false;
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests;

//! Online estimate of the aiding latency (issue 15): the lag, within the
//! state history that delayed fusion already keeps, at which the
//! IMU-propagated changes of the predicted attitude best match the attitude
//! aiding's own changes.
//!
//! Levels cannot tell the lags apart: the filter, fusing at a wrong lag,
//! drags its state after the late aiding until the history at that lag
//! fits it (measured: the mismatch is least at whatever lag is in use).
//! Changes can, because the history is IMU propagation alone between any
//! two of its states (every correction shifts the whole history, see
//! `shift_history`). At each aiding epoch, for every lag `L` and attitude
//! channel, the aiding's change since its previous sample is compared with
//! the change of `h(x̂)` between the history's states `L` and `L + age`
//! periods back. Over one aiding interval a lag error `δ` shows only
//! through the vehicle's angular *acceleration* (`δ·T·α`), below the
//! aiding noise; summed over a block of [`DELAY_BLOCK_EPOCHS`] epochs the
//! per-interval mismatches telescope into the change over the whole block
//! (`δ·(ω(t) − ω(t − block))`, first order in the motion) while the aiding
//! noise enters only at the block's two ends (σ√2). The estimate is the lag
//! whose block mismatches spread least (normalised by the aiding σ) over
//! the last [`DELAY_TAU_BLOCKS`] blocks. Velocity is not compared: its
//! IMU-propagated change carries the filter's attitude error times g
//! (1° is 0.34 m/s over a 2 s block), an error shaped by the lag in use,
//! which pulled the estimate towards that lag. The estimate is the
//! attitude's latency, the fusion horizon; a velocity with a latency of
//! its own is given as `UkfMonitorConfig::velocity_delay_s` and brought to
//! that horizon (`velocity_delay.rs`), else it shares it. PX4 EKF2 takes
//! such latencies as parameters (`EKF2_GPS_DELAY`, …) and fuses against a
//! delayed horizon; here the same history serves to estimate them.
//!
//! Limits: lags up to the history length minus the attitude aiding's
//! interval ([`MAX_DELAY_STEPS`] − 10 = 0.22 s with 10 Hz attitude and a
//! 100 Hz IMU). The estimator sees nothing while a fault is flagged (a
//! gyro ramp changes the attitude's changes as a lag would). A vehicle
//! that does not rotate gives every lag the same spread: the estimate is
//! then arbitrary within the range, and harmless, since without rotation
//! the lag changes little.

use nalgebra::Vector3;

use super::{UkfMonitor, DELAY_RELEARN_STEPS, MAX_DELAY_STEPS};
use crate::math::{wrap_pi, Real};
use crate::model::{ImuVec, MeasVec, Measurement, MeasurementModel, StateVec, VehicleModel, NZ};
use crate::monitor::ChannelState;

/// Aiding epochs summed into one block (2 s at 10 Hz): long enough for
/// the vehicle's rates to change, short against IMU error growth.
const DELAY_BLOCK_EPOCHS: u16 = 20;
/// Blocks averaged per lag (60 s at 10 Hz).
const DELAY_TAU_BLOCKS: f64 = 30.0;
/// Blocks before the estimate is used (6 s at 10 Hz).
const DELAY_MIN_BLOCKS: f64 = 3.0;

const LAGS: usize = MAX_DELAY_STEPS + 1;
/// The aiding channels compared: roll, pitch, yaw.
const ATTITUDE: core::ops::Range<usize> = 3..NZ;

/// Per-lag mean normalised squared block mismatch.
#[derive(Debug, Clone)]
pub(super) struct DelayEstimator<T> {
    /// Per lag, the mean block spread over the attitude channels (below).
    cost: [T; LAGS],
    /// Per lag and attitude channel, the running mean and mean square of
    /// the normalised block mismatch.
    mean: [[T; 3]; LAGS],
    square: [[T; 3]; LAGS],
    /// Per lag and attitude channel, the mismatch summed over this block.
    block: [[T; 3]; LAGS],
    /// Epochs in this block.
    block_epochs: u16,
    /// Lags evaluated at every epoch of every block averaged.
    valid: usize,
    /// Lags evaluated at every epoch of this block.
    block_valid: usize,
    blocks: T,
    /// Each aiding channel's previous value and IMU periods since it.
    prev: [Option<(T, usize)>; NZ],
}

impl<T: Real> DelayEstimator<T> {
    pub(super) fn new() -> Self {
        Self {
            cost: [T::zero(); LAGS],
            mean: [[T::zero(); 3]; LAGS],
            square: [[T::zero(); 3]; LAGS],
            block: [[T::zero(); 3]; LAGS],
            block_epochs: 0,
            valid: LAGS,
            block_valid: LAGS,
            blocks: T::zero(),
            prev: [None; NZ],
        }
    }

    /// One IMU period passed (one state written to the history).
    pub(super) fn tick(&mut self) {
        for (_, age) in self.prev.iter_mut().flatten() {
            *age = age.saturating_add(1);
        }
    }

    /// Drops the block under way and the previous aiding values (a fault
    /// flagged): none of its data reaches the estimate.
    pub(super) fn interrupt(&mut self) {
        self.prev = [None; NZ];
        self.block = [[T::zero(); 3]; LAGS];
        self.block_epochs = 0;
        self.block_valid = LAGS;
    }

    /// One aiding epoch: `history` newest first (lag 0 = the current
    /// prior); `bias` the nominal bias the history was propagated with.
    #[inline(never)] // the predictions' array stays off `update`'s frame
    #[allow(clippy::too_many_arguments)] // one call site, all borrowed
    pub(super) fn observe<'a>(
        &mut self,
        history: impl Iterator<Item = &'a StateVec<T>>,
        meas: &MeasurementModel<T>,
        model: &VehicleModel<T>,
        bias: &ImuVec<T>,
        period: T,
        aiding: &Measurement<T>,
        available: &[bool; NZ],
        sigma: &MeasVec<T>,
        omega: &Vector3<T>,
    ) where
        T: 'a,
    {
        // The gyros' nominal bias is put back into the propagated changes
        // (as the attitude rate it gave at each lag's state): the learner
        // and the drift tracker take a lag error's motion-correlated
        // mismatch partly into that bias, which then leans every lag's
        // block mismatches towards the lag in use (measured on the AUV
        // with 0.2 s late aiding: the estimate 0.13–0.16 s after 20 s,
        // rising to 0.20 s over 5 min; 0.19–0.21 s at 10 s with the gyro
        // bias not learnt). A constant true bias adds `b·T` to every block,
        // which the spread ignores.
        let mut pred = [MeasVec::<T>::zeros(); LAGS];
        // Per lag, the attitude change per IMU period the bias gave there.
        let mut rates = [StateVec::<T>::zeros(); LAGS];
        let mut len = 0;
        for ((p, r), x) in pred.iter_mut().zip(rates.iter_mut()).zip(history) {
            *p = meas.predict(x, omega);
            if let Ok(b) = model.jacobian_input(x) {
                *r = b * bias * period;
            }
            len += 1;
        }
        // Per channel: the aiding's change and the age of its baseline.
        let mut changes: [Option<(T, usize)>; NZ] = [None; NZ];
        // The attitude channels only (see the module documentation).
        for i in ATTITUDE {
            let (Some(a), Some(z), Some(prev), Some(c)) = (
                available.get(i),
                aiding.z.get(i),
                self.prev.get_mut(i),
                changes.get_mut(i),
            ) else {
                continue;
            };
            if !*a {
                continue;
            }
            if let Some((z0, age)) = *prev {
                let d = *z - z0;
                *c = Some((if i >= 3 { wrap_pi(d) } else { d }, age));
            }
            *prev = Some((*z, 0));
        }
        // Only a full history compares the same lags at every epoch.
        if len < LAGS || changes.iter().all(|c| c.is_none()) {
            return;
        }
        let mut evaluated = 0;
        for (lag, acc) in self.block.iter_mut().enumerate() {
            let mut add = [T::zero(); NZ];
            let mut complete = true;
            for ((i, ch), a) in changes.iter().enumerate().zip(add.iter_mut()) {
                let Some((dz, age)) = ch else { continue };
                let (Some(now), Some(then)) = (pred.get(lag), pred.get(lag + age)) else {
                    complete = false;
                    break;
                };
                let (Some(p), Some(q)) = (now.get(i), then.get(i)) else {
                    complete = false;
                    break;
                };
                let (Some(rp), Some(rq)) = (rates.get(lag), rates.get(lag + age)) else {
                    complete = false;
                    break;
                };
                let (Some(rp), Some(rq)) = (rp.get(i), rq.get(i)) else {
                    complete = false;
                    break;
                };
                // Trapezoid over the interval's two ends.
                let back = (*rp + *rq) * T::lit(0.5) * T::lit(*age as f64);
                let dh = if i >= 3 { wrap_pi(*p - *q) } else { *p - *q };
                *a = *dz - dh - back;
            }
            if !complete || !add.iter().all(|v| v.finite()) {
                break;
            }
            for (s, a) in acc.iter_mut().zip(add.iter().skip(ATTITUDE.start)) {
                *s += *a;
            }
            evaluated = lag + 1;
        }
        self.block_valid = self.block_valid.min(evaluated);
        self.block_epochs += 1;
        if self.block_epochs >= DELAY_BLOCK_EPOCHS {
            self.close_block(sigma);
        }
    }

    /// Adds the block to each lag's running moments; the lag's cost is the
    /// spread of its block mismatches about their mean (normalised: the
    /// aiding noise of a telescoped sum is that of its two ends, `σ√2`).
    /// The spread, not the mean square: a constant offset — a gyro bias
    /// learnt while fusing at the wrong lag adds `b·T` to every block — would
    /// otherwise pull the estimate through its cross-term with the
    /// vehicle's slow rate changes (measured: towards the lag in use).
    fn close_block(&mut self, sigma: &MeasVec<T>) {
        let valid = self.block_valid;
        if valid > 0 {
            self.blocks += T::one();
            let k = T::one() / self.blocks.min(T::lit(DELAY_TAU_BLOCKS));
            let norm = T::lit(2.0 * ATTITUDE.len() as f64);
            for (((c, acc), m), q) in self
                .cost
                .iter_mut()
                .zip(self.block.iter())
                .zip(self.mean.iter_mut())
                .zip(self.square.iter_mut())
                .take(valid)
            {
                let mut spread = T::zero();
                for (((a, sg), m), q) in acc
                    .iter()
                    .zip(sigma.iter().skip(ATTITUDE.start))
                    .zip(m.iter_mut())
                    .zip(q.iter_mut())
                {
                    let r = *a / *sg;
                    *m += (r - *m) * k;
                    *q += (r * r - *q) * k;
                    spread += (*q - *m * *m).max(T::zero());
                }
                *c = spread / norm;
            }
            self.valid = self.valid.min(valid);
        }
        self.block = [[T::zero(); 3]; LAGS];
        self.block_epochs = 0;
        self.block_valid = LAGS;
    }

    /// The lag to fuse at: the lag of least block spread (`None` before
    /// enough blocks). No margin is kept around the lag in use: the
    /// lags' means share their data, so neighbours differ by far less than
    /// either's sampling noise and any margin would be a hand-set one.
    pub(super) fn best(&self) -> Option<usize> {
        if self.blocks < T::lit(DELAY_MIN_BLOCKS) {
            return None;
        }
        let mut best: Option<(usize, T)> = None;
        for (lag, c) in self.cost.iter().enumerate().take(self.valid) {
            if best.is_none_or(|(_, b)| *c < b) {
                best = Some((lag, *c));
            }
        }
        best.map(|(lag, _)| lag)
    }
}

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// Feeds the aiding-delay estimator and applies its estimate. While a
    /// fault is flagged the estimator sees nothing (a gyro ramp changes the
    /// attitude's changes like a lag would) and the lag in use is kept.
    #[inline(never)] // own stack frame and one copy (issue 17)
    pub(super) fn estimate_delay(
        &mut self,
        aiding: &Measurement<T>,
        available: &[bool; NZ],
        omega: &Vector3<T>,
    ) {
        let flagged = self
            .report
            .status
            .iter()
            .any(|s| matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative));
        if flagged {
            self.delay_estimator.interrupt();
            return;
        }
        self.delay_estimator.observe(
            self.history.oldest_ordered().rev(),
            &self.meas,
            &self.model,
            &self.nominal_bias,
            self.cfg.imu_period,
            aiding,
            available,
            &self.cfg.meas_sigma,
            omega,
        );
        if let Some(lag) = self.delay_estimator.best() {
            self.delay_steps = lag;
            if lag.abs_diff(self.learned_lag) >= DELAY_RELEARN_STEPS {
                self.relearn_at(lag);
            }
        }
    }

    /// The aiding-delay estimate moved to `lag` during learning: what was
    /// learnt at the old lag (the nominal bias, the inflation) absorbed that
    /// lag's innovations and, frozen once monitoring starts, would flag
    /// for good (measured: a bias learnt at 0.12 s for a 0.2 s latency
    /// flagged a_y for the rest of a fault-free hour). Learning restarts,
    /// so monitoring begins only after `learn_s` at a steady lag. Once
    /// monitoring, a moved lag is applied without relearning: a restart
    /// then would absorb whatever fault is present into the nominal bias
    /// (measured: post-clear false alarms on the aircraft episodes).
    fn relearn_at(&mut self, lag: usize) {
        self.learned_lag = lag;
        self.restart_learning();
    }
}

//! The GNSS velocity's latency in the OTSUKF monitor (issue 15), causally.
//!
//! A receiver reports a velocity some 0.1–0.3 s after the instant it
//! describes. Fused on arrival against the current state, the lag `τ`
//! leaves `τ·a` in the velocity innovation, which the fault filter takes
//! for an accelerometer bias in every turn: on log171 (flight profile) the
//! fault-free accelerometer flags fall from 10/11/10 events per IMU to 1/1/1
//! when the GNSS velocity is shifted by the fitted lag. The OTSUKF has no
//! state history to fuse against (the innovation monitor's delayed
//! fusion), so the lag is moved to the measurement instead: each IMU period
//! the filter's IMU propagation changes the predicted NED velocity by
//! `Δv_k`, and a GNSS velocity that describes the vehicle `n` periods ago is
//! brought to now by adding the last `n` of them, `z + Σ Δv`. Only the IMU
//! propagation enters (no aiding correction), so the term is the corrected
//! specific force integrated over the lag, as PX4 EKF2's output predictor
//! carries its delayed horizon forward.

use nalgebra::Vector3;

use super::OtsukfMonitor;
use crate::math::Real;
use crate::model::Measurement;

/// IMU periods kept: the longest lag (0.64 s at 100 Hz, 1.28 s at 50 Hz).
pub(super) const LAG_RING: usize = 64;

/// The last [`LAG_RING`] per-period changes of the predicted NED velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct VelocityLag<T> {
    ring: [Vector3<T>; LAG_RING],
    /// Next slot written.
    head: usize,
    /// Periods recorded since the last reset (saturating at the ring).
    filled: usize,
}

impl<T: Real> VelocityLag<T> {
    /// Empty.
    pub(super) fn new() -> Self {
        Self {
            ring: [Vector3::zeros(); LAG_RING],
            head: 0,
            filled: 0,
        }
    }

    /// One IMU period's change of the predicted NED velocity (zero when
    /// the filter did not propagate).
    pub(super) fn push(&mut self, dv: Vector3<T>) {
        if let Some(slot) = self.ring.get_mut(self.head) {
            *slot = dv;
        }
        self.head = (self.head + 1) % LAG_RING;
        self.filled = (self.filled + 1).min(LAG_RING);
    }

    /// The velocity change over the last `n` periods; `None` until that
    /// many have been recorded (then the velocity is not fused: fused
    /// uncompensated it would carry `τ·a` into the fault estimate).
    pub(super) fn over(&self, n: usize) -> Option<Vector3<T>> {
        if n > self.filled {
            return None;
        }
        let mut sum = Vector3::zeros();
        for k in 1..=n {
            let i = (self.head + LAG_RING - k) % LAG_RING;
            if let Some(v) = self.ring.get(i) {
                sum += v;
            }
        }
        Some(sum)
    }

    /// Forgets the history (alignment: the velocity jumps).
    pub(super) fn reset(&mut self) {
        self.filled = 0;
    }
}

/// The monitor's side: the per-period changes and the late velocity
/// brought to now.
impl<T: Real> OtsukfMonitor<T> {
    /// The velocity rows of `h(x̂)` (NED for GNSS, body for a DVL), when
    /// the velocity aiding's latency is compensated.
    pub(super) fn predicted_velocity(&self, omega: &Vector3<T>) -> Option<Vector3<T>> {
        if self.lag_steps == 0 {
            return None;
        }
        let z = self.meas.predict(&self.filter.state(), omega);
        Some(z.fixed_rows::<3>(0).into_owned())
    }

    /// The accelerometer fault estimate as a rate of the measured velocity
    /// (rotated to NED for GNSS): added back to each period's propagated
    /// change, so the change is that of the raw specific force. Taken with
    /// the corrected one, the compensation would move with `f̂` itself, a
    /// feedback the fault filter does not model: on S3 with the GNSS 0.2 s
    /// late, compensating 0.3 s made the fault estimates diverge.
    pub(super) fn fault_velocity_rate(&self) -> Vector3<T> {
        let mut x = self.filter.state();
        let f = self.filter.fault();
        for (v, fa) in x.iter_mut().zip(f.iter()).take(3) {
            *v = *fa;
        }
        let z = self.meas.predict(&x, &Vector3::zeros());
        z.fixed_rows::<3>(0).into_owned()
    }

    /// A velocity that describes the vehicle `lag_steps` periods ago,
    /// brought to now by the IMU-propagated change since
    /// (`velocity_lag.rs`); not fused until that change is known.
    pub(super) fn bring_velocity_forward(&self, aiding: &Measurement<T>) -> Measurement<T> {
        let mut a = *aiding;
        if self.lag_steps == 0 || !a.available.iter().take(3).any(|v| *v) {
            return a;
        }
        match self.vel_lag.over(self.lag_steps) {
            Some(dv) => {
                for (z, d) in a.z.iter_mut().zip(dv.iter()) {
                    *z += *d;
                }
            }
            None => {
                for v in a.available.iter_mut().take(3) {
                    *v = false;
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // test code
    use super::*;

    #[test]
    fn the_change_over_the_lag_is_the_sum_of_the_last_periods() {
        let mut lag = VelocityLag::<f64>::new();
        assert_eq!(lag.over(0), Some(Vector3::zeros()));
        // Around the ring more than once: 1, 2, …, 100 m/s per period on x.
        for k in 1..=100 {
            lag.push(Vector3::new(f64::from(k), 0.0, -1.0));
            assert_eq!(lag.over(k as usize + 1), None);
        }
        assert_eq!(lag.over(3).unwrap(), Vector3::new(297.0, 0.0, -3.0));
        let all: f64 = (37..=100).map(f64::from).sum();
        assert_eq!(lag.over(LAG_RING).unwrap().x, all);
        assert_eq!(lag.over(LAG_RING + 1), None);
        lag.reset();
        assert_eq!(lag.over(1), None);
        lag.push(Vector3::new(0.5, 0.0, 0.0));
        assert_eq!(lag.over(1).unwrap().x, 0.5);
    }
}

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

use crate::math::Real;

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

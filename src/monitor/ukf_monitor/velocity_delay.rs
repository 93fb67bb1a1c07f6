//! The velocity aiding's own latency (issue 15,
//! `UkfMonitorConfig::velocity_delay_s`): real aiding arrives with one
//! latency per source (PX4 EKF2: `EKF2_GPS_DELAY`, `EKF2_EV_DELAY`, …); on
//! log171 the GNSS velocity is ≈ 0.22–0.24 s late while the autopilot's
//! attitude is on time.
//!
//! The update is centred at one horizon, the attitude's (`aiding_delay_s`
//! or its online estimate). A velocity measured `d` IMU periods back is
//! brought to that horizon with the velocity change the state history holds
//! between the two: `z_v' = z_v + h_v(x[horizon]) − h_v(x[d])`. The history
//! is IMU propagation alone between any two of its states (every correction
//! shifts all of it, `shift_history`), so the added term is the IMU's own
//! change and the innovation `z_v' − h_v(x[horizon]) = z_v − h_v(x[d])` is
//! that of the velocity at its own time, whichever of the two lags is the
//! longer. This is how the OTSUKF's `velocity_lag.rs` brings a late
//! velocity to now.
//!
//! Limits: `d` up to the history's [`MAX_DELAY_STEPS`](super::MAX_DELAY_STEPS)
//! IMU periods (a longer one is refused by `validate`); until the history
//! holds `d` states written since the last (re-)alignment the velocity is
//! fused at the horizon untranslated; the lag is configured,
//! not estimated (the CLI fits it offline on the learning span).

use super::UkfMonitor;
use crate::math::Real;
use crate::model::{Measurement, StateVec};
use nalgebra::Vector3;

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The history's state `lag` IMU periods back (0: the current prior).
    pub(super) fn history_at(&self, lag: usize) -> Option<StateVec<T>> {
        self.history.oldest_ordered().rev().nth(lag).copied()
    }

    /// The IMU periods the velocity aiding is fused against: its own
    /// latency when configured, else the shared horizon.
    pub(super) fn velocity_lag_steps(&self) -> usize {
        self.velocity_delay_steps.unwrap_or(self.delay_steps)
    }

    /// `aiding` with its velocity brought from its own time to the fusion
    /// horizon `center` (module notes); `None` when nothing is to be
    /// translated (no own velocity latency, no complete velocity triad, or
    /// the history does not reach back that far yet).
    #[inline(never)] // the two predictions stay off `update`'s frame (issue 17)
    pub(super) fn velocity_at_horizon(
        &self,
        aiding: &Measurement<T>,
        center: &StateVec<T>,
        omega: &Vector3<T>,
    ) -> Option<Measurement<T>> {
        let lag = self.velocity_delay_steps?;
        // A state from before the last (re-)alignment is of another
        // trajectory: the change to it would carry the re-alignment's jump
        // (log171, attitude cut 120–150 s: 5 events on IMU1 after it).
        if lag == self.delay_steps
            || lag >= self.history_fresh
            || !aiding.available.iter().take(3).all(|a| *a)
        {
            return None;
        }
        let own = self.history_at(lag)?;
        let change = self.meas.predict(center, omega) - self.meas.predict(&own, omega);
        let mut out = *aiding;
        for (z, c) in out.z.iter_mut().zip(change.iter()).take(3) {
            *z += *c;
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{AidingKind, MeasVec, NZ};
    use crate::monitor::{ConfigError, UkfMonitorConfig, MAX_DELAY_STEPS};

    /// Body velocity under a constant body acceleration at a fixed
    /// attitude, `t` seconds from 0.
    fn state(t: f64) -> StateVec<f64> {
        StateVec::new(10.0 + 1.5 * t, -2.0 - 0.5 * t, 0.25 * t, 0.1, -0.05, 1.2)
    }

    #[test]
    fn a_late_velocity_is_brought_to_the_horizon_in_closed_form() {
        let dt = 0.02;
        for (kind, horizon, own) in [
            (AidingKind::GnssAttitude, 5usize, 12usize),
            (AidingKind::GnssAttitude, 12, 5),
            (AidingKind::DvlCompass, 0, 20),
        ] {
            let mut cfg = UkfMonitorConfig::<f64>::aircraft();
            cfg.aiding = kind;
            cfg.imu_period = dt;
            cfg.aiding_delay_s = horizon as f64 * dt;
            cfg.velocity_delay_s = Some(own as f64 * dt);
            let mut m = UkfMonitor::<f64, 10>::new(cfg).unwrap();
            m.history_fresh = MAX_DELAY_STEPS + 1;
            // The history's newest state is the one at t = 1 s.
            let n = MAX_DELAY_STEPS + 1;
            for k in 0..n {
                m.history.write(state(1.0 - (n - 1 - k) as f64 * dt));
            }
            let omega = Vector3::zeros();
            let truth = |lag: usize| m.meas.predict(&state(1.0 - lag as f64 * dt), &omega);
            // The velocity of its own time, the attitude of the horizon's.
            let mut z = truth(horizon);
            z.fixed_rows_mut::<3>(0)
                .copy_from(&truth(own).fixed_rows::<3>(0));
            let aiding = Measurement {
                z,
                available: [true; NZ],
            };
            let center = m.history_at(horizon).unwrap();
            let out = m.velocity_at_horizon(&aiding, &center, &omega).unwrap();
            let err: MeasVec<f64> = out.z - truth(horizon);
            assert!(err.amax() < 1e-12, "{kind:?} {horizon}/{own}: {err:?}");
            // Nor across a re-alignment (states older than it).
            m.history_fresh = own;
            assert!(m.velocity_at_horizon(&aiding, &center, &omega).is_none());
            // Without its own latency nothing is translated.
            m.history_fresh = MAX_DELAY_STEPS + 1;
            m.velocity_delay_steps = None;
            assert!(m.velocity_at_horizon(&aiding, &center, &omega).is_none());
        }
    }

    #[test]
    fn a_velocity_latency_beyond_the_history_is_refused() {
        let mut cfg = UkfMonitorConfig::<f64>::aircraft();
        cfg.velocity_delay_s = Some((MAX_DELAY_STEPS + 1) as f64 * cfg.imu_period);
        assert_eq!(cfg.validate(), Err(ConfigError::VelocityDelay));
        cfg.velocity_delay_s = Some(-0.01);
        assert_eq!(cfg.validate(), Err(ConfigError::VelocityDelay));
        cfg.velocity_delay_s = Some(MAX_DELAY_STEPS as f64 * cfg.imu_period);
        assert_eq!(cfg.validate(), Ok(()));
        assert_eq!(ConfigError::VelocityDelay.field(), "velocity_delay_s");
    }
}

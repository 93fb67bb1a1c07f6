//! What today's autopilots do with redundant IMUs, as baselines: coarse
//! consistency thresholds between IMUs.
//!
//! - **PX4-like**: `sensors` low-passes each IMU's deviation from the mean
//!   of all IMUs, `d ← 0.95 d + 0.05 (x_i − x̄)` per sample
//!   (`VotedSensorsUpdate::calcGyroInconsistency`), and the EKF2 selector
//!   accumulates `(|d| − EKF2_SEL_IMU_RAT) · dt`, floored at 0, and declares
//!   the IMU with the largest sum faulty once it passes
//!   `EKF2_SEL_IMU_ANGLE` (`EKF2Selector::UpdateErrorScores`). Defaults:
//!   7 °/s and 15° for gyros; `EKF2_SEL_IMU_ACC` 1 m/s² and
//!   `EKF2_SEL_IMU_VELO` 2 m/s for accelerometers.
//! - **ArduPilot-like**: `AP_InertialSensor::gyros_consistent` compares
//!   every IMU with the first one against 5 °/s
//!   (`AP_ARMING_GYRO_ERROR_THRESHOLD`; accelerometers 0.75 m/s²,
//!   `AP_ARMING_ACCEL_ERROR_THRESHOLD`), and the arming check fails once the
//!   set has been inconsistent for 10 s.
//!
//! For single-axis arrays (the cone) a "unit" is one sensor and its
//! deviation is its least-squares residual (PX4-like) or its difference
//! from the prediction of the other sensors (ArduPilot-like).

use core::f64::consts::PI;

/// PX4's `EKF2_SEL_IMU_RAT` default, rad/s.
pub const PX4_GYRO_RATE_THRESHOLD: f64 = 7.0 * PI / 180.0;
/// PX4's `EKF2_SEL_IMU_ANGLE` default, rad.
pub const PX4_GYRO_ANGLE_THRESHOLD: f64 = 15.0 * PI / 180.0;
/// PX4's `EKF2_SEL_IMU_ACC` default, m/s².
pub const PX4_ACCEL_THRESHOLD: f64 = 1.0;
/// PX4's `EKF2_SEL_IMU_VELO` default, m/s.
pub const PX4_VELOCITY_THRESHOLD: f64 = 2.0;
/// ArduPilot's `AP_ARMING_GYRO_ERROR_THRESHOLD`, rad/s.
pub const AP_GYRO_THRESHOLD: f64 = 5.0 * PI / 180.0;
/// ArduPilot's `AP_ARMING_ACCEL_ERROR_THRESHOLD`, m/s².
pub const AP_ACCEL_THRESHOLD: f64 = 0.75;
/// ArduPilot's consistency persistence, s.
pub const AP_PERSISTENCE_S: f64 = 10.0;

/// PX4-like accumulated-inconsistency check over `U` units.
#[derive(Debug, Clone, PartialEq)]
pub struct Px4Like<const U: usize> {
    threshold: f64,
    accumulated_limit: f64,
    diff: [[f64; 3]; U],
    accumulated: [f64; U],
}

impl<const U: usize> Px4Like<U> {
    /// With PX4's gyro (`gyro = true`) or accelerometer defaults.
    pub fn new(gyro: bool) -> Self {
        let (threshold, accumulated_limit) = if gyro {
            (PX4_GYRO_RATE_THRESHOLD, PX4_GYRO_ANGLE_THRESHOLD)
        } else {
            (PX4_ACCEL_THRESHOLD, PX4_VELOCITY_THRESHOLD)
        };
        Self {
            threshold,
            accumulated_limit,
            diff: [[0.0; 3]; U],
            accumulated: [0.0; U],
        }
    }

    /// One sample of each unit's deviation from the mean; returns the unit
    /// declared faulty, if any.
    pub fn step(&mut self, deviation: &[[f64; 3]; U], dt: f64) -> Option<usize> {
        let dt = dt.clamp(0.0, 0.02);
        let mut worst = None;
        let mut largest = 0.0;
        let mut exceeded = false;
        for ((d, dev), acc) in self
            .diff
            .iter_mut()
            .zip(deviation.iter())
            .zip(self.accumulated.iter_mut())
        {
            for (x, y) in d.iter_mut().zip(dev.iter()) {
                *x = 0.95 * *x + 0.05 * y;
            }
            let norm = libm::sqrt(d.iter().map(|x| x * x).sum());
            *acc = (*acc + (norm - self.threshold) * dt).max(0.0);
            exceeded |= *acc > self.accumulated_limit;
        }
        for (i, acc) in self.accumulated.iter().enumerate() {
            if *acc > largest {
                largest = *acc;
                worst = Some(i);
            }
        }
        if exceeded {
            worst
        } else {
            None
        }
    }
}

/// ArduPilot-like consistency check with 10 s persistence.
#[derive(Debug, Clone, PartialEq)]
pub struct ArduPilotLike {
    threshold: f64,
    last_consistent: Option<f64>,
}

impl ArduPilotLike {
    /// With ArduPilot's gyro (`gyro = true`) or accelerometer threshold.
    pub fn new(gyro: bool) -> Self {
        Self {
            threshold: if gyro {
                AP_GYRO_THRESHOLD
            } else {
                AP_ACCEL_THRESHOLD
            },
            last_consistent: None,
        }
    }

    /// One sample of each unit's difference from the primary (unit 0's
    /// entry is ignored) at time `t`; true when inconsistent for 10 s.
    pub fn step(&mut self, difference: &[[f64; 3]], t: f64) -> bool {
        let consistent = difference
            .iter()
            .skip(1)
            .all(|d| libm::sqrt(d.iter().map(|x| x * x).sum()) <= self.threshold);
        if consistent || self.last_consistent.is_none() {
            self.last_consistent = Some(t);
        }
        self.last_consistent
            .is_some_and(|t0| t - t0 > AP_PERSISTENCE_S)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px4_needs_about_ten_degrees_per_second_on_one_of_three() {
        // Deviation from the mean of three is 2/3 of the bias.
        let run = |bias: f64| {
            let mut px4 = Px4Like::<3>::new(true);
            let dev = [
                [2.0 * bias / 3.0, 0.0, 0.0],
                [-bias / 3.0, 0.0, 0.0],
                [-bias / 3.0, 0.0, 0.0],
            ];
            (0..6000).find_map(|k| px4.step(&dev, 0.01).map(|u| (u, k)))
        };
        assert_eq!(run(10.0 * PI / 180.0), None);
        let (unit, k) = run(12.0 * PI / 180.0).unwrap();
        assert_eq!(unit, 0);
        assert!(k > 400, "{k}");
    }

    #[test]
    fn ardupilot_waits_ten_seconds() {
        let mut ap = ArduPilotLike::new(true);
        let diff = [[0.0; 3], [6.0 * PI / 180.0, 0.0, 0.0]];
        let first = (0..2000).find(|k| ap.step(&diff, *k as f64 * 0.01));
        assert_eq!(first, Some(1001));
    }
}

//! Configuration of the redundant-sensor monitor: which tests decide, and
//! the defaults for simulated arrays (white noise) and real flights.

use crate::math::Real;

use super::health::HealthConfig;
use super::multiscale::MultiscaleConfig;

/// Which test's alarm drives isolation and reconfiguration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParityDetector {
    /// \[PAR\]: the window-mean 2-D PCA pattern, normalised by its training
    /// variance.
    Pca,
    /// Windowed χ² of the full parity vector (generalised likelihood test).
    Glt,
    /// Two-sided CUSUM per sensor direction (sequential; small biases).
    Cusum,
    /// Alarm when either the GLT or the CUSUM alarms.
    GltOrCusum,
    /// Real flights: in-flight relative calibration, Huber-clipped blocks
    /// and GLR tests on window means at several lengths with covariances
    /// learned from the data ([`MultiscaleConfig`]).
    Multiscale,
}

/// Configuration of a [`ParityMonitor`](super::ParityMonitor).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParityConfig<T> {
    /// Hardware checks.
    pub health: HealthConfig<T>,
    /// Samples averaged into one block; one decision per block.
    pub block_len: u16,
    /// Blocks in the GLT/PCA window (at most the monitor's `W`).
    pub window_blocks: usize,
    /// Training samples (fault-free; motion helps the leakage fit).
    pub train_samples: u32,
    /// Calibration samples after training (fault-free): the tests run with
    /// their χ²/ARL thresholds and each threshold is raised to 1.25× the
    /// largest statistic seen, when that is higher. Real sensors are not
    /// Gaussian and white (vibration bursts, filter differences); this
    /// keeps the thresholds honest on them. 0 disables.
    pub calibrate_samples: u32,
    /// False-alarm probability per decision of the GLT and PCA tests.
    pub false_alarm: f64,
    /// Factor on the χ²-derived thresholds: covers the error of a
    /// covariance learned from a finite training set.
    pub threshold_margin: T,
    /// Bias (unit) the CUSUMs are tuned to detect fastest.
    pub cusum_bias: T,
    /// In-control average run length of each one-sided CUSUM, decisions.
    pub cusum_arl0: f64,
    /// Ridge on the leakage fit (unit², per sample).
    pub ridge: T,
    /// Time constant, in blocks, with which the offset follows slow bias
    /// drift while every test is quiet (0 disables tracking).
    pub drift_blocks: T,
    /// Consecutive alarmed decisions naming the same sensor before it is
    /// isolated and removed.
    pub isolate_after: u16,
    /// The test whose alarm isolates.
    pub detector: ParityDetector,
    /// Settings of [`ParityDetector::Multiscale`].
    pub multiscale: MultiscaleConfig<T>,
}

impl<T: Real> ParityConfig<T> {
    /// Whether a bias a sensor carries from power-up is judged. Training
    /// learns the sensors' relative offsets (their turn-on biases) in
    /// every detector, so such a fault is only reported by the multi-scale
    /// tests' offset test, which needs a finite
    /// [`offset_limit`](MultiscaleConfig::offset_limit): the gyro default
    /// ([`Self::gyro_flight`]), not the accelerometer one nor the
    /// white-noise tests. When this is false the monitor cannot tell a
    /// sensor faulty since power-up from a healthy one with its turn-on
    /// offset, and its "healthy" covers only faults that appear after
    /// training (`parity-replay` reports it as `power_up_judged`).
    pub fn judges_power_up_offsets(&self) -> bool {
        matches!(self.detector, ParityDetector::Multiscale) && self.multiscale.offset_limit.finite()
    }

    /// Spends a fault-free lead-in of `samples` on training and, when
    /// calibration is enabled, calibration: two thirds train, the rest
    /// calibrates.
    pub fn set_lead_in(&mut self, samples: u32) {
        if self.calibrate_samples > 0 {
            self.train_samples = samples * 2 / 3;
            self.calibrate_samples = samples - self.train_samples;
        } else {
            self.train_samples = samples;
        }
    }

    /// Gyro array defaults for `rate_hz` samples/s and full scale `fs`
    /// (rad/s): 0.1 s blocks, 1 s window, 30 s training, α = 1e-9 per
    /// decision with margin 1.5, CUSUM tuned to 0.05 °/s with ARL0 10⁹
    /// decisions, ridge (0.5 °/s)² (far below any manoeuvre, far above the
    /// noise, so a stationary training fits no leakage from noise), drift
    /// tracking over 5 s (the bias random walk of a consumer MEMS gyro
    /// moves the offset by several window σ per minute), isolation after 3
    /// decisions, GLT-or-CUSUM.
    pub fn gyro(rate_hz: f64, fs: T) -> Self {
        let block = libm::round(rate_hz / 10.0).max(1.0);
        let deg = core::f64::consts::PI / 180.0;
        Self {
            health: HealthConfig::new(fs),
            block_len: block as u16,
            window_blocks: 10,
            train_samples: libm::round(30.0 * rate_hz) as u32,
            calibrate_samples: libm::round(15.0 * rate_hz) as u32,
            false_alarm: 1e-9,
            threshold_margin: T::lit(1.5),
            cusum_bias: T::lit(0.05 * deg),
            cusum_arl0: 1e9,
            ridge: T::lit((0.5 * deg) * (0.5 * deg)),
            drift_blocks: T::lit(50.0),
            isolate_after: 3,
            detector: ParityDetector::GltOrCusum,
            multiscale: MultiscaleConfig::new(T::lit(deg), T::lit(1.2 * deg)),
        }
    }

    /// Accelerometer array defaults: as [`gyro`](Self::gyro) with the CUSUM
    /// tuned to 0.01 m/s² and ridge (0.05 m/s²)².
    pub fn accel(rate_hz: f64, fs: T) -> Self {
        Self {
            cusum_bias: T::lit(0.01),
            ridge: T::lit(0.05 * 0.05),
            multiscale: MultiscaleConfig::new(T::lit(0.1), T::lit(0.75)),
            ..Self::gyro(rate_hz, fs)
        }
    }

    /// Gyro array of a real flight controller (several IMUs on one vibrating
    /// board, logged or sampled at `rate_hz`): the
    /// [`Multiscale`](ParityDetector::Multiscale) detector on ≈ 0.25 s
    /// blocks, 30 s of training (no separate threshold calibration: the
    /// covariances keep learning in flight), isolation after 3 decisions.
    /// Needs a monitor window `W` ≥ 40 blocks. The offset limit, 1.2 °/s,
    /// is the largest relative gyro bias accepted once trained: twice the
    /// largest relative offset of log171's three healthy IMUs (0.6 °/s);
    /// larger ones are reported as a fault present since power-up.
    pub fn gyro_flight(rate_hz: f64, fs: T) -> Self {
        let block = libm::round(rate_hz / 4.0).max(1.0);
        Self {
            block_len: block as u16,
            train_samples: libm::round(30.0 * rate_hz) as u32,
            calibrate_samples: 0,
            drift_blocks: T::zero(),
            detector: ParityDetector::Multiscale,
            ..Self::gyro(rate_hz, fs)
        }
    }

    /// Accelerometer array of a real flight controller: as
    /// [`gyro_flight`](Self::gyro_flight) with accelerometer units and each
    /// sensor's vibration as a regressor (rectification), **without** the
    /// power-up offset test (`offset_limit` infinite): on a vibrating board
    /// the healthy accelerometers' relative a_z offset is set by vibration
    /// rectification, not by the sensors' specified zero-g offsets, and is
    /// as large as the faults such a test would look for (on the realistic
    /// profile a healthy IMU's a_z sits 1.0–1.5 m/s² from the others for
    /// whole flights; a 1.0 m/s² limit named a healthy a_z in 5 of 20
    /// fault-free hours, and on log171 the test isolated 6 of 90 power-up
    /// biases of 0.5 m/s²). An accelerometer bias present since power-up
    /// is learned into the calibration: the monitor cannot judge it, and
    /// only a fault that appears after training is detected. A user whose
    /// board rectifies little may set a finite limit.
    pub fn accel_flight(rate_hz: f64, fs: T) -> Self {
        Self {
            cusum_bias: T::lit(0.01),
            ridge: T::lit(0.05 * 0.05),
            multiscale: MultiscaleConfig {
                vibration: true,
                ..MultiscaleConfig::new(T::lit(0.1), T::lit(f64::INFINITY))
            },
            ..Self::gyro_flight(rate_hz, fs)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_finite_offset_limit_judges_power_up_offsets() {
        assert!(ParityConfig::<f32>::gyro_flight(49.0, 35.0).judges_power_up_offsets());
        assert!(!ParityConfig::<f32>::accel_flight(49.0, 157.0).judges_power_up_offsets());
        // The white-noise tests learn the offset in training too.
        assert!(!ParityConfig::<f32>::gyro(49.0, 35.0).judges_power_up_offsets());
        let mut c = ParityConfig::<f32>::accel_flight(49.0, 157.0);
        c.multiscale.offset_limit = 1.0;
        assert!(c.judges_power_up_offsets());
    }
}

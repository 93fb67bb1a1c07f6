//! IMU error model: what makes a real MEMS IMU differ from the ideal one.
//!
//! `measured = sat(quant((I + S + N)·true + b₀ + b_rw(t) + noise + fault))` per
//! triad, with `S` diagonal scale-factor errors, `N` off-diagonal
//! misalignment/cross-axis terms, `b₀` the turn-on bias, `b_rw` a bias random
//! walk, white noise from the noise density, LSB quantisation and saturation
//! at full scale. Faults enter additively (SPEC §2) before quantisation.

use core::f64::consts::PI;

use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use imu_fdi::model::G0;

const DEG: f64 = PI / 180.0;

/// Parameters of one triad's error model (all 1-σ unless noted).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct TriadErrors {
    /// White-noise density, unit/√Hz (per-sample σ = density·√rate).
    pub noise_density: f64,
    /// Turn-on bias σ, unit (drawn once per run, clipped at 2.5σ).
    pub turn_on_bias: f64,
    /// Bias random walk, unit/√s.
    pub bias_random_walk: f64,
    /// Scale-factor error σ (fraction).
    pub scale_factor: f64,
    /// Misalignment / cross-axis σ (fraction).
    pub misalignment: f64,
    /// Full scale, unit (saturation).
    pub full_scale: f64,
    /// Quantisation step (LSB), unit; 0 disables.
    pub lsb: f64,
}

/// Error model of a 6-axis IMU.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct ImuErrors {
    /// Accelerometer triad (m/s²).
    pub accel: TriadErrors,
    /// Gyro triad (rad/s).
    pub gyro: TriadErrors,
}

impl ImuErrors {
    /// ICM-42688-P class consumer MEMS after board-level calibration, in a
    /// ±4 g / ±250 °/s configuration (AUV): noise 70 µg/√Hz and
    /// 2.8 m°/s/√Hz (datasheet), turn-on bias σ 20 mg and 0.2 °/s (up to
    /// ±0.5 °/s), bias random walk 1e-4 m/s²/√s and 2e-5 rad/s/√s,
    /// scale-factor and cross-axis σ 0.25 % (datasheet untrimmed ±0.5 % and
    /// ±1–2 %; a board calibration brings them to this level).
    pub fn mems_auv() -> Self {
        Self {
            accel: TriadErrors {
                noise_density: 70e-6 * G0,
                turn_on_bias: 0.02 * G0,
                bias_random_walk: 1e-4,
                scale_factor: 0.0025,
                misalignment: 0.0025,
                full_scale: 4.0 * G0,
                lsb: 4.0 * G0 / 32768.0,
            },
            gyro: TriadErrors {
                noise_density: 2.8e-3 * DEG,
                turn_on_bias: 0.2 * DEG,
                bias_random_walk: 2e-5,
                scale_factor: 0.0025,
                misalignment: 0.0025,
                full_scale: 250.0 * DEG,
                lsb: 250.0 * DEG / 32768.0,
            },
        }
    }

    /// The same part at ±16 g / ±2000 °/s (flight controller setting).
    pub fn mems_aircraft() -> Self {
        let mut e = Self::mems_auv();
        e.accel.full_scale = 16.0 * G0;
        e.accel.lsb = 16.0 * G0 / 32768.0;
        e.gyro.full_scale = 2000.0 * DEG;
        e.gyro.lsb = 2000.0 * DEG / 32768.0;
        e
    }

    /// Ideal sensors (the papers' setting): only noise remains.
    pub fn ideal_with_noise(&self) -> Self {
        let strip = |t: TriadErrors| TriadErrors {
            turn_on_bias: 0.0,
            bias_random_walk: 0.0,
            scale_factor: 0.0,
            misalignment: 0.0,
            lsb: 0.0,
            ..t
        };
        Self {
            accel: strip(self.accel),
            gyro: strip(self.gyro),
        }
    }
}

fn gauss(rng: &mut Xoshiro256PlusPlus) -> f64 {
    StandardNormal.sample(rng)
}

/// One triad's drawn error state.
#[derive(Debug, Clone, Copy, PartialEq)]
struct TriadState {
    spec: TriadErrors,
    matrix: [[f64; 3]; 3],
    bias: [f64; 3],
}

impl TriadState {
    fn draw(spec: TriadErrors, rng: &mut Xoshiro256PlusPlus) -> Self {
        let mut matrix = [[0.0; 3]; 3];
        for (i, row) in matrix.iter_mut().enumerate() {
            for (j, m) in row.iter_mut().enumerate() {
                *m = if i == j {
                    1.0 + spec.scale_factor * gauss(rng)
                } else {
                    spec.misalignment * gauss(rng)
                };
            }
        }
        let clip = 2.5 * spec.turn_on_bias;
        let bias = core::array::from_fn(|_| (spec.turn_on_bias * gauss(rng)).clamp(-clip, clip));
        Self { spec, matrix, bias }
    }

    fn measure(
        &mut self,
        truth: &[f64],
        fault: &[f64],
        rate_hz: f64,
        dt: f64,
        rng: &mut Xoshiro256PlusPlus,
    ) -> [f64; 3] {
        let sigma = self.spec.noise_density * libm::sqrt(rate_hz);
        let rw = self.spec.bias_random_walk * libm::sqrt(dt);
        let mut out = [0.0; 3];
        for (i, o) in out.iter_mut().enumerate() {
            if let Some(b) = self.bias.get_mut(i) {
                *b += rw * gauss(rng);
            }
            let row = self.matrix.get(i).copied().unwrap_or([0.0; 3]);
            let scaled: f64 = row.iter().zip(truth.iter()).map(|(m, x)| m * x).sum();
            let f = fault.get(i).copied().unwrap_or(0.0);
            let mut v = scaled + self.bias.get(i).copied().unwrap_or(0.0) + sigma * gauss(rng) + f;
            if self.spec.lsb > 0.0 {
                v = libm::round(v / self.spec.lsb) * self.spec.lsb;
            }
            *o = v.clamp(-self.spec.full_scale, self.spec.full_scale);
        }
        out
    }
}

/// A simulated IMU with its own error draw.
#[derive(Debug, Clone, PartialEq)]
pub struct SimImu {
    accel: TriadState,
    gyro: TriadState,
    rate_hz: f64,
}

impl SimImu {
    /// Draws turn-on bias, scale factor and misalignment.
    pub fn new(errors: &ImuErrors, rate_hz: f64, rng: &mut Xoshiro256PlusPlus) -> Self {
        Self {
            accel: TriadState::draw(errors.accel, rng),
            gyro: TriadState::draw(errors.gyro, rng),
            rate_hz,
        }
    }

    /// The current total bias `[a_x … r]` (turn-on plus random walk).
    pub fn bias(&self) -> [f64; 6] {
        let a = self.accel.bias;
        let g = self.gyro.bias;
        [a[0], a[1], a[2], g[0], g[1], g[2]]
    }

    /// One sample from the ideal output and an additive fault.
    pub fn measure(
        &mut self,
        truth: &[f64; 6],
        fault: &[f64; 6],
        rng: &mut Xoshiro256PlusPlus,
    ) -> [f64; 6] {
        let dt = 1.0 / self.rate_hz;
        let a = self.accel.measure(
            truth.get(0..3).unwrap_or(&[]),
            fault.get(0..3).unwrap_or(&[]),
            self.rate_hz,
            dt,
            rng,
        );
        let g = self.gyro.measure(
            truth.get(3..6).unwrap_or(&[]),
            fault.get(3..6).unwrap_or(&[]),
            self.rate_hz,
            dt,
            rng,
        );
        [a[0], a[1], a[2], g[0], g[1], g[2]]
    }

    /// Full scale per channel.
    pub fn full_scale(&self) -> [f64; 6] {
        let a = self.accel.spec.full_scale;
        let g = self.gyro.spec.full_scale;
        [a, a, a, g, g, g]
    }
}

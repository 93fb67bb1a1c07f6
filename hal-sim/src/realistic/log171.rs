//! The profile fitted to ArduPilot log171 (`tests/data/ap_log171_3imu.csv`):
//! a Pixhawk (PX4v2 board ID) on ArduCopter 3.3-dev, IMU0 MPU6000, IMU1
//! L3GD20 gyro + LSM303D accel, IMU2 MPU9250, logged as 49 Hz point samples
//! after the INS filters; Loiter then Acro.
//!
//! What is physics and what is fitted:
//! - chains from the datasheets and the PX4 drivers ArduPilot 3.3 ran on
//!   this board (their defaults, checked in the PX4 sources: MPU6000 at
//!   1 kHz with the 42 Hz DLPF and a 30 Hz driver filter; L3GD20 at 760 Hz
//!   with a 30 Hz driver filter; LSM303D at 800 Hz): the MPU6000/MPU9250
//!   DLPF is digital, after the ADC, so vibration above 500 Hz folds in;
//!   ArduPilot's 20 Hz INS filter follows (whether 3.3 ran it in series with
//!   the driver's 30 Hz one was not checked: the fitted gains absorb it);
//!   independent crystals (±60 ppm). One departure: PX4 set the LSM303D's
//!   analog anti-alias filter to 50 Hz, and with it IMU1's 0.3 m/s² accel
//!   residual needs a 15–30× local vibration gain; the profile uses the
//!   chip's 773 Hz setting instead (gain ≈ 1.3–1.5), i.e. IMU1's accel
//!   residual is modelled as folded vibration though its true source on
//!   log171 is not identified;
//! - noise densities from the datasheets (MPU6000 0.005 °/s/√Hz and
//!   400 µg/√Hz, L3GD20 0.03 °/s/√Hz, LSM303D 150 µg/√Hz, MPU9250
//!   0.01 °/s/√Hz and 300 µg/√Hz): negligible next to vibration, as on the
//!   real log;
//! - **fitted** on the inter-IMU statistics ([`super::stats`]): the local
//!   vibration gains (per-sample sd), the rotor line (log171's IMU0 x gyro
//!   residual is narrowband tones wandering through 4–24 Hz: a 6th rotor
//!   line near the 1 kHz ODR, which needs the blade-pass to stay in
//!   150–168 Hz so its alias rarely crosses DC), the relative
//!   misalignment (least squares of the 1-s means of each residual on the
//!   other IMUs' mean, × 2/3 to go from residual to per-IMU terms; the
//!   accel-Z rows couple 0.1–0.15 of x and y, far beyond a datasheet's
//!   ±2 % cross-axis: the data show it, its cause is not identified), the
//!   bias instability (the slow part of the 10-s means) and the accel-Z
//!   rectification (opposite on IMU0 and IMU2, as log171's slow az shows);
//! - not from log171: thermal coefficients (small, 0.003 m/s²/K,
//!   0.005 °/s/K; the log has no usable temperature excursion in flight).
//!
//! The fit was done on seeds 1–3 with a damped fixed-point iteration
//! (per-sample variance and 10-s-mean variance solved for independent
//! per-IMU parts); `hal-sim/tests/realistic_profile.rs` prints the table.

use core::f64::consts::PI;

use imu_fdi::model::G0;

use super::flight::FlightParams;
use super::{
    Decimation, ImuParams, RealisticProfile, SensorChain, ThermalParams, VibrationParams, AZ,
    CHANNELS,
};

const DEG: f64 = PI / 180.0;

impl RealisticProfile {
    /// The profile fitted to ArduPilot log171 (see the module docs): 155 s
    /// like the log's fault-free 80–235 s, 137 s Loiter then 18 s Acro,
    /// repeating if [`RealisticProfile::with_duration`] asks for more.
    pub fn log171() -> Self {
        let mpu6000 = ImuParams {
            name: "MPU6000",
            accel: SensorChain {
                clock_ppm: 25.0,
                clock_offset_s: 0.00013,
                ..SensorChain::mpu_accel(42.0)
            },
            gyro: SensorChain {
                clock_ppm: 25.0,
                clock_offset_s: 0.00013,
                ..SensorChain::mpu_gyro(42.0)
            },
            vib_gain: [0.685, 0.376, 0.351, 1.27, 1.34, 1.04],
            misalignment: [
                [0.0012, -0.0068, -0.0033],
                [-0.0186, -0.0405, 0.0037],
                [0.1075, 0.1407, -0.0116],
                [-0.0039, 0.0025, 0.0059],
                [0.0014, 0.0033, -0.0020],
                [0.0001, -0.0110, -0.0010],
            ],
            bias: [0.0; CHANNELS],
            bias_instability: [0.008, 0.0516, 0.109, 0.0, 0.0, 0.0733 * DEG],
            bias_tau_s: 30.0,
            thermal: [0.003, 0.003, 0.003, 0.005 * DEG, 0.005 * DEG, 0.005 * DEG],
            vre: [0.0, 0.0, 0.015],
            lever_arm: [0.01, 0.0, 0.0],
        };
        let l3gd20 = ImuParams {
            name: "L3GD20+LSM303D",
            accel: SensorChain {
                odr_hz: 800.0,
                clock_ppm: -40.0,
                clock_offset_s: 0.00047,
                analog_aa_hz: 773.0,
                chip_lpf_hz: 0.0,
                noise_density: 150e-6 * G0,
                ..SensorChain::mpu_accel(0.0)
            },
            gyro: SensorChain {
                odr_hz: 760.0,
                clock_ppm: 60.0,
                clock_offset_s: 0.00091,
                chip_lpf_hz: 50.0,
                noise_density: 0.03 * DEG,
                ..SensorChain::mpu_gyro(0.0)
            },
            vib_gain: [1.54, 1.34, 1.3, 1.8, 0.996, 1.48],
            misalignment: [
                [0.0179, 0.0259, 0.0131],
                [0.0315, 0.0561, 0.0231],
                [0.0373, -0.0115, -0.0335],
                [0.0093, 0.0030, -0.0026],
                [-0.0029, -0.0011, 0.0067],
                [-0.0013, -0.0031, -0.0010],
            ],
            bias: [0.0; CHANNELS],
            bias_instability: [0.0166, 0.0546, 0.0, 0.0, 0.0841 * DEG, 0.0681 * DEG],
            bias_tau_s: 30.0,
            thermal: [
                -0.003,
                0.003,
                -0.003,
                -0.005 * DEG,
                0.005 * DEG,
                -0.005 * DEG,
            ],
            vre: [0.0, 0.0, -0.002],
            lever_arm: [-0.01, 0.01, 0.0],
        };
        let mpu9250 = ImuParams {
            name: "MPU9250",
            accel: SensorChain {
                clock_ppm: -15.0,
                clock_offset_s: 0.00071,
                noise_density: 300e-6 * G0,
                ..SensorChain::mpu_accel(41.0)
            },
            gyro: SensorChain {
                clock_ppm: -15.0,
                clock_offset_s: 0.00071,
                noise_density: 0.01 * DEG,
                ..SensorChain::mpu_gyro(41.0)
            },
            vib_gain: [0.786, 0.499, 0.545, 0.214, 0.818, 0.513],
            misalignment: [
                [-0.0218, -0.0226, -0.0081],
                [-0.0081, -0.0347, -0.0239],
                [-0.1483, -0.1095, 0.0017],
                [-0.0081, -0.0055, -0.0028],
                [0.0014, -0.0025, -0.0046],
                [0.0013, 0.0140, 0.0019],
            ],
            bias: [0.0; CHANNELS],
            bias_instability: [0.021, 0.0, 0.131, 0.102 * DEG, 0.142 * DEG, 0.0],
            bias_tau_s: 30.0,
            thermal: [0.003, -0.003, 0.003, 0.005 * DEG, -0.005 * DEG, 0.005 * DEG],
            vre: [0.0, 0.0, -0.015],
            lever_arm: [0.0, -0.01, 0.005],
        };
        Self {
            name: "log171",
            internal_hz: 4000.0,
            motion_hz: 500.0,
            // Log171's TimeMS steps: 19–22 ms, mean 20.3 ms.
            log_hz: 49.2,
            log_jitter_s: 0.001,
            decimation: Decimation::PointSample,
            duration_s: 155.0,
            flight: FlightParams::loiter_then_acro(),
            vibration: VibrationParams {
                blade_pass_hz: (150.0, 168.0),
                rotor_spread: 0.03,
                // Peak amplitudes at hover; ArduPilot's guidance calls a
                // frame good below ~15 m/s² (30 m/s² the limit) of VIBE.
                harmonic_amp: [
                    [1.5, 1.5, 3.0, 3.0 * DEG, 3.0 * DEG, 1.5 * DEG],
                    [0.8, 0.8, 1.5, 1.5 * DEG, 1.5 * DEG, 0.8 * DEG],
                    [0.4, 0.4, 0.8, 0.8 * DEG, 0.8 * DEG, 0.4 * DEG],
                ],
                line_order: 6,
                line_amp: [0.5, 0.5, 1.0, 20.0 * DEG, 5.0 * DEG, 3.0 * DEG],
                broadband_sd: [2.0, 2.0, 4.0, 6.0 * DEG, 5.0 * DEG, 2.5 * DEG],
                broadband_band: (700.0, 0.4),
                throttle_exponent: 2.0,
            },
            thermal: ThermalParams {
                warmup_k: 6.0,
                warmup_tau_s: 120.0,
                throttle_k: 8.0,
                lag_s: 20.0,
            },
            imus: [mpu6000, l3gd20, mpu9250],
        }
    }

    /// Log171's board with its z rotor vibration raised 50× (15 g peak
    /// at blade-pass, with 2× and 3×) until the accelerometers clip at
    /// ±16 g: clipping a vibration riding on −1 g is asymmetric and
    /// rectifies to a DC shift (measured 6.3–6.9 m/s² at hover; ArduPilot
    /// asks its EKF tests to cover ≥ 5 m/s² of such accel-Z offset); the
    /// other axes' vibration is doubled.
    pub fn log171_clipping() -> Self {
        let mut p = Self::log171();
        p.name = "log171-clipping";
        // Rectification here is the clipping's, not the small-signal
        // nonlinearity's (whose quadratic law does not hold at 20 g).
        // All three chips see the same z vibration (a loose or unbalanced
        // prop shaking the whole board).
        for imu in p.imus.iter_mut() {
            imu.vre = [0.0; 3];
            imu.vib_gain[AZ] = 1.0;
        }
        for h in p.vibration.harmonic_amp.iter_mut() {
            for (ch, a) in h.iter_mut().enumerate() {
                *a *= if ch == AZ { 50.0 } else { 2.0 };
            }
        }
        p
    }
}

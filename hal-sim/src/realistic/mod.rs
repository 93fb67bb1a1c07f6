//! A redundant-IMU flight that looks like a real one (issue 14, item 1).
//!
//! The white-noise arrays of [`crate::array`] give a parity monitor 0.05 °/s
//! of resolution; on ArduPilot log171 (three IMUs on a Pixhawk, 49 Hz point
//! samples) the residual `IMU k − mean of the others` has a per-sample sd of
//! 1–12 °/s and 0.2–0.5 m/s², with slow wander on top. This module
//! simulates where that comes from, at a high internal rate (4 kHz by
//! default) so the mechanisms are physical, not fitted noise:
//!
//! - **the flight** ([`flight`]): a multirotor in loiter with gusts, then
//!   acro pulses of 100–400 °/s, thrust along −z (what a multirotor's
//!   accelerometers really see);
//! - **vibration**, common to the whole board (rigid body): rotor
//!   harmonics whose blade-pass frequency wanders with throttle (80–200 Hz,
//!   with 2× and 3×; two rotor pairs a little apart so they beat) plus
//!   broadband frame noise up to the kHz range, amplitudes growing with
//!   throttle². ArduPilot's "Measuring Vibration" page and PX4's "Vibration
//!   Isolation" guide describe this spectrum and what it does to the
//!   sensors (aliasing, clipping, accel-Z offsets);
//! - **each IMU's own chain** ([`SensorChain`]): a local transmissibility
//!   per axis (where the chip sits on the board), an optional analog
//!   anti-alias filter (the LSM303D has one; the MPU6000/MPU9250 do not:
//!   their DLPF is digital, after the ADC, so vibration above half the ODR
//!   folds into the band), clipping at full scale (±16 g, ±2000 °/s) at the
//!   ADC, its own ODR clock (offset, ppm skew), white noise from the
//!   datasheet density, LSB quantisation, the chip's digital low-pass, the
//!   driver's 2nd-order low-pass filters (PX4's 30 Hz driver filter and
//!   ArduPilot's 20 Hz `INS_GYRO_FILTER`/`INS_ACCEL_FILTER`);
//! - **per-IMU errors**: relative scale and cross-axis coupling (any size;
//!   up to ~15 % between IMUs is seen on real boards), turn-on bias,
//!   temperature drift (the board warms after arming and with throttle),
//!   accelerometer vibration rectification (2nd-order nonlinearity: a DC
//!   shift ∝ vibration power) and lever arms (rotation makes IMUs at
//!   different places feel different specific force);
//! - **the logger** ([`Decimation`]): point samples of the latest filtered
//!   value at ~49 Hz with a jittery main-loop clock (ArduPilot's IMU/IMU2/
//!   IMU3 messages, as in log171: the vibration aliases into the band), or
//!   PX4-style integrated deltas divided by the interval (`vehicle_imu`).
//!
//! [`RealisticProfile::log171`] is fitted to log171 on the inter-IMU
//! statistics of [`stats`] (`hal-sim/tests/realistic_profile.rs` checks the
//! fit); [`RealisticArray`] runs a profile and yields [`LogRow`]s, the same
//! layout as `tests/data/ap_log171_3imu.csv`.
//!
//! ```
//! use hal_sim::array::ArrayKind;
//! use hal_sim::realistic::{ChannelFault, RealisticArray, RealisticProfile, AZ, GX};
//! use imu_fdi::parity::Reading;
//!
//! // One minute of the log171-like flight with a +1 °/s step on IMU 2's x
//! // gyro from 30 s (several faults: chain `with_fault`).
//! let profile = RealisticProfile::log171().with_duration(60.0);
//! let sim = RealisticArray::new(&profile, 7)
//!     .with_fault(ChannelFault::bias(2, GX, 30.0, f64::INFINITY, 1f64.to_radians()));
//! let mut rows = 0;
//! for row in sim {
//!     // row.t, row.imu[k] = [ax, ay, az, gx, gy, gz] as in the CSV; or the
//!     // nine gyro readings for a `Geometry::triads` parity monitor
//!     // (sensor 3·IMU + axis: IMU 2's gx is sensor 6).
//!     let gyros: [Reading<f64>; 9] = row.readings(ArrayKind::Gyro);
//!     assert!(matches!(gyros[6], Reading::Sample(x) if x.is_finite()));
//!     assert!(row.imu.iter().all(|v| (v[AZ] + 9.8).abs() < 9.0));
//!     rows += 1;
//! }
//! assert!((rows as f64 - 60.0 * 49.2).abs() < 5.0);
//! ```
//!
//! Deterministic from the seed; `no_std`, no allocation.

mod chain;
pub mod dsp;
mod fault;
pub mod flight;
mod log171;
pub mod stats;
mod vibration;

pub use fault::ChannelFault;

use core::f64::consts::PI;

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use imu_fdi::model::G0;
use imu_fdi::parity::Reading;

use crate::array::ArrayKind;
use chain::ChainState;
use dsp::uniform_pair;
use flight::{Flight, FlightParams, Motion};
pub use stats::{inter_imu_stats, InterImuStats, ResidualStats};
use vibration::Vibration;

const DEG: f64 = PI / 180.0;

/// IMUs on the board.
pub const IMUS: usize = 3;
/// Channels per IMU: ax, ay, az (m/s²), gx, gy, gz (rad/s).
pub const CHANNELS: usize = 6;
/// Channel index of x specific force.
pub const AX: usize = 0;
/// Channel index of y specific force.
pub const AY: usize = 1;
/// Channel index of z specific force.
pub const AZ: usize = 2;
/// Channel index of x rate.
pub const GX: usize = 3;
/// Channel index of y rate.
pub const GY: usize = 4;
/// Channel index of z rate.
pub const GZ: usize = 5;

/// One logger row: time and the three IMUs' `[ax, ay, az, gx, gy, gz]`
/// (body FRD, board rotation applied, m/s² and rad/s), as the columns of
/// `tests/data/ap_log171_3imu.csv`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogRow {
    /// Logger time, s.
    pub t: f64,
    /// Per IMU, per channel.
    pub imu: [[f64; CHANNELS]; IMUS],
}

impl LogRow {
    /// The nine readings of one kind for a parity monitor on
    /// `Geometry::triads(&[Matrix3::identity(); 3])`: sensor `3·IMU + axis`
    /// (the layout of [`crate::array::Layout::Triads`]).
    pub fn readings(&self, kind: ArrayKind) -> [Reading<f64>; 3 * IMUS] {
        let first = match kind {
            ArrayKind::Accel => AX,
            ArrayKind::Gyro => GX,
        };
        core::array::from_fn(|i| {
            let v = self
                .imu
                .get(i / 3)
                .and_then(|c| c.get(first + i % 3))
                .copied()
                .unwrap_or(f64::NAN);
            Reading::Sample(v)
        })
    }
}

/// How the logger turns each IMU's sample stream into rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub enum Decimation {
    /// The latest driver-filtered sample at each log tick (ArduPilot's
    /// IMU messages, log171): vibration left after the filters aliases.
    PointSample,
    /// The mean of the raw (chip-filtered) samples since the previous tick,
    /// i.e. delta angle / delta velocity over the interval divided by it
    /// (PX4 `vehicle_imu`): a band-limited average, little aliasing.
    Integrated,
}

/// One sensor (the accelerometer or the gyro) of one IMU: its clock and
/// filters.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct SensorChain {
    /// Output data rate, Hz (the ADC/digital filter rate seen by the driver).
    pub odr_hz: f64,
    /// Clock error, ppm (each chip has its own oscillator).
    pub clock_ppm: f64,
    /// Instant of the first sample, s (phase against the other chips).
    pub clock_offset_s: f64,
    /// Analog anti-alias low-pass before the ADC, Hz (0: none, as on the
    /// MPU6000/MPU9250 whose DLPF is digital).
    pub analog_aa_hz: f64,
    /// On-chip digital low-pass at the ODR, Hz (0: none).
    pub chip_lpf_hz: f64,
    /// Driver/autopilot 2nd-order low-pass filters at the ODR, Hz (0: off).
    pub driver_lpf_hz: [f64; 2],
    /// White-noise density, unit/√Hz (datasheet).
    pub noise_density: f64,
    /// Full scale, unit (clipping).
    pub full_scale: f64,
    /// Quantisation step, unit (0: none).
    pub lsb: f64,
}

impl SensorChain {
    /// MPU6000/MPU9250-class gyro at 1 kHz, ±2000 °/s, DLPF `dlpf_hz`, the
    /// PX4 30 Hz driver filter and ArduPilot's 20 Hz INS filter; noise
    /// 0.005 °/s/√Hz (MPU6000 datasheet).
    pub fn mpu_gyro(dlpf_hz: f64) -> Self {
        Self {
            odr_hz: 1000.0,
            clock_ppm: 0.0,
            clock_offset_s: 0.0,
            analog_aa_hz: 0.0,
            chip_lpf_hz: dlpf_hz,
            driver_lpf_hz: [30.0, 20.0],
            noise_density: 0.005 * DEG,
            full_scale: 2000.0 * DEG,
            lsb: 2000.0 * DEG / 32768.0,
        }
    }

    /// MPU6000/MPU9250-class accelerometer at 1 kHz, ±16 g; noise
    /// 400 µg/√Hz (MPU6000 datasheet).
    pub fn mpu_accel(dlpf_hz: f64) -> Self {
        Self {
            noise_density: 400e-6 * G0,
            full_scale: 16.0 * G0,
            lsb: 16.0 * G0 / 32768.0,
            ..Self::mpu_gyro(dlpf_hz)
        }
    }
}

/// One IMU: its two sensor chains and its errors relative to the body.
/// Channel arrays are in [`LogRow`] order (ax, ay, az, gx, gy, gz).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct ImuParams {
    /// The part (documentation only).
    pub name: &'static str,
    /// Accelerometer chain.
    pub accel: SensorChain,
    /// Gyro chain.
    pub gyro: SensorChain,
    /// Local vibration transmissibility per channel (1: the board's
    /// common vibration; a chip on a flexing part of the PCB sees more).
    pub vib_gain: [f64; CHANNELS],
    /// Scale-factor and misalignment errors: row `ch` is what channel `ch`
    /// measures of the x, y and z axes of its kind beyond the ideal (the
    /// diagonal is the scale-factor error, the rest cross-axis coupling and
    /// mounting misalignment), fractions.
    pub misalignment: [[f64; 3]; CHANNELS],
    /// Residual turn-on bias after calibration, per channel.
    pub bias: [f64; CHANNELS],
    /// In-run bias instability per channel: sd of a Gauss–Markov bias with
    /// time constant `bias_tau_s` (datasheets' "bias stability"; on a
    /// board it also carries uneven heating of the chips), unit.
    pub bias_instability: [f64; CHANNELS],
    /// Correlation time of that bias, s.
    pub bias_tau_s: f64,
    /// Bias temperature coefficient per channel, unit/K.
    pub thermal: [f64; CHANNELS],
    /// Accelerometer vibration rectification: DC shift = coefficient ·
    /// mean-square board vibration (0.1 s average), per accel axis,
    /// 1/(m/s²). Per unit of the common vibration, so it does not move when
    /// `vib_gain` is refitted.
    pub vre: [f64; 3],
    /// Position from the centre of gravity, m (body FRD).
    pub lever_arm: [f64; 3],
}

/// The board's vibration, common to all IMUs.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct VibrationParams {
    /// Blade-pass frequency at throttle 0 and 1, Hz (∝ rotor speed; it
    /// wanders with throttle).
    pub blade_pass_hz: (f64, f64),
    /// Relative speed difference of the two rotor pairs (beating).
    pub rotor_spread: f64,
    /// Amplitude (peak) of the fundamental, 2nd and 3rd harmonic per
    /// channel at hover throttle.
    pub harmonic_amp: [[f64; CHANNELS]; 3],
    /// Order of a high rotor line (a multiple of the blade-pass frequency,
    /// e.g. the motors' electrical commutation line of a 14-pole motor
    /// with 2-blade props at 7×), 0 for none. Near the IMUs' 1 kHz ODR it
    /// folds to a few Hz in a chip without an analog anti-alias filter and
    /// then wanders through the band with throttle: the narrowband
    /// tones log171's IMU0 x gyro shows at 4–24 Hz.
    pub line_order: u32,
    /// Amplitude (peak) of that line per channel at hover throttle.
    pub line_amp: [f64; CHANNELS],
    /// Broadband frame vibration sd per channel at hover throttle.
    pub broadband_sd: [f64; CHANNELS],
    /// Centre and quality of the broadband band-pass, Hz and Q.
    pub broadband_band: (f64, f64),
    /// Amplitudes scale as (throttle / hover throttle) to this power.
    pub throttle_exponent: f64,
}

/// The board temperature: warm-up after power-on plus self-heating with
/// throttle (ESC and motor current), seen through a slow thermal lag.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct ThermalParams {
    /// Warm-up amplitude, K.
    pub warmup_k: f64,
    /// Warm-up time constant, s.
    pub warmup_tau_s: f64,
    /// Heating per unit of throttle above hover, K.
    pub throttle_k: f64,
    /// Thermal lag of the board, s.
    pub lag_s: f64,
}

/// Everything a realistic run needs.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct RealisticProfile {
    /// Name.
    pub name: &'static str,
    /// Internal (physics) rate, Hz.
    pub internal_hz: f64,
    /// Flight-model update rate, Hz (interpolated to the internal rate).
    pub motion_hz: f64,
    /// Logger mean rate, Hz.
    pub log_hz: f64,
    /// Logger tick jitter, s (uniform ±).
    pub log_jitter_s: f64,
    /// How rows are formed.
    pub decimation: Decimation,
    /// Length of the run, s (the first row is at ≈ 1/`log_hz`).
    pub duration_s: f64,
    /// The flight.
    pub flight: FlightParams,
    /// The vibration.
    pub vibration: VibrationParams,
    /// The temperature.
    pub thermal: ThermalParams,
    /// The three IMUs.
    pub imus: [ImuParams; IMUS],
}

impl RealisticProfile {
    /// The same profile for `s` seconds (a false-alarm campaign: the
    /// loiter/acro cycle repeats).
    pub fn with_duration(mut self, s: f64) -> Self {
        self.duration_s = s;
        self
    }

    /// The same profile with `imu`'s `channel` scale factor off by `frac`
    /// (e.g. 0.15: the relative scale errors up to ~15 % seen between IMUs
    /// of real boards; an in-flight relative calibration must absorb it).
    /// Out-of-range indices leave the profile unchanged.
    pub fn with_scale_error(mut self, imu: usize, channel: usize, frac: f64) -> Self {
        if let Some(row) = self
            .imus
            .get_mut(imu)
            .and_then(|i| i.misalignment.get_mut(channel))
        {
            if let Some(d) = row.get_mut(channel % 3) {
                *d += frac;
            }
        }
        self
    }

    /// The same profile logged PX4-style (integrated deltas).
    pub fn integrated(mut self) -> Self {
        self.decimation = Decimation::Integrated;
        self
    }
}

/// Most faults a run carries.
pub const MAX_CHANNEL_FAULTS: usize = 4;

#[derive(Debug, Clone)]
struct ImuState {
    p: ImuParams,
    /// Gauss–Markov part of the bias.
    drift: [f64; CHANNELS],
    accel: ChainState,
    gyro: ChainState,
}

/// A realistic three-IMU run: an iterator of [`LogRow`]s.
#[derive(Debug, Clone)]
pub struct RealisticArray {
    p: RealisticProfile,
    flight: Flight,
    motion: [Motion; 2],
    vibration: Vibration,
    imus: [ImuState; IMUS],
    faults: heapless::Vec<ChannelFault, MAX_CHANNEL_FAULTS>,
    rng: Xoshiro256PlusPlus,
    dt: f64,
    motion_every: u32,
    step: u64,
    t: f64,
    next_log: f64,
    temperature: f64,
    heat: f64,
    vib_power: [f64; 3],
}

impl RealisticArray {
    /// A run of `profile` from `seed`.
    pub fn new(profile: &RealisticProfile, seed: u64) -> Self {
        let p = *profile;
        let mut vib_rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x7669_6272);
        let flight_rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x666c_6967);
        let dt = 1.0 / p.internal_hz;
        let motion_every = libm::round(p.internal_hz / p.motion_hz).max(1.0) as u32;
        let mut flight = Flight::new(p.flight, dt * motion_every as f64, flight_rng);
        let m0 = flight.step();
        let m1 = flight.step();
        let vibration = Vibration::new(p.vibration, p.internal_hz, &mut vib_rng);
        let mut drift_rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6472_6966);
        let imus = p.imus.map(|ip| {
            let mut s = ImuState {
                p: ip,
                // Drawn from its stationary distribution: the flight starts
                // with the bias already wandered, as after arming.
                drift: ip.bias_instability.map(|sd| {
                    let n: f64 = StandardNormal.sample(&mut drift_rng);
                    sd * n
                }),
                accel: ChainState::new(ip.accel, p.internal_hz),
                gyro: ChainState::new(ip.gyro, p.internal_hz),
            };
            // Start the filters in the steady state of hover.
            s.accel.settle([0.0, 0.0, -G0]);
            s.gyro.settle([0.0; 3]);
            s
        });
        Self {
            p,
            flight,
            motion: [m0, m1],
            vibration,
            imus,
            faults: heapless::Vec::new(),
            rng: Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6e6f_6973),
            dt,
            motion_every,
            step: 0,
            t: 0.0,
            next_log: 1.0 / p.log_hz,
            temperature: 0.0,
            heat: 0.0,
            vib_power: [0.0; 3],
        }
    }

    /// The same run with one more fault (ignored beyond
    /// [`MAX_CHANNEL_FAULTS`]).
    pub fn with_fault(mut self, fault: ChannelFault) -> Self {
        let _ = self.faults.push(fault);
        self
    }

    /// The profile being run.
    pub fn profile(&self) -> &RealisticProfile {
        &self.p
    }

    /// True if a fault is active on `imu`/`channel` at `t`.
    pub fn fault_active(&self, imu: usize, channel: usize, t: f64) -> bool {
        self.faults
            .iter()
            .any(|f| f.imu == imu && f.channel == channel && f.active(t))
    }

    /// ADC samples clipped so far per IMU, `[accel, gyro]` (axis-samples),
    /// like ArduPilot's VIBE clip counters.
    pub fn clip_counts(&self) -> [[u64; 2]; IMUS] {
        self.imus.each_ref().map(|s| [s.accel.clips, s.gyro.clips])
    }

    /// Board temperature above its power-on value, K.
    pub fn temperature_k(&self) -> f64 {
        self.temperature
    }

    /// Each IMU's bias per channel now, in the units of the readings: its
    /// constant bias, its bias-instability (Gauss–Markov) state and its
    /// thermal drift — what a healthy sensor's reading carries besides
    /// motion, scale, vibration and (accelerometers) vibration
    /// rectification. Ground truth for judging what a monitor names.
    pub fn biases(&self) -> [[f64; CHANNELS]; IMUS] {
        let temp = self.temperature;
        self.imus.each_ref().map(|s| {
            core::array::from_fn(|ch| {
                s.p.bias.get(ch).copied().unwrap_or(0.0)
                    + s.drift.get(ch).copied().unwrap_or(0.0)
                    + s.p.thermal.get(ch).copied().unwrap_or(0.0) * temp
            })
        })
    }

    fn internal_step(&mut self) {
        let k = (self.step % self.motion_every as u64) as u32;
        if k == 0 && self.step > 0 {
            let next = self.flight.step();
            self.motion = [self.motion[1], next];
        }
        self.step += 1;
        // From the step count, not accumulated: exact over 10-hour runs.
        self.t = self.step as f64 * self.dt;
        let m = self.motion[0].lerp(&self.motion[1], (k + 1) as f64 / self.motion_every as f64);
        let hover = self.p.flight.hover_throttle;
        if k == 0 {
            // Temperature at the flight-model rate (it is slow).
            let th = self.p.thermal;
            let dtm = self.dt * self.motion_every as f64;
            let warm = th.warmup_k * (1.0 - libm::exp(-self.t / th.warmup_tau_s.max(1e-3)));
            self.heat +=
                (th.throttle_k * (m.throttle - hover) - self.heat) * dtm / th.lag_s.max(1e-3);
            self.temperature = warm + self.heat;
            for s in self.imus.iter_mut() {
                let a = dtm / s.p.bias_tau_s.max(1e-3);
                let q = libm::sqrt(2.0 * a);
                for (d, sd) in s.drift.iter_mut().zip(s.p.bias_instability) {
                    if sd > 0.0 {
                        let n: f64 = StandardNormal.sample(&mut self.rng);
                        *d += -a * *d + sd * q * n;
                    }
                }
            }
        }
        let vib = self
            .vibration
            .step(m.throttle, hover, self.dt, &mut self.rng);
        // Mean-square vibration per accel axis, 0.1 s smoothing, for the
        // rectification term (a DC shift ∝ vibration power).
        let a = self.dt / 0.1;
        for (pw, v) in self.vib_power.iter_mut().zip(vib.iter()) {
            *pw += a * (v * v - *pw);
        }
        let t = self.t;
        let temp = self.temperature;
        let w = m.rate;
        let wd = m.rate_dot;
        for (i, s) in self.imus.iter_mut().enumerate() {
            let ip = &s.p;
            let r = ip.lever_arm;
            // f + ω̇×r + ω×(ω×r): what an IMU off the centre of gravity feels.
            let wr = cross(w, r);
            let wwr = cross(w, wr);
            let wdr = cross(wd, r);
            let f: [f64; 3] = core::array::from_fn(|j| m.force[j] + wdr[j] + wwr[j]);
            let mut x = [0.0; CHANNELS];
            for (ch, xo) in x.iter_mut().enumerate() {
                let axis = ch % 3;
                let truth = if ch < 3 { f } else { w };
                let mis = ip.misalignment[ch];
                let mut v = truth[axis]
                    + mis[0] * truth[0]
                    + mis[1] * truth[1]
                    + mis[2] * truth[2]
                    + ip.vib_gain[ch] * vib[ch]
                    + ip.bias[ch]
                    + s.drift[ch]
                    + ip.thermal[ch] * temp;
                if ch < 3 {
                    v += ip.vre[ch] * self.vib_power[ch];
                }
                *xo = v;
            }
            for fl in self.faults.iter().filter(|f| f.imu == i && f.active(t)) {
                if let Some(xo) = x.get_mut(fl.channel) {
                    *xo += fl.bias;
                }
            }
            s.accel.step(t, self.dt, [x[0], x[1], x[2]], &mut self.rng);
            s.gyro.step(t, self.dt, [x[3], x[4], x[5]], &mut self.rng);
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl Iterator for RealisticArray {
    type Item = LogRow;

    fn next(&mut self) -> Option<LogRow> {
        if self.next_log > self.p.duration_s {
            return None;
        }
        while self.t < self.next_log {
            self.internal_step();
        }
        let t = self.next_log;
        let (u, _) = uniform_pair(&mut self.rng);
        // Uniform ±jitter (u is uniform on ±√3).
        self.next_log += 1.0 / self.p.log_hz + self.p.log_jitter_s * u / 1.732_050_807_568_877_2;
        let dec = self.p.decimation;
        let imu = core::array::from_fn(|k| {
            let s = &mut self.imus[k];
            let a = s.accel.take(dec);
            let g = s.gyro.take(dec);
            [a[0], a[1], a[2], g[0], g[1], g[2]]
        });
        Some(LogRow { t, imu })
    }
}

#[cfg(test)]
mod tests;

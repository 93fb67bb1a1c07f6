//! Redundant sensor arrays (SPEC §7): the six-sensor cone and 2- or 3-triad
//! boards, with a per-sensor datasheet-class error model (SPEC §8a), a
//! manoeuvre far larger than the faults, and the faults of S4 and S5 per
//! sensor. `no_std`: the same simulation can feed a monitor on the target.

use core::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use imu_fdi::model::G0;
use imu_fdi::parity::Reading;

use crate::imu_model::{ImuErrors, TriadErrors};

const DEG: f64 = PI / 180.0;

/// What the array measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub enum ArrayKind {
    /// Angular rate, rad/s.
    Gyro,
    /// Specific force, m/s².
    Accel,
}

/// A fault on one sensor of an array.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub enum ArrayFaultKind {
    /// Additive step (unit of the sensor).
    Bias(f64),
    /// Additive ramp, unit per second from onset.
    Ramp(f64),
    /// Output frozen at the last value before onset.
    Stuck,
    /// No sample at all (timeout).
    Dropout,
    /// Every transaction fails.
    BusError,
    /// NaN output.
    Nan,
    /// Output clamped to ± the given level.
    Clip(f64),
    /// Output pinned at + full scale (a railed sensor).
    Saturate,
    /// Spikes of the given amplitude for 30 ms every 0.5 s.
    Spikes(f64),
    /// White noise σ multiplied by the given factor.
    NoiseIncrease(f64),
    /// Scale-factor error (fraction).
    ScaleFactor(f64),
}

/// One row of an array fault table.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct ArrayFault {
    /// Sensor index (from 0; \[PAR\]'s "sensor 6" is 5).
    pub sensor: usize,
    /// Onset, s (scenario time).
    pub start: f64,
    /// End (exclusive), s.
    pub end: f64,
    /// What happens.
    pub kind: ArrayFaultKind,
}

impl ArrayFault {
    /// True while active.
    pub fn active(&self, t: f64) -> bool {
        t >= self.start && t < self.end
    }
}

/// How the sensors are grouped into devices (for the autopilot baselines).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub enum Layout {
    /// Single-axis sensors, each its own device (the cone).
    Single,
    /// Orthogonal triads: sensors `3k..3k+3` are IMU `k`.
    Triads,
}

/// Most fault rows an array scenario carries.
pub const MAX_ARRAY_FAULTS: usize = 8;

/// An array scenario: geometry, sensors, motion, faults.
#[derive(Debug, Clone, PartialEq)]
pub struct ArraySpec<const N: usize> {
    /// Name.
    pub name: &'static str,
    /// Sensing direction of each sensor (body frame, unit).
    pub directions: [[f64; 3]; N],
    /// Gyros or accelerometers.
    pub kind: ArrayKind,
    /// Device grouping.
    pub layout: Layout,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Error model of every sensor (one axis of the triad model).
    pub errors: TriadErrors,
    /// Fault-free lead-in used for training, s (scenario time starts after it).
    pub training_s: f64,
    /// Scenario duration after training, s.
    pub duration_s: f64,
    /// Manoeuvre onset (scenario time), s; the lead-in manoeuvres throughout.
    pub motion_start: f64,
    /// Amplitude scale of the manoeuvre's rates, rad/s.
    pub rate_amp: f64,
    /// Amplitude scale of the manoeuvre's accelerations, m/s².
    pub accel_amp: f64,
    /// Faults.
    pub faults: heapless::Vec<ArrayFault, MAX_ARRAY_FAULTS>,
}

/// Unit directions of the \[PAR\] cone.
pub fn cone6_directions() -> [[f64; 3]; 6] {
    let cos_a = 1.0 / libm::sqrt(3.0);
    let sin_a = libm::sqrt(1.0 - cos_a * cos_a);
    core::array::from_fn(|i| {
        let az = i as f64 * PI / 3.0;
        [sin_a * libm::cos(az), sin_a * libm::sin(az), cos_a]
    })
}

/// Directions of `K` triads yawed by the given angles (rad): sensor
/// `3k + j` is axis `j` of IMU `k`. `N` must be `3K`; extra slots repeat
/// the last triad.
pub fn triad_directions<const N: usize>(yaws: &[f64]) -> [[f64; 3]; N] {
    core::array::from_fn(|i| {
        let yaw = yaws.get(i / 3).or(yaws.last()).copied().unwrap_or(0.0);
        let (s, c) = (libm::sin(yaw), libm::cos(yaw));
        match i % 3 {
            0 => [c, s, 0.0],
            1 => [-s, c, 0.0],
            _ => [0.0, 0.0, 1.0],
        }
    })
}

impl ArraySpec<6> {
    /// S4 (\[PAR\]): six gyros on the cone, 100 Hz, 10 s; a manoeuvre from
    /// t = 1 s with rates up to ~100 °/s; +0.5 °/s bias on sensor 5 (the
    /// paper's sensor 6) from t = 6 s; SPEC §8a gyro errors (±2000 °/s
    /// part). Preceded by 30 s of fault-free manoeuvring for training.
    pub fn s4() -> Self {
        let mut faults = heapless::Vec::new();
        let _ = faults.push(ArrayFault {
            sensor: 5,
            start: 6.0,
            end: f64::INFINITY,
            kind: ArrayFaultKind::Bias(0.5 * DEG),
        });
        Self {
            name: "s4",
            directions: cone6_directions(),
            kind: ArrayKind::Gyro,
            layout: Layout::Single,
            rate_hz: 100.0,
            errors: ImuErrors::mems_aircraft().gyro,
            training_s: 30.0,
            duration_s: 10.0,
            motion_start: 1.0,
            rate_amp: 60.0 * DEG,
            accel_amp: 3.0,
            faults,
        }
    }
}

impl<const N: usize> ArraySpec<N> {
    /// A fault-free array of `directions` flying the same manoeuvre for
    /// `duration_s` after 30 s of training.
    pub fn fault_free(
        name: &'static str,
        directions: [[f64; 3]; N],
        kind: ArrayKind,
        layout: Layout,
        duration_s: f64,
    ) -> Self {
        let e = ImuErrors::mems_aircraft();
        Self {
            name,
            directions,
            kind,
            layout,
            rate_hz: 100.0,
            errors: match kind {
                ArrayKind::Gyro => e.gyro,
                ArrayKind::Accel => e.accel,
            },
            training_s: 30.0,
            duration_s,
            motion_start: 0.0,
            rate_amp: 60.0 * DEG,
            accel_amp: 3.0,
            faults: heapless::Vec::new(),
        }
    }

    /// The same spec with one more fault row (ignored beyond
    /// [`MAX_ARRAY_FAULTS`]).
    pub fn with_fault(mut self, fault: ArrayFault) -> Self {
        let _ = self.faults.push(fault);
        self
    }
}

/// `Σ A sin(ω t + ϕ)` per axis, three terms.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Waves {
    terms: [[(f64, f64, f64); 3]; 3],
}

impl Waves {
    fn draw(rng: &mut Xoshiro256PlusPlus, amp: f64, periods: [f64; 3]) -> Self {
        let terms = core::array::from_fn(|_| {
            core::array::from_fn(|j| {
                let a = amp * [1.0, 0.5, 0.25][j] * rng.random_range(0.6..1.4);
                let p = periods[j] * rng.random_range(0.7..1.3);
                (a, 2.0 * PI / p, rng.random_range(0.0..2.0 * PI))
            })
        });
        Self { terms }
    }

    fn at(&self, t: f64) -> [f64; 3] {
        core::array::from_fn(|i| {
            self.terms
                .get(i)
                .map(|axis| axis.iter().map(|(a, w, p)| a * libm::sin(w * t + p)).sum())
                .unwrap_or(0.0)
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct SensorState {
    direction: [f64; 3],
    scale: f64,
    bias: f64,
}

/// One period of an array run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArraySample<const N: usize> {
    /// Scenario time, s (negative during the training lead-in).
    pub t: f64,
    /// True body vector (rate or specific force).
    pub truth: [f64; 3],
    /// What each sensor delivered.
    pub readings: [Reading<f64>; N],
    /// Which sensors have a fault active.
    pub fault_active: [bool; N],
    /// True during the training lead-in.
    pub training: bool,
}

/// Deterministic simulation of an array scenario.
#[derive(Debug, Clone)]
pub struct ArraySim<const N: usize> {
    spec: ArraySpec<N>,
    rates: Waves,
    accels: Waves,
    sensors: [SensorState; N],
    rng: Xoshiro256PlusPlus,
    k: u64,
    n: u64,
    last: [f64; N],
}

fn gauss(rng: &mut Xoshiro256PlusPlus) -> f64 {
    StandardNormal.sample(rng)
}

impl<const N: usize> ArraySim<N> {
    /// A run of `spec` with `seed` (motion and sensor draws from separate
    /// streams, so changing the fault table keeps the noise).
    pub fn new(spec: &ArraySpec<N>, seed: u64) -> Self {
        let mut rng_motion = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6d6f_7469);
        let mut rng_draw = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6472_6177);
        let rates = Waves::draw(&mut rng_motion, spec.rate_amp, [3.0, 1.3, 0.7]);
        let accels = Waves::draw(&mut rng_motion, spec.accel_amp, [4.0, 1.7, 0.9]);
        let e = spec.errors;
        let sensors = core::array::from_fn(|i| {
            let h = spec.directions.get(i).copied().unwrap_or([0.0, 0.0, 1.0]);
            // Two unit vectors perpendicular to h for the misalignment.
            let a = if libm::fabs(h[0]) < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let e1 = normalize(cross(h, a));
            let e2 = cross(h, e1);
            let (g1, g2) = (gauss(&mut rng_draw), gauss(&mut rng_draw));
            let d = core::array::from_fn(|j| {
                h.get(j).copied().unwrap_or(0.0)
                    + e.misalignment
                        * (g1 * e1.get(j).copied().unwrap_or(0.0)
                            + g2 * e2.get(j).copied().unwrap_or(0.0))
            });
            let clip = 2.5 * e.turn_on_bias;
            SensorState {
                direction: normalize(d),
                scale: 1.0 + e.scale_factor * gauss(&mut rng_draw),
                bias: (e.turn_on_bias * gauss(&mut rng_draw)).clamp(-clip, clip),
            }
        });
        Self {
            n: libm::round((spec.training_s + spec.duration_s) * spec.rate_hz) as u64,
            spec: spec.clone(),
            rates,
            accels,
            sensors,
            rng: Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6e6f_6973),
            k: 0,
            last: [0.0; N],
        }
    }

    /// Samples in the run (lead-in included).
    pub fn len(&self) -> u64 {
        self.n
    }

    /// True for an empty run.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Samples in the training lead-in.
    pub fn training_samples(&self) -> u32 {
        libm::round(self.spec.training_s * self.spec.rate_hz) as u32
    }

    /// The lead-in a monitor may learn from: the training samples less a
    /// 0.1 s margin, at least 3.
    pub fn lead_in_samples(&self) -> u32 {
        self.training_samples().saturating_sub(10).max(3)
    }

    /// True body vector at scenario time `t`.
    pub fn truth(&self, t: f64) -> [f64; 3] {
        // The lead-in always manoeuvres; the scenario starts at rest and
        // ramps the manoeuvre in over 0.5 s from `motion_start`.
        let s = if t < 0.0 {
            1.0
        } else {
            let x = ((t - self.spec.motion_start) / 0.5).clamp(0.0, 1.0);
            x * x * (3.0 - 2.0 * x)
        };
        match self.spec.kind {
            ArrayKind::Gyro => self.rates.at(t).map(|w| s * w),
            ArrayKind::Accel => {
                let a = self.accels.at(t);
                [s * a[0], s * a[1], s * a[2] - G0]
            }
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

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = libm::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if n > 0.0 {
        a.map(|x| x / n)
    } else {
        a
    }
}

impl<const N: usize> Iterator for ArraySim<N> {
    type Item = ArraySample<N>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.k >= self.n {
            return None;
        }
        let rate = self.spec.rate_hz;
        let t = self.k as f64 / rate - self.spec.training_s;
        self.k += 1;
        let truth = self.truth(t);
        let e = self.spec.errors;
        let sigma = e.noise_density * libm::sqrt(rate);
        let rw = e.bias_random_walk * libm::sqrt(1.0 / rate);
        let mut readings = [Reading::Missing; N];
        let mut fault_active = [false; N];
        for i in 0..N {
            let (Some(s), Some(out), Some(fa), Some(last)) = (
                self.sensors.get_mut(i),
                readings.get_mut(i),
                fault_active.get_mut(i),
                self.last.get_mut(i),
            ) else {
                continue;
            };
            s.bias += rw * gauss(&mut self.rng);
            let noise = gauss(&mut self.rng);
            let ideal: f64 = s
                .direction
                .iter()
                .zip(truth.iter())
                .map(|(h, x)| h * x)
                .sum();
            let mut scale = s.scale;
            let mut noise_gain = 1.0;
            let mut add = 0.0;
            let mut reading: Option<Reading<f64>> = None;
            let mut clip = e.full_scale;
            for f in self
                .spec
                .faults
                .iter()
                .filter(|f| f.sensor == i && f.active(t))
            {
                *fa = true;
                let tau = t - f.start;
                match f.kind {
                    ArrayFaultKind::Bias(b) => add += b,
                    ArrayFaultKind::Ramp(r) => add += r * tau,
                    ArrayFaultKind::Stuck => reading = Some(Reading::Sample(*last)),
                    ArrayFaultKind::Dropout => reading = Some(Reading::Missing),
                    ArrayFaultKind::BusError => reading = Some(Reading::BusError),
                    ArrayFaultKind::Nan => reading = Some(Reading::Sample(f64::NAN)),
                    ArrayFaultKind::Clip(level) => clip = clip.min(level),
                    ArrayFaultKind::Saturate => add += 2.0 * e.full_scale,
                    ArrayFaultKind::Spikes(a) => {
                        if libm::fmod(tau, 0.5) < 0.03 {
                            add += a;
                        }
                    }
                    ArrayFaultKind::NoiseIncrease(f) => noise_gain *= f,
                    ArrayFaultKind::ScaleFactor(sf) => scale *= 1.0 + sf,
                }
            }
            let mut v = scale * ideal + s.bias + sigma * noise_gain * noise + add;
            if e.lsb > 0.0 {
                v = libm::round(v / e.lsb) * e.lsb;
            }
            v = v.clamp(-clip, clip);
            *out = match reading {
                Some(r) => r,
                None => {
                    *last = v;
                    Reading::Sample(v)
                }
            };
        }
        Some(ArraySample {
            t,
            truth,
            readings,
            fault_active,
            training: t < 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_manoeuvre_dwarfs_the_fault_and_sensors_see_it() {
        let spec = ArraySpec::s4();
        let sim = ArraySim::new(&spec, 1);
        let peak = sim
            .clone()
            .filter(|s| s.t > 2.0)
            .map(|s| s.truth.iter().map(|x| x.abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        assert!(peak > 20.0 * 0.5 * DEG, "peak rate {} °/s", peak / DEG);
        let at_rest = sim.clone().find(|s| s.t >= 0.0).unwrap();
        assert!(at_rest.truth.iter().all(|x| x.abs() < 1e-12));
        let faulty = sim.clone().find(|s| s.t >= 6.0).unwrap();
        assert_eq!(
            faulty.fault_active,
            [false, false, false, false, false, true]
        );
    }
}

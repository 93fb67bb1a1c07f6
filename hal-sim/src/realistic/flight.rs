//! A manoeuvring multirotor, body frame FRD: loiter with gusts, then acro
//! (rolls, flips and yaw spins at hundreds of °/s), repeating.
//!
//! What a multirotor's accelerometers see is thrust along −z plus a little
//! drag, not gravity rotated by the attitude: the thrust tilts the vehicle to
//! accelerate it, so the body-frame specific force stays near (0, 0, −g·n)
//! with n the load factor. The rates are a damped 2nd-order response to
//! gust noise (the attitude loop's closed-loop bandwidth ≈ 1 Hz), and in
//! acro segments smooth rate pulses like a pilot's stick inputs.

use core::f64::consts::PI;

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use imu_fdi::model::G0;

const DEG: f64 = PI / 180.0;

/// Parameters of the flight.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct FlightParams {
    /// Loiter (gusty hover) segment length, s.
    pub loiter_s: f64,
    /// Acro segment length after each loiter, s (0: loiter only).
    pub acro_s: f64,
    /// Loiter rate sd per body axis (roll, pitch, yaw), rad/s.
    pub loiter_rate_sd: [f64; 3],
    /// Natural frequency of the rate response, Hz.
    pub rate_bandwidth_hz: f64,
    /// Horizontal specific force sd (drag, x and y), m/s².
    pub horizontal_sd: [f64; 2],
    /// Load-factor sd (vertical manoeuvres), fraction of g.
    pub load_factor_sd: f64,
    /// Acro: rate pulse amplitude range, rad/s.
    pub acro_rate: (f64, f64),
    /// Acro: pulse duration range, s.
    pub acro_pulse_s: (f64, f64),
    /// Acro: pause between pulses, s.
    pub acro_gap_s: (f64, f64),
    /// Throttle (0–1) in hover.
    pub hover_throttle: f64,
}

impl FlightParams {
    /// Log171's flight (80–235 s): 137 s of Loiter with 15/23/15 °/s of
    /// roll/pitch/yaw rate sd, then 18 s of Acro with rate pulses of
    /// 40–170 °/s (log171's Acro peaks at 165 °/s).
    pub fn loiter_then_acro() -> Self {
        Self {
            loiter_s: 137.0,
            acro_s: 18.0,
            loiter_rate_sd: [15.0 * DEG, 23.0 * DEG, 15.0 * DEG],
            rate_bandwidth_hz: 0.8,
            horizontal_sd: [0.6, 0.35],
            load_factor_sd: 0.08,
            acro_rate: (40.0 * DEG, 170.0 * DEG),
            acro_pulse_s: (0.4, 1.2),
            acro_gap_s: (0.5, 2.5),
            hover_throttle: 0.5,
        }
    }
}

/// The vehicle's state at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// Body rate, rad/s.
    pub rate: [f64; 3],
    /// Body angular acceleration, rad/s².
    pub rate_dot: [f64; 3],
    /// Specific force at the centre of gravity, m/s².
    pub force: [f64; 3],
    /// Throttle, 0–1 (drives rotor speed, vibration and temperature).
    pub throttle: f64,
}

impl Motion {
    /// Linear interpolation between two states.
    pub fn lerp(&self, o: &Self, a: f64) -> Self {
        let l = |x: f64, y: f64| x + a * (y - x);
        Self {
            rate: core::array::from_fn(|i| l(self.rate[i], o.rate[i])),
            rate_dot: core::array::from_fn(|i| l(self.rate_dot[i], o.rate_dot[i])),
            force: core::array::from_fn(|i| l(self.force[i], o.force[i])),
            throttle: l(self.throttle, o.throttle),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Pulse {
    axis: usize,
    amp: f64,
    start: f64,
    len: f64,
}

/// The flight generator, stepped at a fixed rate.
#[derive(Debug, Clone)]
pub struct Flight {
    p: FlightParams,
    dt: f64,
    t: f64,
    /// Gust response per axis: (rate, rate').
    osc: [(f64, f64); 3],
    horiz: [f64; 2],
    load: f64,
    pulse: Option<Pulse>,
    next_pulse: f64,
    rng: Xoshiro256PlusPlus,
}

fn gauss(rng: &mut Xoshiro256PlusPlus) -> f64 {
    StandardNormal.sample(rng)
}

impl Flight {
    /// A flight stepped every `dt` s.
    pub fn new(p: FlightParams, dt: f64, rng: Xoshiro256PlusPlus) -> Self {
        Self {
            p,
            dt,
            t: 0.0,
            osc: [(0.0, 0.0); 3],
            horiz: [0.0; 2],
            load: 0.0,
            pulse: None,
            next_pulse: 0.0,
            rng,
        }
    }

    fn in_acro(&self, t: f64) -> bool {
        let cycle = self.p.loiter_s + self.p.acro_s;
        self.p.acro_s > 0.0 && cycle > 0.0 && libm::fmod(t, cycle) >= self.p.loiter_s
    }

    /// Advances one step and returns the state.
    pub fn step(&mut self) -> Motion {
        let dt = self.dt;
        self.t += dt;
        let w = 2.0 * PI * self.p.rate_bandwidth_hz;
        let zeta = 0.7;
        let acro = self.in_acro(self.t);
        let mut rate = [0.0; 3];
        let mut rate_dot = [0.0; 3];
        for (i, (x, v)) in self.osc.iter_mut().enumerate() {
            // ẍ + 2ζωẋ + ω²x = b ξ has var(x) = b²/(4ζω³).
            let sd = self.p.loiter_rate_sd.get(i).copied().unwrap_or(0.0);
            let b = sd * libm::sqrt(4.0 * zeta * w * w * w);
            let xi = gauss(&mut self.rng) / libm::sqrt(dt);
            let acc = -2.0 * zeta * w * *v - w * w * *x + b * xi;
            *v += acc * dt;
            *x += *v * dt;
            if let (Some(r), Some(rd)) = (rate.get_mut(i), rate_dot.get_mut(i)) {
                *r = *x;
                *rd = *v;
            }
        }
        if acro {
            if self.pulse.is_none() && self.t >= self.next_pulse {
                let u: f64 = self.rng.random();
                let axis = if u < 0.5 {
                    0
                } else if u < 0.85 {
                    1
                } else {
                    2
                };
                let (lo, hi) = self.p.acro_rate;
                let sign = if self.rng.random::<bool>() { 1.0 } else { -1.0 };
                let (l0, l1) = self.p.acro_pulse_s;
                self.pulse = Some(Pulse {
                    axis,
                    amp: sign * self.rng.random_range(lo..=hi.max(lo)),
                    start: self.t,
                    len: self.rng.random_range(l0..=l1.max(l0)),
                });
            }
        } else {
            self.next_pulse = self.t;
        }
        if let Some(p) = self.pulse {
            let tau = (self.t - p.start) / p.len;
            if tau >= 1.0 {
                self.pulse = None;
                let (g0, g1) = self.p.acro_gap_s;
                self.next_pulse = self.t + self.rng.random_range(g0..=g1.max(g0));
            } else {
                // A sin² bump: zero rate and zero angular acceleration at
                // both ends, like a stick flick.
                let s = libm::sin(PI * tau);
                if let (Some(r), Some(rd)) = (rate.get_mut(p.axis), rate_dot.get_mut(p.axis)) {
                    *r += p.amp * s * s;
                    *rd += p.amp * PI / p.len * libm::sin(2.0 * PI * tau);
                }
            }
        }
        // Drag and load factor: 1st-order Gauss–Markov, τ = 1 s.
        let a = dt / 1.0;
        let q = libm::sqrt(2.0 * a);
        for (h, sd) in self.horiz.iter_mut().zip(self.p.horizontal_sd) {
            *h += -a * *h + sd * q * gauss(&mut self.rng);
        }
        // Acro doubles the load-factor excursions (punch-outs after flips).
        let load_sd = self.p.load_factor_sd * if acro { 2.0 } else { 1.0 };
        self.load += -a * self.load + load_sd * q * gauss(&mut self.rng);
        let n = (1.0 + self.load).max(0.2);
        let [hx, hy] = self.horiz;
        Motion {
            rate,
            rate_dot,
            force: [hx, hy, -G0 * n],
            // Thrust ∝ throttle² for a fixed-pitch prop near hover is
            // usually linearised by the ESC/motor mixer: take it linear.
            throttle: (self.p.hover_throttle * n).clamp(0.05, 1.0),
        }
    }
}

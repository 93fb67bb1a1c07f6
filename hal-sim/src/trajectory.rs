//! Deterministic vehicle trajectories with exact IMU truth.
//!
//! Body velocity and Euler angles are smooth analytic signals (a constant plus
//! a few sinusoids, drawn from the seed), so their derivatives are exact and
//! the true IMU output follows from the model of SPEC §3 with no integration
//! error:
//!
//! ```text
//! p = φ̇ − ψ̇ sinθ,  q = θ̇ cosφ + ψ̇ cosθ sinφ,  r = −θ̇ sinφ + ψ̇ cosθ cosφ
//! a_x = u̇ − (v r − w q − g sinθ), a_y = v̇ − (−u r + w p + g cosθ sinφ),
//! a_z = ẇ − (u q − v p + g cosθ cosφ)
//! ```

use core::f64::consts::PI;

use rand::Rng;
use rand_xoshiro::Xoshiro256PlusPlus;

use imu_fdi::model::G0;

const DEG: f64 = PI / 180.0;
const MAX_TERMS: usize = 3;

/// Which vehicle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "std", serde(rename_all = "lowercase"))]
pub enum Profile {
    /// AUV at ~2 m/s: speed changes, dives/climbs of ±8°, heading sweeps of
    /// ±30° (turn rates up to ~4°/s), wave-induced roll of ±2°.
    Auv,
    /// Fixed-wing aircraft at ~20 m/s: banked turns of ±25°, pitch 0–10°,
    /// heading sweeps of ±90° (up to ~7°/s).
    Aircraft,
    /// The aircraft in gusty wind (S3): on top of the manoeuvres, gusts of
    /// ±1.5 m/s along and ±1 m/s across the flight path (periods 2–6 s) and
    /// the attitude they cause (±3° roll, ±2° pitch at 1.5–3 s) — the
    /// turbulence a GNSS-aided small aircraft sees.
    AircraftWind,
}

/// `c + Σ A_k sin(ω_k t + ϕ_k)` with its derivative.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Signal {
    c: f64,
    terms: [(f64, f64, f64); MAX_TERMS],
}

impl Signal {
    fn value(&self, t: f64) -> f64 {
        self.c
            + self
                .terms
                .iter()
                .map(|(a, w, p)| a * libm::sin(w * t + p))
                .sum::<f64>()
    }
    fn rate(&self, t: f64) -> f64 {
        self.terms
            .iter()
            .map(|(a, w, p)| a * w * libm::cos(w * t + p))
            .sum()
    }
}

/// Builds a signal from nominal (amplitude, period) pairs, randomising
/// amplitude ±30 %, period ±20 % and phase.
fn signal(rng: &mut Xoshiro256PlusPlus, c: f64, spec: &[(f64, f64)]) -> Signal {
    let mut s = Signal {
        c,
        ..Signal::default()
    };
    for (slot, (amp, period)) in s.terms.iter_mut().zip(spec.iter()) {
        let a = amp * rng.random_range(0.7..1.3);
        let p = period * rng.random_range(0.8..1.2);
        *slot = (a, 2.0 * PI / p, rng.random_range(0.0..2.0 * PI));
    }
    s
}

/// Truth at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// State `[u, v, w, φ, θ, ψ]` (ψ wrapped to (−π, π]).
    pub state: [f64; 6],
    /// Ideal IMU output `[a_x, a_y, a_z, p, q, r]`.
    pub imu: [f64; 6],
}

/// A seeded trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Vehicle profile.
    pub profile: Profile,
    gravity: f64,
    vel: [Signal; 3],
    att: [Signal; 3],
}

impl Trajectory {
    /// The trajectory of `profile` for `seed`.
    pub fn new(profile: Profile, rng: &mut Xoshiro256PlusPlus) -> Self {
        let psi0 = rng.random_range(-PI..PI);
        let (vel, att) = match profile {
            Profile::Auv => (
                [
                    signal(rng, 2.0, &[(0.3, 60.0), (0.1, 17.0)]),
                    signal(rng, 0.0, &[(0.05, 23.0)]),
                    signal(rng, 0.0, &[(0.05, 31.0)]),
                ],
                [
                    signal(rng, 0.0, &[(2.0 * DEG, 7.0), (1.0 * DEG, 13.0)]),
                    signal(rng, 0.0, &[(8.0 * DEG, 40.0), (1.0 * DEG, 9.0)]),
                    signal(rng, psi0, &[(30.0 * DEG, 50.0), (10.0 * DEG, 21.0)]),
                ],
            ),
            Profile::AircraftWind => (
                [
                    signal(rng, 20.0, &[(2.0, 30.0), (0.5, 11.0), (1.5, 4.0)]),
                    signal(rng, 0.0, &[(0.5, 17.0), (1.0, 2.7)]),
                    signal(rng, 0.0, &[(1.0, 23.0), (0.7, 3.3)]),
                ],
                [
                    signal(rng, 0.0, &[(25.0 * DEG, 40.0), (3.0 * DEG, 1.7)]),
                    signal(rng, 5.0 * DEG, &[(5.0 * DEG, 25.0), (2.0 * DEG, 2.9)]),
                    signal(rng, psi0, &[(90.0 * DEG, 80.0), (10.0 * DEG, 19.0)]),
                ],
            ),
            Profile::Aircraft => (
                [
                    signal(rng, 20.0, &[(2.0, 30.0), (0.5, 11.0)]),
                    signal(rng, 0.0, &[(0.5, 17.0)]),
                    signal(rng, 0.0, &[(1.0, 23.0)]),
                ],
                [
                    signal(rng, 0.0, &[(25.0 * DEG, 40.0), (3.0 * DEG, 7.0)]),
                    signal(rng, 5.0 * DEG, &[(5.0 * DEG, 25.0), (1.0 * DEG, 5.0)]),
                    signal(rng, psi0, &[(90.0 * DEG, 80.0), (10.0 * DEG, 19.0)]),
                ],
            ),
        };
        Self {
            profile,
            gravity: G0,
            vel,
            att,
        }
    }

    /// State and ideal IMU output at time `t`.
    pub fn at(&self, t: f64) -> Truth {
        let [su, sv, sw] = &self.vel;
        let [sphi, sth, spsi] = &self.att;
        let (u, v, w) = (su.value(t), sv.value(t), sw.value(t));
        let (du, dv, dw) = (su.rate(t), sv.rate(t), sw.rate(t));
        let (phi, th, psi) = (sphi.value(t), sth.value(t), spsi.value(t));
        let (dphi, dth, dpsi) = (sphi.rate(t), sth.rate(t), spsi.rate(t));
        let (sp, cp) = (libm::sin(phi), libm::cos(phi));
        let (st, ct) = (libm::sin(th), libm::cos(th));
        let p = dphi - dpsi * st;
        let q = dth * cp + dpsi * ct * sp;
        let r = -dth * sp + dpsi * ct * cp;
        let g = self.gravity;
        let ax = du - (v * r - w * q - g * st);
        let ay = dv - (-u * r + w * p + g * ct * sp);
        let az = dw - (u * q - v * p + g * ct * cp);
        Truth {
            state: [
                u,
                v,
                w,
                imu_fdi::math::wrap_pi_f64(phi),
                th,
                imu_fdi::math::wrap_pi_f64(psi),
            ],
            imu: [ax, ay, az, p, q, r],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use imu_fdi::model::{ImuVec, StateVec, VehicleModel};
    use rand::SeedableRng;

    #[test]
    fn imu_truth_is_consistent_with_the_filter_model() {
        for profile in [Profile::Auv, Profile::Aircraft, Profile::AircraftWind] {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
            let traj = Trajectory::new(profile, &mut rng);
            let model = VehicleModel::<f64>::default();
            let mut x = StateVec::from(traj.at(0.0).state);
            let dt = 0.001;
            for k in 0..60_000 {
                // Input at the step midpoint: the model holds it over the step.
                let u = ImuVec::from(traj.at((k as f64 + 0.5) * dt).imu);
                x = model.step(&x, &u, dt).unwrap();
            }
            let truth = StateVec::from(traj.at(60.0).state);
            let mut err = x - truth;
            err[5] = imu_fdi::math::wrap_pi_f64(err[5]);
            assert!(err.amax() < 2e-3, "{profile:?}: drift {err}");
        }
    }
}

//! The simulation loop: trajectory → IMU with errors and faults → aiding.

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use imu_fdi::math::wrap_pi_f64;
use imu_fdi::model::{AidingKind, MeasurementModel, StateVec};

use crate::fault::FaultKind;
use crate::imu_model::SimImu;
use crate::scenario::Scenario;
use crate::trajectory::{Trajectory, Truth};

/// One IMU period of simulated data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimSample {
    /// Time, s.
    pub t: f64,
    /// Time since the previous sample (the monitor's measured `dt`), s.
    pub dt: f64,
    /// Truth.
    pub truth: Truth,
    /// Additive fault injected on each channel.
    pub fault: [f64; 6],
    /// Which channels have any fault (additive or hardware) active.
    pub fault_active: [bool; 6],
    /// The IMU sample, or `None` when it was lost (dropout).
    pub imu: Option<[f64; 6]>,
    /// Aiding values `[vel×3, φ, θ, ψ]`.
    pub aiding: [f64; 6],
    /// Which aiding channels arrived in this period.
    pub aiding_available: [bool; 6],
    /// True IMU bias (turn-on + random walk) at this sample.
    pub imu_bias: [f64; 6],
}

/// Deterministic simulator of one scenario run.
///
/// Three independent random streams (trajectory, IMU errors, aiding noise)
/// are derived from the seed, so changing a fault table does not change the
/// noise a run sees.
#[derive(Debug, Clone)]
pub struct Simulator {
    scenario: Scenario,
    trajectory: Trajectory,
    imu: SimImu,
    rng_imu: Xoshiro256PlusPlus,
    rng_aid: Xoshiro256PlusPlus,
    k: u64,
    n: u64,
    vel_every: u64,
    att_every: u64,
    last_output: [f64; 6],
    meas: MeasurementModel<f64>,
}

impl Simulator {
    /// A run of `scenario` with `seed`.
    pub fn new(scenario: &Scenario, seed: u64) -> Self {
        let mut rng_traj = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x7472_616a);
        let mut rng_imu = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x696d_7500);
        let rng_aid = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6169_6400);
        let trajectory = Trajectory::new(scenario.profile, &mut rng_traj);
        let imu = SimImu::new(&scenario.imu_errors, scenario.imu_rate_hz, &mut rng_imu);
        let every = |hz: f64| {
            if hz > 0.0 {
                libm::round(scenario.imu_rate_hz / hz).max(1.0) as u64
            } else {
                u64::MAX
            }
        };
        Self {
            n: libm::round(scenario.duration_s * scenario.imu_rate_hz) as u64,
            vel_every: every(scenario.aiding.vel_rate_hz),
            att_every: every(scenario.aiding.att_rate_hz),
            scenario: scenario.clone(),
            trajectory,
            imu,
            rng_imu,
            rng_aid,
            k: 0,
            last_output: [0.0; 6],
            meas: MeasurementModel::new(scenario.aiding.kind),
        }
    }

    /// The scenario being run.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Number of samples in the run.
    pub fn len(&self) -> u64 {
        self.n
    }

    /// True for an empty run.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    fn gauss(&mut self) -> f64 {
        StandardNormal.sample(&mut self.rng_aid)
    }

    fn apply_hardware(&mut self, t: f64, truth: &Truth, sample: &mut [f64; 6]) -> bool {
        let mut present = true;
        let rate = self.scenario.imu_rate_hz;
        for r in self
            .scenario
            .faults
            .iter()
            .filter(|r| r.is_hardware() && r.active(t))
        {
            let Some(v) = sample.get_mut(r.channel) else {
                continue;
            };
            let last = self.last_output.get(r.channel).copied().unwrap_or(0.0);
            let gyro = r.channel >= 3;
            let spec = if gyro {
                self.scenario.imu_errors.gyro
            } else {
                self.scenario.imu_errors.accel
            };
            match r.kind {
                FaultKind::Stuck => *v = last,
                FaultKind::Dropout => present = false,
                FaultKind::Clip(level) => *v = v.clamp(-level, level),
                FaultKind::Spikes(amp) if spike_phase(t - r.start) < 0.03 => *v += amp,
                FaultKind::NoiseIncrease(factor) => {
                    let extra = spec.noise_density
                        * libm::sqrt(rate)
                        * libm::sqrt((factor * factor - 1.0).max(0.0));
                    let n: f64 = StandardNormal.sample(&mut self.rng_imu);
                    *v += extra * n;
                }
                FaultKind::ScaleFactor(s) => {
                    *v += s * truth.imu.get(r.channel).copied().unwrap_or(0.0)
                }
                _ => {}
            }
        }
        present
    }
}

impl Iterator for Simulator {
    type Item = SimSample;

    fn next(&mut self) -> Option<SimSample> {
        if self.k >= self.n {
            return None;
        }
        let rate = self.scenario.imu_rate_hz;
        let t = self.k as f64 / rate;
        let mut truth = self.trajectory.at(t);
        if self.k > 0 {
            // A real IMU outputs the mean of its signal over the sample
            // period (decimation filter), and the filters integrate that
            // sample over the same period: an instantaneous end-of-period
            // value would put a systematic ½·u̇·dt into every step (0.2 °/s
            // in S3's gusts). Simpson's rule over [t − dt, t].
            let early = self.trajectory.at(t - 1.0 / rate).imu;
            let mid = self.trajectory.at(t - 0.5 / rate).imu;
            let end = truth.imu;
            truth.imu = core::array::from_fn(|i| {
                (early.get(i).copied().unwrap_or(0.0)
                    + 4.0 * mid.get(i).copied().unwrap_or(0.0)
                    + end.get(i).copied().unwrap_or(0.0))
                    / 6.0
            });
        }
        let fault = self.scenario.fault_at(t);
        let fault_active = core::array::from_fn(|c| self.scenario.fault_active(c, t));
        let mut sample = self.imu.measure(&truth.imu, &fault, &mut self.rng_imu);
        let present = self.apply_hardware(t, &truth, &mut sample);
        if present {
            self.last_output = sample;
        }
        let mut aiding = [0.0; 6];
        let mut avail = [false; 6];
        // Aiding describes the vehicle `delay_s` ago.
        let seen = if self.scenario.aiding.delay_s > 0.0 {
            self.trajectory
                .at((t - self.scenario.aiding.delay_s).max(0.0))
        } else {
            truth
        };
        if self.k.is_multiple_of(self.vel_every) {
            let x = StateVec::from(seen.state);
            let v = match self.scenario.aiding.kind {
                AidingKind::DvlCompass => [seen.state[0], seen.state[1], seen.state[2]],
                AidingKind::GnssAttitude => {
                    let z = self.meas.predict(&x, &nalgebra::Vector3::zeros());
                    [z[0], z[1], z[2]]
                }
            };
            let s = self.scenario.aiding.vel_sigma;
            for i in 0..3 {
                let n = self.gauss();
                if let (Some(a), Some(ok), Some(vi)) =
                    (aiding.get_mut(i), avail.get_mut(i), v.get(i))
                {
                    *a = vi + s * n;
                    *ok = true;
                }
            }
        }
        if self.k.is_multiple_of(self.att_every) {
            let sig = self.scenario.aiding.att_sigma;
            for i in 0..3 {
                let n = self.gauss();
                if let (Some(a), Some(ok)) = (aiding.get_mut(3 + i), avail.get_mut(3 + i)) {
                    let offset = if i == 2 {
                        self.scenario.aiding.heading_offset_rad
                    } else {
                        0.0
                    };
                    *a = wrap_pi_f64(
                        seen.state.get(3 + i).copied().unwrap_or(0.0)
                            + offset
                            + sig.get(i).copied().unwrap_or(0.0) * n,
                    );
                    *ok = true;
                }
            }
        }
        self.k += 1;
        Some(SimSample {
            t,
            dt: 1.0 / rate,
            truth,
            fault,
            fault_active,
            imu: present.then_some(sample),
            aiding,
            aiding_available: avail,
            imu_bias: self.imu.bias(),
        })
    }
}

/// `t mod 0.5 s` for t ≥ 0, without `f64 %` (a 3 KB software `fmod` on the
/// Cortex-M4F's soft double precision).
fn spike_phase(t: f64) -> f64 {
    t - libm::floor(t * 2.0) * 0.5
}

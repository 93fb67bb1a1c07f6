//! The optimal two-stage UKF (OTSUKF) as a monitor: joint state and IMU-fault
//! estimation, the corrected IMU sample, and a per-channel decision from the
//! fault estimate and its variance.

use nalgebra::Vector3;

use super::align::align_state;
use super::input::{check_period, in_range, lever_arm_rates, next_phase, usable_aiding, Period};
use super::{
    ChannelState, ConfigError, Health, OtsukfDetail, OtsukfReport, Phase, UkfMonitorConfig,
};
use crate::filter::{Gate, Otsukf, UkfError};
use crate::math::Real;
use crate::model::{
    discrete_process_noise_structured, ImuVec, Mat6, Measurement, MeasurementModel, ModelError,
    StateVec, VehicleModel, NZ, STATE_ANGLES,
};

const MEAS_ANGLES: [bool; NZ] = [false, false, false, true, true, true];

/// Configuration of [`OtsukfMonitor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtsukfConfig<T> {
    /// Vehicle, sensors, aiding, start-up timing and minimum faults (the
    /// detector fields of the innovation monitor are not used).
    pub base: UkfMonitorConfig<T>,
    /// Random-walk power spectral density of the fault model per channel,
    /// ((m/s²)²/s, (rad/s)²/s): `Q^f = psd · dt` per step. It sets how fast a
    /// fault estimate follows a change (and how noisy it is when quiet).
    pub fault_psd: ImuVec<T>,
    /// Initial fault standard deviation per channel (`P^f₀`).
    pub fault_sigma0: ImuVec<T>,
    /// A channel is declared faulty when `|f̂ − b| ≥ k_on·σ_f` and
    /// `|f̂ − b| ≥ min_fault` (`b` the nominal bias learned at start-up)…
    pub k_on: T,
    /// …and cleared when `|f̂ − b| < k_off·σ_f` or `|f̂ − b| < min_fault/2`.
    pub k_off: T,
    /// Adaptive fault noise: when one update moves a channel's fault
    /// estimate by more than `adapt_k` of its standard deviation (the fault
    /// filter is being pulled by a change it was not expecting), that
    /// channel's `Q^f` is multiplied by its `adapt_gain` for `adapt_hold_s`, so a
    /// step is followed in a few aiding periods instead of being smoothed by
    /// a random walk tuned for a quiet bias. A gain of 1 disables it on that
    /// channel.
    pub adapt_k: T,
    /// See [`adapt_k`](Self::adapt_k).
    pub adapt_gain: ImuVec<T>,
    /// See [`adapt_k`](Self::adapt_k).
    pub adapt_hold_s: T,
    /// With `Some(l)`, the adaptation is also held while a monitored
    /// channel's `|f̂ − b| ≥ l·σ_f`, so a fault that keeps changing (a slow
    /// sine) is followed with the faster random walk all the time it is
    /// present, not only after sudden moves. It pays where the aiding is
    /// fast and precise (\[OTS\]'s setting: 100 Hz, 0.01°); with 10 Hz GNSS
    /// the extra fault-estimate noise costs more than the lag it saves
    /// (measured on S2/S3, see the README), hence `None` by default.
    pub adapt_level: Option<T>,
}

impl<T: Real> OtsukfConfig<T> {
    /// Defaults around an innovation-monitor configuration: fault random walk
    /// of 0.05 (m/s²)²/s and (0.5 °/s)²/s — a step is followed within about a
    /// second at 10 Hz aiding — initial fault σ of 1 m/s² and 1 °/s, and a
    /// 4σ / 2σ hysteresis (4σ: the 0.3 m/s² step of S2 is flagged while
    /// S2, S3 and 24 fault-free hours raise no false flag). The `Q^f`
    /// adaptation (×10 for 0.3 s after a 3σ move) is on for the
    /// accelerometers only: with 10 Hz GNSS or 5 Hz DVL/compass aiding it
    /// measured no gain on the gyro channels of S2 and S3 and 2 % more
    /// fault-free noise (README, OTSUKF).
    pub fn from_base(base: UkfMonitorConfig<T>) -> Self {
        let deg = core::f64::consts::PI / 180.0;
        let ga = T::lit(0.05);
        let gg = T::lit((0.5 * deg) * (0.5 * deg));
        Self {
            base,
            fault_psd: ImuVec::new(ga, ga, ga, gg, gg, gg),
            fault_sigma0: ImuVec::new(
                T::one(),
                T::one(),
                T::one(),
                T::lit(deg),
                T::lit(deg),
                T::lit(deg),
            ),
            k_on: T::lit(4.0),
            k_off: T::lit(2.0),
            adapt_k: T::lit(3.0),
            adapt_gain: ImuVec::new(
                T::lit(10.0),
                T::lit(10.0),
                T::lit(10.0),
                T::one(),
                T::one(),
                T::one(),
            ),
            adapt_hold_s: T::lit(0.3),
            adapt_level: None,
        }
    }

    /// Checks every field, the base configuration's included; the error
    /// names the first offending field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.base.validate()?;
        let pos = |v: T| v.finite() && v > T::zero();
        let positive: [(&'static str, bool); 6] = [
            ("fault_psd", self.fault_psd.iter().all(|v| pos(*v))),
            ("fault_sigma0", self.fault_sigma0.iter().all(|v| pos(*v))),
            ("k_on", pos(self.k_on)),
            ("k_off", pos(self.k_off)),
            ("adapt_k", pos(self.adapt_k)),
            ("adapt_level", self.adapt_level.is_none_or(pos)),
        ];
        if let Some(&(field, _)) = positive.iter().find(|(_, ok)| !ok) {
            return Err(ConfigError::NonPositive(field));
        }
        let in_range: [(&'static str, bool); 3] = [
            // Hysteresis: the clear threshold may not exceed the set one.
            ("k_off", self.k_off <= self.k_on),
            (
                "adapt_gain",
                self.adapt_gain.iter().all(|g| g.finite() && *g >= T::one()),
            ),
            (
                "adapt_hold_s",
                self.adapt_hold_s.finite() && self.adapt_hold_s >= T::zero(),
            ),
        ];
        if let Some(&(field, _)) = in_range.iter().find(|(_, ok)| !ok) {
            return Err(ConfigError::OutOfRange(field));
        }
        Ok(())
    }
}

/// The optimal two-stage UKF (OTSUKF) monitor (\[OTS\], SPEC §6) for one IMU.
///
/// Per step: input checks → time update with the corrected input
/// `u_m − f̂` (Jacobians at the full estimate) → two-stage measurement
/// update → outputs. After alignment and a convergence period the fault
/// estimate averaged over a learning period is taken as the nominal bias
/// `b` (SPEC §8a); from then on a channel whose `f̂ − b` leaves its
/// hysteresis band is reported faulty. The corrected sample always removes
/// the whole `f̂`.
#[derive(Debug, Clone)]
pub struct OtsukfMonitor<T> {
    cfg: OtsukfConfig<T>,
    model: VehicleModel<T>,
    meas: MeasurementModel<T>,
    filter: Otsukf<T, 6, 13, 6>,
    gate: Gate<T, NZ>,
    phase: Phase,
    phase_time: T,
    nominal: ImuVec<T>,
    /// Samples averaged into `nominal` so far during learning.
    learn_count: T,
    latched: [i8; 6],
    boost: ImuVec<T>,
}

impl<T: Real> OtsukfMonitor<T> {
    /// A monitor waiting for its first attitude measurement.
    pub fn new(cfg: OtsukfConfig<T>) -> Result<Self, ConfigError> {
        cfg.validate()?;
        let b = &cfg.base;
        let p0 = Mat6::from_diagonal(&b.initial_sigma.component_mul(&b.initial_sigma));
        let pf0 = Mat6::from_diagonal(&cfg.fault_sigma0.component_mul(&cfg.fault_sigma0));
        let qf = Mat6::from_diagonal(&(cfg.fault_psd * b.imu_period));
        let mut filter = Otsukf::new(
            StateVec::zeros(),
            p0,
            ImuVec::zeros(),
            pf0,
            qf,
            &b.sigma,
            STATE_ANGLES,
        )
        .ok_or(ConfigError::SigmaParams)?;
        filter.set_min_variance(StateVec::from_element(T::lit(1e-14)));
        let mut meas = MeasurementModel::new(b.aiding);
        meas.lever_arm = Vector3::new(b.lever_arm[0], b.lever_arm[1], b.lever_arm[2]);
        Ok(Self {
            model: VehicleModel {
                gravity: b.gravity,
                cos_pitch_min: b.cos_pitch_min,
            },
            meas,
            filter,
            gate: Gate::new(b.gate_sigma, b.gate_max_rejections),
            phase: Phase::Aligning,
            phase_time: T::zero(),
            nominal: ImuVec::zeros(),
            learn_count: T::zero(),
            latched: [0; 6],
            boost: ImuVec::zeros(),
            cfg,
        })
    }

    /// The OTSUKF filter.
    pub fn filter(&self) -> &Otsukf<T, 6, 13, 6> {
        &self.filter
    }

    /// One monitor period with the measured `dt` and whatever aiding
    /// arrived. Never panics; anomalies are reported in the health flags.
    #[inline(never)] // one copy in the image, not one per caller (issue 17)
    pub fn step(&mut self, imu: &ImuVec<T>, dt: T, aiding: &Measurement<T>) -> OtsukfReport<T> {
        let b = self.cfg.base;
        let mut health = Health::default();
        let in_range = in_range(imu, &b.full_scale);
        health.input_invalid = !in_range;
        // Unlike the innovation monitor, a gap is not bridged with a capped
        // period: the two-stage filter only predicts over normal periods.
        let dt_ok = matches!(check_period(dt, b.imu_period), Period::Valid(_));
        health.dt_out_of_range = !dt_ok;
        let u_corr = imu - self.filter.fault();
        let omega = lever_arm_rates(in_range, &u_corr);
        if self.phase == Phase::Aligning {
            self.try_align(aiding, &omega);
            return self.compose(imu, health, false);
        }
        if in_range && dt_ok {
            match self.predict(&u_corr, dt) {
                Ok(reset) => health.covariance_reset |= reset,
                Err(ModelError::PitchSingularity) => health.pitch_singular = true,
                Err(ModelError::NonFinite) => health.input_invalid = true,
            }
            self.phase_time += dt;
        }
        let mut updated = false;
        if aiding.any() && !health.pitch_singular {
            let available = usable_aiding(aiding);
            let x_pred = self.filter.state();
            let hjac = self.meas.jacobian(&x_pred, &omega);
            let r = b.meas_sigma.component_mul(&b.meas_sigma);
            let meas = self.meas;
            let prior_var = self.filter.fault_covariance().diagonal();
            let prior_fault = *self.filter.fault();
            let (order, nonlinear) = self.meas.split();
            match self.filter.update_split(
                &order,
                nonlinear,
                &aiding.z,
                &available,
                |s| Ok::<_, ModelError>(meas.predict(s, &omega)),
                &hjac,
                &r,
                &MEAS_ANGLES,
                &mut self.gate,
            ) {
                Ok(out) => {
                    updated = true;
                    // The correction K^f r^f has covariance P^f⁻ − P^f⁺ under
                    // the fault model: standardise it by that.
                    let moved = self.filter.fault() - prior_fault;
                    let spread = prior_var - self.filter.fault_covariance().diagonal();
                    for ((bst, m), v) in self.boost.iter_mut().zip(moved.iter()).zip(spread.iter())
                    {
                        let s = v.max(T::zero()).sqrt_fast();
                        if s > T::zero() && m.abs() > self.cfg.adapt_k * s {
                            *bst = self.cfg.adapt_hold_s;
                        }
                    }
                    health.aiding_rejected =
                        out.bias_free.diag.iter().any(|d| d.available && !d.fused);
                    health.covariance_reset |= out.bias_free.covariance_reset.is_some();
                }
                Err(_) => health.covariance_reset = true,
            }
        }
        self.advance_phase();
        if self.phase == Phase::Monitoring {
            self.decide();
        }
        self.compose(imu, health, updated)
    }

    #[inline(never)] // own stack frame and one copy (issue 17)
    fn try_align(&mut self, aiding: &Measurement<T>, omega: &Vector3<T>) {
        let Some(x) = align_state(&self.model, &self.meas, aiding, omega) else {
            return;
        };
        let s = self.cfg.base.initial_sigma;
        self.filter
            .reset_state(x, Mat6::from_diagonal(&s.component_mul(&s)));
        self.phase = Phase::Converging;
        self.phase_time = T::zero();
    }

    #[inline(never)] // own stack frame and one copy (issue 17)
    fn predict(&mut self, u_corr: &ImuVec<T>, dt: T) -> Result<bool, ModelError> {
        let x = self.filter.state();
        let trig = self.model.attitude_trig(&x)?;
        let (a, b) = self.model.jacobians(&x, u_corr, &trig);
        let qx = discrete_process_noise_structured(&a, &b, &self.cfg.base.process_noise, dt);
        let ad = a * dt;
        let bdt = b * dt;
        // Φ = I + A dt + (A dt)²/2 and, for x_{k+1} = step(x, u_m − f) by
        // the midpoint rule, F = ∂/∂f = −(I + A dt/2) B dt; so
        // Φ V + F = V − B dt + A dt (V + (A dt V − B dt)/2): two products
        // with A's block structure instead of three dense ones.
        let coupling = |v: &Mat6<T>| {
            let t = VehicleModel::mul_state_jacobian(&ad, v);
            let inner = v + (t - bdt) * T::lit(0.5);
            v - bdt + VehicleModel::mul_state_jacobian(&ad, &inner)
        };
        let gain = self.boost.zip_map(&self.cfg.adapt_gain, |b, g| {
            if b > T::zero() {
                g
            } else {
                T::one()
            }
        });
        let qf = self.cfg.fault_psd.component_mul(&gain) * dt;
        self.boost = self.boost.map(|b| (b - dt).max(T::zero()));
        self.filter.set_fault_noise(Mat6::from_diagonal(&qf));
        let model = self.model;
        let u = *u_corr;
        match self.filter.predict_split(
            &VehicleModel::<T>::SPLIT_ORDER,
            VehicleModel::<T>::NONLINEAR_STATES,
            |s| model.step(s, &u, dt),
            |d| model.step_deviation(d, &u, dt),
            coupling,
            &qx,
        ) {
            Ok(()) => Ok(false),
            Err(UkfError::CovarianceReset(_)) => Ok(true),
            Err(UkfError::Model(e)) => Err(e),
            Err(_) => Err(ModelError::NonFinite),
        }
    }

    fn advance_phase(&mut self) {
        let b = &self.cfg.base;
        if self.phase == Phase::Learning {
            // The nominal bias (SPEC §8a): what the filter attributes to
            // the IMU once converged, averaged over the learning period
            // because a single sample of f̂ carries its whole estimation
            // noise into every later fault estimate. Running mean, so
            // the f32 sum cannot swamp the increments.
            self.learn_count += T::one();
            let n = self.learn_count;
            self.nominal += (self.filter.fault() - self.nominal) / n;
        }
        match next_phase(self.phase, self.phase_time, b.converge_s, b.learn_s) {
            Some(Phase::Learning) => {
                self.phase = Phase::Learning;
                self.nominal = ImuVec::zeros();
                self.learn_count = T::zero();
            }
            Some(Phase::Monitoring) => {
                // Capped like the innovation monitor's: anything larger
                // is a fault present from power-on.
                let cap = T::lit(20.0);
                self.nominal = self
                    .nominal
                    .zip_map(&b.min_fault, |f, m| f.max(-m * cap).min(m * cap));
                self.latched = [0; 6];
                self.phase = Phase::Monitoring;
            }
            _ => {}
        }
    }

    /// The per-channel decision on `f̂ − b`, and the `adapt_level` hold of
    /// the `Q^f` boost, which tests the same standardised estimate.
    fn decide(&mut self) {
        let f = self.filter.fault() - self.nominal;
        let pf = self.filter.fault_covariance();
        let hold = self.cfg.adapt_hold_s;
        for ((j, l), bst) in self
            .latched
            .iter_mut()
            .enumerate()
            .zip(self.boost.iter_mut())
        {
            let (Some(fj), Some(var), Some(min)) = (
                f.get(j).copied(),
                pf.get((j, j)).copied(),
                self.cfg.base.min_fault.get(j).copied(),
            ) else {
                continue;
            };
            let sigma = var.max(T::zero()).sqrt_fast();
            let mag = fj.abs();
            if matches!(self.cfg.adapt_level, Some(level) if mag >= level * sigma) {
                *bst = hold;
            }
            if *l == 0 {
                if mag >= self.cfg.k_on * sigma && mag >= min {
                    *l = if fj > T::zero() { 1 } else { -1 };
                }
            } else if mag < self.cfg.k_off * sigma
                || mag < min * T::lit(0.5)
                || (fj > T::zero()) != (*l > 0)
            {
                *l = 0;
            }
        }
    }

    #[inline(never)] // own stack frame and one copy (issue 17)
    fn compose(&self, imu: &ImuVec<T>, health: Health, updated: bool) -> OtsukfReport<T> {
        let fault = *self.filter.fault();
        let pf = self.filter.fault_covariance();
        let px = self.filter.state_variance();
        let status = if self.phase == Phase::Monitoring {
            self.latched.map(|l| match l {
                1 => ChannelState::FaultPositive,
                -1 => ChannelState::FaultNegative,
                _ => ChannelState::Healthy,
            })
        } else {
            [ChannelState::NotMonitored; 6]
        };
        OtsukfReport {
            phase: self.phase,
            status,
            fault_estimate: fault - self.nominal,
            nominal_bias: self.nominal,
            corrected_imu: imu - fault,
            state: self.filter.state(),
            state_sigma: px.map(|v| v.max(T::zero()).sqrt_fast()),
            health,
            updated,
            detail: OtsukfDetail {
                fault_sigma: pf.diagonal().map(|v| v.max(T::zero()).sqrt_fast()),
                total_bias: fault,
            },
        }
    }
}

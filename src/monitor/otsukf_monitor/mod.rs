//! The optimal two-stage UKF (OTSUKF) as a monitor: joint state and IMU-fault
//! estimation, the corrected IMU sample, and a per-channel decision from the
//! fault estimate and its variance.

use nalgebra::Vector3;

use super::align::align_state;
use super::input::{
    check_period, in_range, lever_arm_rates, next_phase, saturated, stand_in, usable_aiding,
    FrozenCheck, ImuGap, Period,
};
use super::realign::AidingTrack;
use super::stale_aiding::{screened_aiding, RepeatedAiding};
use super::{ChannelState, ConfigError, Health, OtsukfDetail, OtsukfReport, Phase};
use crate::filter::{Gate, Otsukf, UkfError};
use crate::math::Real;
use crate::model::{
    discrete_process_noise_structured, ImuVec, Mat6, Measurement, MeasurementModel, ModelError,
    StateVec, VehicleModel, NZ, STATE_ANGLES,
};

#[cfg(feature = "aiding-estimators")]
mod attitude_lag;
#[cfg(not(feature = "aiding-estimators"))]
mod attitude_lag_off;
#[cfg(any(feature = "attitude-rate-test", feature = "velocity-increment-test"))]
mod block_tests;
#[cfg(not(any(feature = "attitude-rate-test", feature = "velocity-increment-test")))]
mod block_tests_off;
mod config;
mod imu_gap;
mod inflation;
mod recover;
mod velocity_lag;

use inflation::Inflation;
use velocity_lag::{VelocityLag, LAG_RING};

pub use config::OtsukfConfig;

/// Statistics pause after an unusable or saturated sample, s.
const INPUT_HOLDOFF_S: f64 = 0.5;

const MEAS_ANGLES: [bool; NZ] = [false, false, false, true, true, true];

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
    /// Channels whose learnt nominal bias was beyond the turn-on bound at
    /// monitoring start (a power-up fault, judged on the whole learning
    /// span, not on the present motion).
    power_up: [bool; 6],
    /// How long each channel has been latched, s (0 when it is not).
    flagged_for: [T; 6],
    boost: ImuVec<T>,
    /// Gate rejections and last fusion per aiding channel (re-alignment).
    track: AidingTrack<T>,
    /// Repeated samples (frozen output).
    frozen: FrozenCheck<T>,
    /// Time the IMU gave the filter nothing to follow (`ImuGap`), and
    /// the triads (velocity, attitude) to re-align after a gap (`imu_gap.rs`).
    imu_gap: ImuGap<T>,
    /// The aiding's previous values (`stale_aiding.rs`).
    repeated: RepeatedAiding<T>,
    gap_realign: [bool; 2],
    /// Time left during which nothing is learned and no new fault is
    /// declared: after an unusable or saturated sample, a re-alignment.
    holdoff: T,
    /// Learned measurement-noise inflation per aiding component.
    inflation: Inflation<T>,
    /// The predicted velocity's recent changes (velocity aiding latency).
    vel_lag: VelocityLag<T>,
    /// The velocity aiding's latency in IMU periods (0: fused on arrival).
    lag_steps: usize,
    /// The attitude aiding's latency: its ring, estimate and lag in use.
    #[cfg(feature = "aiding-estimators")]
    att_lag: attitude_lag::AttitudeLag<T>,
    /// The gyro/attitude-aiding block test (`base.attitude_rate`).
    #[cfg(feature = "attitude-rate-test")]
    att_rate: crate::monitor::block_test::attitude_rate::AttitudeRate<T>,
    /// The accelerometer/GNSS-velocity block test
    /// (`base.velocity_increment`).
    #[cfg(feature = "velocity-increment-test")]
    vel_inc: crate::monitor::block_test::velocity_increment::VelocityIncrement<T>,
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
            power_up: [false; 6],
            flagged_for: [T::zero(); 6],
            boost: ImuVec::zeros(),
            track: AidingTrack::new(),
            frozen: FrozenCheck::new(),
            imu_gap: ImuGap::default(),
            repeated: RepeatedAiding::new(),
            gap_realign: [false; 2],
            holdoff: T::zero(),
            inflation: Inflation::new(),
            vel_lag: VelocityLag::new(),
            lag_steps: cfg.lag_steps(),
            #[cfg(feature = "aiding-estimators")]
            att_lag: attitude_lag::AttitudeLag::new(cfg.attitude_lag_steps()),
            #[cfg(feature = "attitude-rate-test")]
            att_rate: crate::monitor::block_test::attitude_rate::AttitudeRate::for_config(b),
            #[cfg(feature = "velocity-increment-test")]
            vel_inc: crate::monitor::block_test::velocity_increment::VelocityIncrement::for_config(
                b,
            ),
            cfg,
        })
    }

    /// The OTSUKF filter.
    pub fn filter(&self) -> &Otsukf<T, 6, 13, 6> {
        &self.filter
    }

    /// One monitor period with the measured `dt` and whatever aiding
    /// arrived. Never panics; anomalies are reported in the health flags
    /// (what each one does and how it clears: `docs/recovery.md`).
    #[inline(never)] // one copy in the image, not one per caller (issue 17)
    pub fn step(&mut self, imu: &ImuVec<T>, dt: T, aiding: &Measurement<T>) -> OtsukfReport<T> {
        let b = self.cfg.base;
        let mut health = Health::default();
        let in_range = in_range(imu, &b.full_scale);
        health.input_invalid = !in_range;
        health.frozen = self.frozen.update(imu, in_range, b.frozen_samples);
        health.saturated = in_range && saturated(imu, &b.full_scale);
        // Unlike the innovation monitor, a gap is not bridged with a capped
        // period: the two-stage filter only predicts over normal periods.
        let period = check_period(dt, b.imu_period);
        let dt_ok = matches!(period, Period::Valid(_));
        health.dt_out_of_range = !dt_ok;
        let elapsed = match period {
            Period::Valid(d) | Period::Long(d) => d,
            Period::Invalid => T::zero(),
        };
        self.track.elapse(elapsed);
        self.holdoff = (self.holdoff - elapsed).max(T::zero());
        // The flags' ages serve only the block tests' end-of-fault rule
        // (`recover.rs`): not kept in images without them.
        if cfg!(any(
            feature = "attitude-rate-test",
            feature = "velocity-increment-test"
        )) {
            for (a, l) in self.flagged_for.iter_mut().zip(self.latched.iter()) {
                *a = if *l != 0 { *a + elapsed } else { T::zero() };
            }
        }
        // Aiding outside its physical range, or repeating itself, is never used.
        let aiding = &screened_aiding(aiding, b.max_aiding_speed, &mut self.repeated, &mut health);
        let usable = in_range && !health.frozen;
        let bridged = if dt_ok { Some(dt) } else { None };
        if cfg!(feature = "imu-gap-recovery")
            && self
                .imu_gap
                .back_after_gap(dt, bridged, usable, b.imu_period)
        {
            self.hold_after_gap();
        }
        // A short run of unusable samples is bridged with a stand-in, the
        // statistics running on (the innovation monitor's reasons: `step`
        // there); a longer one holds them.
        let bridge = self.imu_gap.bridges(usable, b.imu_period);
        if (!usable && !bridge) || health.saturated {
            self.holdoff = self.holdoff.max(T::lit(INPUT_HOLDOFF_S));
        }
        // Through an invalid or frozen sample the last good one stands in
        // (as in the innovation monitor): the state keeps moving with the
        // vehicle instead of freezing.
        let u_meas = if usable {
            *imu
        } else {
            stand_in(imu, self.frozen.last(), &b.full_scale)
        };
        let u_corr = u_meas - self.filter.fault();
        let omega = lever_arm_rates(usable, &u_corr);
        if self.phase == Phase::Aligning {
            self.try_align(aiding, &omega);
            return self.compose(&u_meas, health, false);
        }
        let v_before = self.predicted_velocity(&omega);
        let x_before = self.att_lag_before();
        let mut propagated = false;
        if dt_ok {
            if bridge {
                self.blocks_sample(&u_meas, dt, true);
            } else {
                self.blocks_sample(imu, dt, usable);
            }
            match self.predict(&u_corr, dt) {
                Ok(reset) => {
                    health.covariance_reset |= reset;
                    propagated = true;
                }
                Err(ModelError::PitchSingularity) => health.pitch_singular = true,
                Err(ModelError::NonFinite) => health.input_invalid = true,
            }
            self.phase_time += dt;
        }
        if self.lag_steps > 0 {
            let dv = match (propagated, v_before, self.predicted_velocity(&omega)) {
                (true, Some(a), Some(b)) => b - a + self.fault_velocity_rate() * dt,
                _ => Vector3::zeros(),
            };
            self.vel_lag.push(dv);
        }
        self.att_lag_period(&x_before, propagated, dt);
        // Through ±90°: the attitude is re-aligned from the aiding.
        if health.pitch_singular && aiding.any() && self.recover_singular(aiding, &omega) {
            health.mark_realigned(false);
        }
        let mut updated = false;
        if aiding.any() && !health.pitch_singular {
            // The velocity and attitude brought to now before anything
            // compares them with the state: re-aligned to a late value in
            // every turn, the state would be pulled back by the lag.
            self.att_lag_epoch(aiding);
            let mut present = self.bring_attitude_forward(&self.bring_velocity_forward(aiding));
            let after_gap = if cfg!(feature = "imu-gap-recovery") {
                self.realign_after_gap(&present, &omega)
            } else {
                None
            };
            if let Some(rest) = after_gap {
                health.mark_realigned(true);
                present = rest;
            }
            let (present, realigned) = self.realign_outliers(&present, &omega);
            if realigned {
                health.mark_realigned(true);
                self.blocks_clear();
            }
            if present.any() {
                if let Some(fused) = self.update(&present, &omega, &mut health) {
                    updated = true;
                    // The block tests take the aiding as it arrived (the
                    // velocity test learns its own lag); `fused` says
                    // which channels count.
                    self.blocks_epoch(aiding, &fused);
                    if self.realign_ended(&present, &omega) {
                        health.mark_realigned(false);
                    }
                }
            }
        }
        let quiet = health == Health::default() && self.holdoff <= T::zero();
        if !quiet {
            self.inflation.break_blocks();
        }
        self.advance_phase(quiet);
        if self.phase == Phase::Monitoring {
            self.decide(self.holdoff <= T::zero());
        }
        // An unusable sample is not passed on: the corrected sample is the
        // stand-in the filter used (never NaN).
        let mut r = self.compose(&u_meas, health, updated);
        self.blocks_apply(&mut r);
        r
    }

    /// The two-stage update with the outlier gate; when applied, the
    /// channels it fused.
    #[inline(never)] // own stack frame and one copy (issue 17)
    fn update(
        &mut self,
        aiding: &Measurement<T>,
        omega: &Vector3<T>,
        health: &mut Health,
    ) -> Option<[bool; NZ]> {
        let b = self.cfg.base;
        let available = usable_aiding(aiding);
        let x_pred = self.filter.state();
        let hjac = self.meas.jacobian(&x_pred, omega);
        let mut r = b.meas_sigma.component_mul(&b.meas_sigma);
        for (v, c) in r.iter_mut().zip(self.inflation.factor().iter()) {
            *v *= *c;
        }
        let meas = self.meas;
        let prior_var = self.filter.fault_covariance().diagonal();
        let prior_fault = *self.filter.fault();
        let (order, nonlinear) = self.meas.split();
        let omega = *omega;
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
                // The correction K^f r^f has covariance P^f⁻ − P^f⁺ under
                // the fault model: standardise it by that.
                let moved = self.filter.fault() - prior_fault;
                let spread = prior_var - self.filter.fault_covariance().diagonal();
                for ((bst, m), v) in self.boost.iter_mut().zip(moved.iter()).zip(spread.iter()) {
                    let s = v.max(T::zero()).sqrt_fast();
                    if s > T::zero() && m.abs() > self.cfg.adapt_k * s {
                        *bst = self.cfg.adapt_hold_s;
                    }
                }
                for (i, d) in out.bias_free.diag.iter().enumerate() {
                    if d.available {
                        self.track.record(i, d.fused);
                        health.aiding_rejected |= !d.fused;
                    }
                }
                // Learned on quiet epochs only (no input or aiding flag, no
                // hold-off): a glitch or an outlier cannot inflate `R`.
                let quiet = *health == Health::default() && self.holdoff <= T::zero();
                if self.phase == Phase::Learning && quiet && b.max_innovation_inflation > T::one() {
                    let len = self.cfg.inflation_block;
                    for (i, ((d, rf), a)) in out
                        .bias_free
                        .diag
                        .iter()
                        .zip(out.fault_innovation.iter())
                        .zip(out.fault_innovation_variance.iter())
                        .enumerate()
                    {
                        if d.fused {
                            self.inflation.observe(i, *rf, *a, len);
                        }
                    }
                }
                health.covariance_reset |= out.bias_free.covariance_reset.is_some();
                Some(out.bias_free.diag.map(|d| d.fused))
            }
            Err(_) => {
                health.covariance_reset = true;
                None
            }
        }
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
        self.vel_lag.reset();
        self.att_lag_reset();
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

    /// Learning takes only `quiet` steps (no health flag, no hold-off):
    /// a glitch cannot poison the nominal bias.
    fn advance_phase(&mut self, quiet: bool) {
        let b = &self.cfg.base;
        if self.phase == Phase::Learning && quiet {
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
                self.inflation.reset();
                self.blocks_reset();
            }
            Some(Phase::Monitoring) => {
                // The turn-on bound, as the innovation monitor's: anything
                // larger is a fault present from power-on.
                let bound = b.nominal_bias_bound();
                self.power_up = core::array::from_fn(
                    |j| matches!((self.nominal.get(j), bound.get(j)), (Some(f), Some(m)) if f.abs() > *m),
                );
                self.nominal = self.nominal.zip_map(&bound, |f, m| f.max(-m).min(m));
                self.latched = [0; 6];
                self.phase = Phase::Monitoring;
                // Frozen from here on: a fault cannot raise its own `R`.
                // `max_innovation_inflation` 1 keeps the nominal `R`.
                self.inflation.freeze(b.max_innovation_inflation);
                self.blocks_start();
            }
            _ => {}
        }
    }

    /// The per-channel decision on `f̂ − b`, and the `adapt_level` hold of
    /// the `Q^f` boost, which tests the same standardised estimate. New
    /// faults are declared only when `may_raise` (not during a hold-off);
    /// a declared one clears as usual.
    fn decide(&mut self, may_raise: bool) {
        let f = self.filter.fault() - self.nominal;
        let pf = self.filter.fault_covariance();
        let hold = self.cfg.adapt_hold_s;
        // No new accelerometer flag while the GNSS velocity's acceleration
        // is beyond what the flight has shown healthy (`block_tests.rs`):
        // log171's hardest turn otherwise flagged a_y on every IMU. A
        // power-up fault rests on the learning span's mean, not on the
        // present motion: it is reported at once (log171 from 100 s: 2 s
        // later otherwise).
        let accel_open = !self.blocks_accel_unlearnt();
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
                let open = j >= 3 || accel_open || self.power_up.get(j).copied().unwrap_or(false);
                if may_raise && open && mag >= self.cfg.k_on * sigma && mag >= min {
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
        // In a hold-off no new fault is declared: an unflagged channel is
        // not judged then, and says so ("never silent").
        let unflagged = if self.holdoff > T::zero() {
            ChannelState::NotMonitored
        } else {
            ChannelState::Healthy
        };
        let status = if self.phase == Phase::Monitoring {
            self.latched.map(|l| match l {
                1 => ChannelState::FaultPositive,
                -1 => ChannelState::FaultNegative,
                _ => unflagged,
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
                innovation_inflation: *self.inflation.factor(),
            },
        }
    }
}

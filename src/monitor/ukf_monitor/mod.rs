use nalgebra::Vector3;

use super::align::align_state;
use super::input::{check_period, in_range, lever_arm_rates, saturated, stand_in, ImuGap, Period};
use super::realign::NEVER_FUSED_S;
use super::stale_aiding::{screened_aiding, RepeatedAiding};
use super::{ConfigError, Health, Phase, UkfMonitorConfig, UkfReport};
use crate::detect::{
    paper_matrix, Detector, InnovationWindow, Persistence, Statistic, TTest,
    PAPER_MATRIX_AS_PRINTED, PAPER_MATRIX_CORRECTED,
};
use crate::filter::{Gate, Ukf};
use crate::math::{try_inverse, Real};
use crate::model::{
    AttitudeTrig, ImuVec, Mat6, Measurement, MeasurementModel, ModelError, StateVec, VehicleModel,
    NX, NZ, ROLL, STATE_ANGLES,
};
use crate::stats::normal_upper_quantile;

#[cfg(feature = "attitude-rate-test")]
mod attitude_rate;
#[cfg(not(feature = "attitude-rate-test"))]
mod attitude_rate_off;
mod compose;
mod delay;
mod detection;
mod fault_track;
mod filter_step;
mod heading;
mod history;
mod imu_gap;
#[cfg(feature = "inflation-tracking")]
mod inflation_cover;
mod phase;
#[cfg(feature = "power-up-check")]
mod power_up;
#[cfg(not(feature = "power-up-check"))]
#[path = "power_up_off.rs"]
mod power_up;
mod realign;
#[cfg(feature = "velocity-increment-test")]
mod regrowth;
#[cfg(not(feature = "velocity-increment-test"))]
mod regrowth_off;
mod velocity_delay;
#[cfg(feature = "velocity-increment-test")]
mod velocity_increment;
#[cfg(not(feature = "velocity-increment-test"))]
mod velocity_increment_off;

use delay::DelayEstimator;

/// Default window length (aiding epochs per t-test window).
pub const DEFAULT_WINDOW: usize = 10;
/// Longest aiding latency the state history covers, in IMU periods.
pub const MAX_DELAY_STEPS: usize = 32;
/// A move of the aiding-delay estimate, in IMU periods, away from the lag
/// the nominal bias is being learnt at that restarts learning (see
/// `UkfMonitor::relearn_at`): 0.03 s at 100 Hz.
const DELAY_RELEARN_STEPS: usize = 3;

const MEAS_ANGLES: [bool; NZ] = [false, false, false, true, true, true];

/// The configured window statistic, or the normalised one when the t-tests
/// are not compiled in (feature `t-statistics`; the configuration is then
/// refused with any other, so this only lets the compiler leave them out).
fn statistic_in_use<T>(cfg: &UkfMonitorConfig<T>) -> Statistic {
    if cfg!(feature = "t-statistics") {
        cfg.statistic
    } else {
        Statistic::Normalized
    }
}

/// The UKF innovation monitor (\[UKF\], SPEC §4–6, §8a) for one IMU.
///
/// Call [`step`](Self::step) once per IMU period with the measured `dt` and
/// whatever aiding arrived in that period. `W` is the t-test window length in
/// aiding epochs.
///
/// Per step: input checks → nominal-bias compensation → UKF predict (and the
/// closed-loop fault sensitivity `X = ∂x̂/∂f`) → UKF update with gating →
/// innovation windows → t-tests → decision rule → debounce → estimates.
/// The sensitivity recursion (`X ← ΦX + B·dt` per step, `X ← (I − KH)X` per
/// update) yields each innovation channel's signature row `m_i = −H_i X⁻`:
/// the run-time form of SPEC §5's `M = H (I − Φ(I − KH))⁻¹ G_f`, valid for
/// any aiding rate and subset.
#[derive(Debug, Clone)]
pub struct UkfMonitor<T, const W: usize = DEFAULT_WINDOW> {
    cfg: UkfMonitorConfig<T>,
    model: VehicleModel<T>,
    meas: MeasurementModel<T>,
    ukf: Ukf<T, NX, 13>,
    gate: Gate<T, NZ>,
    /// Consecutive gate rejections per aiding channel.
    rejection_run: [u16; NZ],
    /// Critical value of the window statistic in use (`t_threshold`).
    threshold: T,
    windows: [InnovationWindow<T, W>; NZ],
    since_seen: [T; NZ],
    /// Time since each aiding channel was last fused, s.
    since_fused: [T; NZ],
    sensitivity: Mat6<T>,
    signature: Mat6<T>,
    latest_innovation: ImuVec<T>,
    latest_variance: ImuVec<T>,
    nominal_bias: ImuVec<T>,
    /// A bias beyond the turn-on bound from power-up (`power_up.rs`).
    power_up: power_up::PowerUpCheck<T>,
    learn_clock: T,
    /// Learned variance inflation of each channel's t statistic (≥ 1).
    inflation: [T; NZ],
    /// Σ clipped t² and count over the learning phase, per channel.
    inflation_sum: [T; NZ],
    inflation_n: [T; NZ],
    /// The motion the learnt inflation covers (`inflation_cover.rs`).
    #[cfg(feature = "inflation-tracking")]
    cover: inflation_cover::InflationCover<T>,
    persistence: Persistence<NZ>,
    paper_inv: Option<Mat6<T>>,
    phase: Phase,
    phase_time: T,
    prev_imu: ImuVec<T>,
    frozen_count: u16,
    /// Time the IMU gave the filter nothing to follow (`ImuGap`), and
    /// the triads (velocity, attitude) to re-align after a gap (`imu_gap.rs`).
    imu_gap: ImuGap<T>,
    /// The aiding's previous values (`stale_aiding.rs`).
    repeated: RepeatedAiding<T>,
    gap_realign: [bool; 2],
    stats_holdoff: T,
    /// How long each channel has been flagged, s (0 when it is not).
    flagged_for: [T; NZ],
    /// Each flag's estimate when it was raised (0 when not flagged): what
    /// the end-of-fault rule holds a fault still present to.
    flag_raised_at: [T; NZ],
    /// The velocity was propagated through an attitude a flagged gyro
    /// fault corrupted (`velocity_increment.rs`, `velocity_tainted`):
    /// until it is re-aligned, the UKF's innovations do not judge the
    /// accelerometers.
    velocity_tainted: bool,
    /// In this episode (until every channel is judged healthy again) an
    /// accelerometer was flagged before any gyro, or the aiding's jump
    /// rule re-aligned the velocity alone (`velocity_tainted`).
    velocity_jumped: bool,
    /// Where the last predict's input Jacobian `B` was taken (the state
    /// before it and its attitude trigonometry): `B` is rebuilt from these
    /// when an estimate needs it, instead of a 36-value copy every IMU
    /// period (issue 17). `None` before the first predict: `B = I`.
    last_input_at: Option<(StateVec<T>, AttitudeTrig<T>)>,
    last_h: Mat6<T>,
    last_dt: T,
    delay_steps: usize,
    /// The velocity aiding's own latency in IMU periods
    /// (`velocity_delay_s`; `None`: it shares `delay_steps`).
    velocity_delay_steps: Option<usize>,
    /// States written to the history since the filter was last
    /// (re-)aligned: older ones are of another trajectory.
    history_fresh: usize,
    /// Online latency estimate (when `estimate_aiding_delay`).
    delay_estimator: DelayEstimator<T>,
    /// The lag the nominal bias and inflation were learnt at.
    learned_lag: usize,
    /// Heading offset of the attitude aiding (`heading.rs`).
    heading: heading::HeadingEstimator<T>,
    /// The tracking fault estimate (`fault_track.rs`).
    tracker: fault_track::FaultTracker<T>,
    /// The gyro/attitude-aiding consistency test (`attitude_rate/`).
    #[cfg(feature = "attitude-rate-test")]
    att_rate: crate::monitor::block_test::attitude_rate::AttitudeRate<T>,
    /// The accelerometer/GNSS-velocity consistency test
    /// (`velocity_increment/`).
    #[cfg(feature = "velocity-increment-test")]
    vel_inc: crate::monitor::block_test::velocity_increment::VelocityIncrement<T>,
    /// The regression of the velocity innovations after a velocity-alone
    /// re-alignment (`regrowth.rs`).
    #[cfg(feature = "velocity-increment-test")]
    regrowth: regrowth::Regrowth<T>,
    history: heapless::HistoryBuf<StateVec<T>, { MAX_DELAY_STEPS + 1 }>,
    report: UkfReport<T>,
}

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// A monitor waiting for its first attitude measurement.
    pub fn new(cfg: UkfMonitorConfig<T>) -> Result<Self, ConfigError> {
        cfg.validate()?;
        // The t quantile is computed (and must exist) whenever the t-tests
        // are compiled in, as for every statistic before the feature.
        let t_quantile = if cfg!(feature = "t-statistics") {
            Some(TTest::<T>::new(cfg.alpha, W).map_err(|_| ConfigError::TTest)?)
        } else if W < 3 {
            return Err(ConfigError::TTest);
        } else {
            None
        };
        let z_threshold = T::lit(normal_upper_quantile(cfg.alpha).map_err(|_| ConfigError::TTest)?);
        let threshold = match (statistic_in_use(&cfg), t_quantile) {
            (Statistic::Raw | Statistic::Whitened, Some(t)) => t.threshold,
            _ => z_threshold,
        };
        let p0 = Mat6::from_diagonal(&cfg.initial_sigma.component_mul(&cfg.initial_sigma));
        let ukf = Ukf::new(StateVec::zeros(), p0, &cfg.sigma, STATE_ANGLES)
            .ok_or(ConfigError::SigmaParams)?;
        let mut meas = MeasurementModel::new(cfg.aiding);
        meas.lever_arm = Vector3::new(cfg.lever_arm[0], cfg.lever_arm[1], cfg.lever_arm[2]);
        let paper_inv = match cfg.detector {
            _ if !cfg!(feature = "alt-detectors") => None,
            Detector::PaperMatrix => try_inverse(&paper_matrix::<T>(&PAPER_MATRIX_CORRECTED)),
            Detector::PaperMatrixAsPrinted => {
                try_inverse(&paper_matrix::<T>(&PAPER_MATRIX_AS_PRINTED))
            }
            _ => None,
        };
        let mut ukf = ukf;
        ukf.set_min_variance(StateVec::from_element(T::lit(1e-14)));
        Ok(Self {
            model: VehicleModel {
                gravity: cfg.gravity,
                cos_pitch_min: cfg.cos_pitch_min,
            },
            meas,
            ukf,
            gate: Gate::new(cfg.gate_sigma, cfg.gate_max_rejections),
            rejection_run: [0; NZ],
            threshold,
            windows: core::array::from_fn(|_| InnovationWindow::new()),
            since_seen: [T::lit(1e9); NZ],
            since_fused: [T::lit(NEVER_FUSED_S); NZ],
            sensitivity: Mat6::zeros(),
            signature: Mat6::zeros(),
            latest_innovation: ImuVec::zeros(),
            latest_variance: ImuVec::from_element(T::one()),
            nominal_bias: ImuVec::zeros(),
            power_up: power_up::PowerUpCheck::default(),
            learn_clock: T::zero(),
            inflation: [T::one(); NZ],
            inflation_sum: [T::zero(); NZ],
            inflation_n: [T::zero(); NZ],
            #[cfg(feature = "inflation-tracking")]
            cover: inflation_cover::InflationCover::default(),
            persistence: Persistence::new(cfg.persistence),
            paper_inv,
            phase: Phase::Aligning,
            phase_time: T::zero(),
            prev_imu: ImuVec::zeros(),
            frozen_count: 0,
            imu_gap: ImuGap::default(),
            repeated: RepeatedAiding::new(),
            gap_realign: [false; 2],
            stats_holdoff: T::zero(),
            flagged_for: [T::zero(); NZ],
            flag_raised_at: [T::zero(); NZ],
            velocity_tainted: false,
            velocity_jumped: false,
            last_input_at: None,
            last_h: Mat6::identity(),
            last_dt: cfg.imu_period,
            delay_steps: (cfg.aiding_delay_s / cfg.imu_period).round().to_f64() as usize,
            velocity_delay_steps: cfg
                .velocity_delay_s
                .map(|d| (d / cfg.imu_period).round().to_f64() as usize),
            history_fresh: 0,
            delay_estimator: DelayEstimator::new(),
            learned_lag: 0,
            heading: heading::HeadingEstimator::new(),
            tracker: fault_track::FaultTracker::new(),
            #[cfg(feature = "attitude-rate-test")]
            att_rate: crate::monitor::block_test::attitude_rate::AttitudeRate::for_config(&cfg),
            #[cfg(feature = "velocity-increment-test")]
            vel_inc: crate::monitor::block_test::velocity_increment::VelocityIncrement::for_config(
                &cfg,
            ),
            #[cfg(feature = "velocity-increment-test")]
            regrowth: regrowth::Regrowth::default(),
            history: heapless::HistoryBuf::new(),
            report: UkfReport::default(),
            cfg,
        })
    }

    /// The configuration in use.
    pub fn config(&self) -> &UkfMonitorConfig<T> {
        &self.cfg
    }
    /// The life-cycle phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// The critical value of the window statistic in use (Student-t
    /// quantile, or the normal quantile for [`Statistic::Normalized`]).
    pub fn t_threshold(&self) -> T {
        self.threshold
    }
    /// The window statistic in use (see [`statistic_in_use`]).
    fn statistic(&self) -> Statistic {
        statistic_in_use(&self.cfg)
    }
    /// The current closed-loop signature matrix `M` (rows innovations,
    /// columns faults; raw units).
    pub fn signature(&self) -> &Mat6<T> {
        &self.signature
    }
    /// The underlying filter.
    pub fn filter(&self) -> &Ukf<T, NX, 13> {
        &self.ukf
    }
    /// The aiding latency the monitor fuses at, s: the configured one, or
    /// with [`estimate_aiding_delay`](UkfMonitorConfig::estimate_aiding_delay)
    /// the online estimate (a multiple of the IMU period, at most
    /// [`MAX_DELAY_STEPS`] periods).
    pub fn aiding_delay_estimate(&self) -> T {
        T::lit(self.delay_steps as f64) * self.cfg.imu_period
    }
    /// The input Jacobian `B` of the last predict (the identity before the
    /// first), rebuilt from where it was taken: the same matrix `predict`
    /// used.
    fn last_input_b(&self) -> Mat6<T> {
        match &self.last_input_at {
            Some((x, t)) => self.model.jacobian_input_with(x, t),
            None => Mat6::identity(),
        }
    }

    /// Overwrites the filter's state and covariance (alignment,
    /// re-alignment): out of line, one copy for those cold sites (≈ 0.2 KB
    /// of the firmware, issue 17), while the two-stage filter's hot
    /// `Ukf::reset` stays inline.
    #[inline(never)]
    fn reset_filter(&mut self, x: StateVec<T>, p: Mat6<T>) {
        self.ukf.reset(x, p);
    }

    /// Clears latched fault decisions (explicit operator reset).
    pub fn reset_faults(&mut self) {
        self.persistence.reset();
    }

    /// What is removed from the IMU before the filter: the nominal bias
    /// and a power-up excess while it is flagged (`power_up.rs`).
    fn removed_bias(&self) -> ImuVec<T> {
        if cfg!(feature = "power-up-check") {
            self.nominal_bias + self.power_up.excess()
        } else {
            // Not an addition of zeros on the MCU.
            self.nominal_bias
        }
    }

    /// Largest nominal bias per channel the learner may assume
    /// ([`UkfMonitorConfig::nominal_bias_bound`]).
    fn nominal_bias_bound(&self) -> ImuVec<T> {
        self.cfg.nominal_bias_bound()
    }

    /// The block tests' per-channel limits for the three channels from
    /// `first` (0: accelerometers, 3: gyros): the nominal-bias bound, and
    /// the smallest deviation reported, `min_fault × threshold_fraction`,
    /// as the UKF's own threshold method has it.
    #[cfg(any(feature = "attitude-rate-test", feature = "velocity-increment-test"))]
    fn block_limits(&self, first: usize) -> super::block_test::ChannelLimits<T> {
        let rows = |v: ImuVec<T>| {
            Vector3::from_fn(|i, _| v.get(first + i).copied().unwrap_or_else(T::zero))
        };
        super::block_test::ChannelLimits {
            nominal: rows(self.nominal_bias_bound()),
            relevant: rows(self.cfg.min_fault * self.cfg.threshold_fraction),
        }
    }

    /// One monitor period. Never panics; every anomaly is reported in
    /// [`Report::health`](super::Report::health).
    ///
    /// Returns a copy of the report; [`step_ref`](Self::step_ref) is the
    /// same step returning a reference to it.
    #[inline]
    pub fn step(&mut self, imu: &ImuVec<T>, dt: T, aiding: &Measurement<T>) -> UkfReport<T> {
        *self.step_ref(imu, dt, aiding)
    }

    /// [`step`](Self::step) returning the report by reference (it lives in
    /// the monitor until the next step): the same step without the copy of
    /// the 320-byte report into the caller's, ≈ 250 instructions through
    /// `memcpy` on the Cortex-M4F (issue 17). The SIL image's per-step
    /// figures are of this call.
    #[inline(never)] // one copy in the image, not one per caller (issue 17)
    pub fn step_ref(&mut self, imu: &ImuVec<T>, dt: T, aiding: &Measurement<T>) -> &UkfReport<T> {
        let mut health = Health::default();
        let mut updated = false;

        // --- input checks -------------------------------------------------
        let dt_use = match check_period(dt, self.cfg.imu_period) {
            Period::Valid(dt) => Some(dt),
            Period::Long(max_dt) => {
                health.dt_out_of_range = true;
                Some(max_dt)
            }
            Period::Invalid => {
                health.dt_out_of_range = true;
                None
            }
        };
        let in_range = in_range(imu, &self.cfg.full_scale);
        health.input_invalid = !in_range;
        if in_range {
            if *imu == self.prev_imu {
                self.frozen_count = self.frozen_count.saturating_add(1);
            } else {
                self.frozen_count = 0;
            }
            self.prev_imu = *imu;
        }
        health.frozen = self.frozen_count >= self.cfg.frozen_samples;
        let saturated = in_range && saturated(imu, &self.cfg.full_scale);
        if saturated {
            self.stats_holdoff = T::lit(0.5);
        }
        health.saturated = saturated;
        let elapsed = dt_use.unwrap_or(T::zero());
        self.stats_holdoff = (self.stats_holdoff - elapsed).fmax(T::zero());
        // Two loops, not one over a chained iterator: the compiler unrolls
        // these, not the chain (issue 17).
        for s in self.since_seen.iter_mut() {
            *s += elapsed;
        }
        for s in self.since_fused.iter_mut() {
            *s += elapsed;
        }

        // Aiding outside its physical range, or repeating itself, is never used.
        let aiding = &screened_aiding(
            aiding,
            self.cfg.max_aiding_speed,
            &mut self.repeated,
            &mut health,
        );

        // --- alignment ----------------------------------------------------
        if self.phase == Phase::Aligning {
            let omega = lever_arm_rates(in_range, imu);
            self.try_align(aiding, &omega);
            let shown = if in_range { *imu } else { self.prev_imu };
            self.compose(&shown, health, false);
            return &self.report;
        }

        // --- the tracking fault estimate's staged aiding epoch ----------
        if self.tracker.pending() {
            self.track_epoch();
        }

        // --- prediction ---------------------------------------------------
        let usable = in_range && !health.frozen;
        if cfg!(feature = "imu-gap-recovery")
            && self
                .imu_gap
                .back_after_gap(dt, dt_use, usable, self.cfg.imu_period)
        {
            self.hold_after_gap();
        }
        // A short run of unusable samples (at most five periods, the gap
        // recovery's bound) is bridged with a stand-in everywhere: the
        // filter and the block tests integrate it as a sample, the
        // statistics run on. Its error is a sample's noise over a period
        // or two; holding the statistics for 0.5 s and dropping the block
        // tests' interval, ring and open block at every bad sample left
        // them without a complete window on log171 with one bad cell in 28
        // rows (`scripts/single-imu-log-damage.py`: IMU1's accelerometer
        // and g_z steps missed). A longer run holds the statistics while
        // the filter dead-reckons on the last good sample (its innovations
        // say nothing about the IMU until it has settled), and the gap
        // recovery clears the windows when the IMU is back.
        let bridge = self.imu_gap.bridges(usable, self.cfg.imu_period);
        if !usable && !bridge {
            self.stats_holdoff = T::lit(0.5);
        }
        if let Some(dt) = dt_use {
            // Through a dropout or an invalid/frozen sample, the last good
            // sample stands in (channel by channel: `stand_in`): better
            // than freezing the state while the vehicle moves, which would
            // flag every channel afterwards.
            let shown = if usable {
                *imu
            } else {
                stand_in(imu, &self.prev_imu, &self.cfg.full_scale)
            };
            let u = shown - self.removed_bias();
            let (sample, live) = if bridge {
                (&shown, true)
            } else {
                (imu, usable)
            };
            self.att_rate_sample(sample, dt, live);
            self.vel_inc_sample(sample, dt, live);
            match self.predict(&u, dt) {
                Ok(reset) => health.covariance_reset |= reset,
                Err(ModelError::PitchSingularity) => health.pitch_singular = true,
                Err(ModelError::NonFinite) => health.input_invalid = true,
            }
            // The learning phase counts only epochs an unresolved heading
            // offset cannot have contaminated (`heading.rs`), so that the
            // accelerometer biases are learnt for `learn_s` of them.
            if !(self.phase == Phase::Learning && self.heading_on() && self.heading.contaminated) {
                self.phase_time += dt;
            }
            self.last_dt = dt;
        }

        // --- measurement update --------------------------------------------
        let meas_ok = aiding.any();
        // Through ±90° (a loop, a tumble): the attitude is re-aligned from
        // the aiding instead of staying singular (issue 16).
        if health.pitch_singular && meas_ok {
            let omega = lever_arm_rates(in_range, &(imu - self.removed_bias()));
            if self.recover_singular(aiding, &omega) {
                health.mark_realigned(false);
            }
        }
        if meas_ok && !health.pitch_singular {
            let omega = lever_arm_rates(in_range, &(imu - self.removed_bias()));
            self.hold_after_loss(aiding);
            let after_gap = if cfg!(feature = "imu-gap-recovery") {
                self.realign_after_gap(aiding, &omega)
            } else {
                None
            };
            if after_gap.is_some() {
                health.mark_realigned(true);
            }
            let aiding = after_gap.as_ref().unwrap_or(aiding);
            let (aiding, realigned) = self.realign_outliers(aiding, &omega);
            if realigned {
                health.mark_realigned(true);
            }
            if aiding.any() {
                match self.update(&aiding, &omega) {
                    Ok((rejected, reset)) => {
                        updated = true;
                        self.att_rate_epoch(&aiding);
                        self.vel_inc_epoch(&aiding);
                        self.cover_epoch(&aiding);
                        health.aiding_rejected |= rejected;
                        health.covariance_reset |= reset;
                    }
                    Err(_) => health.covariance_reset = true,
                }
            }
        }
        for (w, s) in self.windows.iter_mut().zip(self.since_seen.iter()) {
            if *s > self.cfg.aiding_timeout_s {
                w.clear();
            }
        }

        // --- learning, drift tracking, detection ----------------------------
        self.age_flags(elapsed);
        if updated {
            self.after_update(&health);
            if self.realign_ended(aiding, in_range, imu) {
                health.mark_realigned(false);
            }
        }
        self.advance_phase();
        // The corrected sample of an invalid one is the stand-in the filter
        // used (the last good sample): no NaN reaches a flight controller.
        let shown = if in_range { *imu } else { self.prev_imu };
        self.compose(&shown, health, updated);
        &self.report
    }

    #[inline(never)] // own stack frame and one copy (issue 17)
    fn try_align(&mut self, aiding: &Measurement<T>, omega: &Vector3<T>) {
        let Some(x) = align_state(&self.model, &self.meas, aiding, omega) else {
            return;
        };
        let s = self.cfg.initial_sigma;
        self.reset_filter(x, Mat6::from_diagonal(&s.component_mul(&s)));
        self.history_fresh = 0;
        self.sensitivity = Mat6::zeros();
        self.tracker = fault_track::FaultTracker::new();
        self.phase = Phase::Converging;
        self.phase_time = T::zero();
    }
}

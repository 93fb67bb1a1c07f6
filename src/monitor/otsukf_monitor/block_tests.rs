//! The OTSUKF monitor's side of the two block tests (issue 15): the
//! gyro/attitude-aiding test (`UkfMonitorConfig::attitude_rate`) and the
//! accelerometer/GNSS-velocity test (`UkfMonitorConfig::velocity_increment`)
//! of `crate::monitor::block_test`, as the innovation monitor runs them.
//!
//! **Why.** The fault estimate's standard deviation is what its random walk
//! (`fault_psd`, tuned to follow a step in about a second) makes it: on
//! log171 about 0.25 m/s² and 1.2 °/s, so the `k_on = 4` test cannot see a
//! 0.5 m/s² or 2 °/s step. The block tests compare the raw IMU with the
//! aiding over windows of seconds, independently of the filter, with
//! thresholds learnt on the flight; their flags are merged into the report
//! on channels the fault estimate finds healthy, as in the innovation
//! monitor. They see the aiding as it arrives (the velocity test learns
//! its own GNSS lag), not the lag-compensated velocity the filter fuses.

use super::OtsukfMonitor;
use crate::math::Real;
use crate::model::{ImuVec, Measurement, NZ};
use crate::monitor::block_test::{
    merge_block_flags, withhold_coupled_flags, ChannelLimits, EpochContext, IntervalTest,
};
use crate::monitor::{AttitudeRateDetail, OtsukfReport, Phase, VelocityIncrementDetail};
use nalgebra::Vector3;

// With one of the two features off, its half of each hook is compiled out
// and some arguments go unused.
#[cfg_attr(
    not(all(feature = "attitude-rate-test", feature = "velocity-increment-test")),
    allow(unused_variables, unused_mut)
)]
impl<T: Real> OtsukfMonitor<T> {
    /// What the gyro/attitude-aiding test shows (`None` when it is off or
    /// not compiled in).
    pub fn attitude_rate_detail(&self) -> Option<AttitudeRateDetail<T>> {
        #[cfg(feature = "attitude-rate-test")]
        if self.cfg.base.attitude_rate.is_some() {
            return Some(self.att_rate.test.detail);
        }
        None
    }

    /// What the accelerometer/GNSS-velocity test shows and the GNSS lag it
    /// uses, s (`None` when it is off or not compiled in).
    pub fn velocity_increment_detail(&self) -> Option<(VelocityIncrementDetail<T>, T)> {
        #[cfg(feature = "velocity-increment-test")]
        if self.cfg.base.velocity_increment.is_some() {
            return Some((self.vel_inc.test.detail, self.vel_inc.lag_s()));
        }
        None
    }

    /// The GNSS velocity's acceleration is more active than the velocity
    /// test has learnt (`block_test/velocity_increment/aiding_cover.rs`):
    /// the fault estimate's own test raises no new accelerometer flag then
    /// (its σ assumes the aiding noise of the motion it has seen).
    pub(super) fn blocks_accel_unlearnt(&self) -> bool {
        #[cfg(feature = "velocity-increment-test")]
        if let Some(cfg) = self.cfg.base.velocity_increment {
            return self.vel_inc.aiding_motion_unlearnt(&cfg);
        }
        false
    }

    /// Learning or monitoring, no hold-off: the tests integrate.
    fn blocks_live(&self) -> bool {
        matches!(self.phase, Phase::Learning | Phase::Monitoring) && self.holdoff <= T::zero()
    }

    /// The limits of the three channels from `first` (0: accelerometers,
    /// 3: gyros): the nominal-bias cap of `advance_phase`, and the
    /// smallest deviation reported, `min_fault × threshold_fraction`.
    fn block_limits(&self, first: usize) -> ChannelLimits<T> {
        let b = &self.cfg.base;
        let rows = |v: ImuVec<T>| {
            Vector3::from_fn(|i, _| v.get(first + i).copied().unwrap_or_else(T::zero))
        };
        ChannelLimits {
            nominal: rows(b.nominal_bias_bound()),
            relevant: rows(b.min_fault * b.threshold_fraction),
        }
    }

    /// One IMU sample (raw); `usable`: valid.
    pub(super) fn blocks_sample(&mut self, imu: &ImuVec<T>, dt: T, usable: bool) {
        let live = usable && self.blocks_live();
        #[cfg(feature = "attitude-rate-test")]
        if self.cfg.base.attitude_rate.is_some() {
            // At the attitude aiding's latency (`attitude_lag.rs`): the
            // interval between two epochs then spans the same motion in
            // the gyro and the aiding.
            let delay = self.att_lag_steps();
            self.att_rate.sample_delayed(imu, dt, live, delay);
        }
        #[cfg(feature = "velocity-increment-test")]
        if self.cfg.base.velocity_increment.is_some() {
            self.vel_inc.sample(imu, dt, live);
        }
    }

    /// After an applied update: `aiding` as it arrived (not brought
    /// forward), `fused` the channels the filter fused (none of those the
    /// outlier re-alignment withheld).
    pub(super) fn blocks_epoch(&mut self, aiding: &Measurement<T>, fused: &[bool; NZ]) {
        // Nothing is learnt from a block during which the fault estimate
        // flags a channel the test's residual contains: the gyro test's
        // holds only the gyros (and the attitude aiding), the velocity
        // test's the accelerometers and, through the rotation carried
        // between attitude epochs, the gyros.
        let monitoring = self.phase == Phase::Monitoring;
        let flagged = |from: usize| self.latched.iter().skip(from).any(|l| *l != 0);
        let (ext_gyro, ext_any) = (monitoring && flagged(3), monitoring && flagged(0));
        let ctx = |first: usize, m: &Self| EpochContext {
            live: m.blocks_live(),
            fused: fused.iter().skip(first).take(3).all(|f| *f),
            limits: m.block_limits(first),
            timeout_s: m.cfg.base.aiding_timeout_s,
            external: if first == 3 { ext_gyro } else { ext_any },
        };
        #[cfg(feature = "attitude-rate-test")]
        if let Some(cfg) = self.cfg.base.attitude_rate {
            let c = ctx(3, self);
            self.att_rate.aiding_epoch(&cfg, aiding, &c);
        }
        #[cfg(feature = "velocity-increment-test")]
        if let Some(cfg) = self.cfg.base.velocity_increment {
            let c = ctx(0, self);
            self.vel_inc.aiding_epoch(&cfg, aiding, &c);
        }
    }

    /// Adds the tests' flags to a monitoring report: a channel the fault
    /// estimate finds healthy is reported faulty while its test flags it,
    /// with the window mean as its estimate.
    pub(super) fn blocks_apply(&mut self, r: &mut OtsukfReport<T>) {
        if r.phase != Phase::Monitoring {
            return;
        }
        let b = &self.cfg.base;
        #[cfg(feature = "velocity-increment-test")]
        let vel = b.velocity_increment.map(|_| &mut self.vel_inc.test);
        #[cfg(not(feature = "velocity-increment-test"))]
        let vel: Option<&mut crate::monitor::block_test::BlockTest<T>> = None;
        #[cfg(feature = "attitude-rate-test")]
        let att = b.attitude_rate.map(|_| &mut self.att_rate.test);
        #[cfg(not(feature = "attitude-rate-test"))]
        let att: Option<&mut crate::monitor::block_test::BlockTest<T>> = None;
        // A fault one test sees is evidence for the other triad's
        // `withhold_coupled_flags`: the gyro test's (from the last epoch)
        // for the accelerometers, the velocity test's for the gyros.
        let mut elsewhere = att.as_ref().is_some_and(|t| t.sees_fault());
        for (first, test) in [(0, vel), (3, att)] {
            if let Some(t) = test {
                // In a hold-off the channels read `NotMonitored`; a block
                // test's flag still shows (as before the hold-off).
                let held = self.holdoff > T::zero();
                // The fault estimate's flag on a channel the test finds
                // healthy while a fault is evident elsewhere is that
                // fault's coupling.
                let coupled = withhold_coupled_flags(
                    &mut r.status,
                    &mut r.fault_estimate,
                    first,
                    t,
                    elsewhere,
                );
                merge_block_flags(
                    &mut r.status,
                    &mut r.fault_estimate,
                    first,
                    t,
                    held || coupled,
                );
                elsewhere = t.sees_fault();
            } else {
                elsewhere = false;
            }
        }
    }

    /// The channels the fault estimate has flagged (latched) for at least
    /// the block test's shortest window and one block (the window then
    /// lies within the flag) with an estimate `f̂ − b` that window
    /// contradicts (`BlockTest::contradicts`): faults that have ended.
    pub(super) fn blocks_ended(&self) -> [bool; 6] {
        let mut ended = [false; 6];
        if self.phase != Phase::Monitoring {
            return ended;
        }
        let f = self.filter.fault() - self.nominal;
        let b = &self.cfg.base;
        #[cfg(feature = "velocity-increment-test")]
        let vel = b
            .velocity_increment
            .map(|c| (&self.vel_inc.test, c.shortest_span_s()));
        #[cfg(not(feature = "velocity-increment-test"))]
        let vel: Option<(&crate::monitor::block_test::BlockTest<T>, T)> = None;
        #[cfg(feature = "attitude-rate-test")]
        let att = b
            .attitude_rate
            .map(|c| (&self.att_rate.test, c.shortest_span_s()));
        #[cfg(not(feature = "attitude-rate-test"))]
        let att: Option<(&crate::monitor::block_test::BlockTest<T>, T)> = None;
        for (first, test) in [(0, vel), (3, att)] {
            let Some((t, span)) = test else {
                continue;
            };
            for c in 0..3 {
                let j = first + c;
                let (Some(e), Some(l), Some(a), Some(fj)) = (
                    ended.get_mut(j),
                    self.latched.get(j),
                    self.flagged_for.get(j),
                    f.get(j),
                ) else {
                    continue;
                };
                *e = *l != 0 && *a >= span && t.contradicts(c, *fj);
            }
        }
        ended
    }

    /// Forgets the intervals and windows (re-alignment).
    pub(super) fn blocks_clear(&mut self) {
        #[cfg(feature = "attitude-rate-test")]
        self.att_rate.clear_windows();
        #[cfg(feature = "velocity-increment-test")]
        self.vel_inc.clear_windows();
    }

    /// Starts afresh (learning starts).
    pub(super) fn blocks_reset(&mut self) {
        #[cfg(feature = "attitude-rate-test")]
        self.att_rate.reset();
        #[cfg(feature = "velocity-increment-test")]
        self.vel_inc.reset();
    }

    /// Decisions start (monitoring).
    pub(super) fn blocks_start(&mut self) {
        #[cfg(feature = "attitude-rate-test")]
        self.att_rate.test.start_judging();
        #[cfg(feature = "velocity-increment-test")]
        self.vel_inc.test.start_judging();
    }
}

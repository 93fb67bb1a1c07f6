//! The UKF monitor's side of the gyro/attitude-aiding test: feeding it
//! the IMU samples and the fused attitude epochs, merging its flags into
//! the report, and resetting it with the monitor.

use crate::math::Real;
use crate::model::{ImuVec, Measurement};
use crate::monitor::block_test::{
    any_flag, merge_block_flags, withhold_coupled_flags, EpochContext, IntervalTest,
};
use crate::monitor::ukf_monitor::realign::flag_reference;
use crate::monitor::ukf_monitor::UkfMonitor;
use crate::monitor::{AttitudeRateDetail, Phase};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The test runs (configured; compiled in, as this file is).
    pub(in crate::monitor::ukf_monitor) fn attitude_rate_on(&self) -> bool {
        self.cfg.attitude_rate.is_some()
    }

    /// What the gyro/attitude-aiding consistency test shows (`None` when it
    /// is off): ratios, flags, estimates, learnt offset, reddening factors
    /// and degrees of freedom.
    pub fn attitude_rate_detail(&self) -> Option<AttitudeRateDetail<T>> {
        self.attitude_rate_on().then_some(self.att_rate.test.detail)
    }

    /// One IMU sample (raw) into the interval under way; `usable`: the
    /// sample was valid and the statistics are not held (else the interval
    /// is dropped).
    pub(in crate::monitor::ukf_monitor) fn att_rate_sample(
        &mut self,
        imu: &ImuVec<T>,
        dt: T,
        usable: bool,
    ) {
        if self.attitude_rate_on() {
            let live = usable && self.att_rate_live();
            // Integrated at the aiding's latency, as the UKF fuses it.
            self.att_rate
                .sample_delayed(imu, dt, live, self.delay_steps);
        }
    }

    /// Learning or monitoring, statistics not held: the test integrates.
    fn att_rate_live(&self) -> bool {
        matches!(self.phase, Phase::Learning | Phase::Monitoring) && self.stats_holdoff <= T::zero()
    }

    /// After an aiding update: an attitude epoch the UKF fused closes the
    /// interval; one it rejected is skipped (the gyro integrates on).
    pub(in crate::monitor::ukf_monitor) fn att_rate_epoch(&mut self, aiding: &Measurement<T>) {
        let Some(cfg) = self.cfg.attitude_rate else {
            return;
        };
        let ctx = EpochContext {
            live: self.att_rate_live(),
            fused: self
                .report
                .detail
                .diag
                .iter()
                .skip(3)
                .all(|d| d.available && d.fused),
            limits: self.block_limits(3),
            timeout_s: self.cfg.aiding_timeout_s,
            external: self.phase == Phase::Monitoring && any_flag(&self.report.status),
        };
        self.att_rate.aiding_epoch(&cfg, aiding, &ctx);
    }

    /// Adds the test's flags to the report: a gyro channel the UKF finds
    /// healthy is reported faulty while the test flags it, with the window
    /// mean as its estimate. A UKF flag on a gyro the test finds healthy
    /// while a fault is evident on another gyro (this test) or an
    /// accelerometer (`elsewhere`: the velocity test) is withheld first,
    /// that fault's coupling (`withhold_coupled_flags`).
    pub(in crate::monitor::ukf_monitor) fn att_rate_apply(&mut self, elsewhere: bool) {
        if !self.attitude_rate_on() {
            return;
        }
        let coupled = withhold_coupled_flags(
            &mut self.report.status,
            &mut self.report.fault_estimate,
            3,
            &mut self.att_rate.test,
            elsewhere,
        );
        let unjudged = coupled || !self.covered();
        merge_block_flags(
            &mut self.report.status,
            &mut self.report.fault_estimate,
            3,
            &mut self.att_rate.test,
            unjudged,
        );
    }

    /// The test sees a gyro fault (`BlockTest::sees_fault`); false when off.
    pub(in crate::monitor::ukf_monitor) fn att_rate_sees_fault(&self) -> bool {
        self.attitude_rate_on() && self.att_rate.test.sees_fault()
    }

    /// The test is quiet (every ratio below half its threshold) or off: the
    /// UKF's drift tracker may learn.
    pub(in crate::monitor::ukf_monitor) fn att_rate_quiet(&self) -> bool {
        !self.attitude_rate_on() || self.att_rate.test.quiet(T::lit(0.5))
    }

    /// A gyro channel flagged for at least the test's shortest window
    /// (`flagged_for`, s per channel: the window then lies within the
    /// flag) with an estimate that window contradicts
    /// (`BlockTest::contradicts`): the rate fault has ended, what the flag
    /// still sees is the attitude it integrated into the filter.
    pub(in crate::monitor::ukf_monitor) fn att_rate_ended(
        &self,
        flagged_for: &[T; 6],
        raised_at: &[T; 6],
    ) -> [bool; 3] {
        let Some(cfg) = self.cfg.attitude_rate else {
            return [false; 3];
        };
        let span = cfg.shortest_span_s();
        core::array::from_fn(|c| {
            let flagged = flagged_for.get(3 + c).is_some_and(|a| *a >= span);
            let f = self.report.fault_estimate.get(3 + c).copied();
            let f = f.map(|f| flag_reference(f, raised_at.get(3 + c).copied()));
            flagged && f.is_some_and(|f| self.att_rate.test.contradicts(c, f))
        })
    }

    /// Forgets the intervals and windows (re-alignment).
    pub(in crate::monitor::ukf_monitor) fn att_rate_clear(&mut self) {
        self.att_rate.clear_windows();
    }

    /// Starts afresh (learning restarted).
    pub(in crate::monitor::ukf_monitor) fn att_rate_reset(&mut self) {
        self.att_rate.reset();
    }

    /// Decisions start (monitoring).
    pub(in crate::monitor::ukf_monitor) fn att_rate_start(&mut self) {
        self.att_rate.test.start_judging();
    }
}

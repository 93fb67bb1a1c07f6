//! The UKF monitor's side of the accelerometer/GNSS-velocity test: feeding
//! it the IMU samples and the aiding epochs, merging its flags into the
//! report (accelerometer channels), and resetting it with the monitor.

use crate::math::Real;
use crate::model::{ImuVec, Measurement};
use crate::monitor::block_test::{
    any_flag, merge_block_flags, withhold_coupled_flags, EpochContext, IntervalTest,
};
use crate::monitor::ukf_monitor::realign::flag_reference;
use crate::monitor::ukf_monitor::UkfMonitor;
use crate::monitor::{ChannelState, Phase, VelocityIncrementDetail};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The test runs (configured; compiled in, as this file is).
    fn vel_inc_on(&self) -> bool {
        self.cfg.velocity_increment.is_some()
    }

    /// Learning or monitoring, statistics not held: the test integrates.
    /// Also through the hold-off of a velocity-alone re-alignment
    /// (`regrowth.rs`): its increments compare the IMU with the aiding, not
    /// with the re-aligned state, and it is what finds a flagged fault
    /// ended there.
    fn vel_inc_live(&self) -> bool {
        matches!(self.phase, Phase::Learning | Phase::Monitoring)
            && (self.stats_holdoff <= T::zero() || self.regrowth_live())
    }

    /// What the accelerometer/GNSS-velocity consistency test shows (`None`
    /// when it is off): ratios, flags, estimates, learnt offset, reddening
    /// factors and degrees of freedom, in m/s².
    pub fn velocity_increment_detail(&self) -> Option<VelocityIncrementDetail<T>> {
        self.vel_inc_on().then_some(self.vel_inc.test.detail)
    }

    /// The GNSS velocity lag the accelerometer/GNSS-velocity test uses, s
    /// (`None` when it is off).
    pub fn velocity_increment_lag(&self) -> Option<T> {
        self.vel_inc_on().then(|| self.vel_inc.lag_s())
    }

    /// One IMU sample (raw); `usable`: valid (else the ring is dropped).
    pub(in crate::monitor::ukf_monitor) fn vel_inc_sample(
        &mut self,
        imu: &ImuVec<T>,
        dt: T,
        usable: bool,
    ) {
        if self.vel_inc_on() {
            let live = usable && self.vel_inc_live();
            self.vel_inc.sample(imu, dt, live);
        }
    }

    /// After an aiding update: an attitude epoch sets the rotation; a
    /// velocity epoch the UKF fused closes the interval (one it rejected is
    /// skipped: the IMU integrates on).
    pub(in crate::monitor::ukf_monitor) fn vel_inc_epoch(&mut self, aiding: &Measurement<T>) {
        let Some(cfg) = self.cfg.velocity_increment else {
            return;
        };
        // The attitude with the learnt heading offset taken off, as the UKF
        // fuses it: an offset turns the horizontal Δv the test integrates
        // (3° on the aircraft: 221/240 episodes, 62 post-clear events).
        let corrected;
        let aiding = if self.heading_on() {
            corrected = self.correct_heading(aiding);
            &corrected
        } else {
            aiding
        };
        let ctx = EpochContext {
            live: self.vel_inc_live(),
            fused: self
                .report
                .detail
                .diag
                .iter()
                .take(3)
                .all(|d| d.available && d.fused),
            limits: self.block_limits(0),
            timeout_s: self.cfg.aiding_timeout_s,
            external: self.phase == Phase::Monitoring && any_flag(&self.report.status),
        };
        // The attitude is carried to its arrival over the latency the UKF
        // fuses it at.
        self.vel_inc.set_attitude_delay(self.delay_steps);
        self.vel_inc.aiding_epoch(&cfg, aiding, &ctx);
    }

    /// Adds the test's flags to the report: an accelerometer channel the
    /// UKF finds healthy is reported faulty while the test flags it, with
    /// the window mean as its estimate. `tainted`: the UKF's innovations
    /// did not judge the accelerometers this epoch (`velocity_tainted`),
    /// so their `NotMonitored` channels take the test's flags. A UKF flag on
    /// an accelerometer the test finds healthy while a fault is evident on
    /// another accelerometer (this test) or a gyro (`elsewhere`: the
    /// gyro/attitude test) is withheld first (`withhold_coupled_flags`).
    pub(in crate::monitor::ukf_monitor) fn vel_inc_apply(
        &mut self,
        tainted: bool,
        elsewhere: bool,
    ) {
        if self.vel_inc_on() {
            let coupled = withhold_coupled_flags(
                &mut self.report.status,
                &mut self.report.fault_estimate,
                0,
                &mut self.vel_inc.test,
                elsewhere,
            );
            let unjudged = tainted || coupled || !self.covered();
            merge_block_flags(
                &mut self.report.status,
                &mut self.report.fault_estimate,
                0,
                &mut self.vel_inc.test,
                unjudged,
            );
        }
    }

    /// The test sees an accelerometer fault (`BlockTest::sees_fault`);
    /// false when off.
    pub(in crate::monitor::ukf_monitor) fn vel_inc_sees_fault(&self) -> bool {
        self.vel_inc_on() && self.vel_inc.test.sees_fault()
    }

    /// A gyro fault's attitude error in the velocity (issue 15). The
    /// filter propagates its velocity through its attitude, so a gyro
    /// fault's attitude error leaks gravity (g·δθ) into the velocity
    /// innovations, and the UKF's test flags the accelerometers for it
    /// (log171, IMU1 g_x +50 °/s for 5 s at 200 s: a_y and a_z flagged at
    /// 4–5 m/s² from 205.3 s while this test, which rotates the IMU's
    /// velocity increments with the aiding's attitude, saw a ratio ≤ 0.5 on
    /// both). From a gyro flag on until the velocity is re-aligned
    /// (`realign_ended`, with the attitude, once every gyro is judged
    /// healthy again), the accelerometers are judged by this test alone:
    /// a channel only the
    /// UKF's innovations flag is reported `NotMonitored`, and this test's
    /// flags are merged into it. Not when an accelerometer was flagged
    /// first in this episode, or the aiding's jump rule re-aligned the
    /// velocity alone (`velocity_jumped`): the accelerometer went off
    /// first, and a gyro flag then is the attitude the filter tilted to
    /// follow it (log171, IMU0 a_x +5 m/s² for 5 s at 160 s: velocity
    /// re-aligned at 162 s, g_y flagged at 165.1 s, a_x at 165.9 s; at
    /// 140 s: a_x flagged from 141.7 s, g_z at 144.1 s). True while so;
    /// false without this test (nothing else independent of the filter's
    /// attitude would judge the accelerometers).
    pub(in crate::monitor::ukf_monitor) fn velocity_tainted(&mut self) -> bool {
        if !self.vel_inc_on() {
            return false;
        }
        let flagged = |s: &ChannelState| {
            matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative)
        };
        // An episode the jump rule opened on the velocity alone lasts until
        // every channel is judged healthy again.
        if self
            .report
            .status
            .iter()
            .all(|s| matches!(s, ChannelState::Healthy))
        {
            self.velocity_jumped = false;
        }
        // An accelerometer flagged before any gyro is the episode's first
        // fault, as a velocity the jump rule re-aligned alone.
        if !self.velocity_tainted && self.report.status.iter().take(3).any(flagged) {
            self.velocity_jumped = true;
        }
        if !self.velocity_jumped && self.report.status.iter().skip(3).any(flagged) {
            self.velocity_tainted = true;
        }
        if !self.velocity_tainted {
            return false;
        }
        for (s, f) in self
            .report
            .status
            .iter_mut()
            .zip(self.report.fault_estimate.iter_mut())
            .take(3)
        {
            if flagged(s) {
                *s = ChannelState::NotMonitored;
                *f = T::zero();
            }
        }
        true
    }

    /// The test is quiet (every ratio below half its threshold) or off.
    pub(in crate::monitor::ukf_monitor) fn vel_inc_quiet(&self) -> bool {
        !self.vel_inc_on() || self.vel_inc.test.quiet(T::lit(0.5))
    }

    /// An accelerometer channel flagged for at least the test's shortest
    /// window (`flagged_for`, s per channel) with an estimate that window
    /// contradicts (`BlockTest::contradicts`): the fault has ended, what
    /// the flag still sees is the velocity it integrated into the filter.
    pub(in crate::monitor::ukf_monitor) fn vel_inc_ended(
        &self,
        flagged_for: &[T; 6],
        raised_at: &[T; 6],
    ) -> [bool; 3] {
        let Some(cfg) = self.cfg.velocity_increment else {
            return [false; 3];
        };
        let span = cfg.shortest_span_s();
        core::array::from_fn(|c| {
            let flagged = flagged_for.get(c).is_some_and(|a| *a >= span);
            let f = self.report.fault_estimate.get(c).copied();
            let f = f.map(|f| flag_reference(f, raised_at.get(c).copied()));
            flagged && f.is_some_and(|f| self.vel_inc.test.contradicts(c, f))
        })
    }

    /// The test's newest shortest window contradicts a fault of size `f` on
    /// accelerometer `c` (`BlockTest::contradicts`); false when off.
    pub(in crate::monitor::ukf_monitor) fn vel_inc_contradicts(&self, c: usize, f: T) -> bool {
        self.vel_inc_on() && self.vel_inc.test.contradicts(c, f)
    }

    /// Forgets the intervals and windows (re-alignment).
    pub(in crate::monitor::ukf_monitor) fn vel_inc_clear(&mut self) {
        self.vel_inc.clear_windows();
    }

    /// Starts afresh (learning restarted).
    pub(in crate::monitor::ukf_monitor) fn vel_inc_reset(&mut self) {
        self.vel_inc.reset();
    }

    /// Decisions start (monitoring).
    pub(in crate::monitor::ukf_monitor) fn vel_inc_start(&mut self) {
        self.vel_inc.test.start_judging();
    }
}

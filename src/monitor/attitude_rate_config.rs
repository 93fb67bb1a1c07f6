//! Settings of the UKF monitor's two block tests (issue 15,
//! `ukf_monitor/block_test/`): the gyro/attitude-aiding test
//! (`attitude_rate/`: the gyro integrated between attitude-aiding epochs
//! against the aiding's own rotation) and the accelerometer/GNSS-velocity
//! test (`velocity_increment/`: the specific force integrated between
//! velocity epochs against the GNSS velocity change), both summed over
//! seconds, for biases the ten-epoch innovation windows cannot tell from
//! aiding whose errors wander (a real autopilot's attitude, a GNSS
//! receiver's velocity).

use crate::math::Real;

/// Longest window of a block test, in blocks (the monitor keeps twice this many
/// block means: a block is learnt only once every decision that saw it has
/// been made).
pub const ATTITUDE_RATE_MAX_BLOCKS: usize = 20;
/// Window lengths of a block test.
pub const ATTITUDE_RATE_LENGTHS: usize = 3;

/// The gyro/attitude-aiding consistency test's settings
/// ([`UkfMonitorConfig::attitude_rate`](crate::monitor::UkfMonitorConfig::attitude_rate)).
pub type AttitudeRateConfig<T> = BlockTestConfig<T>;
/// The accelerometer/GNSS-velocity consistency test's settings
/// ([`UkfMonitorConfig::velocity_increment`](crate::monitor::UkfMonitorConfig::velocity_increment)).
pub type VelocityIncrementConfig<T> = BlockTestConfig<T>;
/// What the gyro/attitude-aiding test shows (rad/s).
pub type AttitudeRateDetail<T> = BlockTestDetail<T>;
/// What the accelerometer/GNSS-velocity test shows (m/s²).
pub type VelocityIncrementDetail<T> = BlockTestDetail<T>;

/// A block test's settings ([`AttitudeRateConfig`],
/// [`VelocityIncrementConfig`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BlockTestConfig<T> {
    /// Block length, s: the per-epoch residuals (rotations, velocity
    /// changes) are summed over blocks of (about) this length; one decision
    /// per block.
    pub block_s: T,
    /// The three window lengths, in blocks (ascending, at most
    /// [`ATTITUDE_RATE_MAX_BLOCKS`]).
    pub lengths: [u8; ATTITUDE_RATE_LENGTHS],
    /// Design false-alarm rate of the whole test, events per hour: the
    /// per-decision probability (two-sided) is this over the decisions
    /// made in an hour (three channels × three lengths per block),
    /// and the threshold is the Student-t quantile of it at the degrees of
    /// freedom the learnt variance has.
    pub false_alarms_per_hour: f64,
    /// Weight, in independent windows, of the white-noise prior of each
    /// length's reddening factor (window variance over block variance / L).
    pub prior_windows: T,
    /// The reddening factor's prior: white (`false`, ρ = 1) or that of a
    /// first-order moving average with the lag-1 autocorrelation `r₁`
    /// learnt on the blocks (`true`, ρ_L = 1 + 2(1 − 1/L) r₁, at least
    /// 1/L): aiding errors that telescope (`r₁ → −½`) make a window's
    /// variance fall as 1/L², not 1/L, and a white prior then overstates it
    /// up to L times until the windows have shown otherwise.
    pub lag1_prior: bool,
    /// Degrees of freedom a window length needs before it judges.
    pub min_dof: T,
    /// A block is learnt only if every decision that saw it stayed below
    /// this fraction of its threshold on that channel (a fault is never
    /// learnt as noise).
    pub learn_below: T,
    /// Memory of the learnt offset and variances, in blocks (exponential
    /// forgetting).
    pub memory_blocks: T,
    /// Consecutive decisions above threshold, with one sign, before a
    /// channel is flagged.
    pub confirm: u8,
    /// Decisions a flag holds after the last confirmed one (against
    /// flicker of a fault near threshold).
    pub hold: u8,
}

impl<T: Real> BlockTestConfig<T> {
    /// How long a channel must have been flagged before the newest
    /// shortest window lies wholly within the flag, s: that window plus one
    /// block (block boundaries are not the flag's). A window that began
    /// before a fault's onset falls short of it without the fault having
    /// ended.
    pub fn shortest_span_s(&self) -> T {
        let blocks = self.lengths.first().copied().unwrap_or(0);
        self.block_s * T::lit(f64::from(blocks) + 1.0)
    }

    /// The gyro test's: half-second blocks, windows of 2.5, 5 and 10 s, 10 false alarms per
    /// hour by design, a white prior worth 4 windows, judging from 6
    /// degrees of freedom, learning below 0.8 of the threshold, 10 minutes
    /// of memory, two decisions to flag, held for one more.
    pub fn flight() -> Self {
        Self {
            block_s: T::lit(0.5),
            lengths: [5, 10, 20],
            false_alarms_per_hour: 10.0,
            prior_windows: T::lit(4.0),
            lag1_prior: false,
            min_dof: T::lit(6.0),
            learn_below: T::lit(0.8),
            memory_blocks: T::lit(1200.0),
            confirm: 2,
            hold: 1,
        }
    }

    /// The velocity test's: 1-s blocks (five 5-Hz GNSS epochs: the GNSS
    /// velocity's errors telescope over a block, so shorter blocks only add
    /// end terms), windows of 3, 5 and 10 s, the lag-1 prior (those end
    /// terms telescope), and otherwise
    /// [`flight`](Self::flight)'s settings.
    pub fn velocity() -> Self {
        Self {
            block_s: T::one(),
            lengths: [2, 5, 10],
            lag1_prior: true,
            ..Self::flight()
        }
    }

    /// Per-decision false-alarm probability (two-sided) of
    /// [`false_alarms_per_hour`](Self::false_alarms_per_hour).
    pub fn alpha(&self) -> f64 {
        let decisions = 3600.0 / self.block_s.to_f64() * 9.0;
        self.false_alarms_per_hour / decisions
    }

    /// `Err(field)` for a setting out of range.
    pub fn check(&self) -> Result<(), &'static str> {
        let pos = |v: T| v.finite() && v > T::zero();
        let [a, b, c] = self.lengths;
        if !(a > 0 && a < b && b < c && usize::from(c) <= ATTITUDE_RATE_MAX_BLOCKS) {
            return Err("attitude_rate.lengths");
        }
        if !pos(self.block_s) {
            return Err("attitude_rate.block_s");
        }
        let alpha = self.alpha();
        if !(alpha > 0.0 && alpha < 0.5) {
            return Err("attitude_rate.false_alarms_per_hour");
        }
        if !pos(self.prior_windows) {
            return Err("attitude_rate.prior_windows");
        }
        if !(self.min_dof.finite() && self.min_dof >= T::lit(3.0)) {
            return Err("attitude_rate.min_dof");
        }
        if !(pos(self.learn_below) && self.learn_below <= T::one()) {
            return Err("attitude_rate.learn_below");
        }
        if !(pos(self.memory_blocks) && self.memory_blocks > T::one()) {
            return Err("attitude_rate.memory_blocks");
        }
        if self.confirm == 0 {
            return Err("attitude_rate.confirm");
        }
        if usize::from(self.hold) > ATTITUDE_RATE_MAX_BLOCKS {
            return Err("attitude_rate.hold");
        }
        Ok(())
    }
}

/// What a block test shows
/// ([`UkfMonitor::attitude_rate_detail`](crate::monitor::UkfMonitor::attitude_rate_detail),
/// [`UkfMonitor::velocity_increment_detail`](crate::monitor::UkfMonitor::velocity_increment_detail)),
/// in the sensor's units (rad/s, m/s²).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BlockTestDetail<T> {
    /// Per channel (body x, y, z): the largest score over its threshold of
    /// the last decision (0 before a length can judge).
    pub ratio: [T; 3],
    /// Per channel: −1, 0 or +1, the test's flag.
    pub flag: [i8; 3],
    /// Per channel: the window mean less the offset while flagged (0
    /// otherwise).
    pub estimate: [T; 3],
    /// Per channel: the learnt offset against the aiding.
    pub offset: [T; 3],
    /// Per window length: the reddening factor learnt (channel x, y, z).
    pub reddening: [[T; 3]; ATTITUDE_RATE_LENGTHS],
    /// Per window length: the degrees of freedom of its variance
    /// (channel x, y, z).
    pub dof: [[T; 3]; ATTITUDE_RATE_LENGTHS],
}

#[cfg(test)]
mod tests {
    use super::*;

    type Edit = fn(&mut AttitudeRateConfig<f64>);

    #[test]
    fn the_flight_settings_pass_and_bad_ones_are_named() {
        let c = AttitudeRateConfig::<f64>::flight();
        assert_eq!(c.check(), Ok(()));
        // 10 per hour over 7200 blocks × 9 decisions.
        assert!((c.alpha() - 10.0 / 64_800.0).abs() < 1e-12);
        let bad: [(Edit, &str); 6] = [
            (|c| c.lengths = [10, 5, 20], "attitude_rate.lengths"),
            (|c| c.lengths = [5, 10, 21], "attitude_rate.lengths"),
            (|c| c.block_s = f64::NAN, "attitude_rate.block_s"),
            (
                |c| c.false_alarms_per_hour = 0.0,
                "attitude_rate.false_alarms_per_hour",
            ),
            (|c| c.min_dof = 2.0, "attitude_rate.min_dof"),
            (|c| c.confirm = 0, "attitude_rate.confirm"),
        ];
        for (f, name) in bad {
            let mut c = AttitudeRateConfig::flight();
            f(&mut c);
            assert_eq!(c.check(), Err(name));
        }
    }

    /// A flag must be this old before the shortest window lies within it:
    /// the 2.5-s gyro window and the 2-s velocity window, plus one block.
    #[test]
    fn shortest_span_is_the_shortest_window_and_one_block() {
        assert_eq!(AttitudeRateConfig::<f64>::flight().shortest_span_s(), 3.0);
        assert_eq!(
            VelocityIncrementConfig::<f64>::velocity().shortest_span_s(),
            3.0
        );
    }
}

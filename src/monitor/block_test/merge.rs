//! A block test's flags into the UKF monitor's report.

use super::BlockTest;
use crate::math::Real;
use crate::model::ImuVec;
use crate::monitor::ChannelState;

/// Reports the three channels from `first` (0: accelerometer, 3: gyro)
/// faulty where `test` flags them and the UKF finds them healthy, with the
/// test's window mean as the estimate; a channel the UKF flags itself is
/// noted (see [`BlockTest::reports`]). `unjudged`: the monitor's own test
/// did not judge this epoch (`ukf_monitor/inflation_cover.rs`), so a
/// `NotMonitored` channel takes the block test's flag too.
pub(in crate::monitor) fn merge_block_flags<T: Real>(
    status: &mut [ChannelState; 6],
    estimate: &mut ImuVec<T>,
    first: usize,
    test: &mut BlockTest<T>,
    unjudged: bool,
) {
    for c in 0..3 {
        let (Some(st), Some(e)) = (status.get_mut(first + c), estimate.get_mut(first + c)) else {
            continue;
        };
        if matches!(
            st,
            ChannelState::FaultPositive | ChannelState::FaultNegative
        ) {
            test.note_ukf_flag(c);
        }
        let d = &test.detail;
        let (Some(f), Some(m)) = (d.flag.get(c), d.estimate.get(c)) else {
            continue;
        };
        let open = match st {
            ChannelState::Healthy => true,
            ChannelState::NotMonitored => unjudged,
            _ => false,
        };
        if *f == 0 || !open || !test.reports(c) {
            continue;
        }
        *st = if *f > 0 {
            ChannelState::FaultPositive
        } else {
            ChannelState::FaultNegative
        };
        *e = *m;
    }
}

/// Withholds the monitor's own flags on the three channels from `first`
/// that their block test finds healthy while a fault is evident elsewhere:
/// on another channel of the same triad (seen by this test), or on the
/// other triad (`elsewhere`: seen by the other block test, see
/// [`BlockTest::sees_fault`]). Issue 15, cascades after large glitches.
///
/// **Why.** A large gyro fault integrates tens of degrees of attitude
/// error into the filter within a second; its attitude innovations then
/// carry that error on every axis the vehicle's attitude couples, and the
/// filter's own test flags healthy axes (log171, IMU0 g_z +50 °/s for 1 s
/// at 120 s, 23° of roll: g_y flagged 120.9–124.1 s with an estimate of
/// −4 °/s while the block test's ratio on g_y stayed at 0.16–0.23 and on
/// g_z rose to 4.8). Likewise an accelerometer fault tilts the filter's
/// attitude to follow it (then its gyros are flagged) and a gyro fault
/// leaks gravity into its velocity (then its accelerometers are). The
/// block tests compare each raw sensor with the aiding directly, axis by
/// axis (`attitude_rate`: the body rotation of each interval, exact at any
/// rate; `velocity_increment`: the velocity increments rotated by the
/// aiding's attitude), so one channel's fault reaches another channel's
/// test only at second order. While a fault is evident elsewhere and the
/// test judges channel `c` below its threshold, the filter's flag on `c`
/// is that fault's coupling, not evidence of its own: `c` reads
/// `NotMonitored` (the filter cannot judge it now) and takes the block
/// test's flag if that rises (the caller merges with `unjudged`). Nothing
/// changes while no test has seen a fault, or this one cannot judge `c`
/// (ratio 0), so a fault the filter alone detects keeps its flag.
/// Returns whether a flag was withheld.
pub(in crate::monitor) fn withhold_coupled_flags<T: Real>(
    status: &mut [ChannelState; 6],
    estimate: &mut ImuVec<T>,
    first: usize,
    test: &mut BlockTest<T>,
    elsewhere: bool,
) -> bool {
    let flagged =
        |s: &ChannelState| matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative);
    test.note_flags(core::array::from_fn(|c| {
        status.get(first + c).is_some_and(flagged)
    }));
    let d = &test.detail;
    let healthy: [bool; 3] = core::array::from_fn(|c| {
        d.ratio
            .get(c)
            .is_some_and(|r| *r > T::zero() && *r < T::one())
            && d.flag.get(c).is_some_and(|f| *f == 0)
    });
    let sees: [bool; 3] = core::array::from_fn(|c| test.sees(c));
    let mut withheld = false;
    for c in 0..3 {
        let (Some(st), Some(e)) = (status.get_mut(first + c), estimate.get_mut(first + c)) else {
            continue;
        };
        let other = elsewhere || (0..3).any(|j| j != c && sees.get(j).copied().unwrap_or(false));
        if flagged(st) && healthy.get(c).copied().unwrap_or(false) && other {
            *st = ChannelState::NotMonitored;
            *e = T::zero();
            withheld = true;
        }
    }
    withheld
}

#[cfg(test)]
mod tests {
    use super::*;
    use ChannelState::{
        FaultNegative as Neg, FaultPositive as Pos, Healthy as Ok, NotMonitored as Nm,
    };

    /// A test that saw `ratio` and raised `flag` at its last decision.
    fn test_with(ratio: [f64; 3], flag: [i8; 3]) -> BlockTest<f64> {
        let mut t = BlockTest::new(1e-4);
        t.detail.ratio = ratio;
        t.detail.flag = flag;
        t
    }

    /// `withhold_coupled_flags` on a copy of `status`: what it returned and
    /// the status after.
    fn run(
        status: [ChannelState; 6],
        first: usize,
        t: &mut BlockTest<f64>,
        elsewhere: bool,
    ) -> (bool, [ChannelState; 6]) {
        let mut s = status;
        let mut est = ImuVec::<f64>::repeat(0.1);
        let w = withhold_coupled_flags(&mut s, &mut est, first, t, elsewhere);
        for ((before, after), e) in status.iter().zip(s.iter()).zip(est.iter()) {
            // A withheld channel carries no estimate; the others keep theirs.
            let withheld = matches!(before, Pos | Neg) && *after == Nm;
            assert_eq!(*e == 0.0, withheld, "{status:?} → {s:?}");
        }
        (w, s)
    }

    /// The filter flags g_y and g_z.
    const YZ: [ChannelState; 6] = [Ok, Ok, Ok, Ok, Neg, Pos];

    #[test]
    fn a_flag_the_test_contradicts_while_it_sees_another_axis_is_withheld() {
        // g_z above threshold (not yet confirmed), g_y well below it.
        let mut t = test_with([0.05, 0.2, 4.8], [0, 0, 0]);
        assert_eq!(run(YZ, 3, &mut t, false), (true, [Ok, Ok, Ok, Ok, Nm, Pos]));
        // The accelerometer triad is another test's.
        let acc = [Pos, Pos, Ok, Ok, Ok, Ok];
        let mut quiet = test_with([0.1, 0.1, 0.1], [0; 3]);
        assert_eq!(run(acc, 0, &mut quiet, false), (false, acc));
    }

    #[test]
    fn flags_stand_when_the_test_sees_nothing_cannot_judge_or_agrees() {
        let cases = [
            // Sees no fault anywhere: the filter alone detects.
            ([0.1, 0.2, 0.9], [0, 0, 0]),
            // Cannot judge g_y yet (ratio 0).
            ([0.1, 0.0, 3.0], [0, 0, 0]),
            // Sees g_y above threshold too.
            ([0.1, 1.2, 3.0], [0, 0, 0]),
            // Its own flag on g_y is held.
            ([0.1, 0.5, 3.0], [0, -1, 0]),
        ];
        for (ratio, flag) in cases {
            let mut t = test_with(ratio, flag);
            assert_eq!(run(YZ, 3, &mut t, false), (false, YZ), "{ratio:?} {flag:?}");
        }
        // Its flag on another axis is enough evidence of a fault there.
        let mut t = test_with([0.9, 0.3, 0.5], [1, 0, 0]);
        assert_eq!(run(YZ, 3, &mut t, false), (true, [Ok, Ok, Ok, Ok, Nm, Nm]));
    }

    #[test]
    fn a_fault_seen_during_a_flag_still_standing_keeps_withholding() {
        let mut t = test_with([0.1, 0.2, 4.8], [0, 0, 0]);
        assert!(run(YZ, 3, &mut t, false).0);
        // The windows no longer hold the fault, the filter still flags g_z.
        t.detail.ratio = [0.1, 0.2, 0.7];
        assert_eq!(run(YZ, 3, &mut t, false), (true, [Ok, Ok, Ok, Ok, Nm, Pos]));
        // g_z's flag ended: a later flag on g_y alone is the filter's own.
        assert!(!run([Ok; 6], 3, &mut t, false).0);
        assert_eq!(run(YZ, 3, &mut t, false), (false, YZ));
    }

    #[test]
    fn a_fault_the_other_triads_test_sees_withholds_what_this_test_contradicts() {
        // Accelerometer flags the velocity test judges healthy but a_z; a
        // gyro fault seen by the gyro test (`elsewhere`).
        let flags = [Pos, Ok, Neg, Pos, Ok, Ok];
        let mut vel = test_with([0.3, 0.2, 1.5], [0, 0, 0]);
        assert_eq!(
            run(flags, 0, &mut vel, true),
            (true, [Nm, Ok, Neg, Pos, Ok, Ok])
        );
        // Without a fault elsewhere, a_z seen by this test still withholds a_x.
        assert_eq!(
            run(flags, 0, &mut vel, false),
            (true, [Nm, Ok, Neg, Pos, Ok, Ok])
        );
        // Nothing seen anywhere: both stand.
        let mut quiet = test_with([0.3, 0.2, 0.4], [0, 0, 0]);
        assert_eq!(run(flags, 0, &mut quiet, false), (false, flags));
        assert!(!quiet.sees_fault());
        assert!(vel.sees_fault());
    }
}

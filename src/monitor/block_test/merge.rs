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

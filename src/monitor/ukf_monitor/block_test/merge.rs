//! A block test's flags into the UKF monitor's report.

use crate::math::Real;
use crate::monitor::ukf_monitor::UkfMonitor;
use crate::monitor::{BlockTestDetail, ChannelState};

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// Reports the three channels from `first` (0: accelerometer, 3: gyro)
    /// faulty where the test flags them and the UKF finds them healthy,
    /// with the test's window mean as the estimate.
    pub(in crate::monitor::ukf_monitor) fn merge_block_flags(
        &mut self,
        first: usize,
        d: &BlockTestDetail<T>,
    ) {
        for ((st, e), (f, m)) in self
            .report
            .status
            .iter_mut()
            .zip(self.report.fault_estimate.iter_mut())
            .skip(first)
            .zip(d.flag.iter().zip(d.estimate.iter()))
        {
            if *f == 0 || !matches!(st, ChannelState::Healthy) {
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
}

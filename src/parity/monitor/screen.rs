//! The per-period screening of the hardware checks' results: common-mode
//! events (bus, output frozen, saturation) told from sensor failures,
//! failures latched, railed outputs found, newly failed sensors excluded.

use crate::math::Real;

use super::super::health::SensorStatus;
use super::{readmit, ParityMonitor};

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// The per-period screening when some sample is not healthy: common-mode
    /// bus events and saturation, latching, railed outputs, and the
    /// exclusion of newly failed sensors. Returns whether at least half of
    /// the sensors in the set clip (common-mode saturation).
    #[inline(never)]
    pub(super) fn screen_failures(&mut self, status: &mut [SensorStatus; N]) -> bool {
        let mut newly_failed = [false; N];
        let in_set = self.removed.iter().filter(|r| !**r).count();
        // Bus, timing or output failures on at least half of the sensors in
        // the set at once (the shared bus, the power, the scheduler) are
        // common-mode events, not sensor failures: nothing is latched,
        // the sensors are reported with their per-period status and
        // return when their samples do (issue 16: a bus-wide glitch used
        // to latch every sensor and leave the monitor `Lost`).
        let bus_like = self
            .health
            .iter()
            .zip(status.iter())
            .filter(|(h, s)| h.failure().is_none() && s.transient().is_some())
            .count();
        let common_bus = bus_like >= 2 && 2 * bus_like >= in_set;
        // The same for output frozen on at least half of the sensors in the
        // same period: the logger or the driver repeating its last sample
        // (a stale FIFO, a stalled bus), not every sensor failing at once.
        // Reported `Stuck` while it lasts, unused, never latched: a 2-s
        // freeze of every IMU of log171 used to latch all nine sensors and
        // leave the monitor `Lost` for the rest of the flight.
        // A sensor counts as frozen with them once it has repeated for half
        // the limit: their runs need not end in the same period (a healthy
        // sample may have repeated the one before by chance, one period
        // earlier), and half the limit is as unlikely by chance.
        let half = self.cfg.health.stuck_samples / 2;
        let frozen = self
            .health
            .iter()
            .zip(status.iter())
            .filter(|(h, s)| {
                h.failure().is_none()
                    && (**s == SensorStatus::Stuck || h.repeats().saturating_add(1) >= half.max(2))
            })
            .count();
        let common_freeze = frozen >= 2 && 2 * frozen >= in_set;
        for (k, (h, st)) in self.health.iter_mut().zip(status.iter_mut()).enumerate() {
            if h.failure().is_some() || !st.is_failed() {
                continue;
            }
            match st.transient() {
                Some(t) if common_bus => *st = t,
                None if common_freeze && *st == SensorStatus::Stuck => {}
                _ => {
                    h.latch(*st);
                    readmit::mark(&mut newly_failed, k);
                }
            }
        }
        // Railed outputs: long clipping on a minority of sensors.
        let clipping = status
            .iter()
            .filter(|s| **s == SensorStatus::Clipping)
            .count();
        let common_mode = in_set > 0 && 2 * clipping >= in_set;
        for (k, (h, st)) in self.health.iter_mut().zip(status.iter_mut()).enumerate() {
            if !common_mode
                && h.clipping_run() >= self.cfg.health.rail_samples
                && h.failure().is_none()
            {
                h.rail();
                *st = SensorStatus::Railed;
                readmit::mark(&mut newly_failed, k);
            }
        }
        if newly_failed.contains(&true) {
            self.exclude_failed(&newly_failed);
        }
        // A failed sensor stays failed even if another one failed first.
        for k in 0..N {
            let latched = self.health.get(k).and_then(|h| h.failure());
            if latched.is_some() && !self.removed.get(k).copied().unwrap_or(true) {
                self.exclude(k);
            }
        }
        common_mode
    }
}

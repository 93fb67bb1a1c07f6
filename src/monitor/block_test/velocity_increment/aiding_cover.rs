//! The GNSS velocity's own acceleration, and how much of it the flight
//! has shown healthy (issue 15, the OTSUKF monitor's accelerometer
//! decision).
//!
//! **Why.** On log171 the GNSS velocity disagrees with the integrated
//! specific force by about −1 m/s² on a_y for 3 s of the flight's hardest
//! turn (143–148 s, the GNSS acceleration 6–7 m/s² for 5 s), on all three
//! IMUs alike: the velocity test's own 1-s block estimates at its 0.3-s
//! lag read −1.13, −1.08, −0.93 m/s² there against −0.1 to −0.2 before
//! and after. The velocity test does not judge those windows (more active
//! than anything it has learnt); the OTSUKF's fault estimate, whose σ
//! assumes the aiding noise of calm flight, reached 4σ and flagged a_y on
//! every IMU (145.5–148.3 s). That flag then kept the velocity test from
//! learning the turn and masked its a_y reports for a longest window,
//! which cost the OTSUKF three 0.5 m/s² steps the innovation monitor
//! finds (IMU0 a_y, IMU1 a_x, IMU2 a_y).
//!
//! **What.** Each block's mean squared GNSS acceleration `|Δv_G|²/Δt²`
//! (time-weighted over its intervals: the aiding's, so an accelerometer
//! fault cannot read as motion) is counted per half-decade bin, with the
//! velocity test's forgetting, on the blocks the test closes quiet and
//! with no flag of the monitor. The newest shortest window's motion is
//! *unlearnt* when fewer than one longest window of learnt blocks were as
//! active: the aiding's errors at that motion are unknown, as for the
//! block tests' own motion cover and the innovation monitor's inflation
//! cover (`ukf_monitor/inflation_cover.rs`), whose windows there are not
//! judged. Before one longest window of blocks is learnt at all, nothing
//! is unlearnt (the learning phase decides alone).

use super::super::{motion_bin, MOTION_BINS};
use crate::math::Real;

/// Recent block motions kept (the shortest window of the velocity test).
const RECENT: usize = 4;

/// The aiding-motion histogram (see the module notes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::monitor) struct AidingCover<T> {
    /// Learnt blocks per motion bin (forgetting).
    hist: [T; MOTION_BINS],
    /// The newest blocks' motion, newest at `head − 1`.
    recent: [T; RECENT],
    head: usize,
    filled: usize,
    /// The open block's `Σ |Δv|²/Δt` and `Σ Δt`.
    sum: T,
    dt: T,
}

impl<T: Real> AidingCover<T> {
    /// Nothing learnt.
    pub(super) fn new() -> Self {
        Self {
            hist: [T::zero(); MOTION_BINS],
            recent: [T::zero(); RECENT],
            head: 0,
            filled: 0,
            sum: T::zero(),
            dt: T::zero(),
        }
    }

    /// Forgets the recent blocks and the open one; what was learnt is kept.
    pub(super) fn clear_windows(&mut self) {
        self.filled = 0;
        self.drop_block();
    }

    /// Drops the open block.
    pub(super) fn drop_block(&mut self) {
        self.sum = T::zero();
        self.dt = T::zero();
    }

    /// One GNSS interval of the open block: velocity change `dv_sq`
    /// (squared norm, m²/s²) over `dt` s.
    pub(super) fn interval(&mut self, dv_sq: T, dt: T) {
        if dt > T::zero() && dv_sq.finite() {
            self.sum += dv_sq / dt;
            self.dt += dt;
        }
    }

    /// The block closes; `learn`: quiet and unflagged, counted with the
    /// forgetting factor `keep`.
    pub(super) fn close_block(&mut self, learn: bool, keep: T) {
        if self.dt <= T::zero() {
            return;
        }
        let m = self.sum / self.dt;
        self.sum = T::zero();
        self.dt = T::zero();
        if let Some(r) = self.recent.get_mut(self.head) {
            *r = m;
        }
        self.head = (self.head + 1) % RECENT;
        self.filled = (self.filled + 1).min(RECENT);
        if learn {
            let bin = motion_bin(m, MOTION_BINS);
            for (k, h) in self.hist.iter_mut().enumerate() {
                *h = *h * keep + if k == bin { T::one() } else { T::zero() };
            }
        }
    }

    /// The newest `len` blocks' mean motion is more active than `need`
    /// learnt blocks were (false before `need` blocks are learnt, or
    /// without a recent block).
    pub(super) fn unlearnt(&self, len: usize, need: T) -> bool {
        let n = len.clamp(1, RECENT).min(self.filled);
        if n == 0 {
            return false;
        }
        let mut s = T::zero();
        for k in 1..=n {
            if let Some(r) = self.recent.get((self.head + RECENT - k) % RECENT) {
                s += *r;
            }
        }
        let bin = motion_bin(s / T::lit(n as f64), MOTION_BINS);
        let total = self.hist.iter().fold(T::zero(), |a, h| a + *h);
        let tail = self.hist.iter().skip(bin).fold(T::zero(), |a, h| a + *h);
        total >= need && tail < need
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turn_harder_than_anything_learnt_is_unlearnt_until_learnt() {
        let mut c = AidingCover::<f64>::new();
        // Nothing learnt: nothing is unlearnt.
        c.interval(0.04, 0.2);
        c.close_block(false, 1.0);
        assert!(!c.unlearnt(2, 10.0));
        // 30 blocks of cruise at 1 m/s² (0.2 m/s per 0.2-s interval).
        for _ in 0..30 {
            for _ in 0..5 {
                c.interval(0.04, 0.2);
            }
            c.close_block(true, 1.0);
        }
        assert!(!c.unlearnt(2, 10.0));
        // A 6 m/s² turn: unlearnt from its first block to its tenth.
        for k in 0..12 {
            for _ in 0..5 {
                c.interval(1.44, 0.2);
            }
            c.close_block(true, 1.0);
            assert_eq!(c.unlearnt(1, 10.0), k < 9, "block {k}");
        }
        // Calm again: covered by everything learnt.
        for _ in 0..5 {
            c.interval(0.0, 0.2);
        }
        c.close_block(false, 1.0);
        assert!(!c.unlearnt(1, 10.0));
    }
}

//! Aiding that repeats its last values bit for bit: a receiver or an
//! estimator repeating its output (a stale fix, a stalled bus, a logger
//! duplicating rows) brings no new measurement, and fused against a moving
//! IMU it reads as an IMU fault. On log171 with the GNSS velocity rows held
//! for 2–30 s the UKF monitor raised 46 flag events the undamaged flight
//! does not have, and 186 with the attitude rows held
//! (`scripts/single-imu-damaged.py`, kinds `gps frozen`, `att frozen`).
//! A repeated triad is withdrawn like a missing one, so a source that stays
//! frozen ages into the aiding-loss handling (hold-off, re-alignment on its
//! return) exactly as a silent one does. Real sources repeat by chance too
//! — log171's attitude repeats for up to two epochs at rest and its GNSS
//! velocity (cm/s resolution) for one — and losing such an epoch costs
//! nothing; a velocity of exactly zero is kept (a receiver's static hold
//! clamps it there for as long as the vehicle is still). Feature
//! `stale-aiding` (default; off in the MCU images, flash budget).

use super::input::aiding_in_range;
use super::Health;
use crate::math::Real;
use crate::model::{MeasVec, Measurement, NZ};

/// The previous value of each aiding channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RepeatedAiding<T> {
    prev: MeasVec<T>,
    seen: [bool; NZ],
}

impl<T: Real> RepeatedAiding<T> {
    /// No epoch seen.
    pub fn new() -> Self {
        Self {
            prev: MeasVec::zeros(),
            seen: [false; NZ],
        }
    }

    /// Withdraws from `m` each triad (velocity, attitude) whose present
    /// channels — at least two — all repeat their previous values, except
    /// a velocity of exactly zero. True when it withdrew one.
    pub fn withdraw(&mut self, m: &mut Measurement<T>) -> bool {
        let mut withdrew = false;
        let triads = m
            .available
            .chunks_exact_mut(3)
            .zip(m.z.as_slice().chunks_exact(3))
            .zip(self.prev.as_mut_slice().chunks_exact_mut(3))
            .zip(self.seen.chunks_exact_mut(3));
        for (triad, (((a, z), p), s)) in triads.enumerate() {
            let (mut present, mut same, mut zero) = (0, true, true);
            for (((a, z), p), s) in a.iter().zip(z).zip(p.iter_mut()).zip(s.iter_mut()) {
                if *a {
                    present += 1;
                    same &= *s && *z == *p;
                    zero &= *z == T::zero();
                    (*p, *s) = (*z, true);
                }
            }
            if present >= 2 && same && !(triad == 0 && zero) {
                a.fill(false);
                withdrew = true;
            }
        }
        withdrew
    }
}

/// The aiding a single-IMU monitor may use this period: channels outside
/// their physical range withdrawn (`Health::aiding_invalid`), then triads
/// that repeat their last values (`Health::aiding_stale`).
// Out of line: one copy for both monitors. Compiled into the MCU image
// the check cost ≈ 1.1 KB of flash inlined into each step, ≈ 750 B out of
// line — still over the `imu_fdi` budget, hence feature `stale-aiding` is
// off there.
#[inline(never)]
pub(crate) fn screened_aiding<T: Real>(
    aiding: &Measurement<T>,
    max_speed: T,
    repeated: &mut RepeatedAiding<T>,
    health: &mut Health,
) -> Measurement<T> {
    let (mut out, invalid) = aiding_in_range(aiding, max_speed);
    health.aiding_invalid = invalid;
    // Most periods carry no aiding: nothing to compare.
    if cfg!(feature = "stale-aiding") && out.any() {
        health.aiding_stale = repeated.withdraw(&mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn epoch(v: [f64; 3], att: Option<[f64; 3]>) -> Measurement<f64> {
        let mut m = Measurement::none();
        for (i, x) in v.iter().enumerate() {
            m.z[i] = *x;
            m.available[i] = true;
        }
        if let Some(a) = att {
            for (i, x) in a.iter().enumerate() {
                m.z[3 + i] = *x;
                m.available[3 + i] = true;
            }
        }
        m
    }

    #[test]
    fn a_repeated_triad_is_withdrawn_and_a_new_value_is_used_again() {
        let mut r = RepeatedAiding::new();
        let mut m = epoch([1.0, 2.0, 0.5], Some([0.1, 0.2, 0.3]));
        assert!(!r.withdraw(&mut m));
        assert!(m.available.iter().all(|a| *a));
        // Velocity repeated, attitude new: only the velocity goes.
        let mut m = epoch([1.0, 2.0, 0.5], Some([0.1, 0.2, 0.31]));
        assert!(r.withdraw(&mut m));
        assert_eq!(m.available, [false, false, false, true, true, true]);
        // Both repeated (the second time for the velocity).
        let mut m = epoch([1.0, 2.0, 0.5], Some([0.1, 0.2, 0.31]));
        assert!(r.withdraw(&mut m));
        assert!(!m.any());
        // One component changed: a new measurement.
        let mut m = epoch([1.0, 2.0, 0.51], None);
        assert!(!r.withdraw(&mut m));
        assert!(m.any());
    }

    #[test]
    fn a_zero_velocity_and_a_single_channel_are_kept() {
        let mut r = RepeatedAiding::new();
        for _ in 0..3 {
            let mut m = epoch([0.0, 0.0, 0.0], None);
            assert!(!r.withdraw(&mut m), "static hold");
        }
        let mut heading = Measurement::none();
        heading.z[5] = 1.0;
        heading.available[5] = true;
        for _ in 0..3 {
            let mut m = heading;
            assert!(!r.withdraw(&mut m), "one channel repeats by chance");
        }
    }
}

//! The learnt innovation inflation holds for the motion it was learnt at.
//!
//! The inflation (`detection.rs`) says how much wider the window t
//! statistic spreads on this vehicle's healthy data than white noise. On a
//! real flight that spread follows the motion: log171 replayed from the
//! file's start (60 s, on the ground, armed at 72.6 s) learns 1.0–1.3 on
//! the horizontal velocity innovations at rest, and in flight the test
//! then raised 80–105 flag events per IMU; learnt over the first 20 s of
//! flight instead, the factors are 8–25 (and still differ by 2× between
//! learning windows 10 s apart). A factor learnt at rest says nothing of
//! flight. So, as the block tests' "motion cover" (`block_test/`):
//!
//! - per innovation channel, the windows' t² are learnt per half-decade of
//!   the window's motion: the attitude aiding's mean squared rate over
//!   about one window. The aiding's, not the gyro's: a gyro fault would
//!   read as motion, go unjudged and be learnt as spread;
//! - a window is judged with the factor of the windows learnt at least as
//!   active (the same lower bound as at the end of learning), once each
//!   channel has learnt as many of them as the learning phase gave it;
//! - a window more active than that is not judged by the UKF's test (its
//!   channels are `NotMonitored` unless a block test flags them) and is
//!   learnt, so flight gets learnt instead of flagged (log171 from 80 s:
//!   19 % of the monitored time, at monitoring start and in the hardest
//!   turns); judged windows are learnt when quiet (the drift tracker's
//!   rule: no flag, every t below half the threshold, the block tests
//!   quiet);
//! - while monitoring, the sums forget with the memory
//!   [`UkfMonitorConfig::inflation_memory_s`](crate::monitor::UkfMonitorConfig::inflation_memory_s),
//!   so the factors follow the flight (0: frozen at the end of learning,
//!   the former behaviour).
//!
//! A channel the learning phase did not learn (no aiding on it yet) is not
//! learnt later either. A fault that starts in an unjudged, more active
//! stretch may be partly learnt as spread: the factor stays bounded by
//! `max_innovation_inflation`, and the block tests judge on.

use crate::math::Real;
use crate::model::NZ;

/// Bins of the window motion (the aiding's mean squared rate, rad²/s²), half a decade
/// each from 1e-8 up; the last is open.
const BINS: usize = 20;

fn bin<T: Real>(m: T) -> usize {
    crate::monitor::block_test::motion_bin(m, BINS)
}

/// An angle difference brought into (−π, π].
fn wrap_pi<T: Real>(d: T) -> T {
    let pi = T::lit(core::f64::consts::PI);
    if d > pi {
        d - pi - pi
    } else if d <= -pi {
        d + pi + pi
    } else {
        d
    }
}

/// Clip of one window's t² (as in learning: one glitch moves a sum by at
/// most this).
const T2_CLIP: f64 = 100.0;

/// Window motion, and per innovation channel and motion bin the learnt
/// windows' t² sums and counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct InflationCover<T> {
    /// Mean squared rate over about one window (EWMA over `W` epochs).
    motion: T,
    /// Σ clipped t² per channel and bin (forgetting while monitoring).
    s: [[T; BINS]; NZ],
    /// Learnt windows per channel and bin.
    n: [[T; BINS]; NZ],
    /// Windows each channel learnt in the learning phase: what a motion
    /// needs to be covered (0: every channel two windows' worth).
    need: [T; NZ],
    /// `need` is set (monitoring): a channel the learning phase did not
    /// learn (no aiding on it yet) is not learnt afterwards either — its
    /// first windows would carry whatever the filter could not learn
    /// without it (log171 before the GPS fix: a_z's offset), which the
    /// factor must not absorb; it keeps the white-noise factor.
    needs_set: bool,
    /// The previous fused attitude epoch (angles, time).
    prev: Option<([Option<T>; 3], T)>,
}

impl<T: Real> Default for InflationCover<T> {
    fn default() -> Self {
        Self {
            motion: T::zero(),
            s: [[T::zero(); BINS]; NZ],
            n: [[T::zero(); BINS]; NZ],
            need: [T::zero(); NZ],
            needs_set: false,
            prev: None,
        }
    }
}

impl<T: Real> InflationCover<T> {
    /// A fused attitude epoch (`None`: that angle not aided) at time `t`:
    /// the aiding's squared rate since the previous one is this epoch's
    /// motion, averaged over about a window of `w` epochs. The aiding's,
    /// not the gyro's: a gyro fault would read as motion, go unjudged and
    /// be learnt as spread.
    pub(super) fn observe_attitude(&mut self, att: [Option<T>; 3], t: T, w: usize) {
        if let Some((prev, t0)) = self.prev {
            let dt = t - t0;
            let mut rate2 = T::zero();
            let mut any = false;
            for (a, b) in att.iter().zip(prev.iter()) {
                if let (Some(a), Some(b)) = (a, b) {
                    let d = wrap_pi(*a - *b);
                    rate2 += d * d;
                    any = true;
                }
            }
            if any && dt > T::zero() {
                self.observe(rate2 / (dt * dt), w);
            }
        }
        self.prev = Some((att, t));
    }

    /// One aiding epoch with the latest squared rate, window of `w` epochs.
    fn observe(&mut self, rate2: T, w: usize) {
        if rate2.finite() {
            self.motion += (rate2 - self.motion) / T::lit(w.max(1) as f64);
        }
    }

    /// Learns the channels' window t² (`None`: window not full) at this
    /// window's motion; `keep` the memory's factor.
    pub(super) fn learn(&mut self, t2: &[Option<T>; NZ], keep: T) {
        let b = bin(self.motion);
        for (((s, n), t), need) in self
            .s
            .iter_mut()
            .zip(self.n.iter_mut())
            .zip(t2.iter())
            .zip(self.need.iter())
        {
            let Some(t) = t else {
                continue;
            };
            if self.needs_set && *need <= T::zero() {
                continue;
            }
            for (k, (sk, nk)) in s.iter_mut().zip(n.iter_mut()).enumerate() {
                *sk *= keep;
                *nk *= keep;
                if k == b {
                    *sk += t.min(T::lit(T2_CLIP));
                    *nk += T::one();
                }
            }
        }
    }

    /// Channel `c`'s sums over the windows learnt at least as active as
    /// this one.
    pub(super) fn tail(&self, c: usize) -> (T, T) {
        let b = bin(self.motion);
        let sum = |v: Option<&[T; BINS]>| {
            v.map_or(T::zero(), |v| {
                v.iter().skip(b).fold(T::zero(), |a, x| a + *x)
            })
        };
        (sum(self.s.get(c)), sum(self.n.get(c)))
    }

    /// At the end of learning: a motion is covered once each channel has
    /// learnt as many windows at least as active as the learning phase
    /// gave it (`learnt`), at least `floor`.
    pub(super) fn set_need(&mut self, learnt: &[T; NZ], floor: T) {
        for (n, l) in self.need.iter_mut().zip(learnt.iter()) {
            *n = if *l > T::zero() {
                l.max(floor)
            } else {
                T::zero()
            };
        }
        self.needs_set = true;
    }

    /// Every channel that learnt anything learnt what it needs (see
    /// [`set_need`](Self::set_need); `floor` before it is set) at least as
    /// active as this window.
    pub(super) fn covered(&self, floor: T) -> bool {
        let b = bin(self.motion);
        self.n.iter().zip(self.need.iter()).all(|(n, need)| {
            let total = n.iter().fold(T::zero(), |a, x| a + *x);
            total <= T::zero() || n.iter().skip(b).fold(T::zero(), |a, x| a + *x) >= need.max(floor)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rest_does_not_cover_flight_until_flight_is_learnt() {
        let mut c = InflationCover::<f64>::default();
        let at = |t2: f64| [Some(t2); NZ];
        for _ in 0..50 {
            c.observe(2e-6, 10);
        }
        for _ in 0..200 {
            c.observe(2e-6, 10);
            c.learn(&at(1.0), 1.0);
        }
        assert!(c.covered(20.0));
        assert_eq!(c.tail(0), (200.0, 200.0));
        // Take-off: a window far more active than anything learnt.
        for _ in 0..30 {
            c.observe(0.05, 10);
        }
        assert!(!c.covered(20.0));
        // Flight learnt with its own, wider spread.
        for _ in 0..20 {
            c.learn(&at(9.0), 1.0);
        }
        assert!(c.covered(20.0));
        assert_eq!(c.tail(0), (180.0, 20.0));
        // Calm again: judged against everything at least as active.
        for _ in 0..200 {
            c.observe(2e-6, 10);
        }
        assert!(c.covered(20.0));
        assert_eq!(c.tail(0), (380.0, 220.0));
        // A channel that never learnt does not block the cover.
        let mut d = InflationCover::<f64>::default();
        let mut some = [None; NZ];
        some[0] = Some(1.0);
        for _ in 0..30 {
            d.learn(&some, 1.0);
        }
        assert!(d.covered(20.0));
    }
}

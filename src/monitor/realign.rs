//! Re-alignment to the aiding, shared by the single-IMU monitors: after a
//! jump of the aiding that the outlier gate cannot follow (a GNSS or DVL
//! glitch, `docs/recovery.md`), and when the Euler attitude has reached its
//! singularity (pitch through ±90°). The triad concerned is re-initialised
//! from one aiding epoch with the initial covariance instead of being fused
//! — what navigation filters do after a bounded number of rejections
//! (reset / re-alignment, e.g. Groves, *Principles of GNSS, Inertial, and
//! Multisensor Integrated Navigation Systems*, 2nd ed., §17.3.2).

use nalgebra::Vector3;

use crate::math::{wrap_pi, Real};
use crate::model::{
    Mat6, MeasVec, Measurement, MeasurementModel, StateVec, VehicleModel, NX, NZ, PITCH, ROLL,
};

/// The last observation of every aiding channel: consecutive gate
/// rejections and the time since it was last fused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AidingTrack<T> {
    /// Consecutive gate rejections per channel.
    pub rejection_run: [u16; NZ],
    /// Time since each channel was last fused, s.
    pub since_fused: [T; NZ],
}

impl<T: Real> AidingTrack<T> {
    /// Nothing seen yet.
    pub fn new() -> Self {
        Self {
            rejection_run: [0; NZ],
            since_fused: [T::lit(NEVER_FUSED_S); NZ],
        }
    }

    /// Time passes.
    pub fn elapse(&mut self, dt: T) {
        for s in self.since_fused.iter_mut() {
            *s += dt;
        }
    }

    /// Channel `i` was offered to the update: fused or rejected.
    pub fn record(&mut self, i: usize, fused: bool) {
        if let Some(n) = self.rejection_run.get_mut(i) {
            *n = if fused { 0 } else { n.saturating_add(1) };
        }
        if fused {
            if let Some(s) = self.since_fused.get_mut(i) {
                *s = T::zero();
            }
        }
    }

    /// A channel neither fused nor re-aligned counts as one more rejection.
    pub fn withheld(&mut self, i: usize) {
        if let Some(n) = self.rejection_run.get_mut(i) {
            *n = n.saturating_add(1);
        }
    }
}

/// The channels due for re-alignment: present, rejected `limit` times in
/// a row, fused within `timeout` s (a jump of aiding in use — aiding that
/// first arrives or returns after a loss is fused as before), and with an
/// innovation (angles wrapped) beyond `bound` or not finite.
pub(crate) fn realign_due<T: Real>(
    aiding: &Measurement<T>,
    predicted: &MeasVec<T>,
    bound: &MeasVec<T>,
    rejection_run: &[u16; NZ],
    since_fused: &[T; NZ],
    limit: u16,
    timeout: T,
) -> [bool; NZ] {
    let mut due = [false; NZ];
    for (i, d) in due.iter_mut().enumerate() {
        let (Some(a), Some(z), Some(zp), Some(b), Some(run), Some(fused)) = (
            aiding.available.get(i),
            aiding.z.get(i),
            predicted.get(i),
            bound.get(i),
            rejection_run.get(i),
            since_fused.get(i),
        ) else {
            continue;
        };
        let mut innovation = *z - *zp;
        if i >= ROLL {
            innovation = wrap_pi(innovation);
        }
        *d = *a
            && *fused <= timeout
            && *run >= limit
            && (!innovation.finite() || innovation.abs() > *b);
    }
    due
}

/// The channels that return after an aiding loss (present, not fused for
/// longer than `timeout` s, but fused before: `since_fused` below
/// [`NEVER_FUSED_S`]) with an innovation beyond `bound` or not finite: the
/// dead-reckoned state has drifted further than a fused update should
/// pull it (its cross-covariances, grown over the gap, would move the other
/// triad too), so the triad is re-aligned to the aiding instead: the reset
/// of the module header, applied when aiding returns after an outage.
pub(crate) fn returned_beyond<T: Real>(
    aiding: &Measurement<T>,
    predicted: &MeasVec<T>,
    bound: &MeasVec<T>,
    since_fused: &[T; NZ],
    timeout: T,
) -> [bool; NZ] {
    let mut due = [false; NZ];
    for (i, d) in due.iter_mut().enumerate() {
        let (Some(a), Some(z), Some(zp), Some(b), Some(fused)) = (
            aiding.available.get(i),
            aiding.z.get(i),
            predicted.get(i),
            bound.get(i),
            since_fused.get(i),
        ) else {
            continue;
        };
        let mut innovation = *z - *zp;
        if i >= ROLL {
            innovation = wrap_pi(innovation);
        }
        *d = *a && returned(*fused, timeout) && (!innovation.finite() || innovation.abs() > *b);
    }
    due
}

/// `since_fused` of a channel never fused yet, s (larger than any gap).
pub(crate) const NEVER_FUSED_S: f64 = 1e9;

/// Whether a channel last fused `since_fused` s ago returns after a loss:
/// silent beyond `timeout`, but fused at some point before.
pub(crate) fn returned<T: Real>(since_fused: T, timeout: T) -> bool {
    since_fused > timeout && since_fused < T::lit(0.5 * NEVER_FUSED_S)
}

/// A re-alignment after an IMU gap (`ImuGap`): the new state, the states
/// reset, the triads (velocity, attitude) still to re-align and the aiding
/// left to fuse (without the re-aligned channels); `None` when `pending`
/// is empty or this epoch completes neither triad. Both monitors'
/// `imu_gap.rs` apply it with their own reset.
pub(crate) fn gap_realignment<T: Real>(
    model: &VehicleModel<T>,
    meas: &MeasurementModel<T>,
    x: &StateVec<T>,
    aiding: &Measurement<T>,
    omega: &Vector3<T>,
    pending: [bool; 2],
) -> Option<GapRealignment<T>> {
    let [vel, att] = pending;
    if !vel && !att {
        return None;
    }
    let (state, reset) = realigned_state(model, meas, x, aiding, omega, att, vel);
    if !reset.iter().any(|r| *r) {
        return None;
    }
    let done = |i: usize| reset.get(i).copied().unwrap_or(false);
    let mut rest = *aiding;
    for (a, r) in rest.available.iter_mut().zip(reset.iter()) {
        *a &= !*r;
    }
    Some(GapRealignment {
        state,
        reset,
        pending: [vel && !done(0), att && !done(ROLL)],
        rest,
    })
}

/// What [`gap_realignment`] gives.
pub(crate) struct GapRealignment<T: Real> {
    /// The re-aligned state.
    pub state: StateVec<T>,
    /// The states re-initialised.
    pub reset: [bool; NX],
    /// The triads (velocity, attitude) still to re-align.
    pub pending: [bool; 2],
    /// The aiding left to fuse.
    pub rest: Measurement<T>,
}

/// `x` with the attitude triad (when `att`) and the body velocity (when
/// `vel`) re-initialised from `aiding`, and which states were. A triad is
/// re-initialised only when complete and finite in this epoch, an
/// attitude only away from the Euler singularity; the velocity is rotated
/// with the (re-aligned) attitude and corrected for the lever arm with the
/// body rate `omega`.
pub(crate) fn realigned_state<T: Real>(
    model: &VehicleModel<T>,
    meas: &MeasurementModel<T>,
    x: &StateVec<T>,
    aiding: &Measurement<T>,
    omega: &Vector3<T>,
    att: bool,
    vel: bool,
) -> (StateVec<T>, [bool; NX]) {
    let complete = |r: core::ops::Range<usize>| {
        aiding
            .available
            .get(r.clone())
            .is_some_and(|a| a.iter().all(|v| *v))
            && aiding
                .z
                .iter()
                .skip(r.start)
                .take(r.len())
                .all(|v| v.finite())
    };
    let mut x = *x;
    let mut reset = [false; NX];
    if att && complete(ROLL..NZ) {
        let mut xa = x;
        xa.fixed_rows_mut::<3>(ROLL)
            .copy_from(&aiding.z.fixed_rows::<3>(ROLL));
        if model.check_attitude(&xa).is_ok() {
            x = xa;
            for r in reset.iter_mut().skip(ROLL) {
                *r = true;
            }
        }
    }
    if vel && complete(0..3) {
        let v: Vector3<T> = aiding.z.fixed_rows::<3>(0).into_owned();
        let v_imu = meas.velocity_to_body(&x, &v) - omega.cross(&meas.lever_arm);
        if v_imu.iter().all(|c| c.finite()) {
            x.fixed_rows_mut::<3>(0).copy_from(&v_imu);
            for r in reset.iter_mut().take(3) {
                *r = true;
            }
        }
    }
    (x, reset)
}

/// `p` with the rows and columns of the `reset` states zeroed and their
/// variances at `initial_sigma²`: still positive definite when `p` was.
pub(crate) fn reset_covariance<T: Real>(
    p: &Mat6<T>,
    reset: &[bool; NX],
    initial_sigma: &StateVec<T>,
) -> Mat6<T> {
    // Row and column of each reset state zeroed, then its variance: the
    // same matrix as testing every entry for `reset[i] || reset[j]`, in
    // one block per state instead of 36 tests unrolled (2.2 KB of cold
    // re-alignment code in the firmware, issue 17).
    let mut p = *p;
    for (i, ri) in reset.iter().enumerate() {
        if *ri {
            p.row_mut(i).fill(T::zero());
            p.column_mut(i).fill(T::zero());
            let s = initial_sigma.get(i).copied().unwrap_or(T::one());
            if let Some(v) = p.get_mut((i, i)) {
                *v = s * s;
            }
        }
    }
    p
}

/// Whether this epoch's aiding can re-align an attitude the prediction
/// refused (`pitch_singular`: the state or its sigma points reached the
/// Euler singularity): a complete, finite attitude with `|cos θ|` at least
/// twice `cos_pitch_min`, so that the sigma points around it (initial
/// σ of a few degrees) are clear of the singularity too and the prediction
/// can resume (with the defaults: |θ| ≤ 78.5°, the singularity at 84.3°).
pub(crate) fn singular_recoverable<T: Real>(
    model: &VehicleModel<T>,
    aiding: &Measurement<T>,
) -> bool {
    let complete = aiding
        .available
        .get(ROLL..NZ)
        .is_some_and(|a| a.iter().all(|v| *v));
    let finite = aiding.z.iter().skip(ROLL).all(|v| v.finite());
    let clear = aiding
        .z
        .get(PITCH)
        .is_some_and(|theta| theta.sin_cos_fast().1.abs() >= model.cos_pitch_min * T::lit(2.0));
    complete && finite && clear
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pattern of reset states gives the matrix of the entry-wise
    /// definition, bit for bit.
    #[test]
    fn reset_covariance_is_the_entrywise_definition() {
        let p = Mat6::<f32>::from_fn(|i, j| 1.0 + (i * 6 + j) as f32 * 0.37);
        let sigma = StateVec::<f32>::from_fn(|i, _| 0.1 + i as f32);
        for bits in 0u32..64 {
            let reset: [bool; NX] = core::array::from_fn(|i| bits & (1 << i) != 0);
            let want = Mat6::<f32>::from_fn(|i, j| {
                if reset[i] && i == j {
                    sigma[i] * sigma[i]
                } else if reset[i] || reset[j] {
                    0.0
                } else {
                    p[(i, j)]
                }
            });
            assert_eq!(reset_covariance(&p, &reset, &sigma), want, "{reset:?}");
        }
    }
}

//! The UKF monitor's tracking fault estimate (issue 15): a Kalman filter on
//! the fault `f` (a random walk) and on `e`, the part of the monitor's own
//! state estimate that the fault history has moved, from every innovation
//! since monitoring started.
//!
//! Why not the window mean: the monitor's filter does not model the fault,
//! so it absorbs part of it into the state. A constant fault present since
//! forever gives innovations `M f` (`M = −H X⁻`, the closed-loop signature),
//! but a fault that has just appeared or is changing gives less, because
//! the state has not yet been pulled away by it; and a window of `W`
//! epochs both averages too little (noise) and lags by `W/2` epochs. Here
//! the fault's effect on the state is carried explicitly: between aiding
//! epochs `e ← Φ e + Γ f` with `Γ = X⁻ₖ − Φ X⁺ₖ₋₁` (so that a constant fault
//! gives exactly the monitor's sensitivity `X`), the innovation is
//! `r = −H e⁻ + ν` with `ν` the fault-free filter's white innovation of
//! variance `S_ii`, and the filter's own update moves it by
//! `e⁺ = (I − K H) e⁻`. This is the linear system the augmented filter
//! would estimate, so with the same fault random walk its fault estimate
//! is the augmented filter's (to the linearisation), whatever the fault's
//! shape. The window mean stays the detection statistic.
//!
//! The 12-state covariance is kept in 6×6 blocks `P_ee`, `P_ef`, `P_ff`.

use crate::filter::ChannelDiag;
use crate::math::Real;
#[cfg(feature = "fault-tracking")]
use crate::math::{all_finite, mirror_lower};
#[cfg(feature = "fault-tracking")]
use crate::model::StateVec;
use crate::model::{ImuVec, Mat6, NX, NZ};

/// Tracking fault estimator state (see the module notes).
#[cfg(feature = "fault-tracking")]
#[derive(Debug, Clone)]
pub(super) struct FaultTracker<T> {
    /// Running (started at monitoring start, stopped at alignment).
    pub active: bool,
    /// State deviation caused by the fault history, `e`.
    e: StateVec<T>,
    /// Fault estimate, raw units.
    f: ImuVec<T>,
    p_ee: Mat6<T>,
    p_ef: Mat6<T>,
    p_ff: Mat6<T>,
    /// Transition since the last aiding epoch, accumulated per IMU step.
    pub phi: Mat6<T>,
    /// Time since the last aiding epoch, s.
    pub elapsed: T,
    /// The sensitivity `X⁺` after the last aiding update.
    x_post: Mat6<T>,
    /// The starting standard deviation of the fault.
    sigma0: ImuVec<T>,
    /// An aiding epoch staged by the update step, run by the next step
    /// ([`run_epoch`](Self::run_epoch)).
    pending: bool,
    /// The staged epoch: the sensitivity before the update `X⁻`, the
    /// filter's gain `K` and measurement Jacobian `H` (not kept when it is
    /// the identity, `affine`), the innovations, their variances and which
    /// channels are read.
    x_prior: Mat6<T>,
    gain: Mat6<T>,
    h: Mat6<T>,
    affine: bool,
    r: ImuVec<T>,
    var: ImuVec<T>,
    used: [bool; 6],
    gate: T,
    /// The monitored channels when the epoch's report was composed: the
    /// report shows the estimate of those only.
    mask: [bool; 6],
}

#[cfg(feature = "fault-tracking")]
impl<T: Real> FaultTracker<T> {
    /// An inactive tracker.
    pub fn new() -> Self {
        Self {
            active: false,
            e: StateVec::zeros(),
            f: ImuVec::zeros(),
            p_ee: Mat6::zeros(),
            p_ef: Mat6::zeros(),
            p_ff: Mat6::zeros(),
            phi: Mat6::identity(),
            elapsed: T::zero(),
            x_post: Mat6::zeros(),
            sigma0: ImuVec::zeros(),
            pending: false,
            x_prior: Mat6::zeros(),
            gain: Mat6::zeros(),
            h: Mat6::zeros(),
            affine: true,
            r: ImuVec::zeros(),
            var: ImuVec::zeros(),
            used: [false; 6],
            gate: T::zero(),
            mask: [false; 6],
        }
    }

    /// True while an aiding epoch waits for [`run_epoch`](Self::run_epoch).
    pub fn pending(&self) -> bool {
        self.pending
    }

    /// Records the channels the epoch's report monitors (the estimate is
    /// shown on those only).
    pub fn set_mask(&mut self, monitored: [bool; 6]) {
        self.mask = monitored;
    }

    /// The channels set by [`set_mask`](Self::set_mask).
    pub fn mask(&self) -> [bool; 6] {
        self.mask
    }

    /// Stages an aiding epoch: `x_prior` is the sensitivity `X⁻` before the
    /// filter's update, `gate` the outlier gate (σ). The epoch's work (its
    /// propagation, the innovations, the filter's update: several 6×6
    /// block products) runs on the next step, whose count is a
    /// predict-only step's, instead of on the update step, which has the
    /// largest count (issue 17). The estimate is the same, reported one
    /// IMU sample later.
    pub fn begin_epoch(&mut self, x_prior: &Mat6<T>, gate: T) {
        self.x_prior = *x_prior;
        self.gate = gate;
        self.used = [false; 6];
    }

    /// Stages channel `i`'s innovation `r` of variance `var` (see
    /// [`observe`](Self::observe)).
    fn stage(&mut self, i: usize, r: T, var: T) {
        if let (Some(u), Some(rv), Some(vv)) =
            (self.used.get_mut(i), self.r.get_mut(i), self.var.get_mut(i))
        {
            *u = true;
            *rv = r;
            *vv = var;
        }
    }

    /// Completes the staged epoch with the filter's gain `K` and its
    /// measurement Jacobian `H` (`None`: the identity).
    pub fn end_epoch(&mut self, gain: &Mat6<T>, h: Option<&Mat6<T>>) {
        self.gain = *gain;
        self.affine = h.is_none();
        if let Some(h) = h {
            self.h = *h;
        }
        self.pending = true;
    }

    /// Runs the staged epoch: propagation to it, the innovations in channel
    /// order, the filter's update (`x_post`: the sensitivity after it).
    #[inline(never)] // own stack frame, one copy (issue 17)
    pub fn run_epoch(&mut self, psd: &ImuVec<T>, x_post: &Mat6<T>) {
        self.pending = false;
        let x_prior = self.x_prior;
        self.propagate(&x_prior, psd);
        let (gate, affine) = (self.gate, self.affine);
        for i in 0..6 {
            let (Some(&u), Some(&r), Some(&var)) =
                (self.used.get(i), self.r.get(i), self.var.get(i))
            else {
                continue;
            };
            if !u {
                continue;
            }
            if affine {
                self.observe_state(i, r, var, gate);
            } else {
                let h = self.h.row(i).transpose();
                self.observe(&h, r, var, gate);
            }
        }
        let t = if affine {
            Mat6::identity() - self.gain
        } else {
            Mat6::identity() - self.gain * self.h
        };
        self.filter_update(&t, x_post);
    }

    /// Starts from "no fault" with standard deviation `sigma0` (what the
    /// nominal-bias learning may have left), `x` the sensitivity now.
    pub fn start(&mut self, sigma0: &ImuVec<T>, x: &Mat6<T>) {
        *self = Self::new();
        self.active = true;
        self.p_ff = Mat6::from_diagonal(&sigma0.component_mul(sigma0));
        self.x_post = *x;
        self.sigma0 = *sigma0;
    }

    /// The fault estimate and its standard deviation.
    pub fn estimate(&self) -> (ImuVec<T>, ImuVec<T>) {
        let sd = self.p_ff.diagonal().map(|v| v.fmax(T::zero()).sqrt_fast());
        (self.f, sd)
    }

    /// States re-initialised by a re-alignment no longer carry the fault
    /// history: their deviation and its covariance are zero.
    pub fn forget_states(&mut self, reset: &[bool; NX]) {
        for (i, r) in reset.iter().enumerate() {
            if *r {
                if let Some(v) = self.e.get_mut(i) {
                    *v = T::zero();
                }
                self.p_ee.row_mut(i).fill(T::zero());
                self.p_ee.column_mut(i).fill(T::zero());
                self.p_ef.row_mut(i).fill(T::zero());
            }
        }
    }

    /// One IMU step of the transition since the last aiding epoch,
    /// `Φ ← Φ + A Φ dt` (the sensitivity's first-order transition), `a` the
    /// model's state Jacobian. `A = [[Ω, G, 0], [0, L, 0]]` (velocity rows
    /// 0–2: the skew `Ω` and the roll/pitch columns `G`; attitude rows 3–5:
    /// roll/pitch columns `L`; the yaw column zero), so from `Φ = I` the
    /// attitude rows of the velocity columns stay zero and the yaw column
    /// stays `e₅`: only the velocity rows of columns 0–2 and all rows of
    /// columns 3–4 change (the same values as
    /// `VehicleModel::mul_state_jacobian`, which adds the zeros; issue 17).
    ///
    /// Inlined into `predict`, unlike the epoch's methods: without the
    /// feature the stand-in leaves nothing there, and with it a call per
    /// IMU step cost S2 SIL step mean 8,245 against 8,145 inlined.
    pub fn advance(&mut self, a: &Mat6<T>, dt: T) {
        let (w0, w1, w2) = (a[(2, 1)], a[(0, 2)], a[(1, 0)]);
        let p = &mut self.phi;
        for j in 0..3 {
            let (x0, x1, x2) = (p[(0, j)], p[(1, j)], p[(2, j)]);
            p[(0, j)] += (w1 * x2 - w2 * x1) * dt;
            p[(1, j)] += (w2 * x0 - w0 * x2) * dt;
            p[(2, j)] += (w0 * x1 - w1 * x0) * dt;
        }
        for j in 3..5 {
            let (x0, x1, x2) = (p[(0, j)], p[(1, j)], p[(2, j)]);
            let (x3, x4) = (p[(3, j)], p[(4, j)]);
            let g = |r: usize| a[(r, 3)] * x3 + a[(r, 4)] * x4;
            p[(0, j)] += (w1 * x2 - w2 * x1 + g(0)) * dt;
            p[(1, j)] += (w2 * x0 - w0 * x2 + g(1)) * dt;
            p[(2, j)] += (w0 * x1 - w1 * x0 + g(2)) * dt;
            p[(3, j)] += g(3) * dt;
            p[(4, j)] += g(4) * dt;
            p[(5, j)] += g(5) * dt;
        }
        self.elapsed += dt;
    }

    /// Stages every fused or gate-rejected innovation of the update
    /// (channel `i`: variance `S_ii` × the learnt inflation, the time
    /// correlation it measured on the window means, taken as extra
    /// variance per sample); [`run_epoch`](Self::run_epoch) observes them
    /// in channel order.
    #[inline(never)] // off `update`'s frame and inlined code (issue 17)
    pub fn observe_all(&mut self, diag: &[ChannelDiag<T>; NZ], inflation: &[T; NZ]) {
        for ((i, d), c) in diag.iter().enumerate().zip(inflation.iter()) {
            if d.available {
                self.stage(i, d.innovation, d.variance * *c);
            }
        }
    }

    /// Propagation to this aiding epoch: `x_prior` is the sensitivity `X⁻`
    /// now, `psd` the fault's random-walk spectral density.
    #[inline(never)] // off `update`'s frame and inlined code (issue 17)
    pub fn propagate(&mut self, x_prior: &Mat6<T>, psd: &ImuVec<T>) {
        let phi = self.phi;
        // Γ = X⁻ − Φ X⁺.
        let mut gamma = *x_prior;
        mul_acc(
            gamma.as_mut_slice(),
            &phi,
            self.x_post.as_slice(),
            false,
            -T::one(),
        );
        let mut e = StateVec::zeros();
        mul_acc(e.as_mut_slice(), &phi, self.e.as_slice(), false, T::one());
        mul_acc(e.as_mut_slice(), &gamma, self.f.as_slice(), false, T::one());
        self.e = e;
        // [Φ Γ] P [Φ Γ]ᵀ by blocks: a1 = Φ P_ee + Γ P_fe, a2 = Φ P_ef + Γ P_ff,
        // P_ee = a1 Φᵀ + a2 Γᵀ.
        let mut a1 = Mat6::zeros();
        mul_acc(
            a1.as_mut_slice(),
            &phi,
            self.p_ee.as_slice(),
            false,
            T::one(),
        );
        mul_acc(
            a1.as_mut_slice(),
            &gamma,
            self.p_ef.as_slice(),
            true,
            T::one(),
        );
        let mut a2 = Mat6::zeros();
        mul_acc(
            a2.as_mut_slice(),
            &phi,
            self.p_ef.as_slice(),
            false,
            T::one(),
        );
        mul_acc(
            a2.as_mut_slice(),
            &gamma,
            self.p_ff.as_slice(),
            false,
            T::one(),
        );
        let mut p_ee = Mat6::zeros();
        mul_acc(p_ee.as_mut_slice(), &a1, phi.as_slice(), true, T::one());
        mul_acc(p_ee.as_mut_slice(), &a2, gamma.as_slice(), true, T::one());
        mirror_lower(&mut p_ee);
        self.p_ee = p_ee;
        self.p_ef = a2;
        for (i, q) in psd.iter().enumerate() {
            if let Some(v) = self.p_ff.get_mut((i, i)) {
                *v += *q * self.elapsed;
            }
        }
        self.phi = Mat6::identity();
        self.elapsed = T::zero();
    }

    /// One innovation `r` of variance `var` on a channel whose measurement
    /// row is `h` (as a column; `r = −hᵀ e⁻ + ν`). An innovation more than
    /// `gate` σ from what the tracked fault predicts is an aiding outlier,
    /// not fault evidence, and is skipped. The filter's own gate is not
    /// used: it judges the innovation against a fault-free prediction, so it
    /// rejects exactly the epochs a large fault makes most informative.
    pub fn observe(&mut self, h: &StateVec<T>, r: T, var: T, gate: T) {
        let ue = -(self.p_ee * h);
        let uf = -(self.p_ef.tr_mul(h));
        let s = var - h.dot(&ue);
        let y = r + h.dot(&self.e);
        self.correct(&ue, &uf, s, y, gate);
    }

    /// [`observe`](Self::observe) for the measurement row `h = eᵢ` (M1's
    /// Jacobian is the identity): `P_ee h` is a column, `P_efᵀ h` a row and
    /// the two dot products single entries, so no products (issue 17).
    pub fn observe_state(&mut self, i: usize, r: T, var: T, gate: T) {
        let (Some(&pii), Some(&ei)) = (self.p_ee.get((i, i)), self.e.get(i)) else {
            return;
        };
        let ue = -self.p_ee.column(i);
        let uf = -self.p_ef.row(i).transpose();
        self.correct(&ue, &uf, var + pii, r + ei, gate);
    }

    /// The scalar Kalman correction by the innovation `y` of variance `s`,
    /// `ue`, `uf` the (negated) covariances of `e`, `f` with it; `P_ee`
    /// and `P_ff` on their lower triangles, mirrored (symmetric by
    /// construction, 21 products each instead of 36).
    fn correct(&mut self, ue: &StateVec<T>, uf: &ImuVec<T>, s: T, y: T, gate: T) {
        if !s.finite() || s <= T::zero() {
            return;
        }
        if y * y > gate * gate * s {
            return;
        }
        let inv = T::one() / s;
        let ke = ue * inv;
        let kf = uf * inv;
        self.e += ke * y;
        self.f += kf * y;
        // P −= k uᵀ per block (P_ee, P_ff symmetric: the products agree
        // to rounding; mirrored from the lower triangle at the epoch's end).
        outer_sub(self.p_ee.as_mut_slice(), &ke, ue);
        outer_sub(self.p_ef.as_mut_slice(), &ke, uf);
        outer_sub(self.p_ff.as_mut_slice(), &kf, uf);
    }

    /// The monitor's filter update `e⁺ = (I − K H) e⁻`, given `t = I − K H`,
    /// and `x_post` the sensitivity after it.
    #[inline(never)] // own stack frame, one copy (issue 17)
    pub fn filter_update(&mut self, t: &Mat6<T>, x_post: &Mat6<T>) {
        let mut e = StateVec::zeros();
        mul_acc(e.as_mut_slice(), t, self.e.as_slice(), false, T::one());
        self.e = e;
        // P_ee = t P_ee tᵀ, mirrored from its lower triangle: symmetric
        // under rounding without a symmetrising pass.
        let mut a = Mat6::zeros();
        mul_acc(a.as_mut_slice(), t, self.p_ee.as_slice(), false, T::one());
        let mut p = Mat6::zeros();
        mul_acc(p.as_mut_slice(), &a, t.as_slice(), true, T::one());
        mirror_lower(&mut p);
        self.p_ee = p;
        let mut p = Mat6::zeros();
        mul_acc(p.as_mut_slice(), t, self.p_ef.as_slice(), false, T::one());
        self.p_ef = p;
        mirror_lower(&mut self.p_ff);
        // Rounding (f32) must not leave a negative variance (`P_ff` is
        // kept symmetric by `correct`).
        for i in 0..6 {
            for p in [&mut self.p_ee, &mut self.p_ff] {
                if let Some(v) = p.get_mut((i, i)) {
                    *v = v.fmax(T::zero());
                }
            }
        }
        self.x_post = *x_post;
        // A non-finite value (a covariance reset upstream, garbage input)
        // starts the estimate again rather than reporting NaN forever.
        if !(all_finite(self.f.as_slice())
            && all_finite(self.e.as_slice())
            && all_finite(self.p_ee.as_slice())
            && all_finite(self.p_ef.as_slice())
            && all_finite(self.p_ff.as_slice()))
        {
            let sigma0 = self.sigma0;
            self.start(&sigma0, x_post);
        }
    }
}

/// `out += s · A op(B)`, `A` 6×6, `B` 6 rows (column-major, as many
/// columns as `out`), `op(B) = Bᵀ` when `bt` (then `B` is 6×6). One rolled
/// kernel for all of the tracker's block products: fully unrolled, each
/// 6×6 product is ≈ 1.3 KB of flash and the tracker's epoch was 12 KB; this
/// is one copy, its column loop over a run-time count (issue 17).
#[cfg(feature = "fault-tracking")]
#[inline(never)]
fn mul_acc<T: Real>(out: &mut [T], a: &Mat6<T>, b: &[T], bt: bool, s: T) {
    for (j, oc) in out.chunks_exact_mut(6).enumerate() {
        for (k, ac) in a.as_slice().chunks_exact(6).enumerate() {
            let idx = if bt { j + 6 * k } else { k + 6 * j };
            let bkj = b.get(idx).copied().unwrap_or(T::zero()) * s;
            for (o, x) in oc.iter_mut().zip(ac) {
                *o += *x * bkj;
            }
        }
    }
}

/// `P −= k uᵀ` (6×6, column-major).
#[cfg(feature = "fault-tracking")]
#[inline(never)]
fn outer_sub<T: Real>(p: &mut [T], k: &StateVec<T>, u: &StateVec<T>) {
    for (pc, uj) in p.chunks_exact_mut(6).zip(u.iter()) {
        for (v, ki) in pc.iter_mut().zip(k.iter()) {
            *v -= *ki * *uj;
        }
    }
}

/// Without the feature `fault-tracking`: an empty stand-in with the same
/// calls, so the monitor carries no tracker state (≈ 1 KB in f32).
#[cfg(not(feature = "fault-tracking"))]
#[derive(Debug, Clone)]
pub(super) struct FaultTracker<T> {
    /// Never set: the tracker does not run.
    pub active: bool,
    _t: core::marker::PhantomData<T>,
}

#[cfg(not(feature = "fault-tracking"))]
impl<T: Real> FaultTracker<T> {
    /// An inactive tracker.
    pub fn new() -> Self {
        Self {
            active: false,
            _t: core::marker::PhantomData,
        }
    }
    /// Never: no epoch is staged.
    pub fn pending(&self) -> bool {
        false
    }
    /// Does nothing.
    pub fn begin_epoch(&mut self, _x_prior: &Mat6<T>, _gate: T) {}
    /// Does nothing.
    pub fn observe_all(&mut self, _diag: &[ChannelDiag<T>; NZ], _inflation: &[T; NZ]) {}
    /// Does nothing.
    pub fn end_epoch(&mut self, _gain: &Mat6<T>, _h: Option<&Mat6<T>>) {}
    /// Does nothing.
    pub fn run_epoch(&mut self, _psd: &ImuVec<T>, _x_post: &Mat6<T>) {}
    /// Does nothing (the configuration is refused without the feature).
    pub fn start(&mut self, _sigma0: &ImuVec<T>, _x: &Mat6<T>) {}
    /// No estimate.
    pub fn estimate(&self) -> (ImuVec<T>, ImuVec<T>) {
        (ImuVec::zeros(), ImuVec::zeros())
    }
    /// Does nothing.
    pub fn set_mask(&mut self, _monitored: [bool; 6]) {}
    /// No channel.
    pub fn mask(&self) -> [bool; 6] {
        [false; 6]
    }
    /// Does nothing.
    pub fn forget_states(&mut self, _reset: &[bool; NX]) {}
    /// Does nothing.
    pub fn advance(&mut self, _a: &Mat6<T>, _dt: T) {}
}

#[cfg(all(test, feature = "fault-tracking"))]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
    use super::*;
    use nalgebra::{SMatrix, SVector};

    type M12 = SMatrix<f64, 12, 12>;
    type V12 = SVector<f64, 12>;

    /// Deterministic N(0, 1)-ish samples (sum of 12 uniforms − 6).
    struct Noise(u64);
    impl Noise {
        fn next(&mut self) -> f64 {
            let mut s = 0.0;
            for _ in 0..12 {
                self.0 = self
                    .0
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                s += (self.0 >> 11) as f64 / (1u64 << 53) as f64;
            }
            s - 6.0
        }
    }

    /// On a linear system with one scalar measurement per epoch the tracker
    /// run beside a filter that ignores the fault gives exactly the fault
    /// estimate and covariance of the 12-state augmented Kalman filter: the
    /// fault-free filter's innovations are white and independent of the
    /// fault, and the innovations actually seen are those plus `−H e⁻`,
    /// with `e` the state deviation the fault history has caused. The fault
    /// is a random walk with the tracker's spectral density plus a step and
    /// a ramp, whatever its shape.
    #[test]
    fn equals_the_augmented_kalman_filter_on_a_linear_system() {
        let dt = 0.1;
        // Coupled dynamics (a rotation-like block and a gravity-like one).
        let a = Mat6::<f64>::from_fn(|i, j| match (i, j) {
            (0, 1) => 0.3,
            (1, 0) => -0.3,
            (0, 4) => -9.8,
            (1, 3) => 9.8,
            (2, 2) => -0.05,
            (3, 4) => 0.1,
            (4, 3) => -0.1,
            (5, 5) => -0.02,
            _ => 0.0,
        });
        let phi = Mat6::identity() + a * dt + a * a * (dt * dt * 0.5);
        let gamma = Mat6::<f64>::identity() * dt;
        let q = Mat6::from_diagonal(&ImuVec::new(1e-4, 1e-4, 1e-4, 1e-7, 1e-7, 1e-7));
        let r = [
            0.05f64.powi(2),
            0.05f64.powi(2),
            0.05f64.powi(2),
            3e-6,
            3e-6,
            5e-6,
        ];
        let psd = ImuVec::new(0.05, 0.05, 0.05, 8e-5, 8e-5, 8e-5);
        let sigma0 = ImuVec::new(0.2, 0.2, 0.2, 0.02, 0.02, 0.02);
        let p0 = Mat6::from_diagonal(&ImuVec::new(0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3));

        // The augmented filter on (x, f): x' = Φx + Γ(u − f) + w, f' = f + η.
        let mut fa = M12::identity();
        fa.fixed_view_mut::<6, 6>(0, 0).copy_from(&phi);
        fa.fixed_view_mut::<6, 6>(0, 6).copy_from(&(-gamma));
        let mut qa = M12::zeros();
        qa.fixed_view_mut::<6, 6>(0, 0).copy_from(&q);
        for i in 0..6 {
            qa[(6 + i, 6 + i)] = psd[i] * dt;
        }
        let mut xa = V12::zeros();
        let mut pa = M12::zeros();
        pa.fixed_view_mut::<6, 6>(0, 0).copy_from(&p0);
        for i in 0..6 {
            pa[(6 + i, 6 + i)] = sigma0[i] * sigma0[i];
        }
        // The fault-free filter, its sensitivity X, and the tracker.
        let (mut xb, mut pb, mut xs) = (StateVec::<f64>::zeros(), p0, Mat6::<f64>::zeros());
        let mut tr = FaultTracker::<f64>::new();
        tr.start(&sigma0, &xs);

        let mut noise = Noise(7);
        let mut x = StateVec::<f64>::zeros();
        let mut worst_f = 0.0f64;
        let mut worst_p = 0.0f64;
        for k in 0..600 {
            let t = k as f64 * dt;
            let u = ImuVec::new(0.3 * (0.2 * t).sin(), 0.1, 0.0, 0.01, -0.02, 0.0);
            let mut f = ImuVec::zeros();
            if t > 10.0 {
                f[0] = 0.5;
                f[4] = 0.03;
            }
            if t > 20.0 {
                f[2] = 0.05 * (t - 20.0);
                f[3] = -0.002 * (t - 20.0);
            }
            let w = ImuVec::from_fn(|i, _| q[(i, i)].sqrt() * noise.next());
            x = phi * x + gamma * u + w;
            let um = u + f;
            // Predict both filters.
            let mut ua = V12::zeros();
            ua.fixed_rows_mut::<6>(0).copy_from(&(gamma * um));
            xa = fa * xa + ua;
            pa = fa * pa * fa.transpose() + qa;
            xb = phi * xb + gamma * um;
            pb = phi * pb * phi.transpose() + q;
            xs = phi * xs + gamma;
            tr.phi = phi;
            tr.elapsed = dt;
            tr.propagate(&xs, &psd);
            // One scalar measurement, cycling through the channels.
            let i = k % 6;
            let h = nalgebra::RowSVector::<f64, 6>::from_fn(|_, j| if j == i { 1.0 } else { 0.0 });
            let hc = h.transpose();
            let z = x[i] + r[i].sqrt() * noise.next();
            // Augmented update.
            let mut ha = nalgebra::RowSVector::<f64, 12>::zeros();
            ha[i] = 1.0;
            let sa = (ha * pa * ha.transpose())[(0, 0)] + r[i];
            let ka = pa * ha.transpose() / sa;
            xa += ka * (z - (ha * xa)[(0, 0)]);
            pa -= ka * ha * pa;
            // Fault-free filter's update; the tracker sees its innovation.
            let s = (h * pb * h.transpose())[(0, 0)] + r[i];
            let kb = pb * h.transpose() / s;
            let innov = z - (h * xb)[(0, 0)];
            tr.observe(&hc, innov, s, 8.0);
            xb += kb * innov;
            let tm = Mat6::identity() - kb * h;
            pb = tm * pb;
            xs = tm * xs;
            tr.filter_update(&tm, &xs);
            let (fh, sd) = tr.estimate();
            for c in 0..6 {
                let scale = sigma0[c];
                worst_f = worst_f.max((fh[c] - xa[6 + c]).abs() / scale);
                let sa = pa[(6 + c, 6 + c)].sqrt();
                worst_p = worst_p.max((sd[c] - sa).abs() / sa);
            }
        }
        // Equal to rounding (relative to the fault scale / the σ).
        assert!(worst_f < 1e-8, "estimate differs by {worst_f} σ0");
        assert!(worst_p < 1e-8, "σ differs by {worst_p} relative");
        // And it found the faults.
        let (fh, _) = tr.estimate();
        assert!((fh[0] - 0.5).abs() < 0.1, "{fh}");
        // An aiding outlier (100 m/s off) moves nothing.
        let before = tr.clone();
        tr.observe(
            &StateVec::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            100.0,
            r[0],
            8.0,
        );
        assert_eq!(tr.estimate(), before.estimate());
        // A non-finite input restarts the estimate instead of poisoning it.
        tr.observe(
            &StateVec::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            0.0,
            f64::NAN,
            8.0,
        );
        tr.filter_update(&Mat6::identity(), &Mat6::from_element(f64::NAN));
        tr.filter_update(&Mat6::identity(), &Mat6::zeros());
        assert!(tr.estimate().0.iter().all(|v| v.is_finite()));
    }
}

#[cfg(all(test, feature = "fault-tracking"))]
mod structure_tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
    use super::*;
    use crate::model::VehicleModel;

    /// A state Jacobian of the model's form `[[Ω, G, 0], [0, L, 0]]`.
    fn jacobian(seed: f64) -> Mat6<f64> {
        let v = |k: f64| (seed * 1.7 + k * 0.37).sin();
        let (w0, w1, w2) = (v(1.0), v(2.0), v(3.0));
        let mut a = Mat6::zeros();
        a[(2, 1)] = w0;
        a[(1, 2)] = -w0;
        a[(0, 2)] = w1;
        a[(2, 0)] = -w1;
        a[(1, 0)] = w2;
        a[(0, 1)] = -w2;
        for r in 0..6 {
            for c in 3..5 {
                a[(r, c)] = 9.8 * v(10.0 + (r * 2 + c) as f64);
            }
        }
        a
    }

    /// `advance` gives bit for bit the transition of the full product
    /// `Φ += A Φ dt` (`VehicleModel::mul_state_jacobian`) over many steps.
    #[test]
    fn advance_equals_the_full_product() {
        let mut tr = FaultTracker::<f64>::new();
        let mut phi = Mat6::<f64>::identity();
        for k in 0..500 {
            let a = jacobian(k as f64);
            phi += VehicleModel::mul_state_jacobian(&a, &phi) * 0.01;
            tr.advance(&a, 0.01);
        }
        assert_eq!(tr.phi, phi);
        assert!((tr.elapsed - 5.0).abs() < 1e-9);
        // And the transition is far from the identity (the test can fail).
        assert!((phi - Mat6::identity()).abs().max() > 0.5);
    }

    /// `observe_state(i)` is `observe` with the row `eᵢ`, and `mul_acc`
    /// the plain products.
    #[test]
    fn unit_row_and_kernel_equal_the_general_forms() {
        let mut tr = FaultTracker::<f64>::new();
        tr.start(
            &ImuVec::new(0.2, 0.2, 0.2, 0.02, 0.02, 0.02),
            &Mat6::zeros(),
        );
        tr.phi = Mat6::identity() + jacobian(3.0) * 0.05;
        tr.elapsed = 0.1;
        tr.propagate(
            &Mat6::from_fn(|i, j| 0.1 * (i as f64 - j as f64 + 0.5)),
            &ImuVec::repeat(0.05),
        );
        let mut general = tr.clone();
        for i in 0..6 {
            let r = 0.3 * i as f64 - 0.7;
            tr.observe_state(i, r, 0.01, 8.0);
            let h = StateVec::from_fn(|k, _| if k == i { 1.0 } else { 0.0 });
            general.observe(&h, r, 0.01, 8.0);
        }
        let (f, sd) = tr.estimate();
        let (fg, sdg) = general.estimate();
        assert!((f - fg).abs().max() < 1e-12 && (sd - sdg).abs().max() < 1e-12);
        assert!(f.abs().max() > 1e-3, "the estimate moved: {f}");
        let a = jacobian(1.0);
        let b = jacobian(2.0) + Mat6::identity();
        let mut out = Mat6::identity();
        mul_acc(out.as_mut_slice(), &a, b.as_slice(), false, 2.0);
        assert!((out - (Mat6::identity() + a * b * 2.0)).abs().max() < 1e-12);
        let mut out = Mat6::zeros();
        mul_acc(out.as_mut_slice(), &a, b.as_slice(), true, -1.0);
        assert!((out + a * b.transpose()).abs().max() < 1e-12);
    }
}

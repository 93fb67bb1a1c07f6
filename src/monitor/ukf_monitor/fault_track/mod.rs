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

#[cfg(feature = "fault-tracking")]
use crate::filter::ChannelDiag;
#[cfg(feature = "fault-tracking")]
use crate::math::{all_finite, mirror_lower, Real};
#[cfg(feature = "fault-tracking")]
use crate::model::{ImuVec, Mat6, StateVec, NX, NZ};

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

#[cfg(not(feature = "fault-tracking"))]
mod stand_in;
#[cfg(not(feature = "fault-tracking"))]
pub(super) use stand_in::FaultTracker;

#[cfg(all(test, feature = "fault-tracking"))]
mod structure_tests;
#[cfg(all(test, feature = "fault-tracking"))]
mod tests;

//! Additive-noise unscented Kalman filter of fixed size.

use nalgebra::{SMatrix, SVector};

use super::{ChannelDiag, Gate, SigmaParams, SigmaWeights};

mod affine;
mod split;
pub(crate) use crate::math::all_finite;
use crate::math::{
    add_outer_lower, cholesky, cholesky_solve_right, is_identity, lower_finite, mirror_lower,
    symmetrize, wrap_pi, LinalgError, Real,
};

/// Why a UKF step did not complete normally.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum UkfError<E> {
    /// The process or measurement function refused a sigma point; the filter
    /// is unchanged.
    Model(E),
    /// The state covariance lost positive definiteness. Recovery was applied:
    /// the covariance was re-initialised to the reset matrix and the step was
    /// completed with it. Counted in [`Ukf::covariance_resets`].
    CovarianceReset(LinalgError),
    /// The innovation covariance was not positive definite; the update was
    /// skipped and the filter is unchanged.
    InnovationCovariance(LinalgError),
    /// The result contained NaN or infinity; the filter is unchanged.
    NonFinite,
}

impl UkfError<core::convert::Infallible> {
    /// The same error as the error type of a fallible model.
    pub fn widen<E>(self) -> UkfError<E> {
        match self {
            Self::Model(never) => match never {},
            Self::CovarianceReset(e) => UkfError::CovarianceReset(e),
            Self::InnovationCovariance(e) => UkfError::InnovationCovariance(e),
            Self::NonFinite => UkfError::NonFinite,
        }
    }
}

/// What an update produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateOutput<T, const N: usize, const M: usize> {
    /// One diagnostic record per measurement channel.
    pub diag: [ChannelDiag<T>; M],
    /// The gain that was applied (zero columns for channels not fused).
    pub gain: SMatrix<T, N, M>,
    /// The innovation covariance `P_zz` used for the gain (channels not
    /// fused decoupled: unit variance, no cross terms).
    pub innovation_covariance: SMatrix<T, M, M>,
    /// Set when `P` had to be re-initialised before this update (the update
    /// was then done with the reset covariance).
    pub covariance_reset: Option<LinalgError>,
}

/// An unscented Kalman filter with `N` states and `S = 2N + 1` sigma points.
///
/// The process and measurement functions are passed to each call, so one
/// filter type serves the vehicle model, reference models in tests and the
/// augmented filters. Angle components (flagged at construction) use circular
/// means — the weighted mean of wrapped differences to the first sigma point —
/// and wrapped residuals. Sigma points for the update are redrawn from the
/// predicted mean and covariance (\[OTS\] eq. (23)).
///
/// Covariance health: after every step `P` is symmetrised and its diagonal
/// floored at `min_variance`; a failed Cholesky factorisation re-initialises
/// `P` (see [`UkfError::CovarianceReset`]).
#[derive(Debug, Clone)]
pub struct Ukf<T, const N: usize, const S: usize> {
    x: SVector<T, N>,
    p: SMatrix<T, N, N>,
    p_reset: SMatrix<T, N, N>,
    min_variance: SVector<T, N>,
    weights: SigmaWeights<T, S>,
    angles: [bool; N],
    resets: u32,
}

fn diff<T: Real, const K: usize>(
    a: &SVector<T, K>,
    b: &SVector<T, K>,
    angles: &[bool; K],
) -> SVector<T, K> {
    diff_inline(a, b, angles)
}

/// [`diff`] inlined: for the split prediction's sigma points, where the
/// out-of-line call returning through memory cost ≈ 230 instructions per
/// S2 step on the Cortex-M4F (issue 17); elsewhere the one shared copy
/// keeps the flash down (inlined everywhere: +730 bytes of firmware).
#[inline(always)]
fn diff_inline<T: Real, const K: usize>(
    a: &SVector<T, K>,
    b: &SVector<T, K>,
    angles: &[bool; K],
) -> SVector<T, K> {
    let mut d = a - b;
    for (v, is_angle) in d.iter_mut().zip(angles.iter()) {
        if *is_angle {
            *v = wrap_pi(*v);
        }
    }
    d
}

fn weighted_mean<T: Real, const K: usize, const S: usize>(
    pts: &[SVector<T, K>; S],
    wm: &[T; S],
    angles: &[bool; K],
) -> SVector<T, K> {
    let Some(reference) = pts.first() else {
        return SVector::zeros();
    };
    let mut acc = SVector::<T, K>::zeros();
    for (pt, w) in pts.iter().zip(wm.iter()) {
        acc += diff(pt, reference, angles) * *w;
    }
    let mut mean = reference + acc;
    for (v, is_angle) in mean.iter_mut().zip(angles.iter()) {
        if *is_angle {
            *v = wrap_pi(*v);
        }
    }
    mean
}

impl<T: Real, const N: usize, const S: usize> Ukf<T, N, S> {
    /// A filter at `x0` with covariance `p0`, which is also the matrix `P`
    /// is reset to after a numerical failure. Returns `None` when the sigma
    /// parameters are unusable.
    pub fn new(
        x0: SVector<T, N>,
        p0: SMatrix<T, N, N>,
        params: &SigmaParams,
        angles: [bool; N],
    ) -> Option<Self> {
        const { assert!(S == 2 * N + 1, "S must be 2N + 1") };
        let weights = SigmaWeights::new(params)?;
        Some(Self {
            x: x0,
            p: p0,
            p_reset: p0,
            min_variance: SVector::repeat(T::lit(1e-12)),
            weights,
            angles,
            resets: 0,
        })
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<T, N> {
        &self.x
    }
    /// The state covariance.
    pub fn covariance(&self) -> &SMatrix<T, N, N> {
        &self.p
    }
    /// Number of covariance re-initialisations since start.
    pub fn covariance_resets(&self) -> u32 {
        self.resets
    }
    /// Sets the per-state variance floor applied after every step.
    pub fn set_min_variance(&mut self, v: SVector<T, N>) {
        self.min_variance = v;
    }
    /// Sets the covariance that a numerical failure resets to.
    pub fn set_reset_covariance(&mut self, p: SMatrix<T, N, N>) {
        self.p_reset = p;
    }
    /// Overwrites state and covariance (re-alignment, tests).
    pub fn reset(&mut self, x: SVector<T, N>, p: SMatrix<T, N, N>) {
        self.x = x;
        self.p = p;
    }

    /// Sigma point `k` of `center` with the pre-scaled factor `gl = γL`:
    /// the centre, then `+` and `−` each column.
    fn sigma_point(center: &SVector<T, N>, gl: &SMatrix<T, N, N>, k: usize) -> SVector<T, N> {
        match k {
            0 => *center,
            k if k <= N => center + gl.column(k - 1),
            k => center - gl.column((k - 1 - N).min(N.saturating_sub(1))),
        }
    }

    /// Factorises `P`, re-initialising it once if that fails.
    fn factor(&mut self) -> (SMatrix<T, N, N>, Option<LinalgError>) {
        match cholesky(&self.p) {
            Ok(l) => (l, None),
            Err(e) => {
                self.p = self.p_reset;
                self.resets = self.resets.saturating_add(1);
                // The reset matrix is a configuration value checked at start-up;
                // should it fail too, fall back to its diagonal.
                let l = cholesky(&self.p).unwrap_or_else(|_| {
                    SMatrix::<T, N, N>::from_diagonal(
                        &self.p_reset.diagonal().map(|v| v.abs().sqrt_fast()),
                    )
                });
                (l, Some(e))
            }
        }
    }

    /// Floors the diagonal. Both callers built `P` as a lower triangle
    /// mirrored onto the upper one, so it is exactly symmetric already: the
    /// averaging `symmetrize` did here changed no bit (`(a + a)/2 = a`) and
    /// cost ≈ 150 instructions per predict and per update on the M4F.
    fn condition(&mut self) {
        for (i, floor) in self.min_variance.iter().enumerate() {
            if let Some(pii) = self.p.get_mut((i, i)) {
                if *pii < *floor {
                    *pii = *floor;
                }
            }
        }
    }

    /// Time update through `f` with additive process noise `q`.
    pub fn predict<E>(
        &mut self,
        mut f: impl FnMut(&SVector<T, N>) -> Result<SVector<T, N>, E>,
        q: &SMatrix<T, N, N>,
    ) -> Result<(), UkfError<E>> {
        let (l, failure) = self.factor();
        let gl = l * self.weights.gamma;
        let mut y = [SVector::<T, N>::zeros(); S];
        for (k, out) in y.iter_mut().enumerate() {
            *out = f(&Self::sigma_point(&self.x, &gl, k)).map_err(UkfError::Model)?;
        }
        // Deviations from the first point, wrapped once: `e_k = y_k ⊖ y_0`.
        let reference = y.first().copied().unwrap_or_else(SVector::zeros);
        for pt in y.iter_mut() {
            *pt = diff(pt, &reference, &self.angles);
        }
        self.combine(&reference, &y, N, q, failure)
    }

    /// Measurement update with the channels flagged in `available`.
    ///
    /// `h` maps a state to the full `M`-channel prediction, `r` is the
    /// diagonal measurement noise, `meas_angles` flags angle channels and
    /// `gate` decides which available channels are fused. Channels not fused
    /// still get their innovation and variance in the diagnostic record.
    #[allow(clippy::too_many_arguments)]
    pub fn update<const M: usize, E>(
        &mut self,
        z: &SVector<T, M>,
        available: &[bool; M],
        h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<E>> {
        let center = self.x;
        self.update_about(&center, z, available, h, r, meas_angles, gate, None, None)
    }

    /// Update with a measurement that was taken when the state was
    /// `delayed` (a known aiding latency, SPEC §3.1): the sigma points are
    /// spread by the current covariance around the delayed state, and the
    /// correction is applied to the current state. This is the usual
    /// short-delay approximation: it assumes the covariance changes little
    /// over the delay, which holds for delays of a few IMU periods. With
    /// `delayed` equal to the current state it is [`update`](Self::update).
    #[allow(clippy::too_many_arguments)]
    pub fn update_delayed<const M: usize, E>(
        &mut self,
        delayed: &SVector<T, N>,
        z: &SVector<T, M>,
        available: &[bool; M],
        h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<E>> {
        self.update_about(delayed, z, available, h, r, meas_angles, gate, None, None)
    }

    /// [`update_delayed`](Self::update_delayed) with the outlier gate
    /// applied to a different innovation than the one fused (see
    /// [`GateShift`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn update_delayed_gated<const M: usize, E>(
        &mut self,
        delayed: &SVector<T, N>,
        z: &SVector<T, M>,
        available: &[bool; M],
        h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
        shift: &GateShift<T, M>,
        split: Option<Split<'_, T, N, M>>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<E>> {
        self.update_about(
            delayed,
            z,
            available,
            h,
            r,
            meas_angles,
            gate,
            Some(shift),
            split,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn update_about<const M: usize, E>(
        &mut self,
        center: &SVector<T, N>,
        z: &SVector<T, M>,
        available: &[bool; M],
        mut h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
        shift: Option<&GateShift<T, M>>,
        split: Option<Split<'_, T, N, M>>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<E>> {
        // Without a split every state is "nonlinear": the plain sigma points.
        let identity: [usize; N] = core::array::from_fn(|i| i);
        let (order, nonlinear) = match &split {
            Some(sp) => (sp.order, sp.nonlinear),
            None => (&identity, N),
        };
        let (l, failure) = self.factor_permuted(order);
        let gamma = self.weights.gamma;
        // Sigma point k is `center + dx_k`; its image `zs_k`.
        // Column k of the scaled factor, and the images of `center ± col_k`
        // (points 1 + k and 1 + N + k); for the affine columns of a split
        // only `d_k = lin(col_k)`, the images being `z_0 ± d_k`.
        let mut cols = [SVector::<T, N>::zeros(); N];
        let mut lins = [SVector::<T, M>::zeros(); N];
        let mut zs = [SVector::<T, M>::zeros(); S];
        let z0 = h(center).map_err(UkfError::Model)?;
        if let Some(first) = zs.first_mut() {
            *first = z0;
        }
        for (k, (col, lin)) in cols.iter_mut().zip(lins.iter_mut()).enumerate() {
            for (i, oi) in order.iter().enumerate() {
                if let (Some(c), Some(v)) = (col.get_mut(*oi), l.get((i, k))) {
                    *c = *v * gamma;
                }
            }
            let (zp, zm) = match &split {
                Some(sp) if k >= nonlinear => {
                    *lin = (sp.lin)(col);
                    (z0 + *lin, z0 - *lin)
                }
                _ => (
                    h(&(center + *col)).map_err(UkfError::Model)?,
                    h(&(center - *col)).map_err(UkfError::Model)?,
                ),
            };
            if let Some(zo) = zs.get_mut(1 + k) {
                *zo = zp;
            }
            if let Some(zo) = zs.get_mut(1 + N + k) {
                *zo = zm;
            }
        }
        let z_hat = weighted_mean(&zs, &self.weights.wm, meas_angles);
        // P_zz = R + Σ w dz dzᵀ, P_xz = Σ w dx dzᵀ with dx = ±col_k (0 for
        // the centre): per column w·col_k (dz₊ − dz₋)ᵀ, one rank-1 update
        // instead of two. An affine pair has dz± = c ± d_k with
        // c = z_0 ⊖ ẑ, so its two outer products are 2w (d dᵀ + c cᵀ).
        let wc = &self.weights.wc;
        let w_center = wc.first().copied().unwrap_or_else(T::zero);
        let c = diff(&z0, &z_hat, meas_angles);
        let mut pzz = SMatrix::<T, M, M>::from_diagonal(r);
        let mut pxz = SMatrix::<T, N, M>::zeros();
        let mut c_weight = w_center;
        for (k, (col, lin)) in cols.iter().zip(lins.iter()).enumerate() {
            let w = wc.get(1 + k).copied().unwrap_or_else(T::zero);
            let w2 = w + w;
            if split.is_some() && k >= nonlinear {
                add_outer_lower(&mut pzz, lin, w2);
                c_weight += w2;
                pxz.ger(w2, col, lin, T::one());
            } else {
                let (Some(zp), Some(zm)) = (zs.get(1 + k), zs.get(1 + N + k)) else {
                    continue;
                };
                let dp = diff(zp, &z_hat, meas_angles);
                let dm = diff(zm, &z_hat, meas_angles);
                add_outer_lower(&mut pzz, &dp, w);
                add_outer_lower(&mut pzz, &dm, w);
                pxz.ger(w, col, &(dp - dm), T::one());
            }
        }
        add_outer_lower(&mut pzz, &c, c_weight);
        mirror_lower(&mut pzz);
        // Not generic over the model's error type, so one copy of the
        // correction serves both update forms.
        self.correct(
            z,
            &z_hat,
            pzz,
            pxz,
            available,
            meas_angles,
            gate,
            shift,
            failure,
        )
        .map_err(UkfError::widen)
    }

    /// The Kalman correction shared by both update forms.
    #[allow(clippy::too_many_arguments)]
    fn correct<const M: usize>(
        &mut self,
        z: &SVector<T, M>,
        z_hat: &SVector<T, M>,
        mut pzz: SMatrix<T, M, M>,
        mut pxz: SMatrix<T, N, M>,
        available: &[bool; M],
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
        shift: Option<&GateShift<T, M>>,
        failure: Option<LinalgError>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<core::convert::Infallible>> {
        let nu_all = diff(z, z_hat, meas_angles);
        let mut diag = [ChannelDiag::<T>::default(); M];
        let mut nu = SVector::<T, M>::zeros();
        for (i, d) in diag.iter_mut().enumerate() {
            if !available.get(i).copied().unwrap_or(false) {
                continue;
            }
            let s = pzz.get((i, i)).copied().unwrap_or_else(T::one);
            let innovation = nu_all.get(i).copied().unwrap_or_else(T::zero);
            let ratio = match shift {
                None => gate.ratio(innovation, s),
                Some(g) => {
                    let offset = g.innovation_offset.get(i).copied().unwrap_or_else(T::zero);
                    let extra = g.extra_variance.get(i).copied().unwrap_or_else(T::zero);
                    let mut gated = innovation - offset;
                    if meas_angles.get(i).copied().unwrap_or(false) {
                        gated = wrap_pi(gated);
                    }
                    gate.ratio(gated, s + extra)
                }
            };
            let fused = innovation.finite() && s > T::zero() && gate.admit(i, ratio);
            *d = ChannelDiag {
                available: true,
                innovation,
                variance: s,
                test_ratio: ratio,
                fused,
            };
            if let (true, Some(n)) = (fused, nu.get_mut(i)) {
                *n = innovation;
            }
        }
        // Channels not fused: decouple them (unit variance, no cross terms,
        // zero residual) so that the fixed-size gain has zero columns there.
        for (i, d) in diag.iter().enumerate() {
            if !d.fused {
                pzz.set_row(i, &nalgebra::SMatrix::<T, 1, M>::zeros());
                pzz.set_column(i, &SVector::<T, M>::zeros());
                if let Some(v) = pzz.get_mut((i, i)) {
                    *v = T::one();
                }
                pxz.set_column(i, &SVector::<T, N>::zeros());
            }
        }
        let lzz = cholesky(&pzz).map_err(UkfError::InnovationCovariance)?;
        let gain = cholesky_solve_right(&lzz, &pxz);
        let mut x = self.x + gain * nu;
        for (v, is_angle) in x.iter_mut().zip(self.angles.iter()) {
            if *is_angle {
                *v = wrap_pi(*v);
            }
        }
        // K P_zz Kᵀ = K P_xzᵀ (K = P_xz P_zz⁻¹; the columns of channels not
        // fused are zero in both): one product instead of two.
        // The result is symmetric: the lower triangle only, then mirrored.
        let mut p = self.p;
        for j in 0..N {
            for i in j..N {
                let dot = gain.row(i).dot(&pxz.row(j));
                if let Some(v) = p.get_mut((i, j)) {
                    *v -= dot;
                }
            }
        }
        mirror_lower(&mut p);
        // The mirror copied the lower triangle: testing it is testing `P`
        // (21 values, not 36; issue 17).
        if !(all_finite(x.as_slice()) && lower_finite(&p)) {
            return Err(UkfError::NonFinite);
        }
        self.x = x;
        self.p = p;
        self.condition();
        Ok(UpdateOutput {
            diag,
            gain,
            innovation_covariance: pzz,
            covariance_reset: failure,
        })
    }
}

/// A measurement function affine in the trailing states of `order` (see
/// [`Ukf::predict_split`]): `lin` maps a deviation that is zero on the first
/// `nonlinear` states of `order` to `h(x + δ) − h(x)` at the sigma points'
/// centre.
pub(crate) struct Split<'a, T, const N: usize, const M: usize> {
    pub order: &'a [usize; N],
    pub nonlinear: usize,
    pub lin: &'a dyn Fn(&SVector<T, N>) -> SVector<T, M>,
}

/// What the outlier gate tests when it is not the innovation being fused:
/// `ν − innovation_offset` against `P_zz + extra_variance` per channel. The
/// two-stage filter fuses the bias-free innovation `r̄ = z − h(x̄)`, whose
/// mean is the fault's signature `S f̂` and whose spread lacks the fault's
/// `S P^f Sᵀ`; gating `r̄` itself rejects good measurements exactly when a
/// fault appears, so it gates the full innovation `z − h(x̄ + U f̂)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GateShift<T: Real, const M: usize> {
    /// Subtracted from the innovation before gating.
    pub innovation_offset: SVector<T, M>,
    /// Added to the innovation variance before gating.
    pub extra_variance: SVector<T, M>,
}

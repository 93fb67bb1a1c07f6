//! Optimal two-stage UKF, OTSUKF (\[OTS\], SPEC §6): joint estimation of the state
//! and of additive input (IMU) faults modelled as random walks.

use nalgebra::{SMatrix, SVector};

use super::ukf::{all_finite, GateShift, Split};
use super::{Gate, SigmaParams, Ukf, UkfError, UpdateOutput};
use crate::math::{cholesky, cholesky_solve_right, symmetrize, wrap_pi, Real};

/// A bias-free UKF (state `x̄`, covariance `P̄`) and a linear fault filter
/// (`f̂`, `P^f`) coupled by `U`, `V`, `S` (Hsieh & Chen 1999), with `N`
/// states, `S = 2N + 1` sigma points and `L` fault channels.
///
/// The model is `x_{k+1} = f(x_k, u_k − f_k) + ω`, `f_{k+1} = f_k + w^f`,
/// `y = h(x) + ν`. Each step the caller passes the propagation through the
/// *corrected* input (`u_m − f̂`) and the Jacobians `Φ = ∂x_{k+1}/∂x` and
/// `F = ∂x_{k+1}/∂f` at the full estimate. Following SPEC §6 the full
/// estimate `x̂ = x̄ + V f̂` is propagated and shifted back
/// (`x̄_{k+1|k} = UT_f(x̂, P̄) − U f̂`), so the model is never evaluated at the
/// non-physical `x̄`; for a linear model this is exactly the two-stage
/// filter, which equals the augmented-state Kalman filter (tested to 1e-13).
///
/// With `Q^{xf} = 0` the compensated process noise is
/// `Q̄ = Q^x + Ū P^f (P^f_{k+1|k})⁻¹ Q^f Ūᵀ`, positive semi-definite by
/// construction (SPEC §6), and `U = Ū P^f (P^f_{k+1|k})⁻¹`.
#[derive(Debug, Clone)]
pub struct Otsukf<T, const N: usize, const S: usize, const L: usize> {
    bias_free: Ukf<T, N, S>,
    fault: SVector<T, L>,
    pf: SMatrix<T, L, L>,
    pf_reset: SMatrix<T, L, L>,
    qf: SMatrix<T, L, L>,
    u: SMatrix<T, N, L>,
    v: SMatrix<T, N, L>,
    angles: [bool; N],
}

/// What a two-stage update produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtsukfUpdate<T, const N: usize, const M: usize, const L: usize> {
    /// The bias-free filter's update (innovations `r̄`, gain `K^x`, …).
    pub bias_free: UpdateOutput<T, N, M>,
    /// The fault filter's innovation `r^f = r̄ − S f̂` (0 for channels not
    /// fused).
    pub fault_innovation: SVector<T, M>,
    /// The fault filter's gain `K^f`.
    pub fault_gain: SMatrix<T, L, M>,
    /// `diag(A)`, `A = P_yy + S P^f Sᵀ`: the variance the filter predicts
    /// for each component of `r^f` (what a learned inflation compares the
    /// observed `r^f` with).
    pub fault_innovation_variance: SVector<T, M>,
}

fn wrap_angles<T: Real, const K: usize>(v: &mut SVector<T, K>, angles: &[bool; K]) {
    for (x, a) in v.iter_mut().zip(angles.iter()) {
        if *a {
            *x = wrap_pi(*x);
        }
    }
}

impl<T: Real, const N: usize, const S: usize, const L: usize> Otsukf<T, N, S, L> {
    /// The filter at state `x0` (covariance `px0`) and fault `f0`
    /// (covariance `pf0`), uncorrelated (\[OTS\] eq. (27): `P^{xf}₀ = 0`, so
    /// `V₀ = 0`, `x̄₀ = x₀`, `P̄₀ = P^x₀`), with fault random-walk covariance
    /// `qf` per step. `None` for unusable sigma parameters.
    pub fn new(
        x0: SVector<T, N>,
        px0: SMatrix<T, N, N>,
        f0: SVector<T, L>,
        pf0: SMatrix<T, L, L>,
        qf: SMatrix<T, L, L>,
        params: &SigmaParams,
        angles: [bool; N],
    ) -> Option<Self> {
        Some(Self {
            bias_free: Ukf::new(x0, px0, params, angles)?,
            fault: f0,
            pf: pf0,
            pf_reset: pf0,
            qf,
            u: SMatrix::zeros(),
            v: SMatrix::zeros(),
            angles,
        })
    }

    /// The full state estimate `x̂ = x̄ + V f̂`.
    pub fn state(&self) -> SVector<T, N> {
        let mut x = self.bias_free.state() + self.v * self.fault;
        wrap_angles(&mut x, &self.angles);
        x
    }
    /// Its covariance `P^x = P̄ + V P^f Vᵀ`.
    pub fn state_covariance(&self) -> SMatrix<T, N, N> {
        self.bias_free.covariance() + self.v * self.pf * self.v.transpose()
    }
    /// The diagonal of [`state_covariance`](Self::state_covariance)
    /// (`P̄ᵢᵢ + vᵢ P^f vᵢᵀ`, one product instead of two).
    pub fn state_variance(&self) -> SVector<T, N> {
        let vpf = self.v * self.pf;
        SVector::<T, N>::from_fn(|i, _| {
            let pii = self.bias_free.covariance().get((i, i)).copied();
            pii.unwrap_or_else(T::zero) + vpf.row(i).dot(&self.v.row(i))
        })
    }
    /// The fault estimate `f̂`.
    pub fn fault(&self) -> &SVector<T, L> {
        &self.fault
    }
    /// Its covariance `P^f`.
    pub fn fault_covariance(&self) -> &SMatrix<T, L, L> {
        &self.pf
    }
    /// The bias-free filter.
    pub fn bias_free(&self) -> &Ukf<T, N, S> {
        &self.bias_free
    }
    /// Sets the fault random-walk covariance per step (e.g. raised while a
    /// fault is being tracked).
    pub fn set_fault_noise(&mut self, qf: SMatrix<T, L, L>) {
        self.qf = qf;
    }
    /// Sets the per-state variance floor of the bias-free filter.
    pub fn set_min_variance(&mut self, v: SVector<T, N>) {
        self.bias_free.set_min_variance(v);
    }
    /// Overwrites the state (fault estimate and coupling kept at zero
    /// correlation: `V = 0`), e.g. at alignment.
    pub fn reset_state(&mut self, x: SVector<T, N>, px: SMatrix<T, N, N>) {
        self.v = SMatrix::zeros();
        self.u = SMatrix::zeros();
        self.bias_free.reset(x, px);
    }

    /// Restarts the fault channels `channels` at `f0` with their initial
    /// variance (rows and columns of `P^f` zeroed, so it stays positive
    /// definite), e.g. once a fault is known to have ended. The full
    /// state `x̂ = x̄ + V f̂` moves with `f̂` unless `V` is zero (after
    /// [`reset_state`](Self::reset_state)).
    pub fn reset_faults(&mut self, channels: &[bool; L], f0: &SVector<T, L>) {
        for (j, c) in channels.iter().enumerate() {
            if !*c {
                continue;
            }
            if let (Some(f), Some(v)) = (self.fault.get_mut(j), f0.get(j)) {
                *f = *v;
            }
            let v0 = self.pf_reset.get((j, j)).copied().unwrap_or_else(T::one);
            self.pf.row_mut(j).fill(T::zero());
            self.pf.column_mut(j).fill(T::zero());
            if let Some(p) = self.pf.get_mut((j, j)) {
                *p = v0;
            }
        }
    }

    /// Time update. `step` propagates a state through the model with the
    /// corrected input `u_m − f̂`; `phi` and `fmat` are `∂x_{k+1}/∂x` and
    /// `∂x_{k+1}/∂f` at the full estimate; `qx` the state process noise.
    pub fn predict<E>(
        &mut self,
        step: impl FnMut(&SVector<T, N>) -> Result<SVector<T, N>, E>,
        phi: &SMatrix<T, N, N>,
        fmat: &SMatrix<T, N, L>,
        qx: &SMatrix<T, N, N>,
    ) -> Result<(), UkfError<E>> {
        self.predict_with(|v| phi * v + fmat, qx, |ukf, qbar| ukf.predict(step, qbar))
    }

    /// [`predict`](Self::predict) with the bias-free filter's time update
    /// done by [`Ukf::predict_split`] (`order`, `nonlinear` and `lin` as
    /// there, `lin` taken at the full estimate), and `Ū = Φ V + F` computed
    /// by `coupling` from `V`, so that a caller who knows the structure of
    /// `Φ` and `F` need not form them.
    pub fn predict_split<E>(
        &mut self,
        order: &[usize; N],
        nonlinear: usize,
        step: impl FnMut(&SVector<T, N>) -> Result<SVector<T, N>, E>,
        lin: impl Fn(&SVector<T, N>) -> SVector<T, N>,
        coupling: impl FnOnce(&SMatrix<T, N, L>) -> SMatrix<T, N, L>,
        qx: &SMatrix<T, N, N>,
    ) -> Result<(), UkfError<E>> {
        self.predict_with(coupling, qx, |ukf, qbar| {
            ukf.predict_split(order, nonlinear, step, lin, qbar)
        })
    }

    fn predict_with<E>(
        &mut self,
        coupling: impl FnOnce(&SMatrix<T, N, L>) -> SMatrix<T, N, L>,
        qx: &SMatrix<T, N, N>,
        propagate: impl FnOnce(&mut Ukf<T, N, S>, &SMatrix<T, N, N>) -> Result<(), UkfError<E>>,
    ) -> Result<(), UkfError<E>> {
        let x_full = self.state();
        let ubar = coupling(&self.v);
        let mut pf_pred = self.pf + self.qf;
        symmetrize(&mut pf_pred);
        // W = P^f (P^f_{k+1|k})⁻¹; U = Ū W; Q̄ = Q^x + Ū W Q^f Ūᵀ.
        let w = match cholesky(&pf_pred) {
            Ok(l) => cholesky_solve_right(&l, &self.pf),
            Err(_) => {
                // Lost fault covariance: restart the fault filter from its
                // initial covariance (the state filter carries on).
                self.pf = self.pf_reset;
                pf_pred = self.pf + self.qf;
                match cholesky(&pf_pred) {
                    Ok(l) => cholesky_solve_right(&l, &self.pf),
                    Err(e) => return Err(UkfError::CovarianceReset(e)),
                }
            }
        };
        let u = ubar * w;
        // Ū W Q^f Ūᵀ = U Q^f Ūᵀ: two products once U is at hand.
        let mut qbar = qx + (u * self.qf) * ubar.transpose();
        symmetrize(&mut qbar);
        let pbar = *self.bias_free.covariance();
        let x_bar_prev = *self.bias_free.state();
        // Sigma points spread by P̄ around the full estimate.
        self.bias_free.reset(x_full, pbar);
        if let Err(e) = propagate(&mut self.bias_free, &qbar) {
            if !matches!(e, UkfError::CovarianceReset(_)) {
                self.bias_free.reset(x_bar_prev, pbar);
                return Err(e);
            }
        }
        let mut x_bar = self.bias_free.state() - u * self.fault;
        wrap_angles(&mut x_bar, &self.angles);
        let p_pred = *self.bias_free.covariance();
        self.bias_free.reset(x_bar, p_pred);
        self.u = u;
        // Until a measurement arrives the full estimate is x̄ + U f̂
        // (V = U − K^x S with K^x = 0).
        self.v = u;
        self.pf = pf_pred;
        Ok(())
    }

    /// Measurement update. `h` maps a (full) state to the `M` channels, `hjac`
    /// is `∂h/∂x` at the predicted full estimate, `r` the diagonal
    /// measurement noise; `available`, `meas_angles` and `gate` as in
    /// [`Ukf::update`].
    #[allow(clippy::too_many_arguments)]
    pub fn update<const M: usize, E>(
        &mut self,
        z: &SVector<T, M>,
        available: &[bool; M],
        h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        hjac: &SMatrix<T, M, N>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
    ) -> Result<OtsukfUpdate<T, N, M, L>, UkfError<E>> {
        self.update_with(z, available, h, hjac, r, meas_angles, gate, None)
    }

    /// [`update`](Self::update) for a measurement function affine in the
    /// trailing states of `order` (the first `nonlinear` are those `h`
    /// depends on nonlinearly), as [`Ukf::predict_split`] for the process:
    /// the sigma points that leave those states at the predicted full
    /// estimate are mapped through `hjac` instead of `h` — exact when `h`
    /// is affine in the other states with `hjac` as its Jacobian there (M2:
    /// `R(φ, θ, ψ)·v`, affine in `v`).
    #[allow(clippy::too_many_arguments)]
    pub fn update_split<const M: usize, E>(
        &mut self,
        order: &[usize; N],
        nonlinear: usize,
        z: &SVector<T, M>,
        available: &[bool; M],
        h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        hjac: &SMatrix<T, M, N>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
    ) -> Result<OtsukfUpdate<T, N, M, L>, UkfError<E>> {
        let lin = |d: &SVector<T, N>| hjac * d;
        let split = Split {
            order,
            nonlinear,
            lin: &lin,
        };
        self.update_with(z, available, h, hjac, r, meas_angles, gate, Some(split))
    }

    #[allow(clippy::too_many_arguments)]
    fn update_with<const M: usize, E>(
        &mut self,
        z: &SVector<T, M>,
        available: &[bool; M],
        h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        hjac: &SMatrix<T, M, N>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
        split: Option<Split<'_, T, N, M>>,
    ) -> Result<OtsukfUpdate<T, N, M, L>, UkfError<E>> {
        // Predicted full estimate; the bias-free innovation is
        // r̄ = y − h(x̄) ≈ (y + S f̂) − h(x̄ + U f̂).
        let mut x_full = self.bias_free.state() + self.u * self.fault;
        wrap_angles(&mut x_full, &self.angles);
        let mut s = hjac * self.u;
        let mut signature = s * self.fault;
        let mut z_mod = z + signature;
        wrap_angles(&mut z_mod, meas_angles);
        // P^f Sᵀ serves the gate now and the fault gain after.
        let mut pf_st = self.pf * s.transpose();
        // Gate what the augmented filter would: the full innovation, with
        // the fault's uncertainty diag(S P^f Sᵀ) in its variance.
        let mut extra_variance = SVector::<T, M>::zeros();
        for ((e, s_row), pf_col) in extra_variance
            .iter_mut()
            .zip(s.row_iter())
            .zip(pf_st.column_iter())
        {
            *e = s_row.transpose().dot(&pf_col);
        }
        let shift = GateShift {
            innovation_offset: signature,
            extra_variance,
        };
        let out = self.bias_free.update_delayed_gated(
            &x_full,
            &z_mod,
            available,
            h,
            r,
            meas_angles,
            gate,
            &shift,
            split,
        )?;
        // Channels not fused carry no information on the fault either: zero
        // their rows of S (and so of S f̂ and their columns of P^f Sᵀ).
        let mut rbar = SVector::<T, M>::zeros();
        for (i, d) in out.diag.iter().enumerate() {
            if d.fused {
                if let Some(v) = rbar.get_mut(i) {
                    *v = d.innovation;
                }
            } else {
                s.set_row(i, &nalgebra::SMatrix::<T, 1, L>::zeros());
                pf_st.set_column(i, &SVector::<T, L>::zeros());
                if let Some(v) = signature.get_mut(i) {
                    *v = T::zero();
                }
            }
        }
        let mut rf = rbar - signature;
        wrap_angles(&mut rf, meas_angles);
        let pyy = out.innovation_covariance;
        let mut a = pyy + s * pf_st;
        symmetrize(&mut a);
        let la = cholesky(&a).map_err(UkfError::InnovationCovariance)?;
        let kf = cholesky_solve_right(&la, &pf_st);
        let fault = self.fault + kf * rf;
        // P^f − K A Kᵀ = P^f − K (P^f Sᵀ)ᵀ (K = P^f Sᵀ A⁻¹): one product,
        // where the Joseph form (I − K S) P (I − K S)ᵀ + K P_yy Kᵀ, equal
        // for this optimal gain, takes four; symmetrised below, as the
        // bias-free filter's `P − K P_xzᵀ`.
        let mut pf = self.pf - kf * pf_st.transpose();
        symmetrize(&mut pf);
        if !(all_finite(fault.as_slice()) && all_finite(pf.as_slice())) {
            return Err(UkfError::NonFinite);
        }
        self.fault = fault;
        self.pf = pf;
        self.v = self.u - out.gain * s;
        Ok(OtsukfUpdate {
            bias_free: out,
            fault_innovation: rf,
            fault_gain: kf,
            fault_innovation_variance: a.diagonal(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The restarted channels take the given estimate and their initial
    /// variance, uncorrelated; the others keep estimate and covariance.
    #[test]
    fn reset_faults_restarts_only_the_given_channels() {
        let pf0 = SMatrix::<f64, 3, 3>::from_fn(|i, j| if i == j { 2.0 + i as f64 } else { 0.5 });
        let mut f = Otsukf::<f64, 2, 5, 3>::new(
            SVector::zeros(),
            SMatrix::identity(),
            SVector::from([1.0, 2.0, 3.0]),
            pf0,
            SMatrix::identity(),
            &SigmaParams::default(),
            [false; 2],
        )
        .unwrap();
        f.reset_faults(&[false, true, false], &SVector::from([9.0, -1.0, 9.0]));
        assert_eq!(f.fault().as_slice(), &[1.0, -1.0, 3.0]);
        let want = SMatrix::<f64, 3, 3>::new(2.0, 0.0, 0.5, 0.0, 3.0, 0.0, 0.5, 0.0, 4.0);
        assert_eq!(*f.fault_covariance(), want);
    }
}

//! The split unscented transform: the covariance factored with the
//! non-affine coordinates first, so the sigma points that only move the
//! affine ones are mapped exactly by a cheap deviation step instead of the
//! full model.

use nalgebra::{SMatrix, SVector};

use super::*;
use crate::math::{lower_finite, mirror_lower_into};

impl<T: Real, const N: usize, const S: usize> Ukf<T, N, S> {
    /// [`factor`](Self::factor) of `P` with its states permuted into
    /// `order` (row and column `i` of the factor are state `order[i]`).
    pub(super) fn factor_permuted(
        &mut self,
        order: &[usize; N],
    ) -> (SMatrix<T, N, N>, Option<LinalgError>) {
        // The lower triangle only: `cholesky` reads no more.
        let permuted = |p: &SMatrix<T, N, N>| {
            let mut out = SMatrix::<T, N, N>::zeros();
            for (j, b) in order.iter().enumerate() {
                for (i, a) in order.iter().enumerate().skip(j) {
                    if let (Some(o), Some(v)) = (out.get_mut((i, j)), p.get((*a, *b))) {
                        *o = *v;
                    }
                }
            }
            out
        };
        match cholesky(&permuted(&self.p)) {
            Ok(l) => (l, None),
            Err(e) => {
                self.p = self.p_reset;
                self.resets = self.resets.saturating_add(1);
                let pr = permuted(&self.p_reset);
                let l = cholesky(&pr).unwrap_or_else(|_| {
                    SMatrix::<T, N, N>::from_diagonal(&pr.diagonal().map(|v| v.abs().sqrt_fast()))
                });
                (l, Some(e))
            }
        }
    }

    /// Time update through `f` for a process that is *affine in the
    /// trailing states* of `order`: `order` lists every state once, the
    /// first `nonlinear` of them being those `f` depends on nonlinearly, and
    /// `lin` maps any deviation `δ` that is zero on those states to
    /// `f(x + δ) ⊖ f(x)` at the current mean `x` — exactly, not to first
    /// order.
    ///
    /// `P` is factorised with the states permuted into `order`, so the
    /// sigma points of the trailing columns of the (lower-triangular)
    /// factor leave the nonlinear states at the mean: their images are
    /// `f(x) ± lin(γ sₖ)`, with no evaluation of `f`. Only `1 + 2·nonlinear`
    /// points go through `f`. This is the unscented transform with a
    /// different matrix square root of `P` than [`predict`](Self::predict)'s:
    /// the two agree in the mean and covariance to every order the
    /// transform captures (they differ in fourth moments of the nonlinear
    /// states), and are identical for a process affine in every state.
    ///
    /// For the vehicle model the roll and pitch are the nonlinear states:
    /// the velocity enters linearly (given the body rates) and the yaw
    /// additively ([`VehicleModel::step_deviation`](crate::model::VehicleModel::step_deviation)).
    pub fn predict_split<E>(
        &mut self,
        order: &[usize; N],
        nonlinear: usize,
        mut f: impl FnMut(&SVector<T, N>) -> Result<SVector<T, N>, E>,
        lin: impl Fn(&SVector<T, N>) -> SVector<T, N>,
        q: &SMatrix<T, N, N>,
    ) -> Result<(), UkfError<E>> {
        let (l, failure) = self.factor_permuted(order);
        let gamma = self.weights.gamma;
        let reference = f(&self.x).map_err(UkfError::Model)?;
        let mut e = [SVector::<T, N>::zeros(); S];
        for k in 0..N {
            // Column k of the permuted factor, back in state order.
            let mut col = SVector::<T, N>::zeros();
            for (i, oi) in order.iter().enumerate() {
                if let (Some(c), Some(v)) = (col.get_mut(*oi), l.get((i, k))) {
                    *c = *v * gamma;
                }
            }
            let (plus, minus) = if k < nonlinear {
                // One call site of `f` and of the inlined `diff` for both
                // points (flash: one copy instead of two).
                let mut pm = [self.x + col, self.x - col];
                for y in pm.iter_mut() {
                    let fy = f(y).map_err(UkfError::Model)?;
                    *y = diff_inline(&fy, &reference, &self.angles);
                }
                let [yp, ym] = pm;
                (yp, ym)
            } else {
                let d = lin(&col);
                (d, -d)
            };
            if let Some(p) = e.get_mut(1 + k) {
                *p = plus;
            }
            if let Some(m) = e.get_mut(1 + N + k) {
                *m = minus;
            }
        }
        self.combine(&reference, &e, nonlinear, q, failure)
    }

    /// [`update_delayed`](Self::update_delayed) for a measurement function
    /// affine in the trailing states of `order` (the first `nonlinear` are
    /// those `h` depends on nonlinearly), with `hjac` its Jacobian at
    /// `center`: the split transform of [`predict_split`](Self::predict_split)
    /// for the update. The sigma points of the trailing factor columns leave
    /// the nonlinear states at `center`, so their images are
    /// `h(center) ± hjac·γsₖ` exactly, with no evaluation of `h`: M2
    /// (`R(φ, θ, ψ)·v`, affine in the body velocity) needs 7 evaluations
    /// instead of 13 (issue 17). Equal to `update_delayed` in the mean and
    /// covariance to every order the transform captures (tested).
    #[allow(clippy::too_many_arguments)]
    pub fn update_split<const M: usize, E>(
        &mut self,
        center: &SVector<T, N>,
        order: &[usize; N],
        nonlinear: usize,
        z: &SVector<T, M>,
        available: &[bool; M],
        h: impl FnMut(&SVector<T, N>) -> Result<SVector<T, M>, E>,
        hjac: &SMatrix<T, M, N>,
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<E>> {
        let lin = |d: &SVector<T, N>| hjac * d;
        let split = Split {
            order,
            nonlinear,
            lin: &lin,
        };
        self.update_about(
            center,
            z,
            available,
            h,
            r,
            meas_angles,
            gate,
            None,
            Some(split),
        )
    }

    /// The weighted mean and covariance of propagated sigma points given as
    /// deviations `e_k = y_k ⊖ y_0` from the image `reference = y_0` of the
    /// first: the circular mean is `y_0 ⊕ ē` with `ē = Σ wm_k e_k`, and the
    /// deviations from the mean are `e_k − ē` — already on the right
    /// branch, so no second wrap (this halves the wrapping work).
    ///
    /// Columns `k ≥ pairs_from` are symmetric pairs, `e_{1+N+k} = −e_{1+k}`
    /// (the affine points of [`predict_split`](Self::predict_split)): they
    /// add nothing to `ē`, and `(d − ē)(d − ē)ᵀ + (−d − ē)(−d − ē)ᵀ =
    /// 2ddᵀ + 2ēēᵀ`, one outer product per pair instead of two.
    pub(super) fn combine<E>(
        &mut self,
        reference: &SVector<T, N>,
        e: &[SVector<T, N>; S],
        pairs_from: usize,
        q: &SMatrix<T, N, N>,
        failure: Option<LinalgError>,
    ) -> Result<(), UkfError<E>> {
        let is_pair = |k: usize| (k > pairs_from && k <= N) || k > N + pairs_from;
        let mut offset = SVector::<T, N>::zeros();
        for (k, (pt, w)) in e.iter().zip(self.weights.wm.iter()).enumerate() {
            if !is_pair(k) {
                offset += *pt * *w;
            }
        }
        let mut mean = reference + offset;
        for (v, is_angle) in mean.iter_mut().zip(self.angles.iter()) {
            if *is_angle {
                *v = wrap_pi(*v);
            }
        }
        // Accumulate the lower triangle only (the result is symmetric).
        let mut p = *q;
        let mut offset_weight = T::zero();
        for (k, (pt, w)) in e.iter().zip(self.weights.wc.iter()).enumerate() {
            if !is_pair(k) {
                add_outer_lower(&mut p, &(pt - offset), *w);
            } else if k <= N {
                let w2 = *w + *w;
                add_outer_lower(&mut p, pt, w2);
                offset_weight += w2;
            }
        }
        if offset_weight != T::zero() {
            add_outer_lower(&mut p, &offset, offset_weight);
        }
        // The upper triangle is about to be the lower one mirrored: testing
        // the lower triangle is testing the result. Then `P` is written
        // once, mirrored on the way, instead of mirrored in place and
        // copied (issue 17; the same values to the bit).
        if !(all_finite(mean.as_slice()) && lower_finite(&p)) {
            return Err(UkfError::NonFinite);
        }
        self.x = mean;
        mirror_lower_into(&p, &mut self.p);
        self.condition();
        match failure {
            Some(e) => Err(UkfError::CovarianceReset(e)),
            None => Ok(()),
        }
    }
}

//! The Kalman-form update for measurements affine in the state (the
//! unscented transform of an affine map is exact), and its `H = I` case.

use nalgebra::{SMatrix, SVector};

use super::*;

impl<T: Real, const N: usize, const S: usize> Ukf<T, N, S> {
    /// Update with a measurement that is affine in the state,
    /// `h(x) = H x + c`, given `z_center = h(center)` (`center` being the
    /// current state, or the delayed one as in
    /// [`update_delayed`](Self::update_delayed)).
    ///
    /// The unscented transform of an affine map is exact — the sigma points
    /// reproduce the mean and `P` — so the sigma-point update reduces to the
    /// Kalman form `P_zz = H P Hᵀ + R`, `P_xz = P Hᵀ` with the same gating,
    /// masking and angle handling; it equals [`update_delayed`](Self::update_delayed)
    /// to rounding (tested) at a fraction of the cost. The DVL + compass
    /// model (M1) is affine: `H = I`, `c` the lever-arm velocity.
    #[allow(clippy::too_many_arguments)]
    pub fn update_affine<const M: usize>(
        &mut self,
        z_center: &SVector<T, M>,
        h: &SMatrix<T, M, N>,
        z: &SVector<T, M>,
        available: &[bool; M],
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<core::convert::Infallible>> {
        // H = I (M1) needs no products: P_xz = P, P_zz = P + R.
        if M == N && is_identity(h) {
            return self.update_identity(z_center, z, available, r, meas_angles, gate);
        }
        let pxz = self.p * h.transpose();
        // `H P Hᵀ` is symmetric only to rounding. (Adding R below
        // changes the diagonal alone, so the order does not matter.)
        let mut pzz = h * pxz;
        symmetrize(&mut pzz);
        add_diagonal(&mut pzz, r);
        self.correct(
            z,
            z_center,
            pzz,
            pxz,
            available,
            meas_angles,
            gate,
            None,
            None,
        )
    }

    /// [`update_affine`](Self::update_affine) with `H = I` (`M = N`), for a
    /// caller that knows its Jacobian is the identity (M1): the same update
    /// without the 36-entry identity test (issue 17).
    pub(crate) fn update_identity<const M: usize>(
        &mut self,
        z_center: &SVector<T, M>,
        z: &SVector<T, M>,
        available: &[bool; M],
        r: &SVector<T, M>,
        meas_angles: &[bool; M],
        gate: &mut Gate<T, M>,
    ) -> Result<UpdateOutput<T, N, M>, UkfError<core::convert::Infallible>> {
        let pxz =
            SMatrix::<T, N, M>::from_fn(|i, j| self.p.get((i, j)).copied().unwrap_or_else(T::zero));
        // P's lower triangle mirrored: `P` is symmetric to the bit (built
        // mirrored), so this is `P` itself and needs no symmetrising.
        let mut pzz = SMatrix::<T, M, M>::from_fn(|i, j| {
            let (a, b) = if i >= j { (i, j) } else { (j, i) };
            self.p.get((a, b)).copied().unwrap_or_else(T::zero)
        });
        add_diagonal(&mut pzz, r);
        self.correct(
            z,
            z_center,
            pzz,
            pxz,
            available,
            meas_angles,
            gate,
            None,
            None,
        )
    }
}

/// `P_zz += diag(R)`.
fn add_diagonal<T: Real, const M: usize>(pzz: &mut SMatrix<T, M, M>, r: &SVector<T, M>) {
    for (i, ri) in r.iter().enumerate() {
        if let Some(d) = pzz.get_mut((i, i)) {
            *d += *ri;
        }
    }
}

//! The parity space of the active sensors: `V` with `V H = 0`, `V Vᵀ = I`,
//! the least-squares fusion `(HᵀH)⁻¹Hᵀ`, and which sensors can be isolated.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::math::Real;

use super::{ConfigError, Geometry};

/// Smallest pivot of `HᵀH` (relative to its trace) for `H` to count as rank 3.
const RANK_TOLERANCE: f64 = 1e-5;
/// Columns of `V` closer than this (1 − |cos|) are parallel: the two sensors'
/// faults look the same in parity space.
const PARALLEL_TOLERANCE: f64 = 1e-4;
/// A column of `V` with squared norm below this carries no redundancy: that
/// sensor's fault does not show in the parity vector at all.
const UNOBSERVABLE_NORM2: f64 = 1e-4;

/// Parity space of a set of active sensors, computed on the target.
///
/// Rows `0..dim()` of [`v`](Self::v) are an orthonormal basis of the
/// left null space of the active rows of `H`; columns of excluded sensors
/// and rows `dim()..N` are zero, so the fixed-size matrices work for every
/// subset of sensors without reallocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParitySpace<T: Real, const N: usize> {
    geometry: Geometry<T, N>,
    active: [bool; N],
    dim: usize,
    v: SMatrix<T, N, N>,
    lsq: SMatrix<T, 3, N>,
    isolable: [bool; N],
    detectable: [bool; N],
}

impl<T: Real, const N: usize> ParitySpace<T, N> {
    /// Builds `V` and the least-squares matrix for the sensors marked
    /// `active`. Errors: fewer than four active sensors
    /// ([`ConfigError::TooFewSensors`]), active rows of `H` not of rank 3
    /// ([`ConfigError::RankDeficient`]).
    ///
    /// Method: the projector `P = D − H_a (H_aᵀH_a)⁻¹ H_aᵀ` onto the parity
    /// space (`D` = diagonal of active flags, `H_a` = `H` with excluded rows
    /// zeroed) has rank `n_active − 3`; modified Gram–Schmidt with column
    /// pivoting and one re-orthogonalisation pass turns its columns into the
    /// rows of `V`. No SVD and no stored tables.
    pub fn new(geometry: &Geometry<T, N>, active: &[bool; N]) -> Result<Self, ConfigError> {
        let n_active = active.iter().filter(|a| **a).count();
        if n_active < 4 {
            return Err(ConfigError::TooFewSensors);
        }
        let mut ha = *geometry.h();
        for (i, a) in active.iter().enumerate() {
            if !a {
                ha.row_mut(i).fill(T::zero());
            }
        }
        let g: Matrix3<T> = ha.transpose() * ha;
        let g_inv = invert_rank3(&g).ok_or(ConfigError::RankDeficient)?;
        let lsq = g_inv * ha.transpose();
        let mut residual = SMatrix::<T, N, N>::from_fn(|i, j| {
            let d = if i == j && active.get(i).copied().unwrap_or(false) {
                T::one()
            } else {
                T::zero()
            };
            d - ha.row(i).transpose().dot(&lsq.column(j))
        });
        let dim = n_active - 3;
        let mut v = SMatrix::<T, N, N>::zeros();
        for row in 0..dim {
            let (best, norm2) = residual
                .column_iter()
                .map(|c| c.norm_squared())
                .enumerate()
                .fold(
                    (0, T::zero()),
                    |acc, (j, n)| if n > acc.1 { (j, n) } else { acc },
                );
            if norm2 <= T::lit(RANK_TOLERANCE) || !norm2.finite() {
                return Err(ConfigError::RankDeficient);
            }
            let mut basis: SVector<T, N> = residual.column(best) / norm2.sqrt();
            // Second Gram–Schmidt pass: keeps V Vᵀ = I to f32 round-off.
            for k in 0..row {
                let prev = v.row(k).transpose();
                basis -= prev * prev.dot(&basis);
            }
            let n = basis.norm();
            if n <= T::lit(RANK_TOLERANCE) {
                return Err(ConfigError::RankDeficient);
            }
            basis /= n;
            for mut c in residual.column_iter_mut() {
                let proj = basis.dot(&c);
                c.axpy(-proj, &basis, T::one());
            }
            v.set_row(row, &basis.transpose());
        }
        let (isolable, detectable) = isolability(&v, active);
        Ok(Self {
            geometry: *geometry,
            active: *active,
            dim,
            v,
            lsq,
            isolable,
            detectable,
        })
    }

    /// The space with sensor `k` also excluded (reconfiguration).
    pub fn without(&self, k: usize) -> Result<Self, ConfigError> {
        let mut active = self.active;
        if let Some(a) = active.get_mut(k) {
            *a = false;
        }
        Self::new(&self.geometry, &active)
    }

    /// Parity dimension `n_active − 3`.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Which sensors take part.
    pub fn active(&self) -> &[bool; N] {
        &self.active
    }

    /// The geometry the space was built from.
    pub fn geometry(&self) -> &Geometry<T, N> {
        &self.geometry
    }

    /// The parity matrix (rows `dim()..` zero).
    pub fn v(&self) -> &SMatrix<T, N, N> {
        &self.v
    }

    /// The least-squares matrix `(H_aᵀH_a)⁻¹H_aᵀ` (zero columns for
    /// excluded sensors).
    pub fn lsq(&self) -> &SMatrix<T, 3, N> {
        &self.lsq
    }

    /// Sensor `k`'s fault can be told apart from every other sensor's.
    pub fn isolable(&self, k: usize) -> bool {
        self.isolable.get(k).copied().unwrap_or(false)
    }

    /// Sensor `k`'s fault shows in the parity vector.
    pub fn detectable(&self, k: usize) -> bool {
        self.detectable.get(k).copied().unwrap_or(false)
    }

    /// True when every active sensor is isolable: the configuration can
    /// name the faulty sensor, not only say that one is faulty.
    pub fn fully_isolable(&self) -> bool {
        self.active
            .iter()
            .zip(self.isolable.iter())
            .all(|(a, i)| !a || *i)
    }

    /// Parity vector `p = V m` (entries `dim()..` zero).
    pub fn parity(&self, m: &SVector<T, N>) -> SVector<T, N> {
        self.v * m
    }

    /// Least-squares body vector `x̂ = (HᵀH)⁻¹Hᵀ m` from the active sensors.
    pub fn fuse(&self, m: &SVector<T, N>) -> Vector3<T> {
        self.lsq * m
    }

    /// `C = V_new V_selfᵀ`: maps this space's parity vectors to those of a
    /// sub-space (`p_new = C p`), exactly, because every parity direction
    /// of a subset of sensors is also one of the full set. Offsets, motion
    /// leakage and covariances learned in training carry over through `C`
    /// with no retraining.
    pub fn transition_to(&self, sub: &Self) -> SMatrix<T, N, N> {
        sub.v * self.v.transpose()
    }
}

/// Inverse of a symmetric 3×3 matrix, `None` when its smallest Cholesky
/// pivot is below [`RANK_TOLERANCE`] of its trace (rank < 3).
pub(super) fn invert_rank3<T: Real>(g: &Matrix3<T>) -> Option<Matrix3<T>> {
    let trace = g.trace();
    if !trace.finite() || trace <= T::zero() {
        return None;
    }
    let l = crate::math::cholesky(g).ok()?;
    let min_pivot2 = l.diagonal().iter().fold(trace, |m, d| m.min(*d * *d));
    if min_pivot2 <= T::lit(RANK_TOLERANCE) * trace {
        return None;
    }
    let inv = g.try_inverse()?;
    inv.iter().all(|x| x.finite()).then_some(inv)
}

fn isolability<T: Real, const N: usize>(
    v: &SMatrix<T, N, N>,
    active: &[bool; N],
) -> ([bool; N], [bool; N]) {
    let norms: [T; N] = core::array::from_fn(|k| v.column(k).norm_squared());
    let detectable: [bool; N] = core::array::from_fn(|k| {
        active.get(k).copied().unwrap_or(false)
            && norms.get(k).copied().unwrap_or(T::zero()) > T::lit(UNOBSERVABLE_NORM2)
    });
    let isolable = core::array::from_fn(|k| {
        detectable.get(k).copied().unwrap_or(false)
            && (0..N).filter(|j| *j != k).all(|j| {
                if !detectable.get(j).copied().unwrap_or(false) {
                    return true;
                }
                let dot = v.column(k).dot(&v.column(j));
                let nk = norms.get(k).copied().unwrap_or(T::one());
                let nj = norms.get(j).copied().unwrap_or(T::one());
                dot * dot < (T::one() - T::lit(PARALLEL_TOLERANCE)) * nk * nj
            })
    });
    (isolable, detectable)
}

#[cfg(test)]
mod tests {
    use super::super::geometry::yaw_rotation;
    use super::*;

    fn check_space<const N: usize>(s: &ParitySpace<f64, N>, tol: f64) {
        let vh = s.v() * s.geometry().h();
        assert!(vh.amax() < tol, "V H = {vh}");
        let vvt = s.v() * s.v().transpose();
        for i in 0..N {
            for j in 0..N {
                let want = if i == j && i < s.dim() { 1.0 } else { 0.0 };
                assert!((vvt[(i, j)] - want).abs() < tol, "V Vᵀ = {vvt}");
            }
        }
    }

    #[test]
    fn cone6_parity_space_is_orthonormal_and_annihilates_h() {
        let g = Geometry::<f64, 6>::cone6();
        let s = ParitySpace::new(&g, &[true; 6]).unwrap();
        assert_eq!(s.dim(), 3);
        check_space(&s, 1e-14);
        assert!(s.fully_isolable());
        // Least squares recovers x exactly from noise-free measurements.
        let x = Vector3::new(0.3, -1.2, 0.7);
        let m = g.h() * x;
        assert!((s.fuse(&m) - x).norm() < 1e-14);
        assert!(s.parity(&m).norm() < 1e-14);
    }

    #[test]
    fn f32_parity_space_keeps_orthonormality() {
        let g = Geometry::<f32, 6>::cone6();
        let s = ParitySpace::new(&g, &[true; 6]).unwrap();
        let vh = s.v() * g.h();
        assert!(vh.amax() < 1e-6);
        let e = s.v() * s.v().transpose();
        assert!((e.trace() - 3.0).abs() < 1e-5);
    }

    #[test]
    fn two_aligned_triads_detect_but_cannot_isolate() {
        let g =
            Geometry::<f64, 6>::triads(&[Matrix3::identity(), yaw_rotation(core::f64::consts::PI)])
                .unwrap();
        let s = ParitySpace::new(&g, &[true; 6]).unwrap();
        check_space(&s, 1e-14);
        assert!((0..6).all(|k| s.detectable(k) && !s.isolable(k)));
        assert!(!s.fully_isolable());
    }

    #[test]
    fn three_triads_isolate_two_of_three_then_only_detect() {
        let r = yaw_rotation(core::f64::consts::FRAC_PI_4);
        let g = Geometry::<f64, 9>::triads(&[Matrix3::identity(), Matrix3::identity(), r]).unwrap();
        let s = ParitySpace::new(&g, &[true; 9]).unwrap();
        assert_eq!(s.dim(), 6);
        check_space(&s, 1e-14);
        assert!(s.fully_isolable());
        // Drop IMU 0's z: the two remaining z sensors can only be compared.
        let s2 = s.without(2).unwrap();
        check_space(&s2, 1e-14);
        assert!(!s2.isolable(5) && !s2.isolable(8) && s2.detectable(5));
        assert!(s2.isolable(0));
        // Parity vectors map exactly into the sub-space.
        let m = SVector::<f64, 9>::from_fn(|i, _| (i as f64 * 0.37).sin());
        let c = s.transition_to(&s2);
        assert!((c * s.parity(&m) - s2.parity(&m)).norm() < 1e-13);
    }

    #[test]
    fn rank_deficient_and_too_small_sets_are_configuration_errors() {
        let planar = Geometry::<f64, 4>::new(&[
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, -1.0, 0.0],
        ])
        .unwrap();
        assert_eq!(
            ParitySpace::new(&planar, &[true; 4]),
            Err(ConfigError::RankDeficient)
        );
        let g = Geometry::<f64, 6>::cone6();
        assert_eq!(
            ParitySpace::new(&g, &[true, true, true, false, false, false]),
            Err(ConfigError::TooFewSensors)
        );
    }
}

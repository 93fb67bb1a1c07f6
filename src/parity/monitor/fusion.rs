//! The least-squares fusion of the sensors usable this period, with the
//! inverse normal matrix cached per usable subset (issue 14).

use nalgebra::{Matrix3, SVector, Vector3};

use crate::math::Real;

use super::super::space::invert_rank3;
use super::super::Geometry;
use super::ParityMonitor;

/// The inverse normal matrix `(HᵀH)⁻¹` of one subset of usable sensors
/// (`None` inside: that subset is below rank 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct FusionCache<T: Real, const N: usize> {
    usable: [bool; N],
    inv: Option<Matrix3<T>>,
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// [`fuse_subset`] with the inverse normal matrix cached per usable
    /// subset: bit-identical to it (the same sums in the same order, the
    /// same inverse), with the 3×3 factorisation only when the subset
    /// changes (a dropout, clipping, a failure; then once per change).
    pub(super) fn fuse_usable(
        &mut self,
        m: &SVector<T, N>,
        usable: &[bool; N],
    ) -> Option<Vector3<T>> {
        let geometry = self.space.geometry();
        let inv = match self.fusion {
            // Element by element: the array comparison is a `memcmp` call
            // (≈ 75 instructions on the M4F for nine flags).
            Some(c) if c.usable.iter().zip(usable.iter()).all(|(a, b)| a == b) => c.inv,
            _ => {
                let inv = invert_rank3(&normal_matrix(geometry, usable)?);
                self.fusion = Some(FusionCache {
                    usable: *usable,
                    inv,
                });
                inv
            }
        }?;
        let mut hm = Vector3::<T>::zeros();
        for (k, u) in usable.iter().enumerate() {
            if *u {
                hm += geometry.direction(k)? * m.get(k).copied().unwrap_or(T::zero());
            }
        }
        Some(inv * hm)
    }
}

/// `HᵀH` over the sensors marked usable (`None`: a sensor without a
/// direction, which a valid geometry never has).
fn normal_matrix<T: Real, const N: usize>(
    geometry: &Geometry<T, N>,
    usable: &[bool; N],
) -> Option<Matrix3<T>> {
    let mut g = Matrix3::<T>::zeros();
    for (k, u) in usable.iter().enumerate() {
        if *u {
            let h = geometry.direction(k)?;
            g += h * h.transpose();
        }
    }
    Some(g)
}

/// Least squares over the sensors marked usable; `None` below rank 3.
pub(super) fn fuse_subset<T: Real, const N: usize>(
    geometry: &Geometry<T, N>,
    m: &SVector<T, N>,
    usable: &[bool; N],
) -> Option<Vector3<T>> {
    let mut g = Matrix3::<T>::zeros();
    let mut hm = Vector3::<T>::zeros();
    for (k, u) in usable.iter().enumerate() {
        if !u {
            continue;
        }
        let h = geometry.direction(k)?;
        g += h * h.transpose();
        hm += h * m.get(k).copied().unwrap_or(T::zero());
    }
    invert_rank3(&g).map(|inv| inv * hm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parity::{ParityConfig, ParityMonitor};

    /// The cached fusion gives `fuse_subset`'s result bit for bit, through
    /// subset changes, repeats and rank-deficient subsets.
    #[test]
    fn cached_fusion_is_bit_identical_to_the_full_computation() {
        let g = Geometry::<f32, 9>::triads(&[
            Matrix3::identity(),
            Matrix3::identity(),
            crate::parity::yaw_rotation(0.7),
        ])
        .unwrap();
        let cfg = ParityConfig::<f32>::gyro_flight(100.0, 30.0);
        let mut mon = ParityMonitor::<f32, 9, 40>::new(&g, cfg).unwrap();
        let all = [true; 9];
        let mut one_out = all;
        one_out[4] = false;
        // Only IMU 0's x and y, IMU 1's x: rank 2.
        let mut rank2 = [false; 9];
        rank2[0] = true;
        rank2[1] = true;
        rank2[3] = true;
        let masks = [all, all, one_out, one_out, rank2, all, rank2, one_out];
        let mut checked = 0;
        for (step, usable) in masks.iter().cycle().take(40).enumerate() {
            let m = SVector::<f32, 9>::from_fn(|i, _| {
                ((step * 9 + i) as f32 * 0.731).sin() * 3.0 + 0.1 * i as f32
            });
            let want = fuse_subset(&g, &m, usable);
            let got = mon.fuse_usable(&m, usable);
            assert_eq!(want.is_some(), got.is_some(), "step {step}");
            if let (Some(w), Some(x)) = (want, got) {
                for (a, b) in w.iter().zip(x.iter()) {
                    assert_eq!(a.to_bits(), b.to_bits(), "step {step}: {w} vs {x}");
                }
                checked += 1;
            }
        }
        // 2 of every 8 masks are rank 2 (no fusion).
        assert_eq!(checked, 30);
    }
}

//! Carrying the learning elsewhere: into a sub-space at a reconfiguration
//! (in parts, one per monitor step) and into the shadow that judges an
//! isolated sensor (`parity/monitor/readmit.rs`), with the calibration
//! snapshots the latter starts from.

use nalgebra::SMatrix;

use super::lin::pad;
use super::{Multiscale, REGRESSORS};
use crate::math::Real;

/// Entries of the calibration's information matrix kept in a snapshot:
/// its lower triangle.
const LOWER: usize = REGRESSORS * (REGRESSORS + 1) / 2;

/// A calibration kept for re-admission: `sxx`'s lower triangle, column
/// by column, and `spx`. Nothing writes `sxx` above its diagonal (it is
/// zero from `Multiscale::new` on, see `learn_calibration`), so the
/// triangle restores it bit for bit in 544 bytes instead of 1,024: four
/// snapshots (two in each of the monitor's test slots) were 6.4 KB of
/// the nine-sensor monitor's RAM.
pub(super) type CalSnap<T, const N: usize> = ([T; LOWER], SMatrix<T, N, REGRESSORS>);

/// `m`'s lower triangle, column by column.
fn pack_lower<T: Real>(m: &SMatrix<T, REGRESSORS, REGRESSORS>) -> [T; LOWER] {
    let mut out = [T::zero(); LOWER];
    let mut slots = out.iter_mut();
    for (j, col) in m.as_slice().chunks_exact(REGRESSORS).enumerate() {
        for (x, slot) in col.iter().skip(j).zip(&mut slots) {
            *slot = *x;
        }
    }
    out
}

/// Writes the triangle of [`pack_lower`] into `m` (zero above the diagonal).
fn unpack_lower<T: Real>(t: &[T; LOWER], m: &mut SMatrix<T, REGRESSORS, REGRESSORS>) {
    let mut vals = t.iter();
    for (j, col) in m.as_mut_slice().chunks_exact_mut(REGRESSORS).enumerate() {
        for (i, x) in col.iter_mut().enumerate() {
            *x = if i < j {
                T::zero()
            } else {
                vals.next().copied().unwrap_or(T::zero())
            };
        }
    }
}

impl<T: Real, const N: usize, const W: usize> Multiscale<T, N, W> {
    /// This space's tests with `src`'s learning (calibration, covariances,
    /// vibration law, thresholds and counters) and an empty window, no
    /// block in work. Only the learned state is copied (≈ 3.5 KB for nine
    /// sensors, not the ≈ 19 KB with the ring: the copy is a step of its
    /// own, `Reconfig::Shadow`, after the isolating one).
    pub fn copy_learning_from(&mut self, src: &Self) {
        self.cfg = src.cfg;
        self.dim = src.dim;
        // The calibration as it was one to two longest windows before:
        // the blocks a fault's first decisions judged quiet (before any
        // score rose) were learned into the current one, and a calibration
        // that holds a glitch's blocks explains the next glitch away.
        if let Some(Some((sxx, spx))) = src.cal_snaps.get(1) {
            unpack_lower(sxx, &mut self.sxx);
            self.spx = *spx;
        } else {
            self.sxx = src.sxx;
            self.spx = src.spx;
        }
        self.cal_snaps = [None; 2];
        self.since_snap = 0;
        self.ridge = src.ridge;
        self.x_ref = src.x_ref;
        self.energy_range = src.energy_range;
        self.block_cov = src.block_cov;
        self.window_cov = src.window_cov;
        self.scale = src.scale;
        self.updates = src.updates;
        self.scale_h = src.scale_h;
        self.z = src.z;
        self.trained_blocks = src.trained_blocks;
        self.cal_current = false;
        self.covariances_changed();
        self.cancel();
        self.clear_window();
    }

    /// One more decision: every longest window, the calibration is kept
    /// (see `cal_snaps`).
    pub(super) fn snapshot_calibration(&mut self) {
        self.since_snap = self.since_snap.saturating_add(1);
        if self.since_snap >= self.longest() {
            self.since_snap = 0;
            let [newer, older] = &mut self.cal_snaps;
            *older = *newer;
            *newer = Some((pack_lower(&self.sxx), self.spx));
        }
    }

    /// Carries everything learned into a sub-space, part `part` of
    /// [`TRANSFORM_PARTS`](super::TRANSFORM_PARTS) (one per monitor step, issue 17): `c` maps this
    /// space's parity vectors to the sub-space's (`p_new = c p`), `dim` is
    /// the new dimension. The window restarts (its residuals are not
    /// carried).
    pub fn transform_part(&mut self, c: &SMatrix<T, N, N>, dim: usize, part: usize) {
        self.covariances_changed();
        match part {
            0 => {
                // A block in work belongs to the old space.
                self.cancel();
                self.cal_snaps = [None; 2];
                self.since_snap = 0;
                self.clear_window();
                self.dim = dim;
                self.spx = c * self.spx;
                self.block_cov = pad(&(c * self.block_cov * c.transpose()), dim);
            }
            _ => {
                let first = (part - 1) * 2;
                for cov in self.window_cov.iter_mut().skip(first).take(2) {
                    *cov = pad(&(c * *cov * c.transpose()), dim);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parity::ParityConfig;
    use nalgebra::SVector;

    /// The snapshot's triangle restores a lower-triangular `sxx` exactly,
    /// whatever the matrix written into held before.
    #[test]
    fn the_lower_triangle_restores_the_matrix_bit_for_bit() {
        let m = SMatrix::<f32, REGRESSORS, REGRESSORS>::from_fn(|i, j| {
            if i >= j {
                1.0 + (i * REGRESSORS + j) as f32 / 7.0
            } else {
                0.0
            }
        });
        let mut out = SMatrix::<f32, REGRESSORS, REGRESSORS>::from_element(-3.0);
        unpack_lower(&pack_lower(&m), &mut out);
        assert_eq!(out, m);
        assert_eq!(LOWER, 136);
    }

    /// What the packing relies on: learning leaves `sxx` zero above its
    /// diagonal (with and without forgetting).
    #[test]
    fn learning_writes_only_the_lower_triangle_of_the_information_matrix() {
        let cfg = ParityConfig::<f32>::gyro_flight(100.0, 30.0).multiscale;
        let mut ms = Multiscale::<f32, 9, 40>::new(cfg, 6, [1.0; super::super::SCALES]);
        for k in 0..20 {
            let phi = SVector::<f32, REGRESSORS>::from_fn(|i, _| 1.0 + (i * k) as f32 * 0.1);
            let p = SVector::<f32, 9>::from_fn(|i, _| (i + k) as f32 * 0.01);
            ms.learn_calibration(&p, &phi, k % 2 == 0);
        }
        let upper: f32 = (0..REGRESSORS)
            .flat_map(|j| (0..j).map(move |i| (i, j)))
            .map(|(i, j)| ms.sxx[(i, j)].abs())
            .sum();
        assert_eq!(upper, 0.0);
        assert!(ms.sxx[(REGRESSORS - 1, 0)] != 0.0);
    }
}

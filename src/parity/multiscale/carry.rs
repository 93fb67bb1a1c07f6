//! Carrying the learning elsewhere: into a sub-space at a reconfiguration
//! (in parts, one per monitor step) and into the shadow that judges an
//! isolated sensor (`parity/monitor/readmit.rs`), with the calibration
//! snapshots the latter starts from.

use nalgebra::SMatrix;

use super::lin::pad;
use super::Multiscale;
use crate::math::Real;

impl<T: Real, const N: usize, const W: usize> Multiscale<T, N, W> {
    /// This space's tests with `src`'s learning (calibration, covariances,
    /// vibration law, thresholds and counters) and an empty window, no
    /// block in work. Only the learned state is copied (≈ 3.5 KB for nine
    /// sensors, not the ≈ 15 KB with the ring: the copy is made in the
    /// step that isolates, the longest of the flight).
    pub fn copy_learning_from(&mut self, src: &Self) {
        self.cfg = src.cfg;
        self.dim = src.dim;
        // The calibration as it was one to two longest windows before:
        // the blocks a fault's first decisions judged quiet (before any
        // score rose) were learned into the current one, and a calibration
        // that holds a glitch's blocks explains the next glitch away.
        let (sxx, spx) = src
            .cal_snaps
            .get(1)
            .copied()
            .flatten()
            .unwrap_or((src.sxx, src.spx));
        self.sxx = sxx;
        self.spx = spx;
        self.cal_snaps = [None; 2];
        self.since_snap = 0;
        self.ridge = src.ridge;
        self.x_ref = src.x_ref;
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
            self.cal_snaps = [Some((self.sxx, self.spx)), self.cal_snaps[0]];
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

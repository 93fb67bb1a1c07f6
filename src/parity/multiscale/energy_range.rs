//! The range of the vibration regressors the calibration has learned, and
//! the gross test's window mean over the blocks predicted inside it.

use nalgebra::SVector;

use super::{Multiscale, Phi, FIRST_VIBRATION, VIBRATION_REGRESSORS};
use crate::math::Real;

impl<T: Real, const N: usize, const W: usize> Multiscale<T, N, W> {
    /// Widens the learned range of the vibration regressors to `phi`'s.
    pub(super) fn widen_energy_range(&mut self, phi: &Phi<T>) {
        let e = phi.fixed_rows::<VIBRATION_REGRESSORS>(FIRST_VIBRATION);
        match &mut self.energy_range {
            Some((lo, hi)) => {
                for ((l, h), x) in lo.iter_mut().zip(hi.iter_mut()).zip(e.iter()) {
                    *l = l.fmin(*x);
                    *h = h.fmax(*x);
                }
            }
            None => self.energy_range = Some((e.into_owned(), e.into_owned())),
        }
    }

    /// `phi`'s vibration regressors are all within the range the
    /// calibration has learned (true before any learning).
    pub(super) fn within_learned_energy(&self, phi: &Phi<T>) -> bool {
        self.energy_range.as_ref().is_none_or(|(lo, hi)| {
            let e = phi.iter().skip(FIRST_VIBRATION);
            e.zip(lo.iter().zip(hi.iter()))
                .all(|(x, (l, h))| *x >= *l && *x <= *h)
        })
    }

    /// Mean of the newest `len` unclipped, unstandardised residuals over
    /// the blocks whose vibration regressors were within the range the
    /// calibration had learned (`None` before `len` blocks, or when none
    /// was). The nine energy regressors are nearly collinear and their
    /// coefficients poorly determined: beyond the range learned the
    /// prediction extrapolates. The window tests carry that uncertainty
    /// (`φ̄ᵀPφ̄ Σ_b`) and clip the block; the gross test alarms at once,
    /// without either, so it rests on the blocks the calibration predicts
    /// from what it has seen. On log171 at 99 Hz one +3.9 m/s² sample took
    /// IMU2 a_z's energy to ≈ 0.93 (learned ≈ 0.01–0.1) and the reduced
    /// set's frozen calibration predicted that block ≈ 1 m/s² off: a gross
    /// alarm naming that healthy sensor. A fault far beyond any vibration
    /// excursion lasts into blocks of ordinary vibration (a step or a
    /// glitch raises a sensor's energy only in the blocks it starts and
    /// ends in).
    pub(super) fn raw_mean_learned(&self, len: usize) -> Option<SVector<T, N>> {
        self.ring_mean(len, |idx| {
            self.learned_range
                .get(idx)
                .copied()
                .unwrap_or(false)
                .then(|| self.raw.get(idx).copied())
                .flatten()
        })
    }
}

//! The end of training: the block covariance, the vibration law and the
//! starting covariance of every window length from the training blocks.

use nalgebra::{SMatrix, SVector};

use crate::math::{cholesky, Real};

use super::glr::{mahalanobis2, pad};
use super::{Multiscale, Phi};

impl<T: Real, const N: usize, const W: usize> Multiscale<T, N, W> {
    /// Ends training: the residuals of the second half (already pushed with
    /// [`train_residual`](Self::train_residual)) give the block covariance;
    /// each window length starts from the block covariance scaled by the
    /// correlation seen over the shortest window, with the weight of
    /// the training blocks' observations. `None` if degenerate.
    pub fn finish_training(&mut self) -> Option<()> {
        let n = self.filled;
        if n < 8 {
            return None;
        }
        // The vibration law first, from the raw residuals' energies under
        // their own covariance; then everything on the standardised ones.
        let dimf = T::lit(self.dim.max(1) as f64);
        let (mean0, cov0) = self.training_moments(n);
        let l0 = cholesky(&pad(&cov0, self.dim)).ok()?;
        let energies = self
            .levels
            .iter()
            .zip(self.residuals.iter())
            .take(n)
            .map(|(x, r)| (*x, mahalanobis2(&l0, &(r - mean0)) / dimf));
        self.scale.fit(energies);
        // (`raw` stays in sensor units: the gross test must not let a
        // violent block's vibration discount it.)
        for (r, (g, x)) in self
            .residuals
            .iter_mut()
            .zip(self.gains.iter_mut().zip(self.levels.iter()))
            .take(n)
        {
            *g = T::one() / self.scale.predict(*x).sqrt();
            *r *= *g;
        }
        let (mean, cov) = self.training_moments(n);
        self.block_cov = pad(&cov, self.dim);
        cholesky(&self.block_cov).ok()?;
        // Correlation factor over the shortest window that fits in training:
        // variance of overlapping window means ÷ the white-noise value.
        let len = usize::from(self.cfg.scales[0]).min(n / 2).max(1);
        let mut factor_sum = T::zero();
        let mut count = 0usize;
        let l = cholesky(&self.block_cov).ok()?;
        let mut start = 0;
        while start + len <= n {
            let mut s = SVector::<T, N>::zeros();
            for r in self.residuals.iter().skip(start).take(len) {
                s += r - mean;
            }
            let w = s / T::lit(len as f64);
            factor_sum += mahalanobis2(&l, &w);
            count += 1;
            start += 1;
        }
        let dimf = T::lit(self.dim.max(1) as f64);
        let factor = if count > 0 {
            (factor_sum / T::lit(count as f64) * T::lit(len as f64) / dimf).max(T::one())
        } else {
            T::one()
        };
        // Training is too short to see how the longer windows wander (a
        // 10-s mean of 20 s of data is two numbers), so every length starts
        // at the shortest window's covariance: no more sensitive than that
        // until the flight itself has shown the longer windows to be
        // quieter (the covariances keep learning while every test is quiet).
        let shortest = T::lit(f64::from(self.cfg.scales[0]));
        for cov_n in self.window_cov.iter_mut() {
            *cov_n = pad(&(cov * (factor / shortest)), self.dim);
        }
        self.filled = 0;
        self.head = 0;
        self.quiet_blocks = 0;
        // The training estimate rests on the residual blocks that made it;
        // each quiet block in flight then adds one, up to the fixed memory
        // `variance_blocks`; the thresholds follow the degrees of freedom.
        self.updates = n as u32;
        self.trained_blocks = n as u32;
        Some(())
    }

    /// Mean and sample covariance of the first `n` stored residuals.
    fn training_moments(&self, n: usize) -> (SVector<T, N>, SMatrix<T, N, N>) {
        let mut mean = SVector::<T, N>::zeros();
        for r in self.residuals.iter().take(n) {
            mean += r;
        }
        mean /= T::lit(n.max(1) as f64);
        let mut cov = SMatrix::<T, N, N>::zeros();
        for r in self.residuals.iter().take(n) {
            let d = r - mean;
            cov += d * d.transpose();
        }
        cov /= T::lit(n.saturating_sub(1).max(1) as f64);
        (mean, cov)
    }

    /// A training block of the second half: its (unclipped) prior residual
    /// and vibration level `level` are kept for the covariance and the
    /// vibration law.
    pub fn train_residual(&mut self, r: &SVector<T, N>, phi: &Phi<T>, level: T) {
        self.push(r, r, phi, T::one(), level);
    }
}

//! The end of training: the block covariance, the vibration law and the
//! starting covariance of every window length from the training blocks.

use nalgebra::{SMatrix, SVector};

use crate::math::{mirror_lower, Real};

use super::lin::{cholesky_dim, pad, quad_form};
use super::{Multiscale, Phi};

/// Parts of [`Multiscale::finish_training_part`].
pub const FINISH_PARTS: usize = 14;

impl<T: Real, const N: usize, const W: usize> Multiscale<T, N, W> {
    /// Ends training, part `part` of [`FINISH_PARTS`] (one per monitor
    /// step, issue 17): the residuals of the second half (already pushed
    /// with [`train_residual`](Self::train_residual)) give the vibration law
    /// and the block covariance; each window length starts from the block
    /// covariance scaled by the correlation seen over the shortest window.
    /// Loops over the stored residuals run half of them per part; the
    /// covariance being summed, then its factor, live in `block_cov` (unused
    /// in training). `Some(true)` when training is complete, `Some(false)`
    /// when more parts follow, `None` if degenerate.
    pub fn finish_training_part(&mut self, part: usize) -> Option<bool> {
        // Every part may write `block_cov` or `window_cov`.
        self.covariances_changed();
        let n = self.filled;
        if n < 8 {
            return None;
        }
        let dimf = T::lit(self.dim.max(1) as f64);
        let half = n.div_ceil(2);
        let halves = [(0, half), (half, n - half)];
        match part {
            // The vibration law first, from the raw residuals' energies under
            // their own covariance (kept in `gains` until the fit).
            0 => self.begin_moments(n),
            1 | 2 => self.add_moments(halves.get(part - 1)?),
            3 => {
                let cov0 = self.end_moments(n);
                self.block_cov = cholesky_dim(&cov0, self.dim)?;
            }
            4 | 5 => {
                let (first, count) = *halves.get(part - 4)?;
                let (l0, mean0) = (self.block_cov, self.work.train_mean);
                for (g, r) in self
                    .gains
                    .iter_mut()
                    .zip(self.residuals.iter())
                    .skip(first)
                    .take(count)
                {
                    *g = quad_form(&l0, &(r - mean0), self.dim) / dimf;
                }
            }
            6 => {
                let energies = self.levels.iter().copied().zip(self.gains.iter().copied());
                self.scale.fit(energies.take(n));
                // Then everything on the standardised residuals. (`raw`
                // stays in sensor units: the gross test must not let a
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
                self.begin_moments(n);
            }
            7 | 8 => self.add_moments(halves.get(part - 7)?),
            9 => {
                let cov = self.end_moments(n);
                self.block_cov = pad(&cov, self.dim);
                cholesky_dim(&self.block_cov, self.dim)?;
                self.work.train_sum = T::zero();
            }
            10..=13 => {
                // Correlation factor over the shortest window that fits in
                // training: variance of overlapping window means ÷ the
                // white-noise value (a quarter of the windows per part).
                let len = usize::from(self.cfg.scales[0]).min(n / 2).max(1);
                let windows = n + 1 - len;
                let l = cholesky_dim(&self.block_cov, self.dim)?;
                let mean = self.work.train_mean;
                let quarter = windows.div_ceil(4);
                let first = (part - 10) * quarter;
                for start in first..(first + quarter).min(windows) {
                    let mut s = SVector::<T, N>::zeros();
                    for r in self.residuals.iter().skip(start).take(len) {
                        s += r - mean;
                    }
                    let w = s / T::lit(len as f64);
                    self.work.train_sum += quad_form(&l, &w, self.dim);
                }
                if part < 13 {
                    return Some(false);
                }
                let factor = (self.work.train_sum / T::lit(windows as f64) * T::lit(len as f64)
                    / dimf)
                    .max(T::one());
                // Training is too short to see how the longer windows wander
                // (a 10-s mean of 20 s of data is two numbers), so every
                // length starts at the shortest window's covariance: no more
                // sensitive than that until the flight itself has shown the
                // longer windows to be quieter (the covariances keep
                // learning while every test is quiet).
                let shortest = T::lit(f64::from(self.cfg.scales[0]));
                for cov_n in self.window_cov.iter_mut() {
                    *cov_n = pad(&(self.block_cov * (factor / shortest)), self.dim);
                }
                self.filled = 0;
                self.head = 0;
                self.quiet_blocks = 0;
                // The training estimate rests on the residual blocks that
                // made it; each quiet block in flight then adds one, up to
                // the fixed memory `variance_blocks`; the thresholds follow
                // the degrees of freedom.
                self.updates = n as u32;
                self.trained_blocks = n as u32;
                return Some(true);
            }
            _ => return Some(true),
        }
        Some(false)
    }

    /// Mean of the first `n` stored residuals into `work.train_mean`, and
    /// `block_cov` zeroed to sum their covariance in.
    fn begin_moments(&mut self, n: usize) {
        let mut mean = SVector::<T, N>::zeros();
        for r in self.residuals.iter().take(n) {
            mean += r;
        }
        mean /= T::lit(n.max(1) as f64);
        self.work.train_mean = mean;
        self.block_cov = SMatrix::zeros();
    }

    /// Adds the outer products of `count` residuals from `first` to the
    /// covariance being summed (its lower triangle on the leading `dim`
    /// coordinates: it is symmetric, and zero beyond).
    fn add_moments(&mut self, &(first, count): &(usize, usize)) {
        let dim = self.dim.min(N);
        let mean = self.work.train_mean;
        for r in self.residuals.iter().skip(first).take(count) {
            let d = r - mean;
            let ds = d.as_slice();
            for (j, (col, dj)) in self
                .block_cov
                .as_mut_slice()
                .chunks_exact_mut(N)
                .zip(ds)
                .enumerate()
            {
                for (x, di) in col.iter_mut().zip(ds).take(dim).skip(j) {
                    *x += *di * *dj;
                }
            }
        }
    }

    /// The sample covariance summed by [`add_moments`](Self::add_moments).
    fn end_moments(&self, n: usize) -> SMatrix<T, N, N> {
        let mut cov = self.block_cov / T::lit(n.saturating_sub(1).max(1) as f64);
        mirror_lower(&mut cov);
        cov
    }

    /// A training block of the second half: its (unclipped) prior residual
    /// and vibration level `level` are kept for the covariance and the
    /// vibration law.
    pub fn train_residual(&mut self, r: &SVector<T, N>, phi: &Phi<T>, level: T) {
        self.push(r, r, phi, T::one(), level);
    }
}

//! Learning the fault-free parity behaviour: offset, motion leakage and
//! noise covariance (\[PAR\] trains its PCA the same way, SPEC §7/§8a).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::math::Real;

use super::space::invert_rank3;

/// What training learned, in the parity coordinates of the space it was
/// trained in: `r = p − L x̂ − p₀` is the motion-free parity residual and
/// `Σ_b` its covariance over one block of `block_len` samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Baseline<T: Real, const N: usize> {
    /// Offset `p₀` (turn-on biases seen through `V`).
    pub offset: SVector<T, N>,
    /// Motion leakage `L` (scale-factor and misalignment errors, `V(M−I)H`).
    pub leak: SMatrix<T, N, 3>,
    /// Covariance of a block mean of `r` (rows/columns `dim..` zero).
    pub block_cov: SMatrix<T, N, N>,
    /// Block covariance ÷ (per-sample covariance ÷ block length): 1 for
    /// white noise, larger when samples are correlated (filtered sensors,
    /// vibration). Reported so a user sees how far from white their data is.
    pub correlation_factor: T,
}

/// Accumulates training samples in two halves: the first fits offset and
/// leakage (ridge regression of `p` on the fused `x̂`, centred on the first
/// sample to keep `f32` sums well conditioned), the second measures the
/// residual's per-sample and per-block covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trainer<T: Real, const N: usize> {
    total: u32,
    block_len: u16,
    ridge: T,
    n: u32,
    x0: Vector3<T>,
    p0: SVector<T, N>,
    sx: Vector3<T>,
    sp: SVector<T, N>,
    sxx: Matrix3<T>,
    spx: SMatrix<T, N, 3>,
    fit: Option<(SVector<T, N>, SMatrix<T, N, 3>)>,
    n2: u32,
    sr: SVector<T, N>,
    srr: SMatrix<T, N, N>,
    block: SVector<T, N>,
    block_n: u16,
    nb: u32,
    sb: SVector<T, N>,
    sbb: SMatrix<T, N, N>,
}

impl<T: Real, const N: usize> Trainer<T, N> {
    /// A trainer for `total` samples (at least 4 blocks in each half),
    /// blocks of `block_len` samples, ridge `ridge` (unit², per sample) on
    /// the leakage so an unexcited axis gets no leakage instead of noise.
    pub fn new(total: u32, block_len: u16, ridge: T) -> Self {
        Self {
            total,
            block_len: block_len.max(1),
            ridge,
            n: 0,
            x0: Vector3::zeros(),
            p0: SVector::zeros(),
            sx: Vector3::zeros(),
            sp: SVector::zeros(),
            sxx: Matrix3::zeros(),
            spx: SMatrix::zeros(),
            fit: None,
            n2: 0,
            sr: SVector::zeros(),
            srr: SMatrix::zeros(),
            block: SVector::zeros(),
            block_n: 0,
            nb: 0,
            sb: SVector::zeros(),
            sbb: SMatrix::zeros(),
        }
    }

    /// Samples taken so far.
    pub fn samples(&self) -> u32 {
        self.n.saturating_add(self.n2)
    }

    /// True once `total` samples have been taken.
    pub fn done(&self) -> bool {
        self.samples() >= self.total
    }

    /// Adds one parity vector `p` with the fused vector `x̂` of the same sample.
    pub fn add(&mut self, p: &SVector<T, N>, x: &Vector3<T>) {
        match self.fit {
            None => {
                if self.n == 0 {
                    self.x0 = *x;
                    self.p0 = *p;
                }
                let dx = x - self.x0;
                let dp = p - self.p0;
                self.sx += dx;
                self.sp += dp;
                self.sxx += dx * dx.transpose();
                self.spx += dp * dx.transpose();
                self.n = self.n.saturating_add(1);
                if self.n >= self.total / 2 {
                    self.fit = Some(self.solve_fit());
                }
            }
            Some((offset, leak)) => {
                let r = p - leak * x - offset;
                self.sr += r;
                self.srr += r * r.transpose();
                self.n2 = self.n2.saturating_add(1);
                self.block += r;
                self.block_n = self.block_n.saturating_add(1);
                if self.block_n >= self.block_len {
                    let b = self.block / T::lit(f64::from(self.block_len));
                    self.sb += b;
                    self.sbb += b * b.transpose();
                    self.nb = self.nb.saturating_add(1);
                    self.block = SVector::zeros();
                    self.block_n = 0;
                }
            }
        }
    }

    fn solve_fit(&self) -> (SVector<T, N>, SMatrix<T, N, 3>) {
        let n = T::lit(f64::from(self.n.max(1)));
        let mx = self.sx / n;
        let mp = self.sp / n;
        let cxx = self.sxx - mx * self.sx.transpose() + Matrix3::identity() * (self.ridge * n);
        let cpx = self.spx - mp * self.sx.transpose();
        let leak = match invert_rank3(&cxx) {
            Some(inv) => cpx * inv,
            None => SMatrix::zeros(),
        };
        // p ≈ L x + p₀ with both sums centred on the first sample.
        let offset = self.p0 + mp - leak * (self.x0 + mx);
        (offset, leak)
    }

    /// The learned baseline, once enough samples and blocks were seen
    /// (`None` before; also when the data held non-finite values).
    pub fn finish(&self) -> Option<Baseline<T, N>> {
        let (offset, leak) = self.fit?;
        if self.nb < 4 || self.n2 < 8 {
            return None;
        }
        let n2 = T::lit(f64::from(self.n2));
        let mean = self.sr / n2;
        let per_sample = self.srr / n2 - mean * mean.transpose();
        let nb = T::lit(f64::from(self.nb));
        let bmean = self.sb / nb;
        let per_block = self.sbb / nb - bmean * bmean.transpose();
        let len = T::lit(f64::from(self.block_len));
        let white = per_sample.trace() / len;
        let factor = if white > T::zero() {
            (per_block.trace() / white).max(T::one()).min(len)
        } else {
            T::one()
        };
        let block_cov = per_sample * (factor / len);
        let ok = offset
            .iter()
            .chain(leak.iter())
            .chain(block_cov.iter())
            .all(|x| x.finite());
        ok.then_some(Baseline {
            // The second half's mean residual is drift since the fit: keep it.
            offset: offset + mean,
            leak,
            block_cov,
            correlation_factor: factor,
        })
    }
}

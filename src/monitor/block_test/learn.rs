//! The block test's gated learning: offset, block variance,
//! reddening per length, and the motion the learnt blocks cover.

use nalgebra::Vector3;

use super::*;

impl<T: Real> BlockTest<T> {
    /// Learnt blocks (forgetting-weighted) at least as active as the
    /// newest window of `len` blocks (its mean squared rate's bin or above).
    pub(super) fn covered(&self, len: usize) -> T {
        let b = motion_bin(
            self.mean_motion(0, len).unwrap_or_else(T::zero),
            MOTION_BINS,
        );
        self.motion_hist
            .iter()
            .skip(b)
            .fold(T::zero(), |s, h| s + *h)
    }

    /// The mean motion measure of the kept blocks among the `len` ending
    /// `age` blocks before the newest (`None`: none kept).
    pub(super) fn mean_motion(&self, age: usize, len: usize) -> Option<T> {
        let mut s = T::zero();
        let mut n = 0usize;
        for a in age..age + len {
            if let Some(m) = self.slot(a).and_then(|i| self.motion.get(i)) {
                s += *m;
                n += 1;
            }
        }
        (n > 0).then(|| s / T::lit(n as f64))
    }

    /// Learns the block `longest − 1` blocks back (every decision that saw
    /// it has been made) and the windows that end at it, on the channels
    /// where every decision that saw any of their blocks stayed below
    /// `learn_below`.
    pub(super) fn learn(&mut self, cfg: &BlockTestConfig<T>) {
        let longest = usize::from(cfg.lengths[NL - 1]);
        let age = longest - 1;
        let Some(block) = self.slot(age).and_then(|i| self.blocks.get(i)).copied() else {
            self.prev = [None; 3];
            return;
        };
        let mut worst = Vector3::<T>::zeros();
        for a in 0..(age + longest).min(self.filled) {
            if let Some(r) = self.slot(a).and_then(|i| self.ratio_at.get(i)) {
                worst = worst.sup(r);
            }
        }
        let keep = T::one() - T::one() / cfg.memory_blocks;
        let motion = self
            .slot(age)
            .and_then(|i| self.motion.get(i))
            .copied()
            .unwrap_or_else(T::zero);
        let mut windows = [None; NL];
        for (w, len) in windows.iter_mut().zip(cfg.lengths.iter()) {
            *w = self.window(age, usize::from(*len));
        }
        for c in 0..3 {
            if !worst.get(c).is_some_and(|r| *r < cfg.learn_below) {
                if let Some(p) = self.prev.get_mut(c) {
                    *p = None;
                }
                continue;
            }
            let (Some(n), Some(s1), Some(s2), Some(b)) = (
                self.n_b.get_mut(c),
                self.s1.get_mut(c),
                self.s2.get_mut(c),
                block.get(c),
            ) else {
                continue;
            };
            let dev = (*n > T::one()).then(|| *b - *s1 / *n);
            *n = *n * keep + T::one();
            *s1 = *s1 * keep + *b;
            *s2 = *s2 * keep + *b * *b;
            let b = *b;
            if let (Some(Some(p)), Some(n11), Some(s11)) = (
                self.prev.get(c).copied(),
                self.n11.get_mut(c),
                self.s11.get_mut(c),
            ) {
                *n11 = *n11 * keep + T::one();
                *s11 = *s11 * keep + b * p;
            }
            if let Some(p) = self.prev.get_mut(c) {
                *p = Some(b);
            }
            if let Some(d) = dev {
                self.learn_motion_variance(c, d, motion, keep);
            }
            let Some((mean, _, _)) = self.moments(c) else {
                continue;
            };
            let mut factors = [T::one(); NL];
            for (f, len) in factors.iter_mut().zip(cfg.lengths.iter()) {
                *f = self.window_factor(c, age, usize::from(*len), longest);
            }
            for (((q, nw), w), h) in self
                .q_w
                .iter_mut()
                .zip(self.n_w.iter_mut())
                .zip(windows.iter())
                .zip(factors.iter())
            {
                let (Some(q), Some(nw), Some(wc)) = (
                    q.get_mut(c),
                    nw.get_mut(c),
                    w.as_ref().and_then(|w| w.get(c)),
                ) else {
                    continue;
                };
                let d = *wc - mean;
                *q = *q * keep + d * d / h.fmax(T::lit(1e-6));
                *nw = *nw * keep + T::one();
            }
        }
        // The motion the learnt spread holds for: the block counts if any
        // channel learnt it.
        if (0..3).any(|c| worst.get(c).is_some_and(|r| *r < cfg.learn_below)) {
            let bin = motion_bin(motion, MOTION_BINS);
            for (k, h) in self.motion_hist.iter_mut().enumerate() {
                *h = *h * keep + if k == bin { T::one() } else { T::zero() };
            }
        }
        // What the report shows of the learnt state.
        let lengths = cfg.lengths;
        for c in 0..3 {
            let Some((m, _, _)) = self.moments(c) else {
                continue;
            };
            if let Some(o) = self.detail.offset.get_mut(c) {
                *o = m;
            }
            for k in 0..NL {
                let Some((var, nu)) = self.window_variance(cfg, k, c, T::one()) else {
                    continue;
                };
                let Some((_, vb, n)) = self.moments(c) else {
                    continue;
                };
                let len = T::lit(f64::from(lengths.get(k).copied().unwrap_or(1)));
                let rho = var / (vb * (T::one() / len + T::one() / n));
                if let Some(d) = self.detail.reddening.get_mut(k).and_then(|d| d.get_mut(c)) {
                    *d = rho;
                }
                if let Some(d) = self.detail.dof.get_mut(k).and_then(|d| d.get_mut(c)) {
                    *d = nu;
                }
            }
        }
    }
}

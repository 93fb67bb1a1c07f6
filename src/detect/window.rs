use heapless::HistoryBuf;

use crate::math::Real;

/// Sample statistics of a full or partial window.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WindowStats<T> {
    /// Number of samples.
    pub n: usize,
    /// Sample mean.
    pub mean: T,
    /// Sample standard deviation with `n − 1` in the denominator.
    pub std: T,
}

/// The last `N` innovations of one channel.
///
/// Statistics are recomputed exactly over the window (two passes: mean, then
/// centred squares) each time they are asked for. That costs `2N` operations
/// but cannot drift or cancel: the `Σx² − n·mean²` shortcut collapses in
/// `f32` precisely when a fault biases the window, and running (Welford-style)
/// removals accumulate round-off over millions of samples.
#[derive(Debug, Clone)]
pub struct InnovationWindow<T, const N: usize> {
    buf: HistoryBuf<T, N>,
}

impl<T: Real, const N: usize> Default for InnovationWindow<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const N: usize> InnovationWindow<T, N> {
    /// An empty window.
    pub fn new() -> Self {
        const { assert!(N >= 3, "a t-test window needs at least 3 samples") };
        Self {
            buf: HistoryBuf::new(),
        }
    }
    /// Appends a sample, dropping the oldest when full.
    pub fn push(&mut self, x: T) {
        self.buf.write(x);
    }
    /// Empties the window (aiding lost, re-alignment).
    pub fn clear(&mut self) {
        self.buf.clear();
    }
    /// True when the window holds `N` samples.
    pub fn is_full(&self) -> bool {
        self.buf.len() == N
    }
    /// Number of samples held.
    pub fn len(&self) -> usize {
        self.buf.len()
    }
    /// True when no sample is held.
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }
    /// Windowed outlier removal: statistics recomputed without the samples
    /// farther than `k` sample standard deviations from the window mean
    /// (one pass; at most a quarter of the window may be removed, so a
    /// genuine step in the window is not trimmed away). Returns the
    /// statistics and how many samples were dropped.
    pub fn stats_trimmed(&self, k: T) -> Option<(WindowStats<T>, usize)> {
        let full = self.stats()?;
        if !full.std.finite() || full.std <= T::zero() || !k.finite() || k <= T::zero() {
            return Some((full, 0));
        }
        let limit = k * full.std;
        let outliers = self
            .buf
            .iter()
            .filter(|x| (**x - full.mean).abs() > limit)
            .count();
        if outliers == 0 || outliers * 4 > self.buf.len() {
            return Some((full, 0));
        }
        let kept = self.buf.len() - outliers;
        if kept < 2 {
            return Some((full, 0));
        }
        let nf = T::lit(kept as f64);
        let mut sum = T::zero();
        for x in self.buf.iter().filter(|x| (**x - full.mean).abs() <= limit) {
            sum += *x;
        }
        let mean = sum / nf;
        let mut ss = T::zero();
        for x in self.buf.iter().filter(|x| (**x - full.mean).abs() <= limit) {
            let d = *x - mean;
            ss += d * d;
        }
        Some((
            WindowStats {
                n: kept,
                mean,
                std: (ss / (nf - T::one())).sqrt_fast(),
            },
            outliers,
        ))
    }

    /// Mean and standard deviation, or `None` with fewer than two samples.
    pub fn stats(&self) -> Option<WindowStats<T>> {
        let n = self.buf.len();
        if n < 2 {
            return None;
        }
        let nf = T::lit(n as f64);
        let mut sum = T::zero();
        for x in self.buf.iter() {
            sum += *x;
        }
        let mean = sum / nf;
        let mut ss = T::zero();
        for x in self.buf.iter() {
            let d = *x - mean;
            ss += d * d;
        }
        Some(WindowStats {
            n,
            mean,
            std: (ss / (nf - T::one())).sqrt_fast(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outlier_removal_drops_a_spike_but_not_a_step() {
        let mut w = InnovationWindow::<f64, 10>::new();
        for k in 0..10 {
            w.push(if k == 4 {
                50.0
            } else {
                0.01 * f64::from(k % 3)
            });
        }
        let (s, dropped) = w.stats_trimmed(2.5).unwrap();
        assert_eq!((dropped, s.n), (1, 9));
        assert!(s.mean.abs() < 0.02);
        // A step covering half the window is data, not an outlier.
        let mut w = InnovationWindow::<f64, 10>::new();
        for k in 0..10 {
            w.push(if k < 5 { 0.0 } else { 1.0 });
        }
        assert_eq!(w.stats_trimmed(2.5).unwrap().1, 0);
    }
}

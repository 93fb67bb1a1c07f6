use heapless::HistoryBuf;

use crate::math::{keep_rolled, rolled, Real};

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
        // Only with `outlier_k` > 0 (off in the presets): every pass over
        // the window a rolled loop (`math::rolled`), the same operations in
        // the same order as `stats` and the unrolled passes before it.
        let xs = rolled(&self.buf);
        let full = stats_of(xs, keep_rolled)?;
        if !full.std.finite() || full.std <= T::zero() || !k.finite() || k <= T::zero() {
            return Some((full, 0));
        }
        let limit = k * full.std;
        let mut outliers = 0;
        for x in xs.iter() {
            keep_rolled();
            if (*x - full.mean).abs() > limit {
                outliers += 1;
            }
        }
        if outliers == 0 || outliers * 4 > xs.len() {
            return Some((full, 0));
        }
        let kept = xs.len() - outliers;
        if kept < 2 {
            return Some((full, 0));
        }
        let nf = T::lit(kept as f64);
        let mut sum = T::zero();
        for x in xs.iter() {
            keep_rolled();
            if (*x - full.mean).abs() <= limit {
                sum += *x;
            }
        }
        let mean = sum / nf;
        let mut ss = T::zero();
        for x in xs.iter() {
            keep_rolled();
            if (*x - full.mean).abs() <= limit {
                let d = *x - mean;
                ss += d * d;
            }
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
        stats_of(&self.buf, || {})
    }
}

/// [`InnovationWindow::stats`] of the samples `xs`, with `each` run at the
/// top of every loop iteration (`keep_rolled` for a rolled loop).
#[inline(always)]
fn stats_of<T: Real>(xs: &[T], each: impl Fn()) -> Option<WindowStats<T>> {
    let n = xs.len();
    if n < 2 {
        return None;
    }
    let nf = T::lit(n as f64);
    let mut sum = T::zero();
    for x in xs.iter() {
        each();
        sum += *x;
    }
    let mean = sum / nf;
    let mut ss = T::zero();
    for x in xs.iter() {
        each();
        let d = *x - mean;
        ss += d * d;
    }
    Some(WindowStats {
        n,
        mean,
        std: (ss / (nf - T::one())).sqrt_fast(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trimmed statistics as written before the rolled loops: filters
    /// over the window.
    fn trimmed_by_filters(xs: &[f32], k: f32) -> Option<(WindowStats<f32>, usize)> {
        let full = stats_of(xs, || {})?;
        if !full.std.is_finite() || full.std <= 0.0 || !k.is_finite() || k <= 0.0 {
            return Some((full, 0));
        }
        let limit = k * full.std;
        let outliers = xs
            .iter()
            .filter(|x| (**x - full.mean).abs() > limit)
            .count();
        if outliers == 0 || outliers * 4 > xs.len() || xs.len() - outliers < 2 {
            return Some((full, 0));
        }
        let kept = xs.len() - outliers;
        let nf = kept as f32;
        let mut sum = 0.0f32;
        for x in xs.iter().filter(|x| (**x - full.mean).abs() <= limit) {
            sum += *x;
        }
        let mean = sum / nf;
        let mut ss = 0.0f32;
        for x in xs.iter().filter(|x| (**x - full.mean).abs() <= limit) {
            let d = *x - mean;
            ss += d * d;
        }
        Some((
            WindowStats {
                n: kept,
                mean,
                std: (ss / (nf - 1.0)).sqrt_fast(),
            },
            outliers,
        ))
    }

    #[test]
    fn rolled_trimmed_stats_are_bit_identical() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let mut trimmed = 0;
        for case in 0..20_000 {
            let mut w = InnovationWindow::<f32, 10>::new();
            for i in 0..(2 + case % 9) {
                // Occasional spikes, so that some windows are trimmed.
                let spike = if (case + i) % 7 == 0 {
                    40.0 * next()
                } else {
                    0.0
                };
                w.push(next() + spike);
            }
            let k = 1.0 + 2.0 * (next() + 0.5);
            let got = w.stats_trimmed(k);
            let want = trimmed_by_filters(&w.buf, k);
            let bits = |r: Option<(WindowStats<f32>, usize)>| {
                r.map(|(s, d)| (s.n, s.mean.to_bits(), s.std.to_bits(), d))
            };
            assert_eq!(bits(got), bits(want), "case {case}");
            trimmed += usize::from(got.is_some_and(|g| g.1 > 0));
        }
        assert!(trimmed > 1000, "{trimmed} windows trimmed");
    }

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

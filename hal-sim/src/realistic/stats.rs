//! Inter-IMU statistics (issue 14): for each channel and IMU `k`, the
//! residual `IMU k − mean of the other two`, its per-sample sd, the sd of its
//! 1-s, 5-s and 10-s non-overlapping means and the largest |10-s mean| about
//! the overall mean. These are the numbers that decide what a parity monitor
//! can see on real data: per-sample sd is what a white-noise χ² test fights,
//! the windowed means are what a time-averaged test fights.
//!
//! Streaming and allocation-free: feed rows one by one with
//! [`InterImuStats::push`] (a 10-hour run needs no storage), then
//! [`InterImuStats::finish`]. Works the same on a real log and on
//! [`super::RealisticArray`] output.

use super::{LogRow, CHANNELS, IMUS};

/// The averaging windows, s.
pub const WINDOWS_S: [f64; 3] = [1.0, 5.0, 10.0];

/// A window is kept when its samples span at least this fraction of it (a
/// log gap or the end of the data leaves a partial window out).
const MIN_SPAN: f64 = 0.9;

/// The statistics of one residual (one channel, one IMU), in the channel's
/// unit (rad/s or m/s²).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct ResidualStats {
    /// Samples used.
    pub n: u64,
    /// Mean of the residual (the relative bias).
    pub mean: f64,
    /// Per-sample standard deviation.
    pub sd: f64,
    /// Standard deviation of the 1-s, 5-s and 10-s window means
    /// ([`WINDOWS_S`]).
    pub sd_mean: [f64; 3],
    /// Largest |10-s mean − mean of the 10-s means| (the relative bias
    /// removed, as a monitor that calibrates the IMUs against each other
    /// would see it).
    pub max_abs_mean_10s: f64,
}

/// Welford's running mean and variance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Welford {
    n: u64,
    mean: f64,
    m2: f64,
}

impl Welford {
    fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    fn sd(&self) -> f64 {
        if self.n > 1 {
            libm::sqrt(self.m2 / (self.n - 1) as f64)
        } else {
            0.0
        }
    }
}

/// One open averaging window.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Window {
    index: i64,
    first_t: f64,
    last_t: f64,
    sum: f64,
    n: u64,
}

/// Accumulator of one residual.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Residual {
    all: Welford,
    open: [Window; 3],
    means: [Welford; 3],
    min10: f64,
    max10: f64,
}

impl Residual {
    fn new() -> Self {
        Self {
            open: [Window {
                index: -1,
                ..Window::default()
            }; 3],
            min10: f64::INFINITY,
            max10: f64::NEG_INFINITY,
            ..Self::default()
        }
    }

    fn close(&mut self, w: usize) {
        let (Some(win), Some(means)) = (self.open.get(w), self.means.get_mut(w)) else {
            return;
        };
        let len = WINDOWS_S.get(w).copied().unwrap_or(1.0);
        // Span of the samples plus one sample period ≈ the time covered.
        let period = if win.n > 1 {
            (win.last_t - win.first_t) / (win.n - 1) as f64
        } else {
            0.0
        };
        if win.n > 1 && win.last_t - win.first_t + period >= MIN_SPAN * len {
            let m = win.sum / win.n as f64;
            means.push(m);
            if w == 2 {
                self.min10 = self.min10.min(m);
                self.max10 = self.max10.max(m);
            }
        }
    }

    fn push(&mut self, rel_t: f64, x: f64) {
        self.all.push(x);
        for w in 0..3 {
            let len = WINDOWS_S.get(w).copied().unwrap_or(1.0);
            let index = libm::floor(rel_t / len) as i64;
            let open_index = self.open.get(w).map(|o| o.index).unwrap_or(index);
            if index != open_index {
                if open_index >= 0 {
                    self.close(w);
                }
                if let Some(o) = self.open.get_mut(w) {
                    *o = Window {
                        index,
                        first_t: rel_t,
                        last_t: rel_t,
                        sum: 0.0,
                        n: 0,
                    };
                }
            }
            if let Some(o) = self.open.get_mut(w) {
                o.last_t = rel_t;
                o.sum += x;
                o.n += 1;
            }
        }
    }

    fn finish(mut self) -> ResidualStats {
        for w in 0..3 {
            if self.open.get(w).map(|o| o.index >= 0).unwrap_or(false) {
                self.close(w);
            }
        }
        let centre = self.means.get(2).map(|m| m.mean).unwrap_or(0.0);
        let max_abs = if self.max10 >= self.min10 {
            (self.max10 - centre).max(centre - self.min10)
        } else {
            0.0
        };
        ResidualStats {
            n: self.all.n,
            mean: self.all.mean,
            sd: self.all.sd(),
            sd_mean: self.means.map(|m| m.sd()),
            max_abs_mean_10s: max_abs,
        }
    }
}

/// Streaming inter-IMU statistics over rows with `from_s <= t < to_s`.
#[derive(Debug, Clone, PartialEq)]
pub struct InterImuStats {
    from_s: f64,
    to_s: f64,
    acc: [[Residual; IMUS]; CHANNELS],
}

impl InterImuStats {
    /// Statistics of the rows in `[from_s, to_s)`; windows are aligned on
    /// `from_s`.
    pub fn new(from_s: f64, to_s: f64) -> Self {
        Self {
            from_s,
            to_s,
            acc: [[Residual::new(); IMUS]; CHANNELS],
        }
    }

    /// Adds one row (rows must come in time order; rows outside the span
    /// or with a non-finite value are skipped).
    pub fn push(&mut self, row: &LogRow) {
        if !(row.t >= self.from_s && row.t < self.to_s) {
            return;
        }
        if row.imu.iter().flatten().any(|x| !x.is_finite()) {
            return;
        }
        let rel_t = row.t - self.from_s;
        for (ch, per_imu) in self.acc.iter_mut().enumerate() {
            let x = row.imu.map(|v| v.get(ch).copied().unwrap_or(0.0));
            let total: f64 = x.iter().sum();
            for (k, acc) in per_imu.iter_mut().enumerate() {
                let xk = x.get(k).copied().unwrap_or(0.0);
                // IMU k minus the mean of the other two.
                acc.push(rel_t, xk - (total - xk) / (IMUS - 1) as f64);
            }
        }
    }

    /// The statistics, `[channel][imu]`, channels in [`LogRow`] order
    /// (ax, ay, az, gx, gy, gz).
    pub fn finish(self) -> [[ResidualStats; IMUS]; CHANNELS] {
        self.acc.map(|per_imu| per_imu.map(Residual::finish))
    }
}

/// [`InterImuStats`] over a slice of rows, `from_s <= t < to_s`.
pub fn inter_imu_stats(
    rows: &[LogRow],
    from_s: f64,
    to_s: f64,
) -> [[ResidualStats; IMUS]; CHANNELS] {
    let mut s = InterImuStats::new(from_s, to_s);
    for r in rows {
        s.push(r);
    }
    s.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_offset_on_one_imu_is_a_mean_not_a_spread() {
        // 50 Hz for 100 s; IMU 0 reads +1 on every channel, plus a ±0.5
        // square wave of period 20 s on channel 0.
        let mut s = InterImuStats::new(0.0, 100.0);
        for i in 0..5000 {
            let t = i as f64 * 0.02;
            let sq = if libm::fmod(t, 20.0) < 10.0 {
                0.5
            } else {
                -0.5
            };
            let mut row = LogRow {
                t,
                imu: [[0.0; CHANNELS]; IMUS],
            };
            row.imu[0] = [1.0; CHANNELS];
            row.imu[0][0] += sq;
            s.push(&row);
        }
        let st = s.finish();
        let r = st[1][0];
        assert!((r.mean - 1.0).abs() < 1e-12 && r.sd < 1e-9, "{r:?}");
        assert_eq!(st[1][1].mean, -0.5);
        let r = st[0][0];
        assert!((r.max_abs_mean_10s - 0.5).abs() < 1e-9, "{r:?}");
        assert!((r.sd_mean[2] - 0.5 * libm::sqrt(10.0 / 9.0)).abs() < 1e-9);
        assert_eq!(r.n, 5000);
    }
}

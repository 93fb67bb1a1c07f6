//! A log's sample rate from its time stamps, robust to the damage logs
//! carry.
//!
//! Rows over span (the parity replay's estimate until 27 Nov 2026) is
//! wrong whenever the log has a gap: log171's 2-s pause at arming gives
//! 49.06 Hz for a 49.57-Hz logger, a 30-s dropout 41 Hz, and a clock jump
//! of 1,000 s 8 Hz — and the parity monitor, whose training length,
//! blocks and windows are configured in samples from that rate, then
//! behaves differently *before* the damage. The median step is robust to
//! gaps but not to coarse time stamps: a 400-Hz log stamped to the
//! millisecond has steps of 2 and 3 ms, and its median is one of them
//! (500 or 333 Hz). The mean of the steps that are not gaps is robust to
//! both.

/// The mean sample rate, Hz, over the steps of `t` that are positive and
/// at most twice the median step (a longer step means at least one row is
/// missing: a gap, not a sample period). `None` for fewer than two rows or
/// no usable step.
pub fn sample_rate_hz(t: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = t
        .windows(2)
        .filter_map(|w| match w {
            [a, b] => Some(b - a),
            _ => None,
        })
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    steps.sort_by(f64::total_cmp);
    let median = *steps.get(steps.len() / 2)?;
    let (sum, n) = steps
        .iter()
        .filter(|d| **d <= 2.0 * median)
        .fold((0.0, 0_usize), |(s, n), d| (s + d, n + 1));
    (n > 0 && sum > 0.0).then(|| n as f64 / sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamps(n: usize, dt: f64) -> Vec<f64> {
        (0..n).map(|i| 60.0 + i as f64 * dt).collect()
    }

    #[test]
    fn gaps_and_clock_jumps_do_not_change_the_rate() {
        let t = stamps(5000, 1.0 / 49.57);
        let base = sample_rate_hz(&t).unwrap_or(0.0);
        assert!((base - 49.57).abs() < 1e-6, "{base}");
        // A 30-s dropout and a 1,000-s clock jump.
        let cut: Vec<f64> = t
            .iter()
            .copied()
            .filter(|x| !(100.0..130.0).contains(x))
            .collect();
        let jump: Vec<f64> = t
            .iter()
            .map(|x| if *x > 120.0 { x + 1000.0 } else { *x })
            .collect();
        for damaged in [cut, jump] {
            let r = sample_rate_hz(&damaged).unwrap_or(0.0);
            assert!((r - 49.57).abs() < 1e-6, "{r}");
        }
    }

    #[test]
    fn millisecond_stamps_of_a_400_hz_log_give_400_hz() {
        // Steps of 2 and 3 ms: the median would say 333 or 500 Hz.
        let t: Vec<f64> = (0..4000)
            .map(|i| (f64::from(i) * 2.5).floor() / 1000.0)
            .collect();
        let r = sample_rate_hz(&t).unwrap_or(0.0);
        assert!((r - 400.0).abs() < 0.5, "{r}");
    }

    #[test]
    fn repeated_or_backward_stamps_are_not_steps() {
        let mut t = stamps(100, 0.02);
        t.insert(50, t[50]);
        let r = sample_rate_hz(&t).unwrap_or(0.0);
        assert!((r - 50.0).abs() < 1e-6, "{r}");
        // Two rows swapped: the step back is dropped, the two steps of
        // 40 ms around it are within twice the median and count as one
        // period each (the readers skip such rows before this).
        t.swap(20, 21);
        let r = sample_rate_hz(&t).unwrap_or(0.0);
        assert!((r - 98.0 / 2.0).abs() < 1e-6, "{r}");
        assert_eq!(sample_rate_hz(&[1.0]), None);
        assert_eq!(sample_rate_hz(&[1.0, 1.0, 0.5]), None);
    }
}

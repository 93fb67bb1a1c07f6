//! Min/max envelope decimation: each bucket of samples becomes the lowest
//! and the highest value in it, so a plot of a long log at a few thousand
//! pixels still shows every spike (a plain every-n-th-sample decimation
//! drops a one-sample spike with probability 1 − 1/n).
//!
//! The page's own zoom does the same per pixel column in JavaScript
//! (`html.rs`); this is the host half: it bounds how many points the page
//! embeds and draws the standalone SVGs.

/// One bucket of an envelope.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bucket {
    /// Time of the bucket's first sample, s.
    pub t0: f64,
    /// Time of its last sample, s.
    pub t1: f64,
    /// Lowest finite value in the bucket.
    pub lo: f64,
    /// Highest finite value in the bucket.
    pub hi: f64,
}

/// The min/max envelope of `(t, y)` (t ascending) in buckets of `per`
/// consecutive samples (`per` = 1 keeps every sample). Non-finite values are
/// gaps: a bucket with none finite is left out.
pub fn by_count(t: &[f64], y: &[f64], per: usize) -> Vec<Bucket> {
    let per = per.max(1);
    t.chunks(per)
        .zip(y.chunks(per))
        .filter_map(|(tc, yc)| bucket(tc, yc))
        .collect()
}

/// The envelope of the samples with `t0 ≤ t < t1` in `columns` equal time
/// buckets (one per pixel column): what a plot of that span draws.
pub fn by_time(t: &[f64], y: &[f64], t0: f64, t1: f64, columns: usize) -> Vec<Bucket> {
    let columns = columns.max(1);
    let width = (t1 - t0) / columns as f64;
    if width.is_nan() || width <= 0.0 {
        return Vec::new();
    }
    let start = t.partition_point(|x| *x < t0);
    let end = t.partition_point(|x| *x < t1);
    let (Some(ts), Some(ys)) = (t.get(start..end), y.get(start..end)) else {
        return Vec::new();
    };
    // One pass: a sample joins the last bucket when it falls in the same
    // column (computed per sample, so rounding cannot split a column).
    let mut out: Vec<(i64, Bucket)> = Vec::new();
    for (ti, yi) in ts.iter().zip(ys) {
        if !yi.is_finite() {
            continue;
        }
        let col = ((ti - t0) / width).floor() as i64;
        match out.last_mut() {
            Some((c, b)) if *c == col => {
                b.t1 = *ti;
                b.lo = b.lo.min(*yi);
                b.hi = b.hi.max(*yi);
            }
            _ => out.push((
                col,
                Bucket {
                    t0: *ti,
                    t1: *ti,
                    lo: *yi,
                    hi: *yi,
                },
            )),
        }
    }
    out.into_iter().map(|(_, b)| b).collect()
}

fn bucket(t: &[f64], y: &[f64]) -> Option<Bucket> {
    let (lo, hi) = y
        .iter()
        .filter(|v| v.is_finite())
        .fold(None, |acc: Option<(f64, f64)>, v| {
            Some(acc.map_or((*v, *v), |(l, h)| (l.min(*v), h.max(*v))))
        })?;
    Some(Bucket {
        t0: *t.first()?,
        t1: *t.last()?,
        lo,
        hi,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(n: usize) -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.0025).collect();
        let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.01).sin()).collect();
        (t, y)
    }

    #[test]
    fn a_single_sample_spike_survives_every_decimation() {
        // Ten minutes at 400 Hz, one sample at +50 and one at −50, drawn at
        // 1,000 columns (240 samples per column) and in 97-sample buckets.
        let (t, mut y) = ramp(240_000);
        y[123_457] = 50.0;
        y[7] = -50.0;
        let cols = by_time(&t, &y, 0.0, 600.0, 1000);
        assert!(cols.len() <= 1000 && cols.len() >= 999, "{}", cols.len());
        let hi = cols.iter().map(|b| b.hi).fold(f64::MIN, f64::max);
        let lo = cols.iter().map(|b| b.lo).fold(f64::MAX, f64::min);
        assert_eq!((hi, lo), (50.0, -50.0));
        let spike = cols.iter().find(|b| b.hi == 50.0).unwrap();
        assert!(spike.t0 <= t[123_457] && t[123_457] <= spike.t1);
        let buckets = by_count(&t, &y, 97);
        assert_eq!(buckets.len(), 240_000usize.div_ceil(97));
        assert_eq!(buckets.iter().filter(|b| b.hi == 50.0).count(), 1);
        assert_eq!(buckets.iter().filter(|b| b.lo == -50.0).count(), 1);
    }

    #[test]
    fn envelope_bounds_every_sample_and_gaps_stay_gaps() {
        let (t, mut y) = ramp(1000);
        for v in &mut y[100..200] {
            *v = f64::NAN;
        }
        let b = by_count(&t, &y, 50);
        // Buckets 2 and 3 (samples 100–199) are all NaN: left out.
        assert_eq!(b.len(), 18);
        for (i, (ti, yi)) in t.iter().zip(&y).enumerate() {
            if yi.is_nan() {
                continue;
            }
            let k = b.iter().find(|k| k.t0 <= *ti && *ti <= k.t1).unwrap();
            assert!(k.lo <= *yi && *yi <= k.hi, "sample {i}");
        }
        // per = 1 is the identity.
        let id = by_count(&t[..10], &y[..10], 1);
        assert!(id
            .iter()
            .zip(&y[..10])
            .all(|(b, v)| b.lo == *v && b.hi == *v));
    }

    #[test]
    fn zoomed_span_keeps_only_its_samples() {
        let (t, y) = ramp(4000);
        let cols = by_time(&t, &y, 1.0, 2.0, 100);
        assert_eq!(cols.len(), 100);
        assert!(cols.iter().all(|b| b.t0 >= 1.0 && b.t1 < 2.0));
        assert!(by_time(&t, &y, 2.0, 2.0, 10).is_empty());
    }
}

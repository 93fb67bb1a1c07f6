//! The attitude aiding's latency on a replayed log's learning span, for
//! the GNSS velocity's lag fit (`gnss_lag.rs`) of the OTSUKF monitor
//! (issue 15).
//!
//! The velocity fit rotates the specific force to NED by the attitude
//! aiding: an attitude `τ` late rotates it late, and the fit then finds a
//! compromise between the two lags (log171 with its attitude 0.2 s late:
//! 0.10–0.16 s instead of 0.22–0.24 s on time), which the OTSUKF's
//! accelerometer estimates take for a bias in turns. So, with
//! `--aiding-delay auto`, the attitude's own lag is fitted first, on the
//! same span and by the principle of the monitor's online estimate
//! (`otsukf_monitor/attitude_lag.rs`): the aiding's change over 20 epochs
//! (2 s at 10 Hz; its noise enters at the two ends only) against the
//! gyro's Euler-rate integral over the same interval shifted back by the
//! lag, after a constant gyro bias per axis (`b·Δt`). The lag of least
//! residual is kept; a vehicle that does not rotate gives every lag the
//! same cost and the smallest (0) is kept. The attitude rows are then
//! moved back by it before the velocity fit.

/// Attitude epochs spanned by one compared change.
const SPAN_EPOCHS: usize = 20;

/// Wraps an angle to (−π, π].
fn wrap(a: f64) -> f64 {
    let w = (a + core::f64::consts::PI).rem_euclid(2.0 * core::f64::consts::PI);
    w - core::f64::consts::PI
}

/// The Euler-angle rates (roll, pitch, yaw) of body rates `w` at attitude
/// `att` (ZYX); `None` near ±90° pitch.
fn euler_rates(att: [f64; 3], w: [f64; 3]) -> Option<[f64; 3]> {
    let [r, p, _] = att;
    let (sr, cr, cp, tp) = (r.sin(), r.cos(), p.cos(), p.tan());
    if cp.abs() < 0.1 {
        return None;
    }
    let [x, y, z] = w;
    Some([
        x + (sr * y + cr * z) * tp,
        cr * y - sr * z,
        (sr * y + cr * z) / cp,
    ])
}

/// The attitude lag in IMU rows (0 ..= `max_rows`) on rows `t` (s), `imu`
/// (`[a_x, a_y, a_z, p, q, r]`) and `att` (roll, pitch, yaw, rad, where
/// present). `None` with fewer than 10 compared changes.
pub fn estimate(
    t: &[f64],
    imu: &[[f64; 6]],
    att: &[Option<[f64; 3]>],
    max_rows: usize,
) -> Option<usize> {
    let n = t.len().min(imu.len()).min(att.len());
    // Cumulative Euler-rate integral per row (trapezoid), at the attitude
    // held from the aiding (its lag is second order here).
    let mut cum = vec![[0.0f64; 3]; n];
    let mut held = None;
    let mut acc = [0.0f64; 3];
    let mut prev: Option<[f64; 3]> = None;
    for i in 0..n {
        if let Some(a) = att.get(i).copied().flatten() {
            held = Some(a);
        }
        let step = i
            .checked_sub(1)
            .and_then(|j| Some(t.get(i)? - t.get(j)?))
            .filter(|d| *d > 0.0 && *d < 1.0);
        let rate = held
            .zip(imu.get(i))
            .and_then(|(a, s)| euler_rates(a, [s[3], s[4], s[5]]));
        match (rate, step) {
            (Some(e), Some(dt)) => {
                let p = prev.unwrap_or(e);
                acc = core::array::from_fn(|k| acc[k] + 0.5 * (e[k] + p[k]) * dt);
                prev = Some(e);
            }
            _ => prev = None,
        }
        if let Some(c) = cum.get_mut(i) {
            *c = acc;
        }
    }
    let epochs: Vec<(usize, [f64; 3])> = (max_rows..n)
        .filter_map(|i| att.get(i).copied().flatten().map(|a| (i, a)))
        .collect();
    let pairs: Vec<_> = epochs.iter().zip(epochs.iter().skip(SPAN_EPOCHS)).collect();
    if pairs.len() < 10 {
        return None;
    }
    let cost = |lag: usize| -> f64 {
        let res: Vec<([f64; 3], f64)> = pairs
            .iter()
            .filter_map(|((i1, a1), (i2, a2))| {
                let (c1, c2) = (cum.get(i1 - lag)?, cum.get(i2 - lag)?);
                let dt = t.get(*i2)? - t.get(*i1)?;
                Some((
                    core::array::from_fn(|k| wrap(a2[k] - a1[k] - (c2[k] - c1[k]))),
                    dt,
                ))
            })
            .collect();
        super::gnss_lag::sse_after_bias(&res)
    };
    let zero = cost(0);
    Some(
        (0..=max_rows)
            .map(|l| (l, cost(l)))
            .fold((0, zero), |best, c| if c.1 < best.1 { c } else { best })
            .0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vehicle rocking in roll and yaw with its attitude logged 20 rows
    /// late (10 Hz of a 100 Hz log) and a constant gyro bias: the fit
    /// finds 20. Level pitch, so the Euler rates are the body rates.
    #[test]
    fn finds_the_lag_of_a_synthetic_rocking() {
        let dt = 0.01;
        let n = 3000;
        let roll = |t: f64| 0.3 * (1.1 * t).sin();
        let yaw = |t: f64| 0.5 * (0.6 * t).sin();
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        // Roll at zero pitch: p = φ̇; yaw rate ψ̇ = (sinφ q + cosφ r),
        // with q = sinφ ψ̇ and r = cosφ ψ̇ it is ψ̇ and θ̇ = 0.
        let imu: Vec<[f64; 6]> = t
            .iter()
            .map(|&s| {
                let (ph, yd) = (roll(s), 0.3 * (0.6 * s).cos());
                [
                    0.0,
                    0.0,
                    -9.8,
                    0.33 * (1.1 * s).cos() + 0.002,
                    ph.sin() * yd,
                    ph.cos() * yd,
                ]
            })
            .collect();
        for late in [0usize, 20] {
            let att: Vec<Option<[f64; 3]>> = (0..n)
                .map(|i| {
                    (i % 10 == 0 && i >= late).then(|| {
                        let s = (i - late) as f64 * dt;
                        [roll(s), 0.0, yaw(s)]
                    })
                })
                .collect();
            assert_eq!(estimate(&t, &imu, &att, 32), Some(late));
        }
    }
}

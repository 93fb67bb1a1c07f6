//! The GNSS velocity's latency on a replayed log, learned from the log
//! itself (issue 15).
//!
//! A receiver reports a velocity some 0.1–0.3 s after the instant it
//! describes (its tracking loops and solution), and an autopilot logs it on
//! arrival; PX4 EKF2 and ArduPilot's EKF take that lag as a parameter
//! (`EKF2_GPS_DELAY`, `GPS_DELAY_MS`) and fuse against a delayed state. The
//! core's delayed fusion ([`UkfMonitorConfig::aiding_delay_s`]) applies one
//! lag to all aiding and its online estimate reads it off the attitude
//! aiding; on an autopilot log the attitude is the autopilot's own estimate
//! from the same IMUs, with no lag of its own, so neither sees the GNSS's.
//!
//! Here the lag is fitted on the learning span of the IMU being monitored
//! (before monitoring starts, so an injected or real fault later in the log
//! cannot move it): between consecutive GNSS samples the velocity change
//! must equal the specific force, rotated to NED by the attitude aiding and
//! plus gravity, integrated over the same interval *shifted back by the
//! lag*. The lag whose residuals (after a constant accelerometer bias per
//! axis, `b·Δt`) are least is kept. Angular and linear motion must change
//! within the span for the lag to show; a vehicle at rest gives every lag
//! the same cost and the smallest (0) is kept.
//!
//! [`UkfMonitorConfig::aiding_delay_s`]: imu_fdi::monitor::UkfMonitorConfig::aiding_delay_s

/// Standard gravity, m/s² (NED: down positive).
const G: f64 = 9.80665;

/// What [`estimate`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GnssLag {
    /// The lag, in IMU rows.
    pub rows: usize,
    /// RMS of the velocity-change residual at that lag, m/s.
    pub rms_m_s: f64,
    /// The same at lag 0, m/s.
    pub rms_at_zero_m_s: f64,
    /// GNSS intervals compared.
    pub pairs: usize,
}

/// Body (FRD) → NED rotation of a ZYX (yaw, pitch, roll) attitude, applied
/// to `f`.
/// Sum of squares of the residuals `r` over intervals `Δt` left after the
/// least-squares constant rate per axis (`r ≈ b·Δt`): a sensor bias, which
/// no lag explains. Shared with the attitude lag fit (`attitude_lag.rs`).
pub(super) fn sse_after_bias(res: &[([f64; 3], f64)]) -> f64 {
    let (srt, stt) = res.iter().fold(([0.0; 3], 0.0), |(s, q), (r, dt)| {
        (
            [s[0] + r[0] * dt, s[1] + r[1] * dt, s[2] + r[2] * dt],
            q + dt * dt,
        )
    });
    let b: [f64; 3] = core::array::from_fn(|k| if stt > 0.0 { srt[k] / stt } else { 0.0 });
    res.iter()
        .map(|(r, dt)| (0..3).map(|k| (r[k] - b[k] * dt).powi(2)).sum::<f64>())
        .sum()
}

fn to_ned(att: [f64; 3], f: [f64; 3]) -> [f64; 3] {
    let [r, p, y] = att;
    let (sr, cr, sp, cp, sy, cy) = (r.sin(), r.cos(), p.sin(), p.cos(), y.sin(), y.cos());
    let [x, yb, z] = f;
    [
        cp * cy * x + (sr * sp * cy - cr * sy) * yb + (cr * sp * cy + sr * sy) * z,
        cp * sy * x + (sr * sp * sy + cr * cy) * yb + (cr * sp * sy - sr * cy) * z,
        -sp * x + sr * cp * yb + cr * cp * z,
    ]
}

/// The IMU rows with each non-finite cell replaced by its channel's last
/// finite value (0 before the first), as the monitors bridge a bad sample
/// (`input::stand_in`): the lag fits integrate the samples, and one NaN
/// cell made every later integral NaN — on log171 one in IMU1's learning
/// span set the OTSUKF's GPS lag to 0 instead of 0.22 s, and 6 flag
/// events followed.
pub fn bridge_bad_cells(rows: impl IntoIterator<Item = [f64; 6]>) -> Vec<[f64; 6]> {
    let mut last = [0.0f64; 6];
    rows.into_iter()
        .map(|mut s| {
            for (v, l) in s.iter_mut().zip(last.iter_mut()) {
                if v.is_finite() {
                    *l = *v;
                } else {
                    *v = *l;
                }
            }
            s
        })
        .collect()
}

/// The GNSS lag in IMU rows (0 ..= `max_rows`) on rows `t` (s), `imu`
/// (`[a_x, a_y, a_z, p, q, r]`), `vel` (GNSS velocity NED, where present)
/// and `att` (roll, pitch, yaw, rad, where present; held between samples).
/// `None` with fewer than 10 GNSS intervals after the first attitude.
pub fn estimate(
    t: &[f64],
    imu: &[[f64; 6]],
    vel: &[Option<[f64; 3]>],
    att: &[Option<[f64; 3]>],
    max_rows: usize,
) -> Option<GnssLag> {
    let n = t.len().min(imu.len()).min(vel.len()).min(att.len());
    // Cumulative ∫ (C_bn f + g) dt per row (0 before the first attitude).
    let mut cum = vec![[0.0f64; 3]; n];
    let mut held: Option<[f64; 3]> = None;
    let mut first_att = None;
    let mut acc = [0.0f64; 3];
    let mut prev_f: Option<[f64; 3]> = None;
    for i in 0..n {
        if let Some(a) = att.get(i).copied().flatten() {
            held = Some(a);
            first_att.get_or_insert(i);
        }
        if let (Some(a), Some(s), Some(dt)) = (
            held,
            imu.get(i),
            i.checked_sub(1)
                .and_then(|j| Some(t.get(i)? - t.get(j)?))
                .filter(|d| *d > 0.0 && *d < 1.0),
        ) {
            // Trapezoid: the samples are instantaneous (ArduPilot logs the
            // filtered sample, not an interval's average); a rectangle would
            // bias the lag by half a period.
            let f = to_ned(a, [s[0], s[1], s[2]]);
            let p = prev_f.unwrap_or(f);
            acc = core::array::from_fn(|k| {
                let g = if k == 2 { G } else { 0.0 };
                acc[k] + (0.5 * (f[k] + p[k]) + g) * dt
            });
            prev_f = Some(f);
        } else {
            prev_f = None;
        }
        if let Some(c) = cum.get_mut(i) {
            *c = acc;
        }
    }
    let start = first_att? + max_rows;
    let samples: Vec<(usize, [f64; 3])> = (start..n)
        .filter_map(|i| vel.get(i).copied().flatten().map(|v| (i, v)))
        .collect();
    let pairs: Vec<_> = samples
        .windows(2)
        .filter_map(|w| w.first().zip(w.get(1)))
        .collect();
    if pairs.len() < 10 {
        return None;
    }
    let cost = |lag: usize| -> f64 {
        // Residual r = Δv_gnss − Δ∫ over the lagged interval; fit r = b·Δt.
        let res: Vec<([f64; 3], f64)> = pairs
            .iter()
            .filter_map(|((i1, v1), (i2, v2))| {
                let (c1, c2) = (cum.get(i1 - lag)?, cum.get(i2 - lag)?);
                let dt = t.get(*i2)? - t.get(*i1)?;
                Some((
                    core::array::from_fn(|k| (v2[k] - v1[k]) - (c2[k] - c1[k])),
                    dt,
                ))
            })
            .collect();
        (sse_after_bias(&res) / res.len().max(1) as f64).sqrt()
    };
    let rms_at_zero_m_s = cost(0);
    let (rows, rms_m_s) =
        (0..=max_rows)
            .map(|l| (l, cost(l)))
            .fold(
                (0, rms_at_zero_m_s),
                |best, c| if c.1 < best.1 { c } else { best },
            );
    Some(GnssLag {
        rows,
        rms_m_s,
        rms_at_zero_m_s,
        pairs: pairs.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vehicle swinging north–south at a known rate with its GNSS
    /// velocity logged 10 rows late: the fit finds 10, against a closed
    /// form (v = A·sin ωt, a = A·ω·cos ωt).
    #[test]
    fn finds_the_lag_of_a_synthetic_swing() {
        let dt = 0.02;
        let (amp, w) = (3.0, 0.7);
        let n = 3000;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let imu: Vec<[f64; 6]> = t
            .iter()
            .map(|t| [amp * w * (w * t).cos(), 0.0, -G, 0.0, 0.0, 0.0])
            .collect();
        let att: Vec<Option<[f64; 3]>> = (0..n).map(|i| (i % 5 == 0).then_some([0.0; 3])).collect();
        let vel: Vec<Option<[f64; 3]>> = (0..n)
            .map(|i| {
                (i % 10 == 0 && i >= 10).then(|| {
                    let ts = (i - 10) as f64 * dt; // describes 10 rows earlier
                    [amp * (w * ts).sin(), 0.0, 0.0]
                })
            })
            .collect();
        let lag = estimate(&t, &imu, &vel, &att, 25).unwrap_or_else(|| panic!("no estimate"));
        assert_eq!(lag.rows, 10, "{lag:?}");
        assert!(lag.rms_m_s < 1e-4 && lag.rms_at_zero_m_s > 0.02, "{lag:?}");
    }
}

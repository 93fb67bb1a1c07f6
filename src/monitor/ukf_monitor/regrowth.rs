//! The regrowth test (issue 15): after the aiding's jump rule re-aligned
//! the velocity alone, tell an aiding jump from an accelerometer fault.
//!
//! Why: a re-alignment clears the windows and holds the statistics for
//! `converge_s`, and the windows then refill; over those ≈ 5 s every
//! channel reads `NotMonitored`. When what the jump rule saw was an
//! accelerometer fault, not a jump of the aiding, the fault goes on and the
//! re-aligned velocity diverges again (log171, IMU0 a_x +5 m/s² for 3 s at
//! 160 s: re-aligned at 161.1 s, the velocity off by 15 m/s by 163 s,
//! never attributed). The two differ in what follows the re-alignment:
//! after an aiding jump the innovations stay within the filter's own
//! innovation covariance `S` (times the inflation learnt on this vehicle's
//! healthy data); under an accelerometer fault they grow again, as the
//! closed-loop signature of a constant fault since the re-alignment says.
//!
//! The re-alignment zeroes the velocity rows of the fault sensitivity
//! `X = ∂x̂/∂f`, so from then on the accelerometer columns of the
//! signature rows `m_k = −H X⁻` are the response of innovation `k` to a
//! constant accelerometer fault that started at the re-alignment (the
//! filter's gain included: it pulls part of the error back, which the
//! signature knows). The test is the generalised likelihood ratio of a
//! single fault on channel `j` (the window test's isolation rule) over the
//! fused innovations since the re-alignment, weights `w = 1/(c S_kk)` with
//! `c` the learnt inflation:
//!
//! `f̂_j = b_j / A_j`, `z_j = b_j / √A_j`, `A_j = Σ w m_kj²`,
//! `b_j = Σ w m_kj ν_k`.
//!
//! With a healthy IMU `z_j` is standard normal, so the decision
//! `|z_j| > ` the UKF test's own critical value (the normal quantile of
//! `alpha`) has that test's false-alarm rate per decision; no margin is set
//! by hand. The likeliest channel is flagged with the sign and the size
//! of `f̂_j` (the regression slope) when it is an accelerometer (a gyro
//! whose attitude error leaks gravity into the velocity is the likeliest
//! on the attitude rows) and at least the smallest fault reported
//! (`min_fault × threshold_fraction`, as the block tests). The test runs
//! until the UKF's window test judges the accelerometers again, which then
//! holds or drops the flag; meanwhile the accelerometer/GNSS-velocity
//! block test integrates (its increments do not depend on the re-aligned
//! state), and a flag its newest window contradicts is withdrawn (the
//! fault has ended; the regression, over everything since the
//! re-alignment, still holds the ramp it left), or found ended by
//! `realign_ended` once the window test holds it: the way back to nominal.

use super::UkfMonitor;
use crate::filter::ChannelDiag;
use crate::math::Real;
use crate::model::{ImuVec, Mat6, NX, NZ, ROLL};
use crate::monitor::{ChannelState, Phase};

/// Margin (χ² units: twice the log-likelihood ratio) by which the
/// likeliest channel must beat the runner-up to be named: the upper 10⁻³
/// quantile of χ²(1), the parity monitor's isolation margin
/// (`MultiscaleConfig::isolation_margin`) for the same question.
const ISOLATION_MARGIN: f64 = 10.8;

/// The regression since the last velocity-alone re-alignment.
#[derive(Debug, Clone, Copy)]
pub(super) struct Regrowth<T> {
    /// An episode is open: the velocity was re-aligned alone and the
    /// window test does not judge the accelerometers yet.
    active: bool,
    /// `Σ w m_j²` per IMU channel `j` (the diagonal of `A`: each channel
    /// a single-fault hypothesis).
    info: ImuVec<T>,
    /// `Σ w m_j ν`.
    score: ImuVec<T>,
    /// A gyro fault was in play in this episode (until every channel is
    /// judged healthy again): kept across re-alignments.
    gyro_seen: bool,
}

impl<T: Real> Default for Regrowth<T> {
    fn default() -> Self {
        Self {
            active: false,
            info: ImuVec::zeros(),
            score: ImuVec::zeros(),
            gyro_seen: false,
        }
    }
}

impl<T: Real> Regrowth<T> {
    /// Adds one epoch's fused innovations: `signature` the rows of every
    /// aiding channel (columns: the six IMU channels), `diag` their
    /// innovations and `S_kk`, `inflation` the learnt factor per channel.
    /// The attitude rows too: a gyro fault shows there, and its hypothesis
    /// must be able to win (its attitude error leaks gravity into the
    /// velocity, which the accelerometer columns alone would take).
    fn observe(&mut self, signature: &Mat6<T>, diag: &[ChannelDiag<T>; NZ], inflation: &[T; NZ]) {
        for (k, (d, c)) in diag.iter().zip(inflation.iter()).enumerate() {
            let var = d.variance * *c;
            if !(d.available && d.fused && var > T::zero() && d.innovation.finite()) {
                continue;
            }
            let w = T::one() / var;
            let row = signature.row(k);
            for ((a, b), m) in self
                .info
                .iter_mut()
                .zip(self.score.iter_mut())
                .zip(row.iter())
            {
                *a += *m * *m * w;
                *b += *m * d.innovation * w;
            }
        }
    }

    /// The single-fault hypothesis that explains the most (generalised
    /// likelihood ratio, as the window test's decision rule isolates):
    /// channel `j` maximising `b_j² / A_jj`, its estimate `b_j / A_jj` and
    /// z score `b_j / √A_jj` (`None` before any row carries a signature),
    /// with its margin over the runner-up hypothesis, `z_j² − z_i²` (twice
    /// the log-likelihood ratio of the two; zero with a single hypothesis).
    fn ranked(&self) -> Option<((usize, T, T), T)> {
        let mut best: Option<(usize, T, T)> = None;
        let mut second = T::zero();
        for (j, b) in self.score.iter().enumerate() {
            let a = self.info.get(j).copied().unwrap_or_else(T::zero);
            if a <= T::zero() || !a.finite() {
                continue;
            }
            let z = *b / a.sqrt_fast();
            match best {
                Some((_, _, zb)) if z.abs() <= zb.abs() => second = second.fmax(z * z),
                Some((_, _, zb)) => {
                    second = second.fmax(zb * zb);
                    best = Some((j, *b / a, z));
                }
                None => best = Some((j, *b / a, z)),
            }
        }
        best.map(|b| (b, b.2 * b.2 - second))
    }
}

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The jump rule's re-alignment of the `reset` states opens an
    /// episode: the velocity re-aligned alone while monitoring, no gyro
    /// fault in play (`gyro_in_play`; asked before the re-alignment clears
    /// `velocity_tainted`). The attitude re-aligned too is not the
    /// accelerometers' case.
    pub(super) fn regrowth_opens(&self, reset: &[bool; NX]) -> bool {
        let vel = reset.iter().take(3).any(|r| *r);
        let att = reset.iter().skip(ROLL).any(|r| *r);
        vel && !att && self.phase == Phase::Monitoring && !self.gyro_in_play()
    }

    /// Opens an episode (`open`, from `regrowth_opens`) on the statistics
    /// the re-alignment just restarted.
    pub(super) fn regrowth_open(&mut self, open: bool) {
        self.regrowth.active = open;
    }

    /// Closes any episode (every re-alignment restarts the regression).
    pub(super) fn regrowth_close(&mut self) {
        self.regrowth = Regrowth {
            gyro_seen: self.regrowth.gyro_seen,
            ..Regrowth::default()
        };
    }

    /// A gyro fault is flagged or seen by the gyro/attitude test, or was
    /// in this episode (`gyro_seen`), or its attitude error is in the
    /// velocity (`velocity_tainted`): the filter then propagates its
    /// velocity through a wrong attitude, and the velocity's regrowth is
    /// that gravity leak, not an accelerometer. A re-alignment of the
    /// attitude while the gyro fault goes on leaves it off again (log171,
    /// IMU1 g_x +50 °/s for 3 s at 160 s: g_x flagged, everything
    /// re-aligned at 162.7 s, the velocity then alone, a_z attributed at
    /// 164.1 s otherwise).
    fn gyro_in_play(&self) -> bool {
        self.velocity_tainted
            || self.regrowth.gyro_seen
            || self.att_rate_sees_fault()
            || self
                .report
                .status
                .iter()
                .skip(3)
                .any(|s| matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative))
    }

    /// An episode is open (the block test integrates through the hold-off).
    pub(super) fn regrowth_live(&self) -> bool {
        self.regrowth.active && self.phase == Phase::Monitoring
    }

    /// After an aiding update while monitoring, once the other tests have
    /// written the report: closes the episode when the window test judges
    /// the accelerometers again; otherwise adds the epoch and flags the
    /// accelerometer channels nothing else judged (`NotMonitored`) whose
    /// regression finds a fault.
    pub(super) fn regrowth_apply(&mut self) {
        if self
            .report
            .status
            .iter()
            .all(|s| matches!(s, ChannelState::Healthy))
        {
            self.regrowth.gyro_seen = false;
        }
        let gyro = self.gyro_in_play();
        self.regrowth.gyro_seen = gyro;
        if !self.regrowth_live() || gyro {
            self.regrowth.active = false;
            return;
        }
        let judged =
            self.stats_holdoff <= T::zero() && self.windows.iter().take(3).all(|w| w.is_full());
        if judged {
            self.regrowth.active = false;
            return;
        }
        self.regrowth
            .observe(&self.signature, &self.report.detail.diag, &self.inflation);
        let Some(((j, f, z), margin)) = self.regrowth.ranked() else {
            return;
        };
        let relevant = self.cfg.min_fault * self.cfg.threshold_fraction;
        let smallest = relevant.get(j).copied().unwrap_or_else(T::zero);
        // The block test's newest shortest window, independent of the
        // filter, contradicting this size: the fault has ended (the
        // regression, over everything since the re-alignment, still holds
        // the ramp the fault left).
        // A gyro the likeliest: its attitude error, not an accelerometer,
        // drives the velocity; that is the gyro tests' to judge.
        // Two hypotheses that explain the regrowth almost equally well (a
        // −5 m/s² a_x glitch in a pitched turn on log171 was a_z's first by
        // a hair, and IMU1's only a_z's) are not told apart: the channels
        // stay `NotMonitored`, the monitor's "cannot judge", rather than
        // name one that may be healthy.
        if j >= 3
            || z.abs() <= self.t_threshold()
            || margin < T::lit(ISOLATION_MARGIN)
            || f.abs() < smallest
            || self.vel_inc_contradicts(j, f)
        {
            return;
        }
        let (Some(s), Some(e)) = (
            self.report.status.get_mut(j),
            self.report.fault_estimate.get_mut(j),
        ) else {
            return;
        };
        if matches!(s, ChannelState::NotMonitored) {
            *s = if f > T::zero() {
                ChannelState::FaultPositive
            } else {
                ChannelState::FaultNegative
            };
            *e = f;
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
mod tests {
    use super::*;

    /// Nine epochs of noise, within `√S = 0.3` m/s.
    const NOISE: [[f64; 3]; 9] = [
        [0.3, -0.2, 0.1],
        [-0.1, 0.25, -0.3],
        [0.2, 0.0, 0.15],
        [-0.3, 0.1, 0.2],
        [0.1, -0.25, -0.1],
        [-0.2, 0.3, 0.0],
        [0.25, -0.1, -0.2],
        [0.0, 0.2, 0.3],
        [-0.15, -0.3, -0.15],
    ];

    /// Epochs of innovations `ν_k = m_k f + noise` with the signature of a
    /// fault since the re-alignment (`m_k = −t_k I`, the open-loop ramp)
    /// and `S = 0.09`: the regression finds the channel, its sign and size.
    fn run(fault: [f64; 3], noise: &[[f64; 3]]) -> Option<(usize, f64, f64)> {
        let mut r = Regrowth::<f64>::default();
        for (k, n) in noise.iter().enumerate() {
            let t = 0.2 * (k + 1) as f64;
            let sig = Mat6::from_fn(|i, j| if i == j && i < 3 { -t } else { 0.0 });
            let diag = core::array::from_fn(|i| ChannelDiag {
                available: i < 3,
                innovation: if i < 3 { -t * fault[i] + n[i] } else { 0.0 },
                variance: 0.09,
                test_ratio: 0.0,
                fused: i < 3,
            });
            r.observe(&sig, &diag, &[1.0; NZ]);
        }
        r.ranked().map(|(best, _)| best)
    }

    #[test]
    fn a_ramp_on_one_channel_is_attributed_with_its_sign_and_size() {
        let (j, f, z) = run([0.0, -2.0, 0.0], &NOISE).unwrap();
        assert_eq!(j, 1);
        assert!((f + 2.0).abs() < 0.2, "{f}");
        assert!(z < -10.0, "{z}");
    }

    /// Innovations within `S` (an aiding jump the re-alignment followed):
    /// every z score stays within the normal range.
    #[test]
    fn innovations_within_s_give_no_evidence() {
        let (_, _, z) = run([0.0; 3], &NOISE).unwrap();
        assert!(z.abs() < 3.0, "{z}");
    }

    /// Two channels whose signatures are the same direction (a_x and
    /// a_z both seen on the first velocity row alone): the fault explains
    /// both equally, the margin is zero and falls short of
    /// `ISOLATION_MARGIN`; a ramp on one channel of distinct signatures
    /// beats the others by far more than it.
    #[test]
    fn the_margin_is_the_likelihood_ratio_over_the_runner_up() {
        let mut r = Regrowth::<f64>::default();
        for k in 1..=9 {
            let t = 0.2 * f64::from(k);
            let sig = Mat6::from_fn(|i, j| {
                if i == 0 && (j == 0 || j == 2) {
                    -t
                } else {
                    0.0
                }
            });
            let diag = core::array::from_fn(|i| ChannelDiag {
                available: i < 3,
                innovation: if i == 0 { 2.0 * t } else { 0.0 },
                variance: 0.09,
                test_ratio: 0.0,
                fused: i < 3,
            });
            r.observe(&sig, &diag, &[1.0; NZ]);
        }
        let ((_, _, z), margin) = r.ranked().unwrap();
        assert!(z.abs() > 10.0, "{z}");
        assert!(margin.abs() < 1e-9, "{margin}");
        let mut one = Regrowth::<f64>::default();
        for (k, n) in NOISE.iter().enumerate() {
            let t = 0.2 * (k + 1) as f64;
            let sig = Mat6::from_fn(|i, j| if i == j && i < 3 { -t } else { 0.0 });
            let diag = core::array::from_fn(|i| ChannelDiag {
                available: i < 3,
                innovation: if i == 1 {
                    2.0 * t + n[i]
                } else if i < 3 {
                    n[i]
                } else {
                    0.0
                },
                variance: 0.09,
                test_ratio: 0.0,
                fused: i < 3,
            });
            one.observe(&sig, &diag, &[1.0; NZ]);
        }
        let ((j, _, _), margin) = one.ranked().unwrap();
        assert_eq!(j, 1);
        assert!(margin > 10.0 * ISOLATION_MARGIN, "{margin}");
    }

    /// No fused velocity row yet: no decision.
    #[test]
    fn no_rows_no_estimate() {
        assert!(Regrowth::<f32>::default().ranked().is_none());
    }
}

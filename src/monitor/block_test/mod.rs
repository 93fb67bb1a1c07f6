//! The machinery both block tests of the UKF monitor share (issue 15):
//! the gyro/attitude-aiding test (`attitude_rate/`, block means in rad/s)
//! and the accelerometer/GNSS-velocity test (`velocity_increment/`, in
//! m/s²). Each feeds one body-axis block mean per block (the residual
//! summed over the block over its duration) with the block's motion; this
//! keeps the last blocks, judges the windows of `lengths` blocks that end
//! at each new block, and learns from the healthy ones.
//!
//! **What is learnt, and why it gives the false-alarm rate.** Per
//! channel, from the start of the UKF's learning phase and on while
//! monitoring: the offset (mean block, the gyro's turn-on bias against the
//! aiding; clamped to `max_nominal_bias`, or 20 × `min_fault` as the
//! nominal-bias learner, so a larger power-up bias is reported), the block
//! variance `v_B` and each length's reddening factor `ρ_L`, the window
//! variance over `v_B / L`. A 10-s window variance cannot be learnt from
//! 20–70 s of flight alone (2–7 independent windows), while `v_B` has
//! 40–140 blocks: `ρ_L` is therefore a posterior with a white-noise prior
//! (`ρ = 1`) worth `prior_windows` windows, updated by the window means
//! the flight has shown, each overlapping window counting `1.5/L`
//! independent ones (the degrees of freedom of the overlapping-batch-means
//! variance estimator, Meketon & Schmeiser 1984). On log171 the factors
//! are 0.56–1.13 at 150 s (the 10-s windows' at 10.5–10.8 degrees of
//! freedom) and 0.44–1.45 at 234 s (18.6–21.6): better than white where
//! the aiding's errors telescope, up to 1.45 where they wander. The window mean's
//! variance is `v_B·ρ_L·(h̄/L + 1/N)` (`N` blocks in the offset; `h̄` the
//! window's mean relative block variance at its blocks' motion, learnt by
//! regression in `motion_variance`: a turn's blocks spread 2–4× wider
//! than straight flight's on log171), and the
//! threshold the Student-t quantile of the per-decision probability
//! [`AttitudeRateConfig::alpha`] at the degrees of freedom
//! `prior_windows + 1.5·n_L/L` actually learnt: the false-alarm rate
//! follows from the data and the design rate, not from a margin. A length
//! judges once it has `min_dof` degrees of freedom and the offset two
//! longest windows of blocks.
//!
//! **Motion cover.** The spread learnt holds for the motion it was learnt
//! at: a vehicle at rest shows a tiny one, and judging flight against it
//! raised alarms at take-off (log171 from 48 s, on the ground until 80 s:
//! ratios 1.4–3.2 at the first decisions). Each block's mean squared rate
//! is kept, the learnt blocks are counted per half-decade of it, and a
//! window is judged only if at least one longest window of learnt blocks
//! was as active as its mean; until then it neither decides nor stops
//! learning (so flight gets learnt), and a flag it raised is kept, not
//! cleared (not judged is not nominal).
//!
//! **No learning during a fault.** A block is learnt (offset, `v_B`, and
//! the windows that end at it) only once every decision that saw it has
//! been made, and only on the channels where all of those stayed below
//! `learn_below` of the threshold and no channel of the UKF was flagged.
//!
//! **Decisions.** The largest score/threshold ratio over the lengths, with
//! its sign; `confirm` consecutive ratios above 1 with one sign flag the
//! channel, with the window mean (less the offset) as its size. The flag
//! holds for `hold` blocks after the last confirmed decision and then
//! clears. **The way back to nominal**: a 10-s window holds a fault for
//! 10 s after it has ended, so a longer window's verdict is withdrawn as
//! soon as the newest shortest window contradicts it (falls short of the
//! longer window's deviation, in its sign, by more than the shortest
//! window's own threshold deviation: under a persisting fault that has
//! the test's per-decision probability); the longer lengths are then
//! muted on that channel until their windows have flushed, while the
//! shortest still judges. Without it (a fault small against the shortest
//! window's spread) the flag clears once no window holds the fault: at
//! most the longest window plus the hold after the fault ends. Never
//! stuck: the offset is not learnt meanwhile. A flag is merged into
//! the UKF's report only on a gyro channel the UKF judges healthy; before
//! this test can judge it changes nothing (the UKF's test still decides,
//! and `NotMonitored` stays so).

use nalgebra::Vector3;

use crate::math::Real;
use crate::model::{ImuVec, Measurement};
use crate::monitor::{
    BlockTestConfig, BlockTestDetail, ChannelState, ATTITUDE_RATE_LENGTHS as NL,
    ATTITUDE_RATE_MAX_BLOCKS,
};
use crate::stats::student_t_upper_quantile;

mod decide;
mod learn;
mod merge;
mod motion_variance;
#[cfg(test)]
mod motion_variance_tests;
#[cfg(test)]
pub(super) mod test_noise;
pub(super) use merge::merge_block_flags;
#[cfg(feature = "attitude-rate-test")]
pub(super) mod attitude_rate;
pub(super) mod rotation;
#[cfg(feature = "velocity-increment-test")]
pub(super) mod velocity_increment;

/// What a monitor tells a block test at an aiding epoch.
#[derive(Debug, Clone, Copy)]
pub(super) struct EpochContext<T> {
    /// The statistics run (learning or monitoring, not held): else the
    /// interval under way is dropped.
    pub live: bool,
    /// The monitor's filter fused the test's aiding channels this epoch (a
    /// rejected epoch is skipped: the IMU integrates on to the next).
    pub fused: bool,
    /// The monitor's limits for the test's three channels.
    pub limits: ChannelLimits<T>,
    /// Longest interval integrated, s (the aiding timeout).
    pub timeout_s: T,
    /// The monitor flags a channel itself (monitoring): nothing is learnt
    /// from the block.
    pub external: bool,
}

/// What both tests share with their monitors: IMU samples integrate while
/// the statistics run and drop the interval otherwise; an aiding epoch
/// closes it while they run and drops it otherwise.
pub(super) trait IntervalTest<T: Real> {
    /// The test's configuration.
    type Config;
    /// Drops the interval under way.
    fn invalidate(&mut self);
    /// One valid IMU sample (raw) into the interval.
    fn integrate_sample(&mut self, imu: &ImuVec<T>, dt: T);
    /// A live aiding epoch (the test's own use of it).
    fn close(&mut self, cfg: &Self::Config, aiding: &Measurement<T>, ctx: &EpochContext<T>);

    /// One IMU sample; `live`: valid and the statistics run.
    fn sample(&mut self, imu: &ImuVec<T>, dt: T, live: bool) {
        if live {
            self.integrate_sample(imu, dt);
        } else {
            self.invalidate();
        }
    }

    /// A monitor's aiding epoch.
    fn aiding_epoch(&mut self, cfg: &Self::Config, aiding: &Measurement<T>, ctx: &EpochContext<T>) {
        if ctx.live {
            self.close(cfg, aiding, ctx);
        } else {
            self.invalidate();
        }
    }
}

/// A channel of `status` is flagged (either sign).
pub(super) fn any_flag(status: &[ChannelState; 6]) -> bool {
    status
        .iter()
        .any(|s| matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative))
}

/// Block means kept: a block is learnt once every decision that saw it
/// has been made (ages up to two longest windows).
const RING: usize = 2 * ATTITUDE_RATE_MAX_BLOCKS;
/// Independent windows an overlapping window counts, times its length.
const OBM_DOF: f64 = 1.5;
/// Ratio recorded for a block during which the UKF flagged a channel: no
/// learning from it.
const EXTERNAL_FLAG_RATIO: f64 = 1e3;
/// Bins of the learnt blocks' motion (the feeding test's measure: mean
/// squared rate or acceleration), half a decade each from 1e-8 up; the
/// last is open.
pub(super) const MOTION_BINS: usize = 24;
const MOTION_LOG10_MIN: f64 = -8.0;

/// The motion bin of a motion measure among `bins` half-decade bins from
/// 1e-8 up (the last open); shared with the UKF monitor's inflation cover.
pub(in crate::monitor) fn motion_bin<T: Real>(m: T, bins: usize) -> usize {
    let x: f64 = m.to_f64();
    let l = libm::log10(if x > 1e-30 { x } else { 1e-30 });
    let b: f64 = libm::floor((l - MOTION_LOG10_MIN) * 2.0);
    if b <= 0.0 {
        0
    } else {
        (b as usize).min(bins.saturating_sub(1))
    }
}

/// The block test's state (see the module notes).
/// Per-channel limits a block test takes from the monitor's configuration.
#[derive(Debug, Clone, Copy)]
pub(super) struct ChannelLimits<T> {
    /// The largest offset learnt (the nominal-bias bound): a larger
    /// power-up bias is reported.
    pub nominal: Vector3<T>,
    /// The smallest deviation reported (`min_fault × threshold_fraction`,
    /// the UKF's threshold method): a significant deviation below it is a
    /// nominal sensor error the test can resolve, not a fault. Where the
    /// aiding is much quieter than the sensor's nominal scale-factor and
    /// misalignment errors (simulated aiding: a 10-s spread of 0.01 m/s²),
    /// the test otherwise flags those (34 events in 10 simulated hours).
    pub relevant: Vector3<T>,
}

#[derive(Debug, Clone)]
pub(super) struct BlockTest<T> {
    /// Per-decision false-alarm probability, two-sided.
    alpha: f64,
    /// Motion measure of each block in the ring.
    motion: [T; RING],
    /// Learnt blocks per motion bin (same forgetting as the moments).
    motion_hist: [T; MOTION_BINS],
    /// A channel of the UKF was flagged during the open block.
    external: bool,
    /// The last `RING` block means, newest at `head − 1`.
    pub(super) blocks: [Vector3<T>; RING],
    /// The largest score/threshold ratio of each block's decision.
    ratio_at: [Vector3<T>; RING],
    pub(super) head: usize,
    pub(super) filled: usize,
    /// Learnt weight (blocks), sum and sum of squares of the block means.
    pub(super) n_b: Vector3<T>,
    pub(super) s1: Vector3<T>,
    pub(super) s2: Vector3<T>,
    /// Learnt weight and sum of products of consecutive learnt blocks
    /// (lag-1 autocovariance), and the last learnt block per channel
    /// (`None` if the block before it was not learnt).
    n11: Vector3<T>,
    s11: Vector3<T>,
    prev: [Option<T>; 3],
    /// Per length: learnt sum of squared window means (about the offset)
    /// and their count.
    q_w: [Vector3<T>; NL],
    n_w: [Vector3<T>; NL],
    /// Per channel: the learnt sums `Σ1, Σm, Σm², Σd², Σd²m` of the block
    /// variance's regression on motion (`motion_variance`).
    motion_var: [Vector3<T>; 5],
    /// Per length and channel: degrees of freedom and Student-t threshold
    /// last computed (recomputed when the former moves by 1 %).
    quantile: [[(T, T); 3]; NL],
    judging: bool,
    /// Consecutive decisions above threshold per channel, with their sign.
    run: [(u8, i8); 3],
    /// Blocks the flag still holds after the last confirmed decision.
    hold: [u8; 3],
    /// Blocks the longer lengths stay muted per channel (a fault ended).
    mute: [u8; 3],
    /// The length (index) whose decision last confirmed each flag, and the
    /// decisions since.
    flag_len: [u8; 3],
    since_confirm: [u8; 3],
    /// Per channel: the UKF's own test flagged it during the open block,
    /// and the blocks its flag still lies within the longest window.
    ukf_seen: [bool; 3],
    ukf_mask: [u8; 3],
    /// Per channel: the flag was last confirmed outside that mask.
    confirmed_clean: [bool; 3],
    /// Per channel: the newest shortest window's deviation from the offset
    /// and its threshold deviation (`None`: it could not judge).
    shortest: [Option<(T, T)>; 3],
    pub(super) detail: BlockTestDetail<T>,
}

impl<T: Real> BlockTest<T> {
    /// An empty test with per-decision probability `alpha`.
    pub fn new(alpha: f64) -> Self {
        Self {
            alpha,
            motion: [T::zero(); RING],
            motion_hist: [T::zero(); MOTION_BINS],
            external: false,
            blocks: [Vector3::zeros(); RING],
            ratio_at: [Vector3::zeros(); RING],
            head: 0,
            filled: 0,
            n_b: Vector3::zeros(),
            s1: Vector3::zeros(),
            s2: Vector3::zeros(),
            n11: Vector3::zeros(),
            s11: Vector3::zeros(),
            prev: [None; 3],
            q_w: [Vector3::zeros(); NL],
            n_w: [Vector3::zeros(); NL],
            motion_var: [Vector3::zeros(); 5],
            quantile: [[(T::zero(), T::zero()); 3]; NL],
            judging: false,
            run: [(0, 0); 3],
            hold: [0; 3],
            mute: [0; 3],
            flag_len: [0; 3],
            since_confirm: [u8::MAX; 3],
            ukf_seen: [false; 3],
            ukf_mask: [0; 3],
            confirmed_clean: [false; 3],
            shortest: [None; 3],
            detail: BlockTestDetail::default(),
        }
    }

    /// Starts afresh (learning restarted).
    pub fn reset(&mut self) {
        *self = Self::new(self.alpha);
    }

    /// Forgets the block means and the decisions (a re-alignment): what was
    /// learnt is kept.
    pub fn clear_windows(&mut self) {
        self.filled = 0;
        self.prev = [None; 3];
        self.external = false;
        self.run = [(0, 0); 3];
        self.hold = [0; 3];
        self.mute = [0; 3];
        self.ukf_seen = [false; 3];
        self.ukf_mask = [0; 3];
        self.shortest = [None; 3];
        self.detail.flag = [0; 3];
        self.detail.estimate = [T::zero(); 3];
        self.detail.ratio = [T::zero(); 3];
    }

    /// Decisions start (monitoring).
    pub fn start_judging(&mut self) {
        self.judging = true;
    }

    /// The largest ratio of the last decision is below `fraction` on every
    /// channel.
    pub fn quiet(&self, fraction: T) -> bool {
        self.detail.ratio.iter().all(|r| *r < fraction)
    }

    /// The newest shortest window contradicts a fault of size `f` on
    /// channel `c` (less the offset): it finds no fault itself (its
    /// deviation within its threshold deviation) and falls short of `f`,
    /// in its sign, by more than that threshold deviation. Under a fault of
    /// that size still present the second part alone has the test's
    /// per-decision probability (the rule that withdraws a longer window's
    /// verdict, `decide`); the first keeps a fault the window still sees
    /// from being called ended when the two estimates disagree on its
    /// size (log171, 20-s steps of 20 °/s and 3 m/s²: without it, 2 of 36
    /// lost their flag once). False when the window cannot judge.
    pub fn contradicts(&self, c: usize, f: T) -> bool {
        let s = if f > T::zero() { T::one() } else { -T::one() };
        self.shortest
            .get(c)
            .copied()
            .flatten()
            .is_some_and(|(d, lim)| d.abs() <= lim && s * (f - d) > lim)
    }

    /// A channel of the UKF is flagged: the open block is not learnt.
    pub fn mark_external(&mut self, external: bool) {
        self.external |= external;
    }

    /// The UKF's own test flags channel `c`: its windows are the UKF's to
    /// judge while they hold blocks it flagged (`reports`).
    pub fn note_ukf_flag(&mut self, c: usize) {
        if let Some(s) = self.ukf_seen.get_mut(c) {
            *s = true;
        }
    }

    /// The test's flag on channel `c` is reported: the UKF's own test has
    /// not flagged that channel within the longest window, nor had when the
    /// flag was last confirmed. Once the UKF
    /// has found a fault and then cleared it, a window that still holds
    /// the fault's blocks says nothing new: without this rule simulated
    /// 0.3 m/s² steps the UKF found in 1 s stayed flagged by the 10-s
    /// window until 5–13 s after they ended (3 events past the 5-s settle
    /// in 1 h, seeds 100–119).
    pub fn reports(&self, c: usize) -> bool {
        !self.ukf_seen.get(c).copied().unwrap_or(true)
            && self.ukf_mask.get(c).is_some_and(|m| *m == 0)
            && self.confirmed_clean.get(c).copied().unwrap_or(false)
    }

    /// Ring index of the block `age` blocks before the newest.
    pub(super) fn slot(&self, age: usize) -> Option<usize> {
        (age < self.filled).then(|| (self.head + RING - 1 - age) % RING)
    }

    /// Mean of the `len` blocks ending `age` blocks before the newest.
    pub(super) fn window(&self, age: usize, len: usize) -> Option<Vector3<T>> {
        if len == 0 || self.filled < age + len {
            return None;
        }
        let mut s = Vector3::zeros();
        for a in age..age + len {
            s += self.blocks.get(self.slot(a)?)?;
        }
        Some(s / T::lit(len as f64))
    }

    /// A block closed with body-axis mean `mean` and motion measure
    /// `motion`: decides (when judging) and learns, within `limits`.
    pub fn close_block(
        &mut self,
        cfg: &BlockTestConfig<T>,
        mean: Vector3<T>,
        motion: T,
        limits: &ChannelLimits<T>,
    ) {
        if let Some(b) = self.blocks.get_mut(self.head) {
            *b = mean;
        }
        if let Some(m) = self.motion.get_mut(self.head) {
            *m = motion;
        }
        let ext = if self.external {
            T::lit(EXTERNAL_FLAG_RATIO)
        } else {
            T::zero()
        };
        if let Some(r) = self.ratio_at.get_mut(self.head) {
            *r = Vector3::from_element(ext);
        }
        self.external = false;
        let longest = cfg.lengths[NL - 1];
        for (seen, mask) in self.ukf_seen.iter_mut().zip(self.ukf_mask.iter_mut()) {
            *mask = if *seen {
                longest
            } else {
                mask.saturating_sub(1)
            };
            *seen = false;
        }
        self.head = (self.head + 1) % RING;
        self.filled = (self.filled + 1).min(RING);
        if self.judging {
            self.decide(cfg, limits);
        }
        self.learn(cfg);
    }

    /// The learnt offset (unclamped mean), block variance and block count
    /// of channel `c`.
    fn moments(&self, c: usize) -> Option<(T, T, T)> {
        let n = *self.n_b.get(c)?;
        if n <= T::one() {
            return None;
        }
        let m = *self.s1.get(c)? / n;
        let v = (*self.s2.get(c)? / n - m * m).fmax(T::zero());
        Some((m, v, n))
    }

    /// The learnt variance of length `k`'s window mean on channel `c`, for
    /// a window of mean motion factor `h` (`motion_variance`), and its
    /// degrees of freedom (module notes).
    fn window_variance(
        &mut self,
        cfg: &BlockTestConfig<T>,
        k: usize,
        c: usize,
        h: T,
    ) -> Option<(T, T)> {
        let len = T::lit(f64::from(*cfg.lengths.get(k)?));
        let (_, vb, n) = self.moments(c)?;
        if vb <= T::zero() {
            return None;
        }
        let qw = *self.q_w.get(k)?.get(c)?;
        let nw = *self.n_w.get(k)?.get(c)?;
        let white = vb / len;
        let n_eff = nw * T::lit(OBM_DOF) / len;
        let nu = cfg.prior_windows + n_eff;
        let rho_hat = if nw > T::zero() {
            qw / nw / white
        } else {
            T::one()
        };
        let prior = if cfg.lag1_prior {
            self.lag1_reddening(c, len, vb).unwrap_or_else(T::one)
        } else {
            T::one()
        };
        let rho = (cfg.prior_windows * prior + n_eff * rho_hat) / nu;
        Some((vb * rho * (h / len + T::one() / n), nu))
    }

    /// The reddening of a length-`len` window of a first-order moving
    /// average with the blocks' learnt lag-1 autocorrelation (`None` before
    /// there are pairs): `1 + 2(1 − 1/L) r₁`, at least `1/L`.
    fn lag1_reddening(&self, c: usize, len: T, vb: T) -> Option<T> {
        let n = *self.n11.get(c)?;
        if n <= T::one() {
            return None;
        }
        let (m, _, _) = self.moments(c)?;
        let r1 = ((*self.s11.get(c)? / n - m * m) / vb)
            .fmax(-T::lit(0.5))
            .fmin(T::one());
        let inv = T::one() / len;
        Some((T::one() + T::lit(2.0) * (T::one() - inv) * r1).fmax(inv))
    }

    /// The Student-t threshold at `nu` degrees of freedom, cached per
    /// length and channel.
    fn threshold(&mut self, k: usize, c: usize, nu: T) -> Option<T> {
        let alpha = self.alpha;
        let slot = self.quantile.get_mut(k)?.get_mut(c)?;
        if (slot.0 - nu).abs() > nu * T::lit(0.01) {
            let t = student_t_upper_quantile(alpha * 0.5, nu.to_f64()).ok()?;
            *slot = (nu, T::lit(t));
        }
        Some(slot.1)
    }
}

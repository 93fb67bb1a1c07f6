//! Gyro biases judged while the vehicle is at rest (issue 14: a fault
//! present from power-up).
//!
//! In flight the parity tests judge the gyros only *relative* to each
//! other: the in-flight calibration learns each sensor's offset against the
//! others, so a bias present since power-up is only seen through the
//! offset test, and on a board whose x gyros are near-opposite hypotheses
//! it cannot be attributed (docs/parity-real-flights.md, step 7). At rest
//! the true rate is the Earth's (≤ 0.004 °/s), so each gyro's *absolute*
//! mean is its bias, with no relative ambiguity — what autopilots check
//! before arming (ArduPilot's "Gyros not calibrated"/"Gyros inconsistent",
//! PX4's preflight gyro checks).
//!
//! [`RestCheck`] averages the samples into blocks of `block_len`:
//! 1. **Rest**: a block is still when, for every sensing direction, the
//!    median over the sensors sharing it (the median IMU: one faulty IMU
//!    cannot make a moving board look still, nor a still one moving) of
//!    the within-block standard deviation is at most
//!    [`still_factor`](RestConfig::still_factor) × the configured noise,
//!    for the gyros and the accelerometers alike. The noise is the
//!    sensor's per-sample noise at rest (datasheet density × √bandwidth);
//!    a spinning rotor or an airframe in flight shakes the sensors far
//!    above it. The first [`settle_blocks`](RestConfig::settle_blocks) of
//!    a still run are not used (the board may still be settling), and any
//!    block that is not still ends the run and forgets its sums.
//! 2. **Bias**: over the still blocks of the run, each gyro's mean `m` of
//!    its block means and its standard error `s/√n` from their spread
//!    (the data's own noise, not a hand-set margin). A sensor is *above*
//!    when `|m| − t·se > offset_limit` and *within* when
//!    `|m| + t·se < offset_limit`, with `t` the Student-t quantile (ν =
//!    n − 1) at [`false_alarm`](RestConfig::false_alarm), so a healthy
//!    gyro whose bias is within the limit is called above with at most
//!    that probability per decision.
//! 3. **Verdict**: exactly one sensor above, every other active one
//!    within, and its mean more than the limit (beyond both margins) from
//!    every other gyro of its direction → that sensor is biased; after `confirm` such decisions in a
//!    row it is named for isolation ([`RestReport::isolate`]). Two or more
//!    above → [`RestState::CommonMode`]: the board is turning steadily or
//!    several sensors are off — it cannot judge and names none.
//!
//! The caller feeds the gyro and accelerometer samples of the same IMUs
//! and hands a named sensor to
//! [`ParityMonitor::isolate_external`](super::ParityMonitor::isolate_external)
//! of the gyro monitor (the isolation path the parity tests use; the
//! status is latched as
//! [`ParityIsolated`](super::SensorStatus::ParityIsolated) until
//! [`reset`](super::ParityMonitor::reset)).
//!
//! Limits: a steady yaw turn without vibration (a turntable) looks like
//! rest to both sensor kinds; its rate shows on every gyro of that axis
//! (common mode). At a turn rate near the limit one healthy gyro can read
//! above it and the others within; the named sensor must also stand the
//! limit clear of the others, which a turn's gyros, agreeing to within
//! their healthy biases, do not.

use nalgebra::SVector;

use crate::math::Real;
use crate::stats::{normal_upper_quantile, student_t_cornish_fisher};

use super::{ConfigError, Geometry, Reading};

/// Fewest still blocks a verdict rests on: the t quantile is the
/// Cornish–Fisher expansion, within 0.5 % from ν = 12 on.
pub const MIN_REST_BLOCKS: u16 = 13;

/// Settings of the [`RestCheck`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RestConfig<T> {
    /// Samples per block.
    pub block_len: u16,
    /// Per-sample gyro noise at rest, rad/s (an upper bound from the
    /// datasheet).
    pub gyro_noise: T,
    /// Per-sample accelerometer noise at rest, m/s².
    pub accel_noise: T,
    /// A block is still when its median sensor's standard deviation is at
    /// most this multiple of the noise.
    pub still_factor: T,
    /// Still blocks discarded at the start of each still run.
    pub settle_blocks: u16,
    /// Largest absolute gyro bias a healthy sensor shows at rest (its
    /// turn-on bias after the autopilot's calibration), rad/s.
    pub offset_limit: T,
    /// Probability that a gyro within the limit is called above it, per
    /// sensor and decision.
    pub false_alarm: f64,
    /// Consecutive decisions naming the same sensor before it is named
    /// for isolation.
    pub confirm: u16,
}

impl<T: Real> RestConfig<T> {
    /// Defaults for samples at `rate_hz`: blocks of ≈ 0.25 s, noise bounds
    /// for consumer MEMS IMUs — gyro 0.5 °/s and accelerometer 0.06 m/s²
    /// per sample (the noisiest common parts: 0.03 °/s/√Hz and
    /// 400 µg/√Hz, over a 250-Hz bandwidth) — still below twice those (a
    /// white-noise block of 12 samples exceeds 2σ with probability
    /// ≈ 1e-5), 4 settling blocks (1 s), α = 1e-6, 3 decisions to confirm.
    /// `offset_limit` is the gyro monitor's (`MultiscaleConfig::offset_limit`).
    pub fn new(rate_hz: f64, offset_limit: T) -> Self {
        let deg = core::f64::consts::PI / 180.0;
        Self {
            block_len: libm::round(rate_hz / 4.0).max(2.0) as u16,
            gyro_noise: T::lit(0.5 * deg),
            accel_noise: T::lit(0.06),
            still_factor: T::lit(2.0),
            settle_blocks: 4,
            offset_limit,
            false_alarm: 1e-6,
            confirm: 3,
        }
    }
}

/// What the rest check says after a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RestState {
    /// Not at rest (or settling): nothing judged.
    #[default]
    Moving,
    /// At rest; too few blocks, or some gyro neither clearly within nor
    /// clearly beyond the limit.
    Judging,
    /// At rest, every active gyro within the limit.
    WithinLimit,
    /// At rest, this gyro alone beyond the limit.
    Biased(usize),
    /// At rest, two or more gyros beyond the limit: a common motion or
    /// several faulty sensors — none is named.
    CommonMode,
}

/// One report of the rest check.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RestReport {
    /// State at the latest block.
    pub state: RestState,
    /// Still blocks the current verdict rests on.
    pub blocks: u16,
    /// Sensor to isolate now (confirmed this sample).
    pub isolate: Option<usize>,
}

/// Rest detection and absolute gyro-bias check over `N` redundant gyros
/// and `N` accelerometers (see the module documentation).
#[derive(Debug, Clone)]
pub struct RestCheck<T: Real, const N: usize> {
    cfg: RestConfig<T>,
    /// Sensors sharing a sensing direction (index of the group's first).
    gyro_group: [usize; N],
    accel_group: [usize; N],
    /// Block sums, centred on the block's first sample.
    g0: Option<SVector<T, N>>,
    a0: Option<SVector<T, N>>,
    gs: SVector<T, N>,
    gss: SVector<T, N>,
    asum: SVector<T, N>,
    ass: SVector<T, N>,
    n: u16,
    /// Still blocks in a row.
    run: u16,
    /// Sums of the used still blocks' gyro means and their squares,
    /// centred on the run's first used block (so the `f32` variance is not
    /// the difference of two large numbers when a bias is large).
    centre: Option<SVector<T, N>>,
    sum: SVector<T, N>,
    sum2: SVector<T, N>,
    blocks: u16,
    /// Normal quantile at `false_alarm / 2`.
    z: T,
    votes: (Option<usize>, u16),
    state: RestState,
}

impl<T: Real, const N: usize> RestCheck<T, N> {
    /// A check of the gyros of `gyro` and the accelerometers of `accel`
    /// (sensor `i` of both is the same IMU's axis, e.g. triads). Errors: a
    /// block shorter than two samples, a non-positive noise, factor or
    /// limit, or a false-alarm probability outside (0, 0.5).
    pub fn new(
        gyro: &Geometry<T, N>,
        accel: &Geometry<T, N>,
        cfg: RestConfig<T>,
    ) -> Result<Self, ConfigError> {
        let positive = |x: T| x.finite() && x > T::zero();
        if cfg.block_len < 2 {
            return Err(ConfigError::Field("rest.block_len"));
        }
        if !positive(cfg.gyro_noise) || !positive(cfg.accel_noise) {
            return Err(ConfigError::Field("rest.noise"));
        }
        if !positive(cfg.still_factor) {
            return Err(ConfigError::Field("rest.still_factor"));
        }
        if !positive(cfg.offset_limit) {
            return Err(ConfigError::Field("rest.offset_limit"));
        }
        if !(cfg.false_alarm > 0.0 && cfg.false_alarm < 0.5) {
            return Err(ConfigError::Probability);
        }
        let z =
            normal_upper_quantile(cfg.false_alarm * 0.5).map_err(|_| ConfigError::Probability)?;
        Ok(Self {
            cfg,
            gyro_group: groups(gyro),
            accel_group: groups(accel),
            g0: None,
            a0: None,
            gs: SVector::zeros(),
            gss: SVector::zeros(),
            asum: SVector::zeros(),
            ass: SVector::zeros(),
            n: 0,
            run: 0,
            centre: None,
            sum: SVector::zeros(),
            sum2: SVector::zeros(),
            blocks: 0,
            z: T::lit(z),
            votes: (None, 0),
            state: RestState::Moving,
        })
    }

    /// The settings.
    pub fn config(&self) -> &RestConfig<T> {
        &self.cfg
    }

    /// One sample of every gyro and accelerometer; `active` the gyros still
    /// in the monitor's set (the others are not judged nor used for rest).
    pub fn step(
        &mut self,
        gyro: &[Reading<T>; N],
        accel: &[Reading<T>; N],
        active: &[bool; N],
    ) -> RestReport {
        let mut report = RestReport {
            state: self.state,
            blocks: self.blocks,
            isolate: None,
        };
        let sample = |r: &[Reading<T>; N]| -> Option<SVector<T, N>> {
            let mut v = SVector::<T, N>::zeros();
            for ((x, r), a) in v.iter_mut().zip(r.iter()).zip(active.iter()) {
                match r {
                    Reading::Sample(s) if s.finite() => *x = *s,
                    _ if !*a => {}
                    _ => return None,
                }
            }
            Some(v)
        };
        let (Some(g), Some(a)) = (sample(gyro), sample(accel)) else {
            // A gap: the block cannot be judged; the run ends.
            self.moving();
            report.state = self.state;
            report.blocks = 0;
            return report;
        };
        let dg = g - *self.g0.get_or_insert(g);
        let da = a - *self.a0.get_or_insert(a);
        self.gs += dg;
        self.gss += dg.component_mul(&dg);
        self.asum += da;
        self.ass += da.component_mul(&da);
        self.n = self.n.saturating_add(1);
        if self.n >= self.cfg.block_len {
            report.isolate = self.close_block(active);
            report.state = self.state;
            report.blocks = self.blocks;
        }
        report
    }

    /// The open block's sums emptied (the next block starts).
    fn clear_block(&mut self) {
        self.g0 = None;
        self.a0 = None;
        self.gs = SVector::zeros();
        self.gss = SVector::zeros();
        self.asum = SVector::zeros();
        self.ass = SVector::zeros();
        self.n = 0;
    }

    /// Not at rest: the run and its sums are forgotten.
    fn moving(&mut self) {
        self.clear_block();
        self.run = 0;
        self.centre = None;
        self.sum = SVector::zeros();
        self.sum2 = SVector::zeros();
        self.blocks = 0;
        self.votes = (None, 0);
        self.state = RestState::Moving;
    }

    /// A complete block: rest or not, then the bias verdict.
    fn close_block(&mut self, active: &[bool; N]) -> Option<usize> {
        let n = T::lit(f64::from(self.n));
        let gm = self.gs / n;
        let am = self.asum / n;
        let var = |ss: &SVector<T, N>, m: &SVector<T, N>| {
            (ss / n - m.component_mul(m)).map(|v| v.max(T::zero()))
        };
        let (gv, av) = (var(&self.gss, &gm), var(&self.ass, &am));
        let g_mean = gm + self.g0.unwrap_or_else(SVector::zeros);
        let f = self.cfg.still_factor;
        let gl = f * f * self.cfg.gyro_noise * self.cfg.gyro_noise;
        let al = f * f * self.cfg.accel_noise * self.cfg.accel_noise;
        let still = median_below(&gv, &self.gyro_group, active, gl)
            && median_below(&av, &self.accel_group, active, al);
        if !still {
            self.moving();
            return None;
        }
        self.clear_block();
        self.run = self.run.saturating_add(1);
        if self.run <= self.cfg.settle_blocks {
            self.state = RestState::Moving;
            return None;
        }
        // The count saturates after 4.5 h of rest at 0.25-s blocks: the
        // sums stop with it, so the mean stays that of the counted blocks.
        if self.blocks < u16::MAX {
            let d = g_mean - *self.centre.get_or_insert(g_mean);
            self.sum += d;
            self.sum2 += d.component_mul(&d);
            self.blocks += 1;
        }
        self.state = self.verdict(active);
        let RestState::Biased(k) = self.state else {
            self.votes = (None, 0);
            return None;
        };
        self.votes = match self.votes {
            (Some(j), c) if j == k => (Some(k), c.saturating_add(1)),
            _ => (Some(k), 1),
        };
        if self.votes.1 < self.cfg.confirm.max(1) {
            return None;
        }
        self.votes = (None, 0);
        Some(k)
    }

    /// The bias verdict over the still blocks so far.
    fn verdict(&self, active: &[bool; N]) -> RestState {
        if self.blocks < MIN_REST_BLOCKS {
            return RestState::Judging;
        }
        let nb = T::lit(f64::from(self.blocks));
        let t = student_t_cornish_fisher(self.z, nb - T::one());
        let limit = self.cfg.offset_limit;
        let centre = self.centre.unwrap_or_else(SVector::zeros);
        let (mut above, mut unsure, mut who) = (0usize, 0usize, None);
        let mut means = [T::zero(); N];
        let mut margins = [T::zero(); N];
        for (k, ((((s, s2), c), a), (mk, gk))) in self
            .sum
            .iter()
            .zip(self.sum2.iter())
            .zip(centre.iter())
            .zip(active.iter())
            .zip(means.iter_mut().zip(margins.iter_mut()))
            .enumerate()
        {
            if !*a {
                continue;
            }
            let d = *s / nb;
            let var = ((*s2 - d * d * nb) / (nb - T::one())).max(T::zero());
            let m = *c + d;
            let margin = t * (var / nb).sqrt();
            (*mk, *gk) = (m, margin);
            if m.abs() - margin > limit {
                above += 1;
                who = Some(k);
            } else if m.abs() + margin >= limit {
                unsure += 1;
            }
        }
        match (above, unsure, who) {
            (0, 0, _) => RestState::WithinLimit,
            (1, 0, Some(k)) if self.stands_out(k, &means, &margins, active) => RestState::Biased(k),
            (1, 0, Some(_)) => RestState::CommonMode,
            (a, _, _) if a >= 2 => RestState::CommonMode,
            _ => RestState::Judging,
        }
    }

    /// Sensor `k`'s mean differs from every other active gyro sharing its
    /// direction by more than the limit (beyond both margins). A steady
    /// turn at a rate near the limit puts one healthy gyro just above it
    /// and the others just within; their means then agree, and a turn is
    /// no bias of one sensor.
    fn stands_out(&self, k: usize, means: &[T; N], margins: &[T; N], active: &[bool; N]) -> bool {
        let (Some(gk), Some(mk), Some(ek)) = (self.gyro_group.get(k), means.get(k), margins.get(k))
        else {
            return false;
        };
        self.gyro_group
            .iter()
            .zip(means.iter().zip(margins.iter()))
            .zip(active.iter())
            .enumerate()
            .filter(|(j, ((g, _), a))| *j != k && *g == gk && **a)
            .all(|(_, ((_, (m, e)), _))| (*mk - *m).abs() - (*ek + *e) > self.cfg.offset_limit)
    }
}

/// Group index of each sensor: the first sensor whose direction is
/// parallel to its own (|cos| > 0.999).
fn groups<T: Real, const N: usize>(g: &Geometry<T, N>) -> [usize; N] {
    core::array::from_fn(|i| {
        let Some(di) = g.direction(i) else {
            return i;
        };
        (0..i)
            .find(|&j| {
                g.direction(j).is_some_and(|dj| {
                    let c = di.dot(&dj) / (di.norm() * dj.norm());
                    c.abs() > T::lit(0.999)
                })
            })
            .unwrap_or(i)
    })
}

/// For every group of active sensors, its median variance (the upper one
/// for an even count: a quiet faulty sensor cannot make a group look
/// still) is at most `limit`.
fn median_below<T: Real, const N: usize>(
    v: &SVector<T, N>,
    group: &[usize; N],
    active: &[bool; N],
    limit: T,
) -> bool {
    (0..N).all(|g| {
        // Members of group `g` above and at or below the limit.
        let (mut over, mut total) = (0usize, 0usize);
        for ((x, gi), a) in v.iter().zip(group.iter()).zip(active.iter()) {
            if *gi == g && *a {
                total += 1;
                let quiet = *x <= limit;
                if !quiet {
                    over += 1;
                }
            }
        }
        // The median (upper for even counts) is at most the limit when
        // fewer than half the members, rounding down, exceed it.
        total == 0 || 2 * over < total
    })
}

#[cfg(test)]
mod tests;

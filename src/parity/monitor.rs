//! The redundant-sensor monitor: hardware checks, training, the paper's PCA
//! pattern test, a windowed χ² (GLT) test, per-sensor CUSUMs, isolation by
//! fault direction and reconfiguration, with the fused output every period.

use nalgebra::{SMatrix, SVector, Vector3};

use crate::math::{cholesky, cholesky_solve_right, symmetric_eigen, Real};
use crate::stats::{chi_square_upper_quantile, cusum_threshold};

use super::health::{HealthConfig, Reading, SensorHealth, SensorStatus};
use super::multiscale::{Multiscale, MultiscaleConfig, MultiscaleDecision, REGRESSORS};
use super::space::invert_rank3;
use super::training::{Baseline, Trainer};
use super::{ConfigError, Geometry, ParitySpace};

/// Which test's alarm drives isolation and reconfiguration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParityDetector {
    /// \[PAR\]: the window-mean 2-D PCA pattern, normalised by its training
    /// variance.
    Pca,
    /// Windowed χ² of the full parity vector (generalised likelihood test).
    Glt,
    /// Two-sided CUSUM per sensor direction (sequential; small biases).
    Cusum,
    /// Alarm when either the GLT or the CUSUM alarms.
    GltOrCusum,
    /// Real flights: in-flight relative calibration, Huber-clipped blocks
    /// and GLR tests on window means at several lengths with covariances
    /// learned from the data ([`MultiscaleConfig`]).
    Multiscale,
}

/// Configuration of a [`ParityMonitor`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParityConfig<T> {
    /// Hardware checks.
    pub health: HealthConfig<T>,
    /// Samples averaged into one block; one decision per block.
    pub block_len: u16,
    /// Blocks in the GLT/PCA window (at most the monitor's `W`).
    pub window_blocks: usize,
    /// Training samples (fault-free; motion helps the leakage fit).
    pub train_samples: u32,
    /// Calibration samples after training (fault-free): the tests run with
    /// their χ²/ARL thresholds and each threshold is raised to 1.25× the
    /// largest statistic seen, when that is higher. Real sensors are not
    /// Gaussian and white (vibration bursts, filter differences); this
    /// keeps the thresholds honest on them. 0 disables.
    pub calibrate_samples: u32,
    /// False-alarm probability per decision of the GLT and PCA tests.
    pub false_alarm: f64,
    /// Factor on the χ²-derived thresholds: covers the error of a
    /// covariance learned from a finite training set.
    pub threshold_margin: T,
    /// Bias (unit) the CUSUMs are tuned to detect fastest.
    pub cusum_bias: T,
    /// In-control average run length of each one-sided CUSUM, decisions.
    pub cusum_arl0: f64,
    /// Ridge on the leakage fit (unit², per sample).
    pub ridge: T,
    /// Time constant, in blocks, with which the offset follows slow bias
    /// drift while every test is quiet (0 disables tracking).
    pub drift_blocks: T,
    /// Consecutive alarmed decisions naming the same sensor before it is
    /// isolated and removed.
    pub isolate_after: u16,
    /// The test whose alarm isolates.
    pub detector: ParityDetector,
    /// Settings of [`ParityDetector::Multiscale`].
    pub multiscale: MultiscaleConfig<T>,
}

impl<T: Real> ParityConfig<T> {
    /// Spends a fault-free lead-in of `samples` on training and, when
    /// calibration is enabled, calibration: two thirds train, the rest
    /// calibrates.
    pub fn set_lead_in(&mut self, samples: u32) {
        if self.calibrate_samples > 0 {
            self.train_samples = samples * 2 / 3;
            self.calibrate_samples = samples - self.train_samples;
        } else {
            self.train_samples = samples;
        }
    }

    /// Gyro array defaults for `rate_hz` samples/s and full scale `fs`
    /// (rad/s): 0.1 s blocks, 1 s window, 30 s training, α = 1e-9 per
    /// decision with margin 1.5, CUSUM tuned to 0.05 °/s with ARL0 10⁹
    /// decisions, ridge (0.5 °/s)² (far below any manoeuvre, far above the
    /// noise, so a stationary training fits no leakage from noise), drift
    /// tracking over 5 s (the bias random walk of a consumer MEMS gyro
    /// moves the offset by several window σ per minute), isolation after 3
    /// decisions, GLT-or-CUSUM.
    pub fn gyro(rate_hz: f64, fs: T) -> Self {
        let block = libm::round(rate_hz / 10.0).max(1.0);
        let deg = core::f64::consts::PI / 180.0;
        Self {
            health: HealthConfig::new(fs),
            block_len: block as u16,
            window_blocks: 10,
            train_samples: libm::round(30.0 * rate_hz) as u32,
            calibrate_samples: libm::round(15.0 * rate_hz) as u32,
            false_alarm: 1e-9,
            threshold_margin: T::lit(1.5),
            cusum_bias: T::lit(0.05 * deg),
            cusum_arl0: 1e9,
            ridge: T::lit((0.5 * deg) * (0.5 * deg)),
            drift_blocks: T::lit(50.0),
            isolate_after: 3,
            detector: ParityDetector::GltOrCusum,
            multiscale: MultiscaleConfig::new(T::lit(deg), T::lit(1.2 * deg)),
        }
    }

    /// Accelerometer array defaults: as [`gyro`](Self::gyro) with the CUSUM
    /// tuned to 0.01 m/s² and ridge (0.05 m/s²)².
    pub fn accel(rate_hz: f64, fs: T) -> Self {
        Self {
            cusum_bias: T::lit(0.01),
            ridge: T::lit(0.05 * 0.05),
            multiscale: MultiscaleConfig::new(T::lit(0.1), T::lit(0.75)),
            ..Self::gyro(rate_hz, fs)
        }
    }

    /// Gyro array of a real flight controller (several IMUs on one vibrating
    /// board, logged or sampled at `rate_hz`): the
    /// [`Multiscale`](ParityDetector::Multiscale) detector on ≈ 0.25 s
    /// blocks, 30 s of training (no separate threshold calibration: the
    /// covariances keep learning in flight), isolation after 3 decisions.
    /// Needs a monitor window `W` ≥ 40 blocks. The offset limit, 1.2 °/s,
    /// is the largest relative gyro bias accepted once trained: twice the
    /// largest relative offset of log171's three healthy IMUs (0.6 °/s);
    /// larger ones are reported as a fault present since power-up.
    pub fn gyro_flight(rate_hz: f64, fs: T) -> Self {
        let block = libm::round(rate_hz / 4.0).max(1.0);
        Self {
            block_len: block as u16,
            train_samples: libm::round(30.0 * rate_hz) as u32,
            calibrate_samples: 0,
            drift_blocks: T::zero(),
            detector: ParityDetector::Multiscale,
            ..Self::gyro(rate_hz, fs)
        }
    }

    /// Accelerometer array of a real flight controller: as
    /// [`gyro_flight`](Self::gyro_flight) with accelerometer units, each
    /// sensor's vibration as a regressor (rectification) and an offset limit
    /// of 0.75 m/s², ArduPilot's accelerometer consistency threshold.
    pub fn accel_flight(rate_hz: f64, fs: T) -> Self {
        Self {
            cusum_bias: T::lit(0.01),
            ridge: T::lit(0.05 * 0.05),
            multiscale: MultiscaleConfig {
                vibration: true,
                ..MultiscaleConfig::new(T::lit(0.1), T::lit(1.0))
            },
            ..Self::gyro_flight(rate_hz, fs)
        }
    }
}

/// Monitor phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParityPhase {
    /// Learning offset, leakage and noise; no decisions.
    Training,
    /// Running the tests fault-free to calibrate their thresholds; no
    /// alarms.
    Calibrating,
    /// Testing every block.
    Monitoring,
    /// Three or fewer healthy sensors remain: fusing without monitoring.
    NoRedundancy,
    /// Fewer than three usable sensors, or their geometry lost rank.
    Lost,
}

/// Alarm state of each test at the latest decision.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DetectorFlags {
    /// PCA pattern test.
    pub pca: bool,
    /// Windowed χ² test.
    pub glt: bool,
    /// Any CUSUM.
    pub cusum: bool,
}

/// What the monitor says every period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParityReport<T: Real, const N: usize> {
    /// Phase.
    pub phase: ParityPhase,
    /// Least-squares body vector from the sensors usable this period
    /// (`None` when fewer than three independent ones are).
    pub fused: Option<Vector3<T>>,
    /// Health of each sensor this period.
    pub status: [SensorStatus; N],
    /// A new decision was taken this period (one per block).
    pub decision: bool,
    /// Alarm of each test at the latest decision.
    pub flags: DetectorFlags,
    /// The configured detector alarms.
    pub fault: bool,
    /// χ² statistic of the window and its threshold.
    pub glt: T,
    /// Threshold of [`glt`](Self::glt).
    pub glt_threshold: T,
    /// \[PAR\] pattern mean `Wᵀ p̄` (unit of the sensors).
    pub pattern: [T; 2],
    /// Normalised pattern statistic and its threshold.
    pub pca: T,
    /// Threshold of [`pca`](Self::pca).
    pub pca_threshold: T,
    /// Largest CUSUM ÷ its threshold (alarm above 1).
    pub cusum_ratio: T,
    /// Sensor whose fault direction best explains the window mean.
    pub suspect: Option<usize>,
    /// Least-squares bias of the suspect (unit).
    pub bias_estimate: T,
    /// Sensor isolated and removed in this period.
    pub isolated: Option<usize>,
    /// At least half of the sensors still in the set clip this period: a
    /// common-mode saturation (violent manoeuvre, crash), not a sensor fault.
    pub common_mode_saturation: bool,
    /// Parity dimension in use.
    pub parity_dim: usize,
    /// Latest decision of the multi-scale tests (ratio to threshold,
    /// suspect, bias, isolation margin).
    pub multiscale: MultiscaleDecision<T>,
}

/// Sums over the block being accumulated for the multi-scale tests.
#[derive(Debug, Clone, Copy, PartialEq)]
struct BlockSums<T: Real, const N: usize> {
    p: SVector<T, N>,
    x: Vector3<T>,
    /// First sample of the block, the sensors' sums are centred on.
    m0: Option<SVector<T, N>>,
    m: SVector<T, N>,
    mm: SVector<T, N>,
    n: u16,
}

impl<T: Real, const N: usize> Default for BlockSums<T, N> {
    fn default() -> Self {
        Self {
            p: SVector::zeros(),
            x: Vector3::zeros(),
            m0: None,
            m: SVector::zeros(),
            mm: SVector::zeros(),
            n: 0,
        }
    }
}

/// Derived per-space quantities (recomputed on reconfiguration).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tests<T: Real, const N: usize> {
    baseline: Baseline<T, N>,
    /// `Σ_b⁻¹` (identity block beyond `dim`, then zeroed).
    cov_inv: SMatrix<T, N, N>,
    /// Column k: `a_k = Σ_b⁻¹ v_k`.
    a: SMatrix<T, N, N>,
    /// `q_k = v_kᵀ Σ_b⁻¹ v_k`.
    q: [T; N],
    glt_threshold: T,
    pca_basis: SMatrix<T, N, 2>,
    pca_var: [T; 2],
    pca_threshold: T,
    kappa: [T; N],
    cusum_h: [T; N],
}

/// Parity-space monitor of `N` redundant single-axis sensors of one kind,
/// with a window of up to `W` blocks. Allocation-free and panic-free.
#[derive(Debug, Clone)]
pub struct ParityMonitor<T: Real, const N: usize, const W: usize> {
    cfg: ParityConfig<T>,
    space: ParitySpace<T, N>,
    health: [SensorHealth<T>; N],
    trainer: Trainer<T, N>,
    tests: Option<Tests<T, N>>,
    phase: ParityPhase,
    block: SVector<T, N>,
    block_n: u16,
    window: [SVector<T, N>; W],
    head: usize,
    filled: usize,
    cusum_pos: [T; N],
    cusum_neg: [T; N],
    suspect_run: (Option<usize>, u16),
    removed: [bool; N],
    /// Threshold factors `[GLT, PCA, CUSUM]` from calibration.
    scales: [T; 3],
    /// Largest statistic ÷ threshold seen in calibration, same order.
    peaks: [T; 3],
    calibrated: u32,
    /// χ² quantiles at `false_alarm` by degrees of freedom (index), computed
    /// once at configuration: reconfiguring in flight then costs no
    /// software-`f64` root finding.
    chi2: [T; N],
    last: ParityReport<T, N>,
    /// Multi-scale tests (with [`ParityDetector::Multiscale`]).
    ms: Option<Multiscale<T, N, W>>,
    /// Block being accumulated for them.
    ms_block: BlockSums<T, N>,
    /// The previous block (`p̄`, `x̄`, per-sensor variance) and the fused
    /// mean before it: a block is processed when the next one is complete,
    /// so its skew regressor is the centred difference.
    ms_prev: Option<(SVector<T, N>, Vector3<T>, SVector<T, N>)>,
    ms_prev2: Option<Vector3<T>>,
    /// Blocks seen since (re)training began.
    ms_blocks: u32,
    ms_trained: bool,
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// A monitor of the array `geometry`. Errors: rank-deficient geometry,
    /// fewer than four sensors, a window longer than `W` or zero, a bad
    /// false-alarm probability.
    pub fn new(geometry: &Geometry<T, N>, cfg: ParityConfig<T>) -> Result<Self, ConfigError> {
        cfg.validate()?;
        if cfg.window_blocks == 0 || cfg.window_blocks > W || cfg.block_len == 0 {
            return Err(ConfigError::Window);
        }
        if cfg.detector == ParityDetector::Multiscale && cfg.multiscale.check(W).is_err() {
            return Err(ConfigError::Multiscale);
        }
        if !(cfg.false_alarm > 0.0 && cfg.false_alarm < 0.5)
            || cfg.cusum_arl0.is_nan()
            || cfg.cusum_arl0 <= 1.0
        {
            return Err(ConfigError::Probability);
        }
        let space = ParitySpace::new(geometry, &[true; N])?;
        let mut chi2 = [T::zero(); N];
        // The χ² table serves the white-noise tests only; the multi-scale
        // tests have their own thresholds (and the table costs ≈ 2.6 M
        // instructions of software f64 on the M4F).
        let white = cfg.detector != ParityDetector::Multiscale;
        for (dof, q) in chi2.iter_mut().enumerate().skip(1).filter(|_| white) {
            let x = chi_square_upper_quantile(cfg.false_alarm, dof as u32)
                .map_err(|_| ConfigError::Probability)?;
            *q = T::lit(x);
        }
        let report = ParityReport {
            phase: ParityPhase::Training,
            fused: None,
            status: [SensorStatus::Healthy; N],
            decision: false,
            flags: DetectorFlags::default(),
            fault: false,
            glt: T::zero(),
            glt_threshold: T::zero(),
            pattern: [T::zero(); 2],
            pca: T::zero(),
            pca_threshold: T::zero(),
            cusum_ratio: T::zero(),
            suspect: None,
            bias_estimate: T::zero(),
            isolated: None,
            common_mode_saturation: false,
            parity_dim: space.dim(),
            multiscale: MultiscaleDecision::default(),
        };
        Self {
            trainer: Trainer::new(cfg.train_samples, cfg.block_len, cfg.ridge),
            cfg,
            space,
            health: [SensorHealth::default(); N],
            tests: None,
            phase: ParityPhase::Training,
            block: SVector::zeros(),
            block_n: 0,
            window: [SVector::zeros(); W],
            head: 0,
            filled: 0,
            cusum_pos: [T::zero(); N],
            cusum_neg: [T::zero(); N],
            suspect_run: (None, 0),
            removed: [false; N],
            scales: [T::one(); 3],
            peaks: [T::zero(); 3],
            calibrated: 0,
            chi2,
            last: report,
            ms: None,
            ms_block: BlockSums::default(),
            ms_prev: None,
            ms_prev2: None,
            ms_blocks: 0,
            ms_trained: false,
        }
        .with_multiscale()
    }

    /// Creates the multi-scale tests when they are the detector (their
    /// thresholds are computed here, once).
    fn with_multiscale(mut self) -> Result<Self, ConfigError> {
        if self.cfg.detector == ParityDetector::Multiscale {
            let h = Multiscale::<T, N, W>::thresholds(&self.cfg.multiscale)
                .ok_or(ConfigError::Multiscale)?;
            self.ms = Some(Multiscale::new(self.cfg.multiscale, self.space.dim(), h));
        }
        Ok(self)
    }

    /// Back to training with every sensor healthy (an explicit reset after
    /// maintenance; latched failures clear).
    pub fn reset(&mut self) -> Result<(), ConfigError> {
        *self = Self::new(self.space.geometry(), self.cfg)?;
        Ok(())
    }

    /// The parity space in use (after any reconfiguration).
    pub fn space(&self) -> &ParitySpace<T, N> {
        &self.space
    }

    /// What training learned (in the current space), once trained.
    pub fn baseline(&self) -> Option<&Baseline<T, N>> {
        self.tests.as_ref().map(|t| &t.baseline)
    }

    /// Current phase.
    pub fn phase(&self) -> ParityPhase {
        self.phase
    }

    /// One period: checks each reading, fuses the usable ones, and — when
    /// every active sensor delivered a usable sample — trains or tests.
    pub fn step(&mut self, readings: &[Reading<T>; N]) -> ParityReport<T, N> {
        let mut m = SVector::<T, N>::zeros();
        let mut usable = [false; N];
        let mut status = [SensorStatus::Healthy; N];
        let mut newly_failed = None;
        for (k, (reading, health)) in readings.iter().zip(self.health.iter_mut()).enumerate() {
            let was_failed = health.failure().is_some();
            let (value, s) = health.check(*reading, &self.cfg.health);
            if let (Some(x), Some(slot), Some(u)) = (value, m.get_mut(k), usable.get_mut(k)) {
                *slot = x;
                *u = true;
            }
            if let Some(st) = status.get_mut(k) {
                *st = s;
            }
            if !was_failed && s.is_failed() && newly_failed.is_none() {
                newly_failed = Some(k);
            }
        }
        // Railed outputs: long clipping on a minority of sensors.
        let in_set = self.removed.iter().filter(|r| !**r).count();
        let clipping = status
            .iter()
            .filter(|s| **s == SensorStatus::Clipping)
            .count();
        let common_mode = in_set > 0 && 2 * clipping >= in_set;
        for (k, (h, st)) in self.health.iter_mut().zip(status.iter_mut()).enumerate() {
            if !common_mode
                && h.clipping_run() >= self.cfg.health.rail_samples
                && h.failure().is_none()
            {
                h.rail();
                *st = SensorStatus::Railed;
                newly_failed = newly_failed.or(Some(k));
            }
        }
        let mut report = self.last;
        report.decision = false;
        report.isolated = None;
        report.common_mode_saturation = common_mode;
        if let Some(k) = newly_failed {
            self.exclude(k);
        }
        // A failed sensor stays failed even if another one failed first.
        for k in 0..N {
            let latched = self.health.get(k).and_then(|h| h.failure());
            if latched.is_some() && !self.removed.get(k).copied().unwrap_or(true) {
                self.exclude(k);
            }
        }
        report.fused = fuse_subset(self.space.geometry(), &m, &usable);
        let all_active_usable = self
            .space
            .active()
            .iter()
            .zip(usable.iter())
            .all(|(a, u)| !a || *u);
        if all_active_usable
            && matches!(
                self.phase,
                ParityPhase::Training | ParityPhase::Calibrating | ParityPhase::Monitoring
            )
        {
            let p = self.space.parity(&m);
            let x = self.space.fuse(&m);
            if self.ms.is_some() {
                // The multi-scale tests alone: the white-noise tests would
                // only cost time (their statistics are not reported).
                self.multiscale_sample(&m, &p, &x, &mut report);
                if self.ms_trained && self.phase == ParityPhase::Training {
                    self.phase = ParityPhase::Monitoring;
                }
            } else {
                match self.phase {
                    ParityPhase::Training => self.train(&p, &x),
                    _ => self.monitor(&p, &x, &mut report),
                }
            }
        }
        report.phase = self.phase;
        if self.ms.is_some() && !self.ms_trained && self.phase == ParityPhase::Monitoring {
            // The multi-scale tests are still learning: cannot judge yet.
            report.phase = ParityPhase::Training;
        }
        report.status = status;
        report.parity_dim = self.space.dim();
        if let Some(t) = &self.tests {
            report.glt_threshold = t.glt_threshold;
            report.pca_threshold = t.pca_threshold;
        }
        self.last = report;
        report
    }

    fn train(&mut self, p: &SVector<T, N>, x: &Vector3<T>) {
        self.trainer.add(p, x);
        if !self.trainer.done() {
            return;
        }
        match self
            .trainer
            .finish()
            .and_then(|b| derive_tests(&self.space, b, &self.cfg, &self.scales, &self.chi2))
        {
            Some(t) => {
                self.tests = Some(t);
                self.phase = if self.cfg.calibrate_samples > 0 {
                    ParityPhase::Calibrating
                } else {
                    ParityPhase::Monitoring
                };
            }
            // Non-finite training data: train again rather than test with it.
            None => {
                self.trainer =
                    Trainer::new(self.cfg.train_samples, self.cfg.block_len, self.cfg.ridge)
            }
        }
    }

    fn monitor(&mut self, p: &SVector<T, N>, x: &Vector3<T>, report: &mut ParityReport<T, N>) {
        let Some(t) = self.tests else {
            return;
        };
        let r = p - t.baseline.leak * x - t.baseline.offset;
        self.block += r;
        self.block_n = self.block_n.saturating_add(1);
        if self.block_n < self.cfg.block_len {
            return;
        }
        let b = self.block / T::lit(f64::from(self.cfg.block_len));
        self.block = SVector::zeros();
        self.block_n = 0;
        if let Some(slot) = self.window.get_mut(self.head) {
            *slot = b;
        }
        let k_win = self.cfg.window_blocks;
        self.head = (self.head + 1) % k_win;
        self.filled = (self.filled + 1).min(k_win);
        report.decision = true;

        // CUSUMs: per sensor direction, on the standardised block projection.
        let mut cusum_ratio = T::zero();
        let mut cusum_arg = None;
        for k in 0..N {
            let (Some(&q), Some(&kappa), Some(&h)) = (t.q.get(k), t.kappa.get(k), t.cusum_h.get(k))
            else {
                continue;
            };
            if q <= T::zero() || h <= T::zero() {
                continue;
            }
            let s = t.a.column(k).dot(&b) / q.sqrt();
            let (Some(gp), Some(gn)) = (self.cusum_pos.get_mut(k), self.cusum_neg.get_mut(k))
            else {
                continue;
            };
            *gp = (*gp + s - kappa).max(T::zero());
            *gn = (*gn - s - kappa).max(T::zero());
            let ratio = gp.max(*gn) / h;
            if !ratio.finite() {
                *gp = T::zero();
                *gn = T::zero();
                continue;
            }
            if ratio > cusum_ratio {
                cusum_ratio = ratio;
                cusum_arg = Some(k);
            }
        }
        report.cusum_ratio = cusum_ratio;
        report.flags.cusum = cusum_ratio > T::one();

        // Window tests once the window is full.
        let mut mean = SVector::<T, N>::zeros();
        if self.filled >= k_win {
            for w in self.window.iter().take(k_win) {
                mean += w;
            }
            mean /= T::lit(k_win as f64);
            let kf = T::lit(k_win as f64);
            report.glt = kf * mean.dot(&(t.cov_inv * mean));
            report.flags.glt = report.glt > t.glt_threshold;
            let y = t.pca_basis.transpose() * mean;
            report.pattern = [y.x, y.y];
            let mut pca = T::zero();
            for (yi, vi) in y.iter().zip(t.pca_var.iter()) {
                if *vi > T::zero() {
                    pca += *yi * *yi / *vi;
                }
            }
            report.pca = kf * pca;
            report.flags.pca = report.pca > t.pca_threshold;
            if !report.glt.finite() || !report.pca.finite() {
                // Cannot happen with finite samples; never let NaN decide.
                report.flags.glt = false;
                report.flags.pca = false;
                self.filled = 0;
            }
        }
        if self.phase == ParityPhase::Calibrating {
            self.calibrate(&t, &b, report);
            return;
        }
        let fault = match self.cfg.detector {
            ParityDetector::Pca => report.flags.pca,
            ParityDetector::Glt => report.flags.glt,
            ParityDetector::Cusum => report.flags.cusum,
            ParityDetector::GltOrCusum => report.flags.glt || report.flags.cusum,
            // Decided per block in `multiscale_block`.
            ParityDetector::Multiscale => return,
        };
        report.fault = fault;

        // Isolation: the direction that explains the window mean best (or,
        // before the window fills, the CUSUM that fired).
        let basis = if self.filled >= k_win { mean } else { b };
        let (suspect, bias) = isolate(&t, &basis, self.space.active());
        report.suspect = if self.filled >= k_win {
            suspect
        } else {
            cusum_arg.or(suspect)
        };
        report.bias_estimate = bias;

        if !fault {
            self.suspect_run = (None, 0);
            let quiet = report.glt < t.glt_threshold * T::lit(0.5) && cusum_ratio < T::lit(0.5);
            if quiet && self.cfg.drift_blocks > T::one() {
                // Follow slow bias drift (within the bias-instability spec).
                let gain = T::one() / self.cfg.drift_blocks;
                if let Some(tests) = self.tests.as_mut() {
                    tests.baseline.offset += b * gain;
                }
            }
            return;
        }
        let Some(k) = report.suspect else {
            return;
        };
        if !self.space.isolable(k) {
            // Detect-only geometry (e.g. two aligned triads): say so by not
            // isolating; `fault` stays raised.
            self.suspect_run = (None, 0);
            return;
        }
        self.suspect_run = match self.suspect_run {
            (Some(j), n) if j == k => (Some(k), n.saturating_add(1)),
            _ => (Some(k), 1),
        };
        if self.suspect_run.1 >= self.cfg.isolate_after {
            if let Some(h) = self.health.get_mut(k) {
                h.isolate();
            }
            self.exclude(k);
            report.isolated = Some(k);
            report.fault = false;
            report.flags = DetectorFlags::default();
        }
    }

    /// Accumulates one sample into the multi-scale block; a complete block
    /// processes the one before it (whose centred difference is now known).
    fn multiscale_sample(
        &mut self,
        m: &SVector<T, N>,
        p: &SVector<T, N>,
        x: &Vector3<T>,
        report: &mut ParityReport<T, N>,
    ) {
        let b = &mut self.ms_block;
        // Centre the sensor sums on the block's first sample so the f32
        // variance is not the difference of two large numbers.
        let m0 = *b.m0.get_or_insert(*m);
        let dm = m - m0;
        b.p += p;
        b.x += x;
        b.m += dm;
        b.mm += dm.component_mul(&dm);
        b.n = b.n.saturating_add(1);
        if b.n < self.cfg.block_len {
            return;
        }
        let n = T::lit(f64::from(b.n));
        let (pb, xb) = (b.p / n, b.x / n);
        let mean = b.m / n;
        let eb = (b.mm / n - mean.component_mul(&mean)).map(|v| v.max(T::zero()));
        self.ms_block = BlockSums::default();
        if let (Some((p_prev, x_prev, e_prev)), Some(x_before)) = (self.ms_prev, self.ms_prev2) {
            let dx = (xb - x_before) * T::lit(0.5);
            self.multiscale_block(&p_prev, &x_prev, &dx, &e_prev, report);
        }
        self.ms_prev2 = self.ms_prev.map(|(_, x, _)| x);
        self.ms_prev = Some((pb, xb, eb));
    }

    /// One block through the multi-scale tests: training (first two thirds
    /// calibrate, the last third measures the residual's covariance), then
    /// a decision per block, with isolation after `isolate_after` agreeing
    /// decisions whose hypothesis beats the runner-up by the margin.
    fn multiscale_block(
        &mut self,
        p: &SVector<T, N>,
        x: &Vector3<T>,
        dx: &Vector3<T>,
        e: &SVector<T, N>,
        report: &mut ParityReport<T, N>,
    ) {
        let train_blocks = (self.cfg.train_samples / u32::from(self.cfg.block_len.max(1))).max(12);
        let cfg = self.cfg.multiscale;
        let v = *self.space.v();
        let active = *self.space.active();
        let Some(ms) = self.ms.as_mut() else {
            return;
        };
        // Sensors out of the set may read anything: no vibration regressor.
        let e = SVector::<T, N>::from_fn(|i, _| {
            if active.get(i).copied().unwrap_or(false) {
                e.get(i).copied().unwrap_or(T::zero())
            } else {
                T::zero()
            }
        });
        let phi: SVector<T, REGRESSORS> = ms.regressor(x, dx, &e);
        if !self.ms_trained {
            self.ms_blocks = self.ms_blocks.saturating_add(1);
            if self.ms_blocks <= train_blocks * 2 / 3 {
                ms.learn_calibration(p, &phi, false);
                return;
            }
            if let Some(r) = ms.residual(p, &phi) {
                ms.train_residual(&r, &phi);
            }
            ms.learn_calibration(p, &phi, false);
            if self.ms_blocks >= train_blocks {
                if ms.finish_training(train_blocks).is_some() {
                    self.ms_trained = true;
                } else {
                    // Degenerate training data: start again.
                    *ms = Multiscale::new(cfg, self.space.dim(), ms.threshold_set());
                    self.ms_blocks = 0;
                }
            }
            return;
        }
        let Some(r) = ms.residual(p, &phi) else {
            return;
        };
        let mut d = ms.decide(p, &phi, &r, &v, &active);
        // A relative bias the calibration holds beyond the offset limit is
        // a fault present since power-up (or since training).
        if d.ratio <= T::one() {
            if let Some((k, bias, margin)) = ms.offset_fault(&v, &active) {
                d = MultiscaleDecision {
                    ratio: T::one() + T::lit(1e-3),
                    scale: 0,
                    suspect: Some(k),
                    bias,
                    margin,
                    isolate: Some((k, margin)),
                    learning: false,
                };
            }
        }
        report.decision = true;
        report.multiscale = d;
        report.fault = d.ratio > T::one();
        report.suspect = d.suspect;
        report.bias_estimate = d.bias;
        let candidate = d
            .isolate
            .filter(|(k, m)| report.fault && *m >= cfg.isolation_margin && self.space.isolable(*k))
            .map(|(k, _)| k);
        let Some(k) = candidate else {
            if !report.fault {
                self.suspect_run = (None, 0);
            }
            return;
        };
        self.suspect_run = match self.suspect_run {
            (Some(j), n) if j == k => (Some(k), n.saturating_add(1)),
            _ => (Some(k), 1),
        };
        if self.suspect_run.1 >= self.cfg.isolate_after {
            if let Some(h) = self.health.get_mut(k) {
                h.isolate();
            }
            self.exclude(k);
            report.isolated = Some(k);
            report.fault = false;
        }
    }

    /// One calibration decision: records each statistic against its
    /// threshold, raises no alarm; at the end scales the thresholds.
    fn calibrate(
        &mut self,
        t: &Tests<T, N>,
        block: &SVector<T, N>,
        report: &mut ParityReport<T, N>,
    ) {
        let ratios = [
            report.glt / t.glt_threshold,
            if t.pca_threshold > T::zero() {
                report.pca / t.pca_threshold
            } else {
                T::zero()
            },
            report.cusum_ratio,
        ];
        for (p, r) in self.peaks.iter_mut().zip(ratios.iter()) {
            if r.finite() && *r > *p {
                *p = *r;
            }
        }
        report.flags = DetectorFlags::default();
        report.fault = false;
        // Follow drift during calibration too (the offset keeps learning).
        if self.cfg.drift_blocks > T::one() {
            let gain = T::one() / self.cfg.drift_blocks;
            if let Some(tests) = self.tests.as_mut() {
                tests.baseline.offset += block * gain;
            }
        }
        self.calibrated = self
            .calibrated
            .saturating_add(u32::from(self.cfg.block_len));
        if self.calibrated < self.cfg.calibrate_samples {
            return;
        }
        for (s, p) in self.scales.iter_mut().zip(self.peaks.iter()) {
            *s = (*p * T::lit(1.25)).max(T::one());
        }
        let baseline = self.tests.map(|t| t.baseline);
        self.tests = baseline
            .and_then(|b| derive_tests(&self.space, b, &self.cfg, &self.scales, &self.chi2));
        self.phase = if self.tests.is_some() {
            ParityPhase::Monitoring
        } else {
            ParityPhase::Lost
        };
        self.filled = 0;
        self.head = 0;
        self.cusum_pos = [T::zero(); N];
        self.cusum_neg = [T::zero(); N];
    }

    /// Threshold factors `[GLT, PCA, CUSUM]` set by calibration (1 = the
    /// χ²/ARL thresholds held).
    pub fn threshold_scales(&self) -> [T; 3] {
        self.scales
    }

    /// Removes sensor `k` from the set and carries the learned baseline
    /// into the reduced parity space.
    fn exclude(&mut self, k: usize) {
        match self.removed.get_mut(k) {
            Some(r) if !*r => *r = true,
            _ => return,
        }
        let active: [bool; N] =
            core::array::from_fn(|i| !self.removed.get(i).copied().unwrap_or(true));
        self.block = SVector::zeros();
        self.block_n = 0;
        self.filled = 0;
        self.head = 0;
        self.cusum_pos = [T::zero(); N];
        self.cusum_neg = [T::zero(); N];
        self.suspect_run = (None, 0);
        self.ms_block = BlockSums::default();
        self.ms_prev = None;
        self.ms_prev2 = None;
        match self.space.without(k) {
            Ok(sub) => {
                let c = self.space.transition_to(&sub);
                if let Some(ms) = self.ms.as_mut() {
                    if self.ms_trained {
                        ms.transform(&c, sub.dim());
                    } else {
                        // Failed while training: train the reduced set.
                        *ms = Multiscale::new(self.cfg.multiscale, sub.dim(), ms.threshold_set());
                        self.ms_blocks = 0;
                    }
                }
                if let Some(t) = self.tests {
                    let b = Baseline {
                        offset: c * t.baseline.offset,
                        leak: c * t.baseline.leak,
                        block_cov: c * t.baseline.block_cov * c.transpose(),
                        correlation_factor: t.baseline.correlation_factor,
                    };
                    self.tests = derive_tests(&sub, b, &self.cfg, &self.scales, &self.chi2);
                    if self.tests.is_none() {
                        self.phase = ParityPhase::Lost;
                    }
                } else {
                    // Failed during training: start training the reduced set.
                    self.trainer =
                        Trainer::new(self.cfg.train_samples, self.cfg.block_len, self.cfg.ridge);
                }
                self.space = sub;
            }
            Err(_) => {
                let usable = active.iter().filter(|a| **a).count();
                let rank_ok = usable >= 3
                    && fuse_subset(self.space.geometry(), &SVector::zeros(), &active).is_some();
                self.phase = if rank_ok {
                    ParityPhase::NoRedundancy
                } else {
                    ParityPhase::Lost
                };
                // No parity space is left; fusion uses the health masks.
                self.tests = None;
                self.ms = None;
            }
        }
    }
}

/// Builds every threshold and projection for `space` from `baseline`.
fn derive_tests<T: Real, const N: usize>(
    space: &ParitySpace<T, N>,
    baseline: Baseline<T, N>,
    cfg: &ParityConfig<T>,
    scales: &[T; 3],
    chi2: &[T; N],
) -> Option<Tests<T, N>> {
    let [glt_scale, pca_scale, cusum_scale] = *scales;
    let dim = space.dim();
    if dim == 0 {
        return None;
    }
    // Pad the unused block with identity so the factorisation is full rank.
    let padded = SMatrix::<T, N, N>::from_fn(|i, j| {
        if i < dim && j < dim {
            at(&baseline.block_cov, i, j)
        } else if i == j {
            T::one()
        } else {
            T::zero()
        }
    });
    let l = cholesky(&padded).ok()?;
    let mut cov_inv = cholesky_solve_right(&l, &SMatrix::<T, N, N>::identity());
    let mut a = cholesky_solve_right(&l, &space.v().transpose()).transpose();
    for i in dim..N {
        cov_inv.row_mut(i).fill(T::zero());
        cov_inv.column_mut(i).fill(T::zero());
        a.row_mut(i).fill(T::zero());
    }
    let q: [T; N] = core::array::from_fn(|k| {
        if space.detectable(k) {
            space.v().column(k).dot(&a.column(k))
        } else {
            T::zero()
        }
    });
    let margin = cfg.threshold_margin;
    let glt_threshold = *chi2.get(dim)? * margin * glt_scale;
    let (values, vectors) = symmetric_eigen(&SMatrix::<T, N, N>::from_fn(|i, j| {
        if i < dim && j < dim {
            at(&baseline.block_cov, i, j)
        } else {
            T::zero()
        }
    }))?;
    let pca_dims = dim.min(2);
    let mut pca_basis = SMatrix::<T, N, 2>::zeros();
    let mut pca_var = [T::zero(); 2];
    for c in 0..pca_dims {
        pca_basis.set_column(c, &vectors.column(c));
        if let Some(v) = pca_var.get_mut(c) {
            *v = values.get(c).copied().unwrap_or(T::zero());
        }
    }
    let pca_threshold = *chi2.get(pca_dims)? * margin * pca_scale;
    let mut kappa = [T::zero(); N];
    let mut cusum_h = [T::zero(); N];
    for k in 0..N {
        let (Some(&qk), Some(kk), Some(hk)) = (q.get(k), kappa.get_mut(k), cusum_h.get_mut(k))
        else {
            continue;
        };
        if qk <= T::zero() {
            continue;
        }
        // A bias b on sensor k shifts the standardised projection by b·√q_k.
        let shift = (cfg.cusum_bias * qk.sqrt()).to_f64();
        let kappa_k = 0.5 * shift;
        *kk = T::lit(kappa_k);
        *hk = T::lit(cusum_threshold(kappa_k, cfg.cusum_arl0).ok()?) * margin * cusum_scale;
    }
    Some(Tests {
        baseline,
        cov_inv,
        a,
        q,
        glt_threshold,
        pca_basis,
        pca_var,
        pca_threshold,
        kappa,
        cusum_h,
    })
}

fn at<T: Real, const N: usize>(m: &SMatrix<T, N, N>, i: usize, j: usize) -> T {
    m.get((i, j)).copied().unwrap_or(T::zero())
}

/// Sensor maximising `(a_kᵀ r)² / q_k` and its bias estimate `a_kᵀ r / q_k`.
fn isolate<T: Real, const N: usize>(
    t: &Tests<T, N>,
    r: &SVector<T, N>,
    active: &[bool; N],
) -> (Option<usize>, T) {
    let mut best = (None, T::zero(), T::zero());
    for k in 0..N {
        let (Some(&q), Some(&a)) = (t.q.get(k), active.get(k)) else {
            continue;
        };
        if !a || q <= T::zero() {
            continue;
        }
        let z = t.a.column(k).dot(r);
        let score = z * z / q;
        if score > best.1 {
            best = (Some(k), score, z / q);
        }
    }
    (best.0, best.2)
}

/// Least squares over the sensors marked usable; `None` below rank 3.
fn fuse_subset<T: Real, const N: usize>(
    geometry: &Geometry<T, N>,
    m: &SVector<T, N>,
    usable: &[bool; N],
) -> Option<Vector3<T>> {
    let mut g = nalgebra::Matrix3::<T>::zeros();
    let mut hm = Vector3::<T>::zeros();
    for (k, u) in usable.iter().enumerate() {
        if !u {
            continue;
        }
        let h = geometry.direction(k)?;
        g += h * h.transpose();
        hm += h * m.get(k).copied().unwrap_or(T::zero());
    }
    invert_rank3(&g).map(|inv| inv * hm)
}

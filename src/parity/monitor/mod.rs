//! The redundant-sensor monitor: hardware checks, training, the paper's PCA
//! pattern test, a windowed χ² (GLT) test, per-sensor CUSUMs, isolation by
//! fault direction and reconfiguration, with the fused output every period.

use nalgebra::{SVector, Vector3};

use crate::math::Real;
use crate::stats::chi_square_upper_quantile;

use super::config::{ParityConfig, ParityDetector};
use super::health::{Reading, SensorHealth, SensorStatus};
use super::multiscale::{Multiscale, MultiscaleDecision, SCALES};
use super::training::{Baseline, Trainer};
use super::{ConfigError, Geometry, ParitySpace};
pub use reconfig::reconfig_steps;

mod build;
mod external;
mod flight;
mod fusion;
mod readmit;
mod reconfig;
mod retrain;
mod screen;
mod slots;
mod white;

use flight::BlockSums;
use fusion::{fuse_subset, FusionCache};
use readmit::Readmission;
pub use readmit::MAX_ISOLATIONS;
use reconfig::Reconfig;
use slots::TestSlots;
use white::Tests;

/// Monitor phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParityPhase {
    /// Learning offset, leakage and noise, then (white-noise tests) building
    /// the tests from them one stage per step; no decisions.
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
    /// Sensor re-admitted into the set in this period, after its
    /// probation (multi-scale tests, see `docs/recovery.md`).
    pub readmitted: Option<usize>,
    /// At least half of the sensors still in the set clip this period: a
    /// common-mode saturation (violent manoeuvre, crash), not a sensor fault.
    pub common_mode_saturation: bool,
    /// Parity dimension in use.
    pub parity_dim: usize,
    /// Latest decision of the multi-scale tests (ratio to threshold,
    /// suspect, bias, isolation margin).
    pub multiscale: MultiscaleDecision<T>,
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
    /// The window test has seen a gross bias since the CUSUMs last ran
    /// without one (`white.rs`, `restart_after_gross`).
    cusum_gross: bool,
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
    /// The report, written in place during the step (issue 14: a local
    /// copy and its write-back cost two 124-byte copies per sample on the
    /// M4F); `step_ref` returns a reference to it.
    last: ParityReport<T, N>,
    /// Multi-scale tests (with [`ParityDetector::Multiscale`]) and the
    /// storage of the re-admission shadow's (`readmit.rs`, `slots.rs`).
    ms: TestSlots<T, N, W>,
    /// Block being accumulated for them.
    ms_block: BlockSums<T, N>,
    /// The previous block (`p̄`, `x̄`, per-sensor variance) and the fused
    /// mean before it: a block is processed when the next one is complete,
    /// so its skew regressor is the centred difference.
    ms_prev: Option<(SVector<T, N>, Vector3<T>, SVector<T, N>)>,
    ms_prev2: Option<Vector3<T>>,
    /// Blocks seen since (re)training began.
    ms_blocks: u32,
    /// Blocks the multi-scale alarm still holds after its last decision
    /// above threshold.
    ms_hold: u16,
    /// Consecutive decisions above threshold (the alarm's confirmation).
    ms_above: u16,
    ms_trained: bool,
    /// White-noise tests being built (end of training) or rebuilt (after
    /// an isolation or a failure).
    reconfig: Reconfig<T, N>,
    /// A block completed while the tests were still being built at the end
    /// of training, decided once they are.
    held: Option<SVector<T, N>>,
    /// The fusion's `(HᵀH)⁻¹` over the last usable subset (`None` inside:
    /// that subset is below rank 3). It only changes when the subset does,
    /// so the per-sample fusion reuses it (issue 14: the 3×3 Cholesky and
    /// inverse were ≈ 1 k instructions of every M4F step).
    fusion: Option<FusionCache<T, N>>,
    /// A sensor isolated by the multi-scale tests, judged for re-admission
    /// by the full set's frozen tests (`readmit.rs`).
    readmission: Readmission<T, N>,
}

impl<T: Real, const N: usize, const W: usize> ParityMonitor<T, N, W> {
    /// A monitor of the array `geometry`. Errors: rank-deficient geometry,
    /// fewer than four sensors, a window longer than `W` or zero, a bad
    /// false-alarm probability.
    // Out of line: its temporaries (two `Multiscale` of ≈ 19 KB for nine
    // sensors, the report) then live in its own frame, not in the caller's
    // for as long as the caller runs.
    #[inline(never)]
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
            readmitted: None,
            common_mode_saturation: false,
            parity_dim: space.dim(),
            multiscale: MultiscaleDecision::default(),
        };
        // The multi-scale tests when they are the detector (their
        // thresholds are computed here, once). The monitor is built in the
        // return value, not moved through a builder: each move is a copy
        // of the whole monitor on the stack (≈ 44 KB for nine sensors).
        let ms = match cfg.detector {
            ParityDetector::Multiscale => {
                let h = Multiscale::<T, N, W>::thresholds(&cfg.multiscale)
                    .ok_or(ConfigError::Multiscale)?;
                Some(Multiscale::new(cfg.multiscale, space.dim(), h))
            }
            _ => None,
        };
        Ok(Self {
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
            cusum_gross: false,
            suspect_run: (None, 0),
            removed: [false; N],
            scales: [T::one(); 3],
            peaks: [T::zero(); 3],
            calibrated: 0,
            chi2,
            last: report,
            // The shadow's thresholds come with the learning it is given.
            ms: TestSlots {
                a: ms,
                b: Multiscale::new(cfg.multiscale, space.dim(), [T::one(); SCALES]),
                b_live: false,
            },
            ms_block: BlockSums::default(),
            ms_prev: None,
            ms_hold: 0,
            ms_above: 0,
            ms_prev2: None,
            ms_blocks: 0,
            ms_trained: false,
            reconfig: Reconfig::Idle,
            held: None,
            fusion: None,
            readmission: Readmission::new(space),
        })
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
    ///
    /// Returns a copy of the report; [`step_ref`](Self::step_ref) is the
    /// same step returning a reference to it.
    #[inline]
    pub fn step(&mut self, readings: &[Reading<T>; N]) -> ParityReport<T, N> {
        *self.step_ref(readings)
    }

    /// [`step`](Self::step) returning the report by reference (it lives in
    /// the monitor until the next step): the same step without the copy of
    /// the report into the caller's (issue 14, as `UkfMonitor::step_ref`).
    #[inline(never)] // one copy in the image, not one per caller
    pub fn step_ref(&mut self, readings: &[Reading<T>; N]) -> &ParityReport<T, N> {
        let mut usable = [false; N];
        let mut status = [SensorStatus::Healthy; N];
        let mut quiet = true;
        let (health, removed, cfg) = (&mut self.health, &self.removed, &self.cfg.health);

        // The sample vector built by `from_fn`, in sensor order: a zero fill
        // written over in the loop was not removed by the compiler (a
        // 36-byte `memclr` call per step, 36 instructions on the M4F).
        let mut m = SVector::<T, N>::from_fn(|k, _| {
            let (Some(reading), Some(health), Some(removed)) =
                (readings.get(k), health.get_mut(k), removed.get(k))
            else {
                return T::zero();
            };
            let (value, s) = health.check_unlatched(*reading, cfg);
            // Healthy, or failed before and already out of the set.
            quiet &= s == SensorStatus::Healthy || (*removed && health.failure().is_some());
            if let Some(u) = usable.get_mut(k) {
                *u = value.is_some();
            }
            if let Some(st) = status.get_mut(k) {
                *st = s;
            }
            value.unwrap_or(T::zero())
        });
        // Every sensor healthy or already removed after a failure (the usual
        // period): the screening below would latch, rail and exclude nothing
        // (a latched sensor reports its failure, never `Healthy`, and is
        // skipped by every pass; a healthy sample has no clipping run), and
        // with nothing clipping there is no common-mode saturation, so its
        // passes over the sensors are skipped (issue 14: ≈ 350 instructions
        // per sample on the M4F). A zero `rail_samples` would rail a healthy
        // sensor, so it takes the full screening.
        let common_mode = if quiet && self.cfg.health.rail_samples > 0 {
            false
        } else {
            self.screen_failures(&mut status)
        };
        self.last.decision = false;
        self.last.isolated = None;
        self.last.readmitted = None;
        self.last.common_mode_saturation = common_mode;
        self.last.fused = self.fuse_usable(&m, &usable);
        // One stage of a reconfiguration in progress, or else of the
        // multi-scale block in work (issue 17: a block's work spread over
        // the next block's samples, which may isolate and reconfigure): both
        // before this sample is projected.
        let staged = !self.configured();
        self.advance_reconfig(false);
        self.multiscale_advance(false);
        if self.readmission.judging() {
            self.shadow_step(&mut m);
        }
        if self.training_without_some() {
            self.retrain_if_resumed();
        }
        let all_active_usable = self
            .space
            .active()
            .iter()
            .zip(usable.iter())
            .all(|(a, u)| !a || *u);
        if all_active_usable
            && self.accepts_samples()
            && matches!(
                self.phase,
                ParityPhase::Training | ParityPhase::Calibrating | ParityPhase::Monitoring
            )
        {
            let (p, x) = project(&self.space, &m);
            if self.ms.is_some() {
                // The multi-scale tests alone: the white-noise tests would
                // only cost time (their statistics are not reported).
                self.multiscale_sample(&m, &p, &x);
                if self.ms_trained && self.phase == ParityPhase::Training {
                    self.phase = ParityPhase::Monitoring;
                }
            } else {
                match self.phase {
                    ParityPhase::Training if self.tests.is_none() => self.train(&p, &x),
                    _ => self.monitor(&p, &x, staged),
                }
            }
        }
        self.last.phase = self.phase;
        if matches!(self.phase, ParityPhase::NoRedundancy | ParityPhase::Lost) {
            // No parity space left: nothing is tested, so nothing is
            // alarmed — the phase says the monitor cannot judge (issue 16:
            // the last alarm used to stay in the report for good, found by
            // the parity fuzz target once it checked dimension 1 too).
            self.last.fault = false;
            self.last.flags = DetectorFlags::default();
            self.last.cusum_ratio = T::zero();
            self.last.suspect = None;
        }
        if self.ms.is_some() && !self.ms_trained && self.phase == ParityPhase::Monitoring {
            // The multi-scale tests are still learning: cannot judge yet.
            self.last.phase = ParityPhase::Training;
        }
        self.last.status = status;
        self.last.parity_dim =
            if matches!(self.phase, ParityPhase::NoRedundancy | ParityPhase::Lost) {
                0
            } else {
                self.space.dim()
            };
        if let Some(t) = self.tests.as_ref().filter(|_| self.configured()) {
            self.last.glt_threshold = t.glt_threshold;
            self.last.pca_threshold = t.pca_threshold;
        }
        &self.last
    }

    /// Threshold factors `[GLT, PCA, CUSUM]` set by calibration (1 = the
    /// χ²/ARL thresholds held).
    pub fn threshold_scales(&self) -> [T; 3] {
        self.scales
    }

    /// One more alarmed decision naming sensor `k` (both detectors): after
    /// `isolate_after` in a row it is isolated, removed from the set and
    /// the alarm cleared. True when it was isolated now.
    fn vote_to_isolate(&mut self, k: usize) -> bool {
        self.suspect_run = match self.suspect_run {
            (Some(j), n) if j == k => (Some(k), n.saturating_add(1)),
            _ => (Some(k), 1),
        };
        if self.suspect_run.1 < self.cfg.isolate_after {
            return false;
        }
        if let Some(h) = self.health.get_mut(k) {
            h.isolate();
        }
        if self.ms.is_some() {
            self.start_shadow(k);
            self.exclude_between_blocks(k);
        } else {
            self.exclude(k);
        }
        self.last.isolated = Some(k);
        self.last.fault = false;
        true
    }

    /// Removes sensor `k` from the set and carries the learned baseline
    /// into the reduced parity space.
    fn exclude(&mut self, k: usize) {
        // A reconfiguration still in progress ends first (a second
        // failure within its few steps).
        self.advance_reconfig(true);
        if self.readmission.judging() && !self.readmission.judges(k) {
            // The shadow's space holds the sensor leaving now.
            self.drop_shadow();
        }
        match self.removed.get_mut(k) {
            Some(r) if !*r => *r = true,
            _ => return,
        }
        self.block = SVector::zeros();
        self.block_n = 0;
        self.held = None;
        self.filled = 0;
        self.head = 0;
        self.cusum_pos = [T::zero(); N];
        self.cusum_neg = [T::zero(); N];
        self.cusum_gross = false;
        self.suspect_run = (None, 0);
        self.ms_block = BlockSums::default();
        self.ms_prev = None;
        self.ms_prev2 = None;
        self.ms_hold = 0;
        self.ms_above = 0;
        if let Some(ms) = self.ms.live_mut() {
            // The block in work belongs to the old space.
            ms.cancel();
        }
        // The reduced space and what carries into it: from the next step,
        // in stages.
        self.reconfig = Reconfig::Space(k);
    }

    /// The parity space without sensor `k` (already marked removed); `None`
    /// when none is left: then fusing without monitoring, or lost.
    fn reduced_space(&mut self, k: usize) -> Option<ParitySpace<T, N>> {
        if let Ok(sub) = self.space.without(k) {
            return Some(sub);
        }
        let active: [bool; N] =
            core::array::from_fn(|i| !self.removed.get(i).copied().unwrap_or(true));
        let usable = active.iter().filter(|a| **a).count();
        let rank_ok =
            usable >= 3 && fuse_subset(self.space.geometry(), &SVector::zeros(), &active).is_some();
        self.phase = if rank_ok {
            ParityPhase::NoRedundancy
        } else {
            ParityPhase::Lost
        };
        // No parity space is left; fusion uses the health masks.
        self.drop_shadow();
        self.tests = None;
        self.ms.clear();
        None
    }
}

/// The sample's parity vector `V m` and least-squares body vector, out of
/// line: compiled inside `step_ref` these two products (≈ 230 instructions
/// at best on the M4F) took 60–130 more, by how much else of the step was
/// live in registers around them, which changed with any edit elsewhere.
#[inline(never)]
fn project<T: Real, const N: usize>(
    space: &ParitySpace<T, N>,
    m: &SVector<T, N>,
) -> (SVector<T, N>, Vector3<T>) {
    (space.parity(m), space.fuse(m))
}

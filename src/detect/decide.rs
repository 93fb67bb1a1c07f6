//! The decision rule (\[UKF\] §3, SPEC §5): from the t-test windows of the
//! six innovation channels to a signed flag per IMU channel — the threshold
//! method, a decoupling matrix (the paper's or the run-time one), or GLR
//! isolation on the run-time signature matrix.

use super::{
    decouple_flags, glr_isolate, runtime_sign_matrix, t_statistic, Detector, InnovationWindow,
    Statistic,
};
use crate::math::Real;
use crate::model::{ImuVec, Mat6, NZ};

/// Most simultaneous faults GLR isolation peels off.
const GLR_MAX_FAULTS: usize = 3;

/// What the windows say, per innovation channel (zeros where a window is
/// not full).
#[derive(Debug, Clone, Copy)]
pub(crate) struct WindowEvidence<T> {
    /// The window is full.
    pub full: [bool; NZ],
    /// Test statistic: `t` of the window, or `z` for [`Statistic::Normalized`].
    pub tstat: [T; NZ],
    /// Window mean `r̄`.
    pub rbar: ImuVec<T>,
    /// Inverse variance of the mean (0 where it has none).
    pub weight: ImuVec<T>,
}

/// The statistics of every full window: mean, test statistic and the
/// variance of the mean, after outlier trimming when `outlier_k > 0`.
pub(crate) fn window_evidence<T: Real, const W: usize>(
    windows: &[InnovationWindow<T, W>; NZ],
    statistic: Statistic,
    outlier_k: T,
) -> WindowEvidence<T> {
    // Per innovation channel with a full window: (statistic, mean, variance of the mean).
    let stats: [Option<(T, T, T)>; NZ] = core::array::from_fn(|i| {
        let w = windows.get(i)?;
        if !w.is_full() {
            return None;
        }
        let s = if outlier_k > T::zero() {
            w.stats_trimmed(outlier_k)?.0
        } else {
            w.stats()?
        };
        let n = T::lit(s.n as f64);
        Some(match statistic {
            Statistic::Normalized => (s.mean * n.sqrt_fast(), s.mean, T::one() / n),
            _ => (t_statistic(&s), s.mean, s.std * s.std / n),
        })
    });
    WindowEvidence {
        full: stats.map(|s| s.is_some()),
        tstat: stats.map(|s| s.map_or(T::zero(), |v| v.0)),
        rbar: ImuVec::from_iterator(stats.iter().map(|s| s.map_or(T::zero(), |v| v.1))),
        weight: ImuVec::from_iterator(stats.iter().map(|s| {
            s.map_or(T::zero(), |v| {
                if v.2 > T::zero() {
                    T::one() / v.2
                } else {
                    T::zero()
                }
            })
        })),
    }
}

/// The two-sided test per channel: +1 / −1 where the statistic reaches the
/// critical value, else 0.
pub(crate) fn test_flags<T: Real>(tstat: &[T; NZ], threshold: T) -> [i8; NZ] {
    tstat.map(|t| {
        if t >= threshold {
            1i8
        } else if t <= -threshold {
            -1
        } else {
            0
        }
    })
}

/// The decision rule and the tuning it reads.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DecisionRule<'a, T> {
    /// Which rule.
    pub detector: Detector,
    /// Inverse of the paper's sign matrix, for the paper-matrix rules.
    pub paper_inv: Option<&'a Mat6<T>>,
    /// Smallest fault per IMU channel (threshold method, run-time matrix).
    pub min_fault: &'a ImuVec<T>,
    /// Threshold method: fraction of `min_fault` the mapped mean must exceed.
    pub threshold_fraction: T,
    /// Run-time sign matrix dead-band, relative to the row maximum.
    pub sign_deadband: T,
    /// GLR acceptance threshold.
    pub glr_threshold: T,
    /// GLR: relative size of a further simultaneous fault.
    pub glr_relative: T,
}

impl<T: Real> DecisionRule<'_, T> {
    /// Signed flag per IMU channel from the test flags, the window means
    /// `rbar` with their weights, and the signature matrix `m_eff` in the
    /// windows' units (rows innovations, columns faults).
    pub(crate) fn decide(
        &self,
        m_eff: &Mat6<T>,
        flags: &[i8; NZ],
        rbar: &ImuVec<T>,
        weight: &ImuVec<T>,
    ) -> [i8; NZ] {
        // Without the feature `alt-detectors` the configuration admits only
        // GLR (`UkfMonitorConfig::validate`): the other rules are left out.
        let detector = if cfg!(feature = "alt-detectors") {
            self.detector
        } else {
            Detector::RuntimeMatrixGlr
        };
        match detector {
            Detector::Threshold => {
                let mut d = [0i8; NZ];
                let diag = m_eff.diagonal();
                for ((((dj, fl), r), mjj), mf) in d
                    .iter_mut()
                    .zip(flags.iter())
                    .zip(rbar.iter())
                    .zip(diag.iter())
                    .zip(self.min_fault.iter())
                {
                    if *fl != 0 && *mjj != T::zero() {
                        let f = *r / *mjj;
                        if f.abs() > *mf * self.threshold_fraction {
                            *dj = if f > T::zero() { 1 } else { -1 };
                        }
                    }
                }
                d
            }
            Detector::PaperMatrix | Detector::PaperMatrixAsPrinted => match self.paper_inv {
                Some(ci) => decouple_flags(ci, flags).0,
                None => [0; NZ],
            },
            Detector::RuntimeMatrix => {
                let sigma = weight.map(|w| {
                    if w > T::zero() {
                        T::one() / w.sqrt_fast()
                    } else {
                        T::zero()
                    }
                });
                let c = runtime_sign_matrix(m_eff, self.min_fault, &sigma, self.sign_deadband);
                match crate::math::try_inverse(&c) {
                    Some(ci) => decouple_flags(&ci, flags).0,
                    None => [0; NZ],
                }
            }
            Detector::RuntimeMatrixGlr => {
                if flags.iter().any(|f| *f != 0) {
                    glr_isolate(
                        m_eff,
                        rbar,
                        weight,
                        self.glr_threshold,
                        self.glr_relative,
                        GLR_MAX_FAULTS,
                    )
                    .signs
                } else {
                    [0; NZ]
                }
            }
        }
    }
}

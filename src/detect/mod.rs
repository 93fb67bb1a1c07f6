//! Innovation-based fault detection (\[UKF\] §3, SPEC §5): ring-buffer windows,
//! the windowed t-test, the threshold and decoupling-matrix methods,
//! signature-based (GLR) isolation, and the fault estimators of SPEC §6.

mod decide;
mod decouple;
mod estimator;
mod glr;
mod persistence;
mod ttest;
mod window;

pub(crate) use decide::{test_flags, window_evidence, DecisionRule, WindowEvidence};
pub use decouple::{
    decouple_flags, paper_matrix, runtime_sign_matrix, PAPER_MATRIX_AS_PRINTED,
    PAPER_MATRIX_CORRECTED,
};
pub use estimator::{estimate_as_written, estimate_corrected};
pub(crate) use estimator::{estimate_as_written_blocks, estimate_as_written_identity};
pub use glr::{glr_isolate, GlrResult};
pub use persistence::Persistence;
pub use ttest::{t_statistic, TTest};
pub use window::{InnovationWindow, WindowStats};

/// Which decision rule turns innovation statistics into IMU channel flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Detector {
    /// \[UKF\] §3.1: IMU channel i ↔ innovation channel i, flagged when its
    /// t-test fires and |window mean| exceeds the channel threshold.
    Threshold,
    /// \[UKF\] §3.2 with the paper's fixed sign matrix (erratum applied).
    PaperMatrix,
    /// \[UKF\] §3.2 with the paper's matrix exactly as printed (a_x sign wrong).
    PaperMatrixAsPrinted,
    /// `C⁻¹·flag` with `C` the dead-banded sign pattern of the closed-loop
    /// signature matrix `M`, rebuilt every update.
    RuntimeMatrix,
    /// The default: t-tests trigger, and the run-time signature matrix `M`
    /// isolates by greedy GLR (simultaneous faults are peeled off one by one
    /// while the residual is still significant).
    RuntimeMatrixGlr,
}

/// Which samples enter the t-test windows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Statistic {
    /// The paper's test on raw innovations (variance estimated in the window).
    Raw,
    /// The same t-test on innovations pre-whitened by the filter's `√S_ii`.
    Whitened,
    /// Windowed normalised-innovation test: the filter's `S_ii` is used as
    /// the known variance, `z = Σ rᵢ/√S_ii / √n`, compared with the normal
    /// quantile. No variance is estimated in the window, so it reacts as soon
    /// as a few in-fault samples arrive instead of when the window is full of
    /// them (SPEC §5 "stronger alternative").
    Normalized,
}

//! Filters: the generic fixed-size unscented Kalman filter and its sigma-point
//! machinery, the per-channel diagnostic record every update produces, and
//! the optimal two-stage UKF (OTSUKF, [`Otsukf`]) for joint state and fault estimation.

mod diag;
mod sigma;
mod two_stage;
mod ukf;

pub use diag::{ChannelDiag, Gate};
pub use sigma::{SigmaParams, SigmaWeights};
pub use two_stage::{Otsukf, OtsukfUpdate};
pub use ukf::{Ukf, UkfError, UpdateOutput};

/// The OTSUKF filter's former name.
#[deprecated(note = "renamed `Otsukf`: the optimal two-stage UKF (OTSUKF)")]
pub type TwoStageUkf<T, const N: usize, const S: usize, const L: usize> = Otsukf<T, N, S, L>;
/// The OTSUKF update output's former name.
#[deprecated(note = "renamed `OtsukfUpdate`")]
pub type TwoStageUpdate<T, const N: usize, const M: usize, const L: usize> =
    OtsukfUpdate<T, N, M, L>;

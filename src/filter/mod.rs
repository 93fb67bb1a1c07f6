//! Filters: the generic fixed-size unscented Kalman filter and its sigma-point
//! machinery, the per-channel diagnostic record every update produces, and
//! the optimal two-stage UKF for joint state and fault estimation.

mod diag;
mod sigma;
mod two_stage;
mod ukf;

pub use diag::{ChannelDiag, Gate};
pub use sigma::{SigmaParams, SigmaWeights};
pub use two_stage::{TwoStageUkf, TwoStageUpdate};
pub use ukf::{Ukf, UkfError, UpdateOutput};

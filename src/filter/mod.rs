//! Filters: the generic fixed-size unscented Kalman filter and its sigma-point
//! machinery, plus the per-channel diagnostic record every update produces.

mod diag;
mod sigma;
mod ukf;

pub use diag::{ChannelDiag, Gate};
pub use sigma::{SigmaParams, SigmaWeights};
pub use ukf::{Ukf, UkfError, UpdateOutput};

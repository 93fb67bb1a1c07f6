//! Numerics shared by every filter: the scalar trait (`f32` on target, `f64`
//! for references), fast accurate `f32` trigonometry, angle wrapping and a
//! fixed-size Cholesky factorisation that fails with a value, not a panic.

mod angle;
mod cholesky;
mod real;
mod trig;

pub use angle::{wrap_pi, wrap_pi_f64};
pub use cholesky::{cholesky, cholesky_solve_right, symmetrize, LinalgError};
pub use real::Real;
pub use trig::sin_cos_f32;

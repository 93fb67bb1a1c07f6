//! Numerics shared by every filter: the scalar trait (`f32` on target, `f64`
//! for references), fast accurate `f32` trigonometry, angle wrapping and a
//! fixed-size Cholesky factorisation that fails with a value, not a panic.

mod angle;
mod cholesky;
mod identity;
mod inverse;
mod jacobi;
mod real;
mod sqrt;
mod trig;

pub use angle::{wrap_pi, wrap_pi_f64};
pub use cholesky::{
    add_outer_lower, cholesky, cholesky_reference, cholesky_solve_right, mirror_lower, symmetrize,
    LinalgError,
};
pub(crate) use cholesky::{lower_finite, mirror_lower_into, sub_product};
pub use identity::is_identity;
pub use inverse::try_inverse;
pub use jacobi::symmetric_eigen;
pub(crate) use real::all_finite;
pub use real::Real;
pub use sqrt::sqrt_f32;
pub use trig::{shift_sin_cos, sin_cos_f32};

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

/// `s`, hidden from the optimiser: a loop over it (and only over such
/// slices: a fixed-size array in the same `zip` bounds the trip count
/// again) stays rolled, its length unknown at compile time. For code off
/// the measured step (end of learning, re-alignment, options the presets
/// leave off), where a fully unrolled fixed-size loop costs flash and
/// saves no instruction that counts (issue 17). The loop's operations and
/// their order are unchanged.
#[inline(always)]
pub(crate) fn rolled<X>(s: &[X]) -> &[X] {
    core::hint::black_box(s)
}

/// An empty barrier the optimiser cannot see through: in the body of a
/// loop over [`rolled`] slices it keeps the loop from being unrolled at run
/// time as well (the Cortex-M4F's unroller leaves loops with calls alone),
/// at no instruction of its own.
#[inline(always)]
pub(crate) fn keep_rolled() {
    core::hint::black_box(());
}

/// [`rolled`] for a mutable slice.
#[inline(always)]
pub(crate) fn rolled_mut<X>(s: &mut [X]) -> &mut [X] {
    core::hint::black_box(s)
}

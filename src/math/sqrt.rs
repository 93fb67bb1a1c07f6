//! `f32` square root for the filters' hot path.
//!
//! `libm::sqrtf` is a software routine on ARM (61 instructions on the
//! Cortex-M4F, measured under QEMU), while the FPU has `vsqrt.f32` (one
//! instruction, 14 cycles). Rust has no stable `core` square root, and inline
//! `asm!` cannot name the single-precision registers on this target (its
//! `sreg` class requires the double-precision `vfp2` feature the M4F lacks),
//! so the instruction lives in a two-instruction naked function: with the
//! hard-float ABI (`eabihf`) the argument and the result are both in `s0`.
//! Everywhere else (host tests, soft-float targets) it is `libm::sqrtf`,
//! which is correctly rounded — as is `vsqrt` — so both give identical bits.

/// Correctly rounded `√x` (NaN for negative input, as IEEE 754 requires).
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[inline]
pub fn sqrt_f32(x: f32) -> f32 {
    vsqrt(x)
}

/// Correctly rounded `√x` (NaN for negative input, as IEEE 754 requires).
#[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
#[inline]
pub fn sqrt_f32(x: f32) -> f32 {
    libm::sqrtf(x)
}

// The one unsafe item of the crate: a naked function is `unsafe` to declare
// because the compiler cannot check that its body follows the calling
// convention. Here it does: AAPCS-VFP passes the first `f32` argument in s0
// and returns an `f32` in s0; vsqrt touches nothing else; `bx lr` returns.
// `.fpu` names the M4F's FPU for the assembler, which otherwise assumes none.
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[allow(unsafe_code)]
#[unsafe(naked)]
extern "C" fn vsqrt(_x: f32) -> f32 {
    core::arch::naked_asm!(".fpu fpv4-sp-d16", "vsqrt.f32 s0, s0", "bx lr")
}

//! # imu-fdi-qemu
//!
//! The software-in-the-loop images of `imu-fdi` for QEMU's `netduinoplus2`
//! (STM32F405, Cortex-M4F): `sil` (scenario S2 from `hal-sim` through the
//! `f32` monitor, or through the driver and the periodic task with
//! `sil-chip`) and `target-tests` (f32 numerics and costs on the target).
//! Run them with `cargo sil`, `cargo sil-chip`, `cargo target-tests` or
//! `scripts/qemu-sil.sh`.
//!
//! The library holds what both images share: instruction counting; and
//! the comparison with the `kfilter` crate's UKF ([`kfilter_cmp`]).
#![no_std]
#![allow(unsafe_code)] // one volatile read of a peripheral register

/// TIM2 counter (CNT) of the STM32F4 (TIM2 base 0x4000_0000 + 0x24).
#[cfg(target_os = "none")]
const TIM2_CNT: *const u32 = 0x4000_0024 as *const u32;

/// Instructions executed so far (mod 2³²). Under `qemu-system-arm -icount
/// shift=0` the TIM2 counter advances once per executed instruction without
/// any timer set-up, so two reads around a call give its cost, repeatably.
#[cfg(target_os = "none")]
pub fn instructions() -> u32 {
    // SAFETY: a read-only, aligned, always-mapped peripheral register.
    unsafe { core::ptr::read_volatile(TIM2_CNT) }
}

#[cfg(all(target_os = "none", feature = "sil"))]
pub mod kfilter_cmp;

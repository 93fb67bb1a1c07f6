//! Instruction counting on QEMU's `netduinoplus2` (STM32F405), for the
//! software-in-the-loop and on-target test images.
#![allow(unsafe_code)] // one volatile read of a peripheral register

/// TIM2 counter (CNT) of the STM32F4 (TIM2 base 0x4000_0000 + 0x24).
const TIM2_CNT: *const u32 = 0x4000_0024 as *const u32;

/// Instructions executed so far (mod 2³²). Under `qemu-system-arm -icount
/// shift=0` the TIM2 counter advances once per executed instruction without
/// any timer set-up, so two reads around a call give its cost, repeatably.
pub fn instructions() -> u32 {
    // SAFETY: a read-only, aligned, always-mapped peripheral register.
    unsafe { core::ptr::read_volatile(TIM2_CNT) }
}

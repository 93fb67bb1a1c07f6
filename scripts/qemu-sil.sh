#!/usr/bin/env bash
# On QEMU's netduinoplus2 (STM32F405, Cortex-M4F):
#  1. the on-target tests (hal-sim/src/bin/target_tests.rs): f32 numerics on
#     the emulated FPU against host-computed expectations, plus a profile of
#     the pieces of a monitor step in instructions;
#  2. the software-in-the-loop image (hal-sim/src/bin/sil.rs): scenario S2
#     through the f32 monitor, with instructions per step, peak stack, and
#     the image's flash and static RAM.
# Exits non-zero if a test fails, the image faults, or S2 is not detected.
set -euo pipefail
cd "$(dirname "$0")/.."
elf=target/thumbv7em-none-eabihf/release/sil
echo "== on-target tests (QEMU)"
timeout 300 cargo target-tests -q
echo "== S2 software-in-the-loop (QEMU)"
cargo build -q -p hal-sim --bin sil --no-default-features --features sil --target thumbv7em-none-eabihf --release
timeout 300 cargo sil -q
echo "image sizes (bytes; .text + .rodata + .vector_table are flash, .data + .bss static RAM):"
size -A "$elf" | awk '$1 ~ /^\.(vector_table|text|rodata|data|bss|uninit)$/ { print "  " $1, $2; if ($1 != ".data" && $1 != ".bss" && $1 != ".uninit") f += $2; else r += $2 } END { printf "  flash %d (%.1f KiB)\n", f, f / 1024; print "  static RAM", r }'
echo "note: the SIL image also carries hal-sim's f64 vehicle/sensor simulation (software double precision on the M4F)."

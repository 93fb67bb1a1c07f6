#!/usr/bin/env bash
# On QEMU's netduinoplus2 (STM32F405, Cortex-M4F):
#  1. the on-target tests (qemu/src/bin/target_tests.rs): f32 numerics on
#     the emulated FPU against host-computed expectations, and a profile of
#     the pieces of a monitor step in instructions;
#  2. the software-in-the-loop image (qemu/src/bin/sil.rs): scenario S2
#     straight into the f32 monitor — instructions per step, peak stack,
#     flash and static RAM (the budget figures);
#  3. the same image along the firmware's data path (feature sil-chip): the
#     ICM-42688-P driver reading hal-sim's emulated chip, into the Monitor task.
# Exits non-zero if a test fails, an image faults, or S2 is not detected.
set -euo pipefail
cd "$(dirname "$0")/.."
elf=target/thumbv7em-none-eabihf/release/sil
sizes() {
  size -A "$elf" | awk '$1 ~ /^\.(vector_table|text|rodata|data|bss|uninit)$/ { if ($1 != ".data" && $1 != ".bss" && $1 != ".uninit") f += $2; else r += $2 } END { printf "image: flash %d bytes (%.1f KiB; .vector_table + .text + .rodata), static RAM %d bytes (.data + .bss)\n", f, f / 1024, r }'
}
echo "== on-target tests (QEMU)"
timeout 300 cargo target-tests -q
echo "== S2 software-in-the-loop, monitor (QEMU)"
timeout 300 cargo sil -q
sizes
echo "== S2 software-in-the-loop, driver + emulated chip + Monitor task (QEMU)"
timeout 300 cargo sil-chip -q | sed 's/^fault /chip fault /'
sizes
echo "note: both SIL images also carry hal-sim's f64 vehicle/sensor simulation (software double precision on the M4F)."

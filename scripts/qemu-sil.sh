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
# Exits non-zero if a test fails, an image faults, S2 is not detected, or
# either image's peak stack exceeds issue 17's 12,288 B (sil.rs,
# STACK_BUDGET).
set -euo pipefail
cd "$(dirname "$0")/.."
elf=target/thumbv7em-none-eabihf/mcu/sil
sizes() {
  size -A "$elf" | awk '$1 ~ /^\.(vector_table|text|rodata|data|bss|uninit)$/ { if ($1 != ".data" && $1 != ".bss" && $1 != ".uninit") f += $2; else r += $2 } END { printf "image: flash %d bytes (%.1f KiB; .vector_table + .text + .rodata), static RAM %d bytes (.data + .bss)\n", f, f / 1024, r }'
}
echo "== on-target tests (QEMU)"
timeout 300 cargo target-tests -q | tee target/qemu-target-tests.txt
echo "== S2 software-in-the-loop, monitor (QEMU)"
timeout 300 cargo sil -q | tee target/qemu-sil-monitor.txt
sizes | tee -a target/qemu-sil-monitor.txt
echo "== S2 software-in-the-loop, driver + emulated chip + Monitor task (QEMU)"
timeout 300 cargo sil-chip -q | tee target/qemu-sil-chip.txt | sed 's/^fault /chip fault /'
sizes
echo "note: both SIL images also carry hal-sim's f64 vehicle/sensor simulation (software double precision on the M4F)."

# The budget figures as one line of JSON (issue 17): instructions per step
# (UKF monitor: the S2 SIL image; two-stage monitor and parity: the on-target
# tests; parity_readmit_step: the step that re-admits a sensor isolated by a
# 1-s glitch, parity_readmit_flight_step_max: that flight's largest step), peak stack of the S2 SIL image and of its monitor steps alone
# (the deepest write below the caller's frame) and, last in the line,
# chip_stack_peak_bytes: the peak stack of the chip-path image; flash of the firmware, of the
# SIL image and of the imu_fdi code inside the firmware (sum of the sizes of
# its `imu_fdi::` symbols, from arm-none-eabi-nm); and the kfilter 0.5 UKF's
# predict + update on the same model and aiding (the on-target tests), with
# kfilter_ratio = UKF monitor step mean ÷ kfilter predict + update (the
# issue's definition: the monitor's mean step, most of them predict-only)
# and kfilter_filter_ratio = imu-fdi's own Ukf predict + update ÷ kfilter's
# (the like-for-like pair).
if ! command -v arm-none-eabi-nm >/dev/null; then
  apt-get update -qq && apt-get install -y -qq binutils-arm-none-eabi >/dev/null
fi
cargo build-firmware -q
fw=target/thumbv7em-none-eabihf/mcu/firmware
flash() {
  size -A "$1" | awk '$1 ~ /^\.(vector_table|text|rodata)$/ { f += $2 } END { print f }'
}
field() { # field FILE REGEX: the first number captured by REGEX
  sed -n -E "s/$2/\1/p" "$1" | head -n 1
}
tt=target/qemu-target-tests.txt
sm=target/qemu-sil-monitor.txt
sc=target/qemu-sil-chip.txt
kf=$(field "$tt" '^kfilter 0.5 UKF.*predict\+update mean ([0-9]+) instructions.*')
ours=$(field "$tt" '^kfilter 0.5 UKF.*imu-fdi Ukf predict_split\+update mean ([0-9]+).*')
ukf_mean=$(field "$sm" '^instructions per step: mean ([0-9]+) max [0-9]+.*')
imu_fdi_bytes=$(arm-none-eabi-nm --size-sort -C -S --radix=d "$fw" | awk '$3 ~ /^[tTrR]$/ && /imu_fdi::/ { s += $2 } END { print s + 0 }')
printf '{"ukf_step_mean":%s,"ukf_step_max":%s,"otsukf_step_mean":%s,"otsukf_step_max":%s,"parity_step_mean":%s,"parity_step_max":%s,"parity_config":%s,"parity_flight_step_mean":%s,"parity_flight_step_max":%s,"parity_flight_config":%s,"parity_readmit_step":%s,"parity_readmit_flight_step_max":%s,"stack_peak_bytes":%s,"monitor_stack_bytes":%s,"firmware_flash_bytes":%s,"sil_flash_bytes":%s,"imu_fdi_flash_bytes":%s,"kfilter_step_mean":%s,"ukf_filter_step_mean":%s,"kfilter_ratio":%s,"kfilter_filter_ratio":%s,"chip_stack_peak_bytes":%s}\n' \
  "$ukf_mean" \
  "$(field "$sm" '^instructions per step: mean [0-9]+ max ([0-9]+).*')" \
  "$(field "$tt" '^two-stage UKF monitor .*mean ([0-9]+) max [0-9]+ instructions.*')" \
  "$(field "$tt" '^two-stage UKF monitor .*mean [0-9]+ max ([0-9]+) instructions.*')" \
  "$(field "$tt" '^parity monitor \(cone6.*per step mean ([0-9]+) max [0-9]+.*')" \
  "$(field "$tt" '^parity monitor \(cone6.*per step mean [0-9]+ max ([0-9]+).*')" \
  "$(field "$tt" '^parity monitor \(cone6.*configuration ([0-9]+) instructions.*')" \
  "$(field "$tt" '^parity monitor for real flights .*per step mean ([0-9]+) max [0-9]+.*')" \
  "$(field "$tt" '^parity monitor for real flights .*per step mean [0-9]+ max ([0-9]+).*')" \
  "$(field "$tt" '^parity monitor for real flights .*configuration ([0-9]+) instructions.*')" \
  "$(field "$tt" '^parity monitor re-admission .*re-admitting step ([0-9]+) instructions.*')" \
  "$(field "$tt" '^parity monitor re-admission .*largest step ([0-9]+) instructions.*')" \
  "$(field "$sm" '^peak stack: ([0-9]+) bytes.*')" \
  "$(field "$sm" '^monitor step stack: ([0-9]+) bytes.*')" \
  "$(flash "$fw")" \
  "$(field "$sm" '^image: flash ([0-9]+) bytes.*')" \
  "$imu_fdi_bytes" \
  "$kf" "$ours" \
  "$(awk -v a="$ukf_mean" -v b="$kf" 'BEGIN { printf "%.3f", a / b }')" \
  "$(awk -v a="$ours" -v b="$kf" 'BEGIN { printf "%.3f", a / b }')" \
  "$(field "$sc" '^peak stack: ([0-9]+) bytes.*')"

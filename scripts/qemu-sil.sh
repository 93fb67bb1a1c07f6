#!/usr/bin/env bash
# Runs the software-in-the-loop image (S2 through the f32 monitor on QEMU's
# STM32F405) and prints its instruction counts, stack high-water mark, flash
# and static RAM. Exits non-zero if the image fails or detects differently.
set -euo pipefail
cd "$(dirname "$0")/.."
elf=target/thumbv7em-none-eabihf/release/sil
cargo build -q -p hal-sim --bin sil --no-default-features --features sil --target thumbv7em-none-eabihf --release
timeout 300 cargo sil -q
echo "image sizes (bytes; .text + .rodata + .vector_table are flash, .data + .bss static RAM):"
size -A "$elf" | awk '$1 ~ /^\.(vector_table|text|rodata|data|bss|uninit)$/ { print "  " $1, $2; if ($1 != ".data" && $1 != ".bss" && $1 != ".uninit") f += $2; else r += $2 } END { print "  flash", f; print "  static RAM", r }'
echo "note: this image also contains hal-sim's f64 vehicle/sensor simulation and the profiling code."

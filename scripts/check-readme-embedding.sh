#!/usr/bin/env bash
# Builds the README's `no_std` embedding — its TOML and Rust blocks under
# "Using the crate", nothing else — as an external crate for the MCU target,
# with the dependency pointed at this checkout (issue 18).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
section=$(sed -n '/^## Using the crate/,/^## /p' "$root/README.md")
toml=$(printf '%s\n' "$section" | sed -n '/^```toml$/,/^```$/p' | sed '1d;$d')
rust=$(printf '%s\n' "$section" | awk '/^```rust$/{n++; if (n==1) {on=1; next}} on && /^```$/{exit} on')
[ -n "$toml" ] && [ -n "$rust" ] || { echo "README: no embedding blocks under 'Using the crate'" >&2; exit 1; }
mkdir -p "$work/src"
{
  printf '[package]\nname = "readme-embedding"\nversion = "0.0.0"\nedition = "2021"\n\n[workspace]\n\n'
  # The README's dependency line, pointed at this checkout.
  printf '%s\n' "$toml" | sed -E "s|^imu-fdi = .*|imu-fdi = { path = \"$root\" }|"
} > "$work/Cargo.toml"
printf '%s\n' "$rust" > "$work/src/lib.rs"
CARGO_TARGET_DIR="$root/target/readme-embedding" \
  cargo build --quiet --release --manifest-path "$work/Cargo.toml" --target thumbv7em-none-eabihf
echo "README embedding: builds for thumbv7em-none-eabihf (no_std, $(wc -l < "$work/src/lib.rs") lines)"

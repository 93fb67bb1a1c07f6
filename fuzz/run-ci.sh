#!/usr/bin/env bash
# Runs every fuzz target for a bounded time on a copy of its checked-in
# seed corpus (the worktree stays clean). Usage: fuzz/run-ci.sh [seconds per target]
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-25}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The CLI targets write their input to a scratch file: keep it in memory.
export TMPDIR=$work
cargo +nightly fuzz build -s none -O
for t in $(cargo +nightly fuzz list); do
  mkdir -p "$work/corpus/$t"
  cp corpus/"$t"/seed-* "$work/corpus/$t/" 2>/dev/null || true
  mkdir -p "$work/artifacts/$t"
  echo "fuzz $t: ${secs} s"
  if ! cargo +nightly fuzz run -s none -O "$t" "$work/corpus/$t" -- \
    -max_total_time="$secs" -print_final_stats=1 -artifact_prefix="$work/artifacts/$t/" \
    >"$work/$t.log" 2>&1; then
    tail -n 60 "$work/$t.log" >&2
    echo "fuzz $t found a failure (input above; rerun locally, see fuzz/README.md)" >&2
    exit 1
  fi
  grep -E '^(stat::number_of_executed_units|imu-fdi-fuzz)' "$work/$t.log" || true
done

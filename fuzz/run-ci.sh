#!/usr/bin/env bash
# The CI's fuzz step: a reproducible regression run. Every target starts
# from a copy of its checked-in seeds (corpus/<target>/seed-*; the worktree
# stays clean) with a fixed libFuzzer seed and a fixed number of inputs, so
# every run tries the same inputs and a failure in CI reproduces locally
# with the same command. The input counts are sized to about 25 s per
# target on the CI machine (2 shared cores), measured with --measure.
# Long exploratory runs: fuzz/README.md.
#
# Usage: fuzz/run-ci.sh                 the regression run (what .ci/run does)
#        fuzz/run-ci.sh --measure [S]   each target for S s (25) with the same
#                                       seed: prints the inputs it ran, to size RUNS
set -euo pipefail
cd "$(dirname "$0")"

# libFuzzer's -seed: the random sequence of mutations.
SEED=1
# Inputs per target (-runs=): what `run-ci.sh --measure 25` ran in 25 s on
# the development machine (2 cores shared with other builds, load ≈ 6, 25 Nov
# 2026), rounded down; a less loaded machine takes less.
declare -A RUNS=(
  [csv_files]=7000
  [dataflash_file]=7000
  [icm42688]=6000000
  [otsukf_monitor]=1400
  [parity_monitor]=40000
  [toml_scenario]=7500
  [ukf_monitor]=1900
  [ulog_file]=5500
)

mode=ci
secs=25
if [ "${1:-}" = "--measure" ]; then
  mode=measure
  secs=${2:-25}
elif [ $# -gt 0 ]; then
  echo "usage: fuzz/run-ci.sh [--measure [seconds]]" >&2
  exit 2
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The CLI targets write their input to a scratch file: keep it in memory.
export TMPDIR=$work
cargo +nightly fuzz build -s none -O
for t in $(cargo +nightly fuzz list); do
  if [ "$mode" = measure ]; then
    limit="-max_total_time=$secs"
  else
    runs=${RUNS[$t]:-}
    if [ -z "$runs" ]; then
      echo "fuzz/run-ci.sh: no input count for target $t: add it to RUNS (run-ci.sh --measure)" >&2
      exit 1
    fi
    limit="-runs=$runs"
  fi
  mkdir -p "$work/corpus/$t" "$work/artifacts/$t"
  cp corpus/"$t"/seed-* "$work/corpus/$t/" 2>/dev/null || true
  start=$(date +%s)
  if ! cargo +nightly fuzz run -s none -O "$t" "$work/corpus/$t" -- \
    -seed="$SEED" "$limit" -print_final_stats=1 -artifact_prefix="$work/artifacts/$t/" \
    >"$work/$t.log" 2>&1; then
    tail -n 60 "$work/$t.log" >&2
    echo "fuzz $t found a failure (input above, base64 for short ones); the same run reproduces it: bash fuzz/run-ci.sh" >&2
    exit 1
  fi
  inputs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/$t.log" | tail -1)
  echo "fuzz $t: ${inputs:-?} inputs in $(($(date +%s) - start)) s (-seed=$SEED $limit)"
  grep -E '^imu-fdi-fuzz' "$work/$t.log" | tail -1 || true
done

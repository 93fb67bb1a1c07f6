#!/usr/bin/env bash
# Regenerates the README gallery into target/gallery and fails if any
# committed PNG in docs/gallery differs (the figures must stay true).
# To update: cargo sim gallery   (writes docs/gallery), then commit.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run -q -p imu-fdi-cli --release --bin imu-fdi-sim -- gallery --out target/gallery > /dev/null
status=0
for f in docs/gallery/*.png; do
  if ! cmp -s "$f" "target/gallery/$(basename "$f")"; then
    echo "gallery drift: $f differs from a fresh 'cargo sim gallery'"
    status=1
  fi
done
n_new=$(ls target/gallery/*.png | wc -l)
n_old=$(ls docs/gallery/*.png | wc -l)
if [ "$n_new" != "$n_old" ]; then
  echo "gallery drift: $n_new figures generated, $n_old committed"
  status=1
fi
[ $status -eq 0 ] && echo "gallery: $n_old committed figures identical to a fresh run"
exit $status

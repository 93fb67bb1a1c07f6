#!/usr/bin/env bash
# Issue 15's power-up figures on log171: a bias present from the first row
# on one channel of one IMU (every channel in turn), replayed through one
# single-IMU monitor (ukf | otsukf) with learning from FROM (default 80 s).
# Prints, per channel, the time from monitoring start to the first flag of
# the right sign ("MISS": never) and, in brackets, the flag events on the
# IMU's other channels. Needs python3.
# Sizes: ACC (m/s², default 4) and GYRO_DEG (°/s, default 10); IMU (default
# 0); SIGN (1 or -1, default 1).
# Usage: scripts/single-imu-power-up.sh [ukf|otsukf] [extra replay options]
#   e.g. scripts/single-imu-power-up.sh ukf --turn-on-bias 4,20   (the former bound)
set -euo pipefail
cd "$(dirname "$0")/.."
MON=${1:-ukf}
shift || true
ACC=${ACC:-4}
FROM=${FROM:-80}
IMU=${IMU:-0}
SIGN=${SIGN:-1}
GYRO=$(python3 -c "import math; print(math.radians(${GYRO_DEG:-10}))")
DATA=${DATA:-tests/data}
BIN=./target/release/imu-fdi-sim
cargo build -q -p imu-fdi-cli --release --bin imu-fdi-sim
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
line="$MON, learning from $FROM s, IMU$IMU, ${ACC} m/s² / ${GYRO_DEG:-10} °/s from power-up:"
for ch in 0 1 2 3 4 5; do
  cat >"$TMP/f.toml" <<TOML
[sizes]
accel = [$ACC, 0.0, 0.0]
gyro = [$GYRO, 0.0, 0.0]
f_unit = [1.0, 0.017453292519943295]
[[faults]]
channel = $ch
start = 0.0
end = 100000.0
kind = "E1"
sign = $SIGN
TOML
  $BIN replay "$DATA/ap_log171_3imu.csv" --gnss "$DATA/ap_log171_gps_vel_ned.csv" \
    --att "$DATA/ap_log171_attitude_quat.csv" --from "$FROM" --to 235 --monitor "$MON" \
    --faults "$TMP/f.toml" --inject-imu "$IMU" --json "$@" 2>/dev/null >"$TMP/s.json"
  line="$line $(python3 - "$TMP/s.json" "$IMU" "$ch" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); imu = int(sys.argv[2]); ch = int(sys.argv[3])
c = s["channels"][6 * imu + ch]; m = s["monitoring_from_s"]; d = c.get("first_correct_s")
other = sum(x["flag_events"] for j, x in enumerate(s["channels"][6 * imu:6 * imu + 6]) if j != ch)
name = c["channel"].split("_")[-1]
print("%s %s%s" % (name, "%.1fs" % (d - m) if d is not None else "MISS", " (+%d)" % other if other else ""))
PY
)"
done
echo "$line"

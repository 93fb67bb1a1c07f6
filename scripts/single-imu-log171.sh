#!/usr/bin/env bash
# Issue 15's log171 figures for one single-IMU monitor (ukf | otsukf): the
# real flight (ArduPilot log171, the extracts shipped in tests/data: SPEC §10
# IMU CSV + GPS velocity + attitude, mapped by `replay`), cut at 235 s, each IMU monitored alone. Prints the
# fault-free flag events per IMU, then for every IMU and axis a 2 °/s gyro
# step and a 0.5 m/s² accelerometer step (default positive, 150–170 s) and whether
# it was flagged with the right sign within 10 s ("0.0s": already flagged
# at onset). Needs python3.
# Step sizes: ACC (m/s², default 0.5) and GYRO_DEG (°/s, default 2); ONSET
# (s, default 150; the step lasts 20 s), SIGN (1 or -1, default 1) and FROM
# (start of the replay, s, default 80).
# Usage: scripts/single-imu-log171.sh [ukf|otsukf] [extra replay options]
#   e.g. scripts/single-imu-log171.sh ukf --aiding-delay auto --heading-offset auto
# DATA (default tests/data) and IMU_CSV (default $DATA/ap_log171_3imu.csv)
# point it at other copies of the extracts; BIN (default
# ./target/release/imu-fdi-sim) runs another build of the tool, NOBUILD=1
# skips the cargo build. ATT_LATE (s, default 0) replays the attitude
# aiding that much late: every time stamp of the attitude extract moved by
# it (an aiding source with latency the monitor is not told about; with
# `--aiding-delay auto` the UKF monitor estimates it).
set -euo pipefail
cd "$(dirname "$0")/.."
MON=${1:-ukf}
ACC=${ACC:-0.5}
ONSET=${ONSET:-150}
FROM=${FROM:-80}
SIGN=${SIGN:-1}
GYRO=$(python3 -c "import math; print(math.radians(${GYRO_DEG:-2}))")
shift || true
DATA=${DATA:-tests/data}
IMU_CSV=${IMU_CSV:-$DATA/ap_log171_3imu.csv}
BIN=${BIN:-./target/release/imu-fdi-sim}
[[ -n "${NOBUILD:-}" ]] || cargo build -q -p imu-fdi-cli --release --bin imu-fdi-sim
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
ATT="$DATA/ap_log171_attitude_quat.csv"
if [[ -n "${ATT_LATE:-}" ]]; then
  python3 - "$ATT" "$TMP/att_late.csv" "$ATT_LATE" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
t = rows[0].index("time_s")
for r in rows[1:]:
    r[t] = "%.4f" % (float(r[t]) + float(sys.argv[3]))
csv.writer(open(sys.argv[2], "w", newline="")).writerows(rows)
PY
  ATT="$TMP/att_late.csv"
fi
LOG=(replay "$IMU_CSV" --gnss "$DATA/ap_log171_gps_vel_ned.csv"
  --att "$ATT" --from "$FROM" --to 235 --monitor "$MON" "$@")
$BIN "${LOG[@]}" --json 2>/dev/null >"$TMP/free.json"
python3 - "$TMP/free.json" "$FROM" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"{s['monitor']}: log171 {sys.argv[2]}–235 s, monitoring from {s['monitoring_from_s']} s")
if s.get("aiding_delay_s"):
    print("  aiding delay (%s): %s s; heading offset (%s): %s deg" % (
        s["aiding_delay_mode"], ", ".join("%.3f" % d for d in s["aiding_delay_s"]),
        "estimated" if s["heading_offset_estimated"] else "off",
        ", ".join("%.2f" % h for h in s["heading_offset_deg"])))
print("  velocity aiding delay (%s): %s s" % (s["velocity_delay_mode"],
    ", ".join("%.2f" % d for d in s["velocity_delay_s"])))
if s.get("ukf_velocity_lag_s"):
    print("  UKF velocity lag compensated (--velocity-lag): %s s" % ", ".join(
        "%.2f" % d for d in s["ukf_velocity_lag_s"]))
if s.get("velocity_increment_lag_s"):
    print("  velocity-increment test: GNSS lag %s s; accel offset %s m/s2" % (
        ", ".join("%.1f" % d for d in s["velocity_increment_lag_s"]),
        "; ".join(" ".join("%+.2f" % x for x in o) for o in s["velocity_increment_offset_m_s2"])))
if s.get("innovation_inflation_factor"):
    print("  learned inflation [vn ve vd roll pitch yaw]: " + "; ".join(
        " ".join("%.1f" % x for x in f) for f in s["innovation_inflation_factor"]))
for k in range(s["imus"]):
    ch = s["channels"][6 * k:6 * k + 6]
    ev = sum(c["flag_events"] for c in ch)
    per = ", ".join(f"{c['channel']} {c['flag_events']}" for c in ch if c["flag_events"])
    print(f"  IMU{k} fault-free: {ev} flag events [{per or 'none'}]")
PY
ok=0; n=0
for imu in 0 1 2; do
  line="  IMU$imu steps:"
  for k in 0 1 2 3 4 5; do
    cat >"$TMP/f.toml" <<TOML
[sizes]
accel = [$ACC, 0.0, 0.0]
gyro = [$GYRO, 0.0, 0.0]
f_unit = [1.0, 0.017453292519943295]
[[faults]]
channel = $k
start = $ONSET
end = $(python3 -c "print(${ONSET} + 20.0)")
kind = "E1"
sign = $SIGN
TOML
    $BIN "${LOG[@]}" --faults "$TMP/f.toml" --inject-imu $imu --json 2>/dev/null >"$TMP/inj.json"
    r=$(python3 -c '
import json,sys
s=json.load(open(sys.argv[1])); i=6*int(sys.argv[2])+int(sys.argv[3])
c=s["channels"][i]; d=c["first_correct_s"]; t0=float(sys.argv[4])
print(("%s %.1fs" % (c["channel"].split("_")[-1], d-t0)) if d is not None and d-t0<=10.0 else "%s MISS" % c["channel"].split("_")[-1])
' "$TMP/inj.json" $imu $k $ONSET)
    line+=" $r"; n=$((n+1)); [[ $r == *MISS* ]] || ok=$((ok+1))
  done
  echo "$line"
done
echo "  steps detected within 10 s: $ok/$n"

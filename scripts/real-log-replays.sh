#!/usr/bin/env bash
# Replays every real log of ../shared/data (or $DATA) through the single-IMU
# UKF monitor (`replay`, flight profile), fault-free and with one injected
# step per channel (1 m/s², 10 °/s, 5 s), and prints the table of the
# issue note. Needs python3 for the JSON.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${DATA:-../shared/data}
BIN=./target/release/imu-fdi-sim
cargo build -q -p imu-fdi-cli --release --bin imu-fdi-sim
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# log | extra options | injection onset (s, log time)
LOGS=(
  "ap_log171_px4v2_3imu_crash.bin|--from 80 --to 239|150"
  "px4_fmuv3_outdoor_flight.ulg|--learn 10|5100"
  "px4_v6xrt_3imu_flight_tail.ulg|--learn 8|424"
  "px4_v6c_2imu_indoor_flight.ulg||150"
  "px4_v6c_2imu_indoor_flight.ulg|--att-sigma-deg 1,1,30|150"
  "px4_auavx21_bench_248hz.ulg||150"
  # The CSV extracts, mapped (pyulog read the v6xrt log past the corrupt
  # message at 432 s where px4-ulog stops: its whole 96 s are here).
  "ap_log171_imu_3x.csv|--gnss $DATA/ap_log171_gps_vel_ned.csv --att $DATA/ap_log171_attitude_quat.csv --from 80 --to 239|150"
  "px4_v6xrt_sensor_combined_primary_imu.csv|--gnss $DATA/px4_v6xrt_gps_vel_ned.csv --att $DATA/px4_v6xrt_attitude_quat.csv --from 415|460"
)
CH=(ax ay az gx gy gz)
for entry in "${LOGS[@]}"; do
  IFS='|' read -r log opts onset <<<"$entry"
  # shellcheck disable=SC2086
  $BIN replay "$DATA/$log" $opts --summary "$TMP/free.json" >/dev/null
  line="${log} ${opts//$DATA\//}: "
  line+=$(python3 -c '
import json,sys
s=json.load(open(sys.argv[1]))
n=s["monitored_samples"]; f=[c for c in s["channels"]]
flag=sum(c["flagged_samples"] for c in f[:6]); cm=sum(c["common_mode_samples"] for c in f[:6])
per=", ".join("%s %d" % (c["channel"], c["flagged_samples"]) for c in f if c["flagged_samples"])
print("monitored %d samples from %.1f s; IMU0 flagged %d (%d common-mode) [%s]" % (n, s["monitoring_from_s"], flag, cm, per or "none"))
' "$TMP/free.json")
  echo "$line"
  for k in 0 1 2 3 4 5; do
    size=1.0; [ $k -ge 3 ] && size=0.17453292519943295
    cat >"$TMP/f.toml" <<TOML
[sizes]
accel = [1.0, 0.0, 0.0]
gyro = [0.17453292519943295, 0.0, 0.0]
f_unit = [1.0, 0.017453292519943295]
[[faults]]
channel = $k
start = $onset
end = $(python3 -c "print($onset+5)")
kind = "E1"
sign = 1.0
TOML
    # shellcheck disable=SC2086
    $BIN replay "$DATA/$log" $opts --faults "$TMP/f.toml" --summary "$TMP/inj.json" >/dev/null
    python3 -c '
import json,sys
s=json.load(open(sys.argv[1])); k=int(sys.argv[2]); t0=float(sys.argv[3])
c=s["channels"][k]
d=c["first_correct_s"]
ok=c["correct_samples"]; n=c["fault_samples"]
print(f"   {sys.argv[4]} step at {t0}: " + (f"detected after {d-t0:.2f} s, {ok}/{n} fault samples flagged" if d is not None else f"not detected ({ok}/{n})"))
' "$TMP/inj.json" $k "$onset" "${CH[$k]}"
  done
done

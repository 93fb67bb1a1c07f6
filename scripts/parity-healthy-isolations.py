#!/usr/bin/env python3
"""Issue 14's worst failure, counted: of the parity step table's cases
(`parity-table`, every IMU x axis x sign at the given onsets and training
starts, steps starting 10 s before the crash at 239 s), how many pass, how many the table marks with a false alarm, and
how many of those isolate a *healthy* sensor (each such case replayed with
`parity-replay --inject ... --train-start T --json`; isolations before the
crash, 239 s). Use onsets and training starts other than the table's
defaults to measure on cases no rule was designed on.

Usage: scripts/parity-healthy-isolations.py BIN KIND SIZE ONSETS TRAIN_STARTS
  e.g. scripts/parity-healthy-isolations.py target/release/imu-fdi-sim accel 0.3 \\
       8,30,50,70,90,110 64,84,97
  KIND gyro|accel, SIZE in deg/s or m/s2, ONSETS s after monitoring starts,
  TRAIN_STARTS s of the log (comma-separated). CSV (env): another copy of
  tests/data/ap_log171_3imu.csv."""
import json
import os
import subprocess
import sys

CRASH = 239.0


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd[:3])}: failed: {p.stderr.strip()}")
    return json.loads(p.stdout)


def main():
    if len(sys.argv) != 6 or sys.argv[2] not in ("gyro", "accel"):
        sys.exit(__doc__)
    binary, kind, size, onsets, trains = sys.argv[1:6]
    log = os.environ.get("CSV", "tests/data/ap_log171_3imu.csv")
    table = run([binary, "parity-table", log, "--kind", kind, "--size", size,
                 "--onsets", onsets, "--train-starts", trains, "--json"])
    # As the table's text does: a step must start 10 s before the crash.
    cases = [c for c in table["cases"] if c["injection"]["onset_s"] + 10.0 < CRASH]
    passed = sum(c["isolated"] and not c["false_alarm"] for c in cases)
    flagged = [c for c in cases if c["false_alarm"]]
    healthy = []
    for c in flagged:
        inj = c["injection"]
        axis = "xyz".index(inj["channel"][-1])
        channel = axis + (3 if kind == "gyro" else 0)
        step = inj.get("size_m_s2", inj.get("size_deg_s"))
        spec = f"{inj['imu']},{channel},{step},{inj['onset_s']},{inj['end_s']}"
        r = run([binary, "parity-replay", log, "--train-start", str(c["train_start_s"]),
                 "--inject", spec, "--json"])
        right = 3 * inj["imu"] + axis
        wrong = [i for i in r[kind]["isolations"] if i["t_s"] < CRASH and i["sensor"] != right]
        if wrong:
            healthy.append((spec, c["train_start_s"], wrong))
    print(f"{kind} {size}: {passed}/{len(cases)} isolated within 10 s with no false alarm; "
          f"{len(flagged)} cases with a false alarm, {len(healthy)} isolating a healthy sensor")
    for spec, ts, wrong in healthy:
        print(f"  --inject {spec} --train-start {ts}: isolated {wrong}")
    return 1 if healthy else 0


if __name__ == "__main__":
    sys.exit(main())

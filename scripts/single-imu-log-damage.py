#!/usr/bin/env python3
"""Issue 15: the single-IMU monitors on whole copies of log171's IMU extract
damaged the way loggers and converters damage a file (the real logs "cut
and damaged in other ways"; parity-log-damage.py does the same for the
parity monitor, single-imu-damaged.py cuts or freezes spells):
  dropout30   the IMU rows of 150-180 s removed (a 30-s logging gap);
  jitter      every IMU time stamp moved by up to +-4 ms (seeded);
  duplicates  every 50th IMU row written twice (same time stamp);
  decimate2   every other IMU row (24.8 Hz);
  upsample2   an IMU row interpolated between each two (99 Hz; the arming
              gap left alone);
  nan         0.2 % of the IMU cells (seeded) written as NaN: the monitor
              rejects those rows (every channel of the IMU) and bridges
              them with the last good sample;
  blank       the same for empty cells (seed differs).
The aiding extracts (GNSS velocity, attitude) are left as they are. Each
copy is replayed 80-235 s (`replay --monitor MON --json`, each IMU alone)
fault-free, and with a 2 deg/s gyro or 0.5 m/s2 accelerometer step on
each channel of IMU1 (20 s from 195 s, after the dropout). Printed per copy: rows, rejected rows (IMU0), the
IMU rate the replay estimated, monitoring start, fault-free flag events
per IMU and each step's detection delay (`first_correct_s` − onset, or
"missed" beyond 10 s). A copy passes when it raises no flag event the
undamaged log does not and finds both steps within 10 s.

Usage: scripts/single-imu-log-damage.py BIN ukf|otsukf
  BIN: the imu-fdi-sim binary (cargo build --release -p imu-fdi-cli
  --bin imu-fdi-sim). DATA (env): another copy of tests/data."""
import csv
import json
import math
import os
import random
import subprocess
import sys
import tempfile

ONSET, LENGTH = 195.0, 20.0
STEPS = list(enumerate(["ax", "ay", "az", "gx", "gy", "gz"]))


def damages(data):
    t = [float(r[0]) for r in data]
    rng = random.Random(1)
    up = []
    for a, b, ta, tb in zip(data, data[1:], t, t[1:]):
        up.append(a)
        if tb - ta < 0.05:
            up.append([f"{(float(x) + float(y)) / 2:.6f}" for x, y in zip(a, b)])
    up.append(data[-1])

    def cells(seed, text):
        r = random.Random(seed)
        out = []
        for row in data:
            row = row[:]
            if r.random() < 0.002 * (len(row) - 1):
                row[r.randrange(1, len(row))] = text
            out.append(row)
        return out

    return [
        ("dropout30", [r for r, x in zip(data, t) if not 150.0 <= x < 180.0]),
        ("jitter", [[f"{x + rng.uniform(-0.004, 0.004):.4f}"] + r[1:] for r, x in zip(data, t)]),
        ("duplicates", [y for i, r in enumerate(data) for y in ([r, r] if i % 50 == 0 else [r])]),
        ("decimate2", data[::2]),
        ("upsample2", up),
        ("nan", cells(3, "nan")),
        ("blank", cells(4, "")),
    ]


def replay(binary, mon, data_dir, path, faults=None, imu=None):
    cmd = [binary, "replay", path, "--gnss", os.path.join(data_dir, "ap_log171_gps_vel_ned.csv"),
           "--att", os.path.join(data_dir, "ap_log171_attitude_quat.csv"),
           "--from", "80", "--to", "235", "--monitor", mon, "--json"]
    if faults:
        cmd += ["--faults", faults, "--inject-imu", str(imu)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{path}: replay failed: {p.stderr.strip()}")
    return json.loads(p.stdout)


def main():
    if len(sys.argv) != 3 or sys.argv[2] not in ("ukf", "otsukf"):
        sys.exit(__doc__)
    binary, mon = sys.argv[1], sys.argv[2]
    data_dir = os.environ.get("DATA", os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                   "..", "tests", "data"))
    src = os.path.join(data_dir, "ap_log171_3imu.csv")
    try:
        rows = list(csv.reader(open(src)))
    except OSError as e:
        sys.exit(f"{src}: {e.strerror}")
    hdr, data = rows[0], rows[1:]
    tmp = tempfile.mkdtemp()
    faults = []
    for ch, name in STEPS:
        f = os.path.join(tmp, f"{name}.toml")
        with open(f, "w") as fh:
            fh.write(f"[sizes]\naccel = [0.5, 0.0, 0.0]\ngyro = [{math.radians(2.0)}, 0.0, 0.0]\n"
                     f"f_unit = [1.0, 0.017453292519943295]\n[[faults]]\nchannel = {ch}\n"
                     f"start = {ONSET}\nend = {ONSET + LENGTH}\nkind = \"E1\"\nsign = 1\n")
        faults.append((ch, name, f))
    base = None
    failed = 0
    copies = [("undamaged", data)] + damages(data)
    for name, rows_d in copies:
        path = os.path.join(tmp, f"{name}.csv")
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(hdr)
            w.writerows(rows_d)
        s = replay(binary, mon, data_dir, path)
        ch = s["channels"]
        ev = [sum(c["flag_events"] for c in ch[6 * k:6 * k + 6]) for k in range(s["imus"])]
        found = []
        for c, cname, f in faults:
            j = replay(binary, mon, data_dir, path, f, 1)
            d = j["channels"][6 + c]["first_correct_s"]
            found.append((cname, None if d is None or d - ONSET > 10.0 else d - ONSET))
        if base is None:
            base = ev
            base_found = [d is not None for _, d in found]
        ok = all(e <= b for e, b in zip(ev, base)) and all(
            d is not None or not b for (_, d), b in zip(found, base_found))
        failed += 0 if ok or name == "undamaged" else 1
        steps = ", ".join(f"{n} {'missed' if d is None else f'{d:.1f} s'}" for n, d in found)
        print(f"{mon} {name:10}: {s['rows']} rows, {s['rejected_imu_rows']} rejected (IMU0), "
              f"{s['imu_rate_hz']:.1f} Hz, monitoring from {s['monitoring_from_s']} s, "
              f"flag events per IMU {'/'.join(map(str, ev))}; IMU1 steps: {steps}"
              f"{'' if ok else '  <- differs'}")
    print(f"{mon}: {failed} of {len(copies) - 1} damaged copies raise more flag events than "
          "the undamaged log or miss a step")
    return failed


if __name__ == "__main__":
    sys.exit(1 if main() else 0)

#!/usr/bin/env python3
"""Writes tests/data/ap_log171_3imu.csv (SPEC §10 columns) from the CSV
extract of ArduPilot log171 (dronekit-la-testdata, CC BY-SA 3.0).

Usage: python3 scripts/extract_log171.py ../shared/data/ap_log171_imu_3x.csv

Keeps t >= 60 s (12 s before arming, the flight, the crash and the end of
the log), the three IMUs' gyro (rad/s, 4 decimals = 0.006 deg/s, below the
sensor noise) and accelerometer (m/s^2, 3 decimals), renamed to
imu{k}_{ax,ay,az,gx,gy,gz}. Nothing else is changed.
"""
import csv
import sys

src = sys.argv[1]
dst = "tests/data/ap_log171_3imu.csv"
with open(src) as f, open(dst, "w", newline="") as g:
    r = csv.DictReader(f)
    w = csv.writer(g, lineterminator="\n")
    cols = ["t"]
    for k in range(3):
        cols += [f"imu{k}_{a}" for a in ("ax", "ay", "az", "gx", "gy", "gz")]
    w.writerow(cols)
    n = 0
    for row in r:
        t = float(row["time_s"])
        if t < 60.0:
            continue
        out = [f"{t:.3f}"]
        for k in range(3):
            out += [f"{float(row[f'imu{k}_accel_{a}_m_s2']):.3f}" for a in "xyz"]
            out += [f"{float(row[f'imu{k}_gyro_{a}_rad_s']):.4f}" for a in "xyz"]
        w.writerow(out)
        n += 1
print(f"wrote {n} rows to {dst}")

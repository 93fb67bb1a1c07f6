#!/usr/bin/env python3
# Issue 15: the block tests' tail on log171 (fault-free, 80-235 s cut at
# each start): the decisions whose largest score/threshold ratio is >= 1,
# from `replay --out` CSVs (columns ratio_ax ... ratio_gz and imuN_ratio_*;
# a decision repeats over the rows of its block, so each change of value
# counts once). Prints per start and summed: decisions and those >= 1, for
# the accelerometer (velocity-increment) and gyro (attitude-rate) channels.
# usage: scripts/block-test-tail.py BIN ukf|otsukf FROM...
#   e.g. scripts/block-test-tail.py target/release/imu-fdi-sim ukf 60 70 75 80 90 100
import csv, os, subprocess, sys, tempfile

if len(sys.argv) < 4 or sys.argv[2] not in ('ukf', 'otsukf'):
    sys.exit('usage: block-test-tail.py BIN ukf|otsukf FROM...')
B, mon, starts = sys.argv[1], sys.argv[2], sys.argv[3:]
D = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'tests', 'data')
total = {'acc': [0, 0], 'gyro': [0, 0]}
with tempfile.TemporaryDirectory() as tmp:
    for f in starts:
        out = os.path.join(tmp, f + '.csv')
        subprocess.run([B, 'replay', D + '/ap_log171_3imu.csv', '--gnss',
                        D + '/ap_log171_gps_vel_ned.csv', '--att',
                        D + '/ap_log171_attitude_quat.csv', '--from', f, '--to', '235',
                        '--monitor', mon, '--out', out], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        rows = csv.reader(open(out))
        head = next(rows)
        cols = [(i, n) for i, n in enumerate(head) if 'ratio_' in n]
        prev = {i: None for i, _ in cols}
        this = {'acc': [0, 0], 'gyro': [0, 0]}
        for row in rows:
            for i, n in cols:
                v = float(row[i] or 0)
                if v != prev[i] and v > 0:
                    k = 'acc' if n[-2] == 'a' else 'gyro'
                    this[k][0] += 1
                    this[k][1] += v >= 1
                prev[i] = v
        for k in total:
            total[k][0] += this[k][0]
            total[k][1] += this[k][1]
        print(f"FROM={f} " + " ".join(f"{k}: decisions {v[0]} >=1 {v[1]}" for k, v in this.items()))
print("ALL " + " ".join(f"{k}: decisions {v[0]} >=1 {v[1]}" for k, v in total.items()))

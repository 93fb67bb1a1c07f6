#!/usr/bin/env python3
"""The parity monitor on whole copies of log171 damaged the way loggers and
converters damage a file (issue 14: the real logs "cut and damaged in other
ways"), beside parity-damaged.py's spells in flight:
  dropout30   the rows of 150-180 s removed (a 30-s logging gap);
  clockjump   every time stamp from 150 s on moved by +1,000 s;
  jitter      every time stamp moved by up to +-4 ms (seeded);
  duplicates  every 50th row written twice (same time stamp);
  decimate2   every other row (24.8 Hz);
  upsample2   a row interpolated between each two (99 Hz; the arming gap
              left alone).
For each training start, each copy is replayed fault-free and with a
10 deg/s step on IMU1's z gyro from 190 s to the crash. Printed per copy:
monitoring start, alarms and isolations before the crash (239 s on the
log's own clock), spells not judged, and when the step was isolated.
A copy passes when it starts monitoring within 1 s of the undamaged log,
alarms and isolates nothing the undamaged log does not, and isolates the
step within 10 s.

Usage: scripts/parity-log-damage.py BIN [TRAIN_START ...]
  BIN: the imu-fdi-sim binary (cargo build --release -p imu-fdi-cli);
  TRAIN_START: training starts, s (default 80). CSV (env): another copy of
  tests/data/ap_log171_3imu.csv."""
import csv
import json
import os
import random
import subprocess
import sys
import tempfile

CRASH = 239.0
JUMP_AT, JUMP = 150.0, 1000.0
STEP_AT = 190.0


def damages(data):
    """(name, rows, clock, back) per damage; clock maps a time of the
    undamaged log to the damaged file's, back the other way."""
    t = [float(r[0]) for r in data]
    same = lambda x: x
    rng = random.Random(1)
    up = []
    for a, b, ta, tb in zip(data, data[1:], t, t[1:]):
        up.append(a)
        if tb - ta < 0.05:
            up.append([f"{(float(x) + float(y)) / 2:.6f}" for x, y in zip(a, b)])
    up.append(data[-1])
    return [
        ("dropout30", [r for r, x in zip(data, t) if not JUMP_AT <= x < JUMP_AT + 30], same,
         same),
        ("clockjump", [[f"{x + JUMP:.3f}"] + r[1:] if x >= JUMP_AT else r
                       for r, x in zip(data, t)],
         lambda x: x + JUMP if x >= JUMP_AT else x,
         lambda x: x - JUMP if x >= JUMP_AT + JUMP else x),
        ("jitter", [[f"{x + rng.uniform(-0.004, 0.004):.4f}"] + r[1:]
                    for r, x in zip(data, t)], same, same),
        ("duplicates", [y for i, r in enumerate(data) for y in ([r, r] if i % 50 == 0 else [r])],
         same, same),
        ("decimate2", data[::2], same, same),
        ("upsample2", up, same, same),
    ]


def replay(binary, path, ts, inject=None):
    cmd = [binary, "parity-replay", path, "--train-start", str(ts), "--json"]
    if inject:
        cmd += ["--inject", inject]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{path}: parity-replay failed: {p.stderr.strip()}")
    return json.loads(p.stdout)


def events(j, back):
    """Alarms, isolations and spells not judged before the crash, both
    kinds, sensor and second (of the undamaged log's clock)."""
    out = []
    for k in ("gyro", "accel"):
        out += [f"{k} alarm {a['sensor']}@{back(a['start_s']):.0f}" for a in j[k]["alarms"]
                if back(a["start_s"]) < CRASH]
        out += [f"{k} isolated {i['sensor']}@{back(i['t_s']):.0f}" for i in j[k]["isolations"]
                if back(i["t_s"]) < CRASH]
        out += [f"{k} not judging @{back(s['start_s']):.0f}"
                for s in j[k].get("not_judging", []) if back(s["start_s"]) < CRASH]
    return out


def step_isolated(j, at):
    """Time from the step's onset to IMU1 g_z's isolation, s, or None."""
    t = [i["t_s"] for i in j["gyro"]["isolations"] if i["sensor"] == 5 and i["t_s"] >= at]
    return min(t) - at if t else None


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    binary, starts = sys.argv[1], sys.argv[2:] or ["80"]
    src = os.environ.get("CSV", "tests/data/ap_log171_3imu.csv")
    try:
        rows = list(csv.reader(open(src)))
    except OSError as e:
        sys.exit(f"{src}: {e.strerror}")
    hdr, data = rows[0], rows[1:]
    tmp = tempfile.mkdtemp()
    failed = 0
    copies = [("undamaged", data, lambda x: x, lambda x: x)] + damages(data)
    for ts in starts:
        base = None
        for name, rows_d, clock, back in copies:
            path = os.path.join(tmp, f"{name}.csv")
            with open(path, "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(hdr)
                w.writerows(rows_d)
            free = replay(binary, path, clock(float(ts)))
            step_at = clock(STEP_AT)
            step = replay(binary, path, clock(float(ts)),
                          f"1,5,10,{step_at},{clock(CRASH)}")
            ev = events(free, back)
            delay = step_isolated(step, step_at)
            mon = [free[k]["monitoring_from_s"] for k in ("gyro", "accel")]
            mon = [None if m is None else round(back(m), 2) for m in mon]
            if base is None:
                base, base_mon = ev, mon
            # Training ends with its configured length of flight: a block
            # more or less at another rate, not seconds.
            same_start = all(m is not None and b is not None and abs(m - b) <= 1.0
                             for m, b in zip(mon, base_mon))
            ok = ev == base and same_start and delay is not None and delay <= 10.0
            failed += 0 if ok else 1
            d = "missed" if delay is None else f"{delay:.1f} s"
            print(f"training {ts} s, {name:10}: monitoring from {mon[0]}/{mon[1]} s, "
                  f"before the crash {ev or 'nothing'}; step isolated {d}"
                  f"{'' if ok else '  <- differs'}")
    print(f"{failed} of {len(starts) * (len(copies) - 1)} damaged copies differ from the "
          "undamaged log or miss the step")


if __name__ == "__main__":
    main()

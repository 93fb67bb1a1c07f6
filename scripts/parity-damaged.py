#!/usr/bin/env python3
"""The parity monitor on log171 damaged the way a logger or a board damages
it (issue 14, "never stuck"): each spell (0.5, 2 and 5 s at 120, 150, 180
and 210 s) is one of
  cut      the rows removed, every IMU (a logging dropout: the next row
           carries the time);
  holdall  every IMU's row held at the spell's first (the logger or the
           driver repeating a sample: a common-mode event, not a failure);
  hold1    IMU1's cells held (a frozen IMU: a real sensor failure).
For each, `parity-replay --json` (gyro and accel) is compared with the
undamaged log's: alarms before the crash (239 s), isolations of a sensor
that was not damaged, whether the monitor ever monitors or stops judging
(`not_judging`: lost, no redundancy, training again); each line also
lists the statuses raised and the re-admissions. Prints one line per spell
and the totals.

Usage: scripts/parity-damaged.py BIN [TRAIN_START ...]
  BIN: the imu-fdi-sim binary (cargo build --release -p imu-fdi-cli);
  TRAIN_START: training starts, s (default 80). CSV (env): another copy of
  tests/data/ap_log171_3imu.csv."""
import csv
import json
import os
import subprocess
import sys
import tempfile

CRASH = 239.0


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    binary = sys.argv[1]
    starts = sys.argv[2:] or ["80"]
    src = os.environ.get("CSV", "tests/data/ap_log171_3imu.csv")
    try:
        rows = list(csv.reader(open(src)))
    except OSError as e:
        sys.exit(f"{src}: {e.strerror}")
    hdr, data = rows[0], rows[1:]
    tmp = tempfile.mkdtemp()
    totals = {}
    for ts in starts:
        base = replay(binary, src, ts)
        print(f"training from {ts} s; undamaged: " + summary(base, None))
        for kind in ("cut", "holdall", "hold1"):
            for onset in (120, 150, 180, 210):
                for dur in (0.5, 2, 5):
                    path = os.path.join(tmp, f"{kind}_{onset}_{dur}.csv")
                    write(path, hdr, damage(data, kind, onset, dur))
                    j = replay(binary, path, ts)
                    extra = count(j, kind) - count(base, kind)
                    t = totals.setdefault(kind, [0, 0])
                    t[0] += max(extra, 0)
                    t[1] += unjudged(j)
                    print(f"  {kind:7} {onset} s + {dur:>3} s: {summary(j, kind)}")
    for kind, (extra, unj) in totals.items():
        print(f"{kind}: {extra} alarms/isolations beyond the undamaged runs, "
              f"{unj} runs never monitoring or not judging before the crash")


def damage(data, kind, onset, dur):
    out, first = [], None
    for r in data:
        inside = onset <= float(r[0]) < onset + dur
        if not inside:
            out.append(r)
        elif kind == "holdall":
            first = first or r
            out.append([r[0]] + first[1:])
        elif kind == "hold1":
            first = first or r
            out.append(r[:7] + first[7:13] + r[13:])
    return out


def write(path, hdr, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(hdr)
        w.writerows(rows)


def replay(binary, path, ts):
    p = subprocess.run([binary, "parity-replay", path, "--train-start", ts, "--json"],
                       capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{path}: parity-replay failed: {p.stderr.strip()}")
    return json.loads(p.stdout)


def count(j, kind):
    """Alarms before the crash and isolations of an undamaged sensor."""
    n = 0
    for k in ("gyro", "accel"):
        n += sum(1 for a in j[k]["alarms"] if a["start_s"] < CRASH)
        n += sum(1 for i in j[k]["isolations"] if i["t_s"] < CRASH
                 and not (kind == "hold1" and 3 <= i["sensor"] < 6))
    return n


def unjudged(j):
    """1 if either kind never starts monitoring, or stops judging (lost,
    no redundancy, training again) before the crash."""
    for k in ("gyro", "accel"):
        if j[k]["monitoring_from_s"] is None:
            return 1
        if any(s["start_s"] < CRASH for s in j[k].get("not_judging", [])):
            return 1
    return 0


def summary(j, kind):
    parts = []
    for k in ("gyro", "accel"):
        d = j[k]
        al = [a for a in d["alarms"] if a["start_s"] < CRASH]
        iso = [i for i in d["isolations"] if i["t_s"] < CRASH]
        st = sorted({s["status"] for s in d["statuses"] if s["t_s"] < CRASH})
        back = len(d.get("readmissions", []))
        off = [f"{o['start_s']:.1f}-{o['end_s']:.1f} {o['phase']}" for o in d.get("not_judging", [])]
        parts.append(f"{k}: monitoring from {d['monitoring_from_s']}, not judging {off}, {len(al)} alarms, "
                     f"isolated {[i['sensor'] for i in iso]}, statuses {st}, {back} re-admitted")
    return "; ".join(parts)


if __name__ == "__main__":
    main()

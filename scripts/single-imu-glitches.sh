#!/usr/bin/env bash
# Issue 15's recovery after large short glitches on the real flight log171
# for one single-IMU monitor (ukf | otsukf), replayed as
# scripts/single-imu-log171.sh does (80–235 s, each IMU monitored alone).
# One E1 step per replay: every IMU × channel (ax ay az gx gy gz), sizes
# ACC_SIZES (m/s², default "3 5") and GYRO_SIZES (°/s, default "20 50"),
# durations DURS (s, default "0.5 1 3 5"), onsets ONSETS (s, default
# "120 160 200"), sign SIGN (1 or -1, default 1). Per size/duration it
# prints how many cases were back to nominal within 5 s of the glitch's end (no flag on that IMU that
# is not also in the fault-free replay), the worst time back, and how many
# cascaded (a flag on another channel, or a new flag on the glitched
# channel after the glitch ended, once it had been raised). A flag that
# resumes after a span the monitor did not judge (`NotMonitored`: log171's
# manoeuvres at 122 and 125 s) is one event; the last line also gives the
# count with such a span ending a flag (the count before 27 Nov 2026). A flag
# event that overlaps a fault-free event of the same channel is not counted. CASES=1 lists every slow or
# cascading case. Needs python3.
# BIN runs another build of the tool (default: ./target/release/imu-fdi-sim,
# built first).
# Usage: scripts/single-imu-glitches.sh [ukf|otsukf] [extra replay options]
set -euo pipefail
cd "$(dirname "$0")/.."
MON=${1:-ukf}
shift || true
DATA=${DATA:-tests/data}
IMU_CSV=${IMU_CSV:-$DATA/ap_log171_3imu.csv}
if [ -z "${BIN:-}" ]; then
  BIN=./target/release/imu-fdi-sim
  cargo build -q -p imu-fdi-cli --release --bin imu-fdi-sim
fi
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
python3 - "$BIN" "$MON" "$TMP" "$IMU_CSV" "$DATA" "${ACC_SIZES:-3 5}" \
  "${GYRO_SIZES:-20 50}" "${DURS:-0.5 1 3 5}" "${ONSETS:-120 160 200}" \
  "${CASES:-0}" "${SIGN:-1}" "$@" <<'PY'
import csv, math, subprocess, sys
from collections import defaultdict

BIN, MON, TMP, IMU_CSV, DATA = sys.argv[1:6]
ACC = [float(x) for x in sys.argv[6].split()]
GYR = [float(x) for x in sys.argv[7].split()]
DURS = [float(x) for x in sys.argv[8].split()]
ONSETS = [float(x) for x in sys.argv[9].split()]
LIST = sys.argv[10] == "1"
SIGN = int(sys.argv[11])
EXTRA = sys.argv[12:]
CH = ["ax", "ay", "az", "gx", "gy", "gz"]
SETTLE = 5.0


def replay(out, faults=None, imu=0):
    cmd = [BIN, "replay", IMU_CSV, "--gnss", f"{DATA}/ap_log171_gps_vel_ned.csv",
           "--att", f"{DATA}/ap_log171_attitude_quat.csv", "--from", "80",
           "--to", "235", "--monitor", MON, "--out", out, "--json"] + EXTRA
    if faults:
        cmd += ["--faults", faults, "--inject-imu", str(imu)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    rows = list(csv.reader(open(out)))
    return rows[0], rows[1:]


def events(rows, imu, bridge=True):
    """Flag events per channel of one IMU: list of (channel, on, off). With
    `bridge`, a flag that resumes after a span the monitor did not judge
    (`NotMonitored`, an empty cell: a manoeuvre beyond what was learnt) is
    the same event; otherwise that span ends it."""
    pre = "" if imu == 0 else f"imu{imu}_"
    head, body = rows
    t = [float(r[0]) for r in body]
    ev = []
    for c in CH:
        j = head.index(pre + "flag_" + c)
        on = None
        gap = None  # start of an unjudged span within an event
        for ti, r in zip(t, body):
            v = r[j]
            if bridge and v == "" and on is not None:
                gap = ti if gap is None else gap
                continue
            fl = v not in ("", "0")
            if fl and on is None:
                on = ti
            if fl:
                gap = None
            if not fl and on is not None:
                ev.append((c, on, ti if gap is None else gap))
                on = None
                gap = None
        if on is not None:
            ev.append((c, on, math.inf if gap is None else gap))
    return ev


free_rows = replay(f"{TMP}/free.csv")
free = {(k, b): events(free_rows, k, b) for k in range(3) for b in (True, False)}


def new(e, k, b=True):
    return not any(f[0] == e[0] and f[1] < e[2] and e[1] < f[2] for f in free[(k, b)])


def cascades(ev, ch, end):
    """A flag on another channel, or a new flag on the glitched channel
    after the glitch ended, once it had been raised before."""
    own = [e for e in ev if e[0] == CH[ch]]
    other = [e for e in ev if e[0] != CH[ch]]
    return bool(other) or any(e[1] > end for e in own[1:])


groups = defaultdict(lambda: [0, 0, 0, 0, 0.0])  # n, flagged, back, cascade, worst
slow = []
split_cascades = 0  # counted with unjudged spans ending a flag
other_ch = 0  # cases with a flag on another channel
for kind, sizes in (("acc", ACC), ("gyro", GYR)):
    for size in sizes:
        for dur in DURS:
            for onset in ONSETS:
                for imu in range(3):
                    for ax in range(3):
                        ch = ax if kind == "acc" else 3 + ax
                        acc = size if kind == "acc" else 0.0
                        gyr = math.radians(size) if kind == "gyro" else 0.0
                        with open(f"{TMP}/f.toml", "w") as f:
                            f.write(f"[sizes]\naccel = [{acc}, 0.0, 0.0]\n"
                                    f"gyro = [{gyr}, 0.0, 0.0]\n"
                                    "f_unit = [1.0, 0.017453292519943295]\n"
                                    f"[[faults]]\nchannel = {ch}\nstart = {onset}\n"
                                    f"end = {onset + dur}\nkind = \"E1\"\nsign = {SIGN}\n")
                        rows = replay(f"{TMP}/inj.csv", f"{TMP}/f.toml", imu)
                        end = onset + dur
                        ev = [e for e in events(rows, imu) if e[2] > onset and new(e, imu)]
                        own = [e for e in ev if e[0] == CH[ch]]
                        cascade = cascades(ev, ch, end)
                        split = [e for e in events(rows, imu, False)
                                 if e[2] > onset and new(e, imu, False)]
                        split_cascades += cascades(split, ch, end)
                        other_ch += any(e[0] != CH[ch] for e in ev)
                        back = max([0.0] + [e[2] - end for e in ev])
                        g = groups[(kind, size, dur)]
                        g[0] += 1
                        g[1] += bool(own)
                        g[2] += back <= SETTLE
                        g[3] += cascade
                        g[4] = max(g[4], back)
                        if back > SETTLE or cascade:
                            slow.append((kind, size, dur, onset, imu, CH[ch], back,
                                         " ".join("%s %.1f-%.1f" % e for e in ev)))

print(f"{MON}: log171 80–235 s, one E1 glitch per replay (3 IMUs × 3 axes × "
      f"{len(ONSETS)} onsets {'/'.join('%g' % o for o in ONSETS)} s per row)")
print("  glitch            cases flagged back<=5s worst_back_s cascade")
for (kind, size, dur), g in groups.items():
    unit = "m/s2" if kind == "acc" else "deg/s"
    worst = "inf" if math.isinf(g[4]) else "%.1f" % g[4]
    print(f"  {kind:4} {size:4g} {unit:5} {dur:3g}s {g[0]:5} {g[1]:7} {g[2]:9} "
          f"{worst:>12} {g[3]:7}")
tot = [sum(g[i] for g in groups.values()) for i in range(4)]
print(f"  all: {tot[2]}/{tot[0]} back to nominal within {SETTLE:g} s, "
      f"{tot[3]} cascades ({other_ch} on another channel; {split_cascades} "
      f"if an unjudged span ends a flag), {tot[1]} flagged")
if LIST:
    for s in slow:
        print("  slow/cascade: %s %g %gs @%g IMU%d %s back %.1f s: %s" % s)
PY

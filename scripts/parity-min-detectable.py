#!/usr/bin/env python3
"""The smallest step the parity monitor for real flights isolates at ZERO
false alarms on the realistic simulated profile (issue 14: "min detectable
step at 0 false alarms over >= 10 simulated hours is reported for gyro and
accel").

The monitor's only sensitivity knob is the multi-scale tests' per-decision
false-alarm probability (`parity-realistic --false-alarm P`, flight
default 1e-6): every threshold and the isolation follow from it and the
learned covariances. For each P this runs, per kind:
  - fault-free one-hour flights on the design seeds (1000...) and on
    held-out seeds (20000...): alarm events and sensors isolated;
  - steps of each size on every IMU x axis x sign (ROUNDS x 18 flights of
    100 s, onset 60 s, 15 s long): detected (an alarm within 10 s of
    onset), isolated to the right sensor within 10 s, and flights with any
    other alarm or a healthy sensor isolated (those count as neither).
It then names the most sensitive P with 0 alarm events on all fault-free
hours, and there the smallest size detected, and the smallest isolated,
in at least 90 % of its flights ("none" when no size reaches it, "-" when
no P is clean).

Usage: scripts/parity-min-detectable.py BIN [options]
  BIN            the imu-fdi-sim binary (cargo build --release -p imu-fdi-cli)
  --alphas A,..  per-decision probabilities (default 1e-6,1e-8,1e-10)
  --hours H      fault-free hours per seed set (default 10)
  --rounds R     step rounds per size (default 2: 36 flights)
  --kind K       gyro, accel or both (default both)
  --design-seed S / --held-out-seed S   first seeds (default 1000 / 20000)
"""
import argparse
import json
import subprocess
import sys

SIZES = {"gyro": [1.0, 2.0, 3.0, 5.0], "accel": [0.2, 0.3, 0.5, 1.0]}
UNIT = {"gyro": "deg/s", "accel": "m/s2"}
SHARE = 0.9


def fail(msg):
    print(f"parity-min-detectable: {msg}", file=sys.stderr)
    sys.exit(1)


def run(bin_path, args):
    try:
        out = subprocess.run([bin_path, "parity-realistic", "--json", *args],
                             capture_output=True, text=True, check=False)
    except OSError as e:
        fail(f"{bin_path}: {e.strerror}")
    if out.returncode != 0:
        fail(f"{bin_path} parity-realistic {' '.join(args)}: "
             f"{(out.stderr.strip().splitlines() or ['failed'])[-1]}")
    try:
        return json.loads(out.stdout)["kinds"][0]
    except (ValueError, KeyError, IndexError):
        fail(f"{bin_path}: parity-realistic printed no JSON kinds")


def smallest(sizes, steps, key):
    """The smallest size whose flights reach SHARE on `key`, or None."""
    for sz, s in zip(sizes, steps):
        if s["cases"] and s[key] >= SHARE * s["cases"]:
            return sz
    return None


def main():
    ap = argparse.ArgumentParser(add_help=True)
    ap.add_argument("bin")
    ap.add_argument("--alphas", default="1e-6,1e-8,1e-10")
    ap.add_argument("--hours", type=int, default=10)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--kind", default="both", choices=["gyro", "accel", "both"])
    ap.add_argument("--design-seed", type=int, default=1000)
    ap.add_argument("--held-out-seed", type=int, default=20000)
    a = ap.parse_args()
    try:
        alphas = [float(x) for x in a.alphas.split(",")]
    except ValueError:
        fail(f"--alphas: '{a.alphas}' is not a list of numbers")
    if any(not 0.0 < p < 0.5 for p in alphas) or a.hours < 1 or a.rounds < 1:
        fail("--alphas must lie in (0, 0.5), --hours and --rounds be at least 1")
    kinds = ["gyro", "accel"] if a.kind == "both" else [a.kind]
    for kind in kinds:
        sizes = SIZES[kind]
        print(f"{kind}: fault-free {a.hours} h design (seeds {a.design_seed}...) + "
              f"{a.hours} h held out ({a.held_out_seed}...); steps {a.rounds * 18} "
              f"flights per size: detected/isolated (flights with a false alarm)")
        print("  P      design ev/iso  held-out ev/iso  " +
              "  ".join(f"{s:g} {UNIT[kind]}" for s in sizes))
        clean = None
        for p in alphas:
            base = ["--kind", kind, "--false-alarm", f"{p:g}"]
            d = run(a.bin, base + ["--hours", str(a.hours), "--rounds", "0",
                                   "--fault-free-seed", str(a.design_seed)])
            h = run(a.bin, base + ["--hours", str(a.hours), "--rounds", "0",
                                   "--fault-free-seed", str(a.held_out_seed)])
            st = run(a.bin, base + ["--hours", "0", "--rounds", str(a.rounds),
                                    "--sizes", ",".join(f"{s:g}" for s in sizes)])
            steps = st["steps"]
            cells = [f"{s['detected']}/{s['isolated']} ({s['flights_with_false_alarm']})"
                     for s in steps]
            print(f"  {p:<6g} {d['fault_free_alarm_events']:>6}/{d['fault_free_isolations']:<6}"
                  f" {h['fault_free_alarm_events']:>9}/{h['fault_free_isolations']:<6}   "
                  + "  ".join(f"{c:>12}" for c in cells))
            events = d["fault_free_alarm_events"] + h["fault_free_alarm_events"]
            if clean is None and events == 0:
                clean = (p, smallest(sizes, steps, "detected"),
                         smallest(sizes, steps, "isolated"))
        if clean is None:
            print(f"  min detectable step at 0 false alarms ({2 * a.hours} h): - "
                  "(no P above is clean)")
        else:
            p, det, iso = clean
            what = lambda sz: f"{sz:g} {UNIT[kind]}" if sz is not None else \
                f"none of {sizes[-1]:g} {UNIT[kind]} or less"
            print(f"  at 0 false alarms ({2 * a.hours} h, P = {p:g}), in >= {SHARE:.0%} of "
                  f"flights within 10 s: detected from {what(det)}, isolated from {what(iso)}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Force quality of a device-sim trace (issue 12): how the force the device received changes from one pose to
the next while the comb is in the hair, away from the scripted path's corners (device-sim moves the device
through them with unbounded acceleration, which the coupling's damper feels whatever the follower does).

    python3 bench/device_forces.py bench/out/device-1000.csv [--path bench/device-comb.toml] [--away 0.04] [--felt]
    python3 bench/device_forces.py bench/out/replay-4000/device_force.csv

A trace is either device-sim's (`--out`: one line per pose it sent, the force answered or, with --felt, the force
its own rendering gave the hand) or the server's own force at the device loop's rate: `coiffure replay` of a
`serve --record` file writes `device_force.csv`, one line per device step with the time of the pose it took
(bench/device_loop.sh records and replays when RECORD=1).

Prints, per trace: the one-step change of the force vector (N) during the strokes (from the second waypoint to
the last but one) more than --away s from any waypoint: median, p90, p99, max and how many steps exceed 0.05 N (the acceptance of issue 31) and 0.1 N;
and the peak force anywhere.
"""
import argparse
import csv
import math
import tomllib

ap = argparse.ArgumentParser()
ap.add_argument("traces", nargs="+")
ap.add_argument("--path", default="bench/device-comb.toml")
ap.add_argument("--away", type=float, default=0.04)
ap.add_argument("--felt", action="store_true", help="the force the hand felt (hx,hy,hz: device-sim --render's own rendering) instead of the answered one")
a = ap.parse_args()
with open(a.path, "rb") as f:
    corners = [w["t"] for w in tomllib.load(f)["tool"]["path"]]
start, end = corners[1], corners[-2]
for trace in a.traces:
    rows = list(csv.DictReader(open(trace)))
    # device_force.csv: the device steps that took no pose (NaN time) are not in the strokes.
    t = [float(r["t"]) for r in rows]
    k = ("hx", "hy", "hz") if a.felt else ("fx", "fy", "fz")
    f = [(float(r[k[0]]), float(r[k[1]]), float(r[k[2]])) for r in rows]
    steps = sorted(
        math.dist(f[i], f[i - 1])
        for i in range(1, len(f))
        if math.isfinite(t[i]) and start <= t[i] <= end and min(abs(t[i] - c) for c in corners) > a.away and all(map(math.isfinite, f[i] + f[i - 1]))
    )
    n = len(steps)
    q = lambda p: steps[min(n - 1, int(p * n))]
    peak = max(math.hypot(*x) for x in f if all(map(math.isfinite, x)))
    rate = "device step" if "period" in rows[0] else "pose"
    print(f"{trace}: one-step force change (a {rate}) in the strokes, {a.away} s from the corners: median {q(0.5):.4f} N, p90 {q(0.9):.4f} N, "
          f"p99 {q(0.99):.4f} N, max {steps[-1]:.3f} N, {sum(x > 0.05 for x in steps)} over 0.05 N and {sum(x > 0.1 for x in steps)} over 0.1 N of {n}; peak force {peak:.3f} N")

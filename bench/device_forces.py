#!/usr/bin/env python3
"""Force quality of a device-sim trace (issue 12): how the force the device received changes from one pose to
the next while the comb is in the hair, away from the scripted path's corners (device-sim moves the device
through them with unbounded acceleration, which the coupling's damper feels whatever the follower does).

    python3 bench/device_forces.py bench/out/device-1000.csv [--path bench/device-comb.toml] [--away 0.04] [--felt]

Prints, per trace: the one-step change of the force vector (N) during the strokes (from the second waypoint to
the last but one) more than --away s from any waypoint: median, p90, p99, max and how many steps exceed 0.1 N;
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
    t = [float(r["t"]) for r in rows]
    k = ("hx", "hy", "hz") if a.felt else ("fx", "fy", "fz")
    f = [(float(r[k[0]]), float(r[k[1]]), float(r[k[2]])) for r in rows]
    steps = sorted(
        math.dist(f[i], f[i - 1])
        for i in range(1, len(f))
        if start <= t[i] <= end and min(abs(t[i] - c) for c in corners) > a.away and all(map(math.isfinite, f[i] + f[i - 1]))
    )
    n = len(steps)
    q = lambda p: steps[min(n - 1, int(p * n))]
    peak = max(math.hypot(*x) for x in f if all(map(math.isfinite, x)))
    print(f"{trace}: one-step force change in the strokes, {a.away} s from the corners: median {q(0.5):.4f} N, p90 {q(0.9):.4f} N, "
          f"p99 {q(0.99):.4f} N, max {steps[-1]:.3f} N, {sum(x > 0.1 for x in steps)} of {n} over 0.1 N; peak force {peak:.3f} N")

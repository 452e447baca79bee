"""A sweep of 64 tress scenarios in-process (threads) and on Ray in local mode: wall time.

    .venv/bin/python bench/python_sweep.py [--n 64]

The scenarios are the comb stroke of examples/scenarios/comb-h1.toml with 64 different patch seeds (and the
four Table 1 hair types in turn). Ray's start-up is timed separately (`ray.init`), then the sweep.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import sys
import time

import coiffure

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "examples" / "python"))
from combing_sweep import comb_stroke  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=64)
    args = ap.parse_args()
    types = ["H1", "H2", "GA1", "GC3"]
    scenarios = []
    for i in range(args.n):
        s = comb_stroke(types[i % 4], 0.0)
        s["name"] = f"comb-{i}"
        s["patch"]["seed"] = i + 1
        scenarios.append(s)
    print(f"{args.n} scenarios, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    t0 = time.perf_counter()
    local = coiffure.sweep(scenarios)
    t_in = time.perf_counter() - t0
    print(f"in-process: {t_in:.1f} s wall ({local['wall_time'].sum():.1f} s of scenario time; errors {local['error'].notna().sum()})")
    import ray

    t0 = time.perf_counter()
    ray.init(address="local", include_dashboard=False, log_to_driver=False)
    t_init = time.perf_counter() - t0
    t0 = time.perf_counter()
    remote = coiffure.sweep(scenarios, ray_address="local")
    t_ray = time.perf_counter() - t0
    ray.shutdown()
    print(f"Ray local:  {t_ray:.1f} s wall after ray.init ({t_init:.1f} s) ({remote['wall_time'].sum():.1f} s of scenario time; errors {remote['error'].notna().sum()})")
    peak = "peak_force_n"
    print(f"same peak forces: {bool((local[peak] == remote[peak]).all())}")


if __name__ == "__main__":
    main()

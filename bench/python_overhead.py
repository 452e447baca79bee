"""Overhead of coiffure.run_scenario against the command line for the same scenario (target: under 5 %).

    .venv/bin/python bench/python_overhead.py [SCENARIO.toml] [--repeat 5]

Times, alternately, `coiffure run SCENARIO --out TMP` as a process (target/release/coiffure, built by
`cargo build --release -p coiffure-server`) and `coiffure.run_scenario(SCENARIO)` in this process, and prints
the median wall time of each and the relative difference. Both run the same engine code; the Python call
also converts the trace to numpy arrays, the CLI also writes force.csv and summary files.
"""

from __future__ import annotations

import argparse
import pathlib
import statistics
import subprocess
import tempfile
import time

import coiffure

REPO = pathlib.Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(REPO / "examples" / "scenarios" / "comb-h1.toml"))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cli", default=str(REPO / "target" / "release" / "coiffure"))
    args = ap.parse_args()
    cli, py = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            subprocess.run([args.cli, "run", args.scenario, "--out", tmp], check=True, capture_output=True)
            cli.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            coiffure.run_scenario(args.scenario)
            py.append(time.perf_counter() - t0)
    c, p = statistics.median(cli), statistics.median(py)
    print(f"scenario {args.scenario}")
    print(f"CLI (process)      median {c:.3f} s  runs {', '.join(f'{x:.3f}' for x in cli)}")
    print(f"run_scenario       median {p:.3f} s  runs {', '.join(f'{x:.3f}' for x in py)}")
    print(f"overhead           {100 * (p - c) / c:+.1f} %")


if __name__ == "__main__":
    main()

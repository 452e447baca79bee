"""Combing force of the four Table 1 hair types, dry and wet, as a sweep; writes docs/img/combing-sweep.png.

    .venv/bin/pip install "./crates/python[ray]" matplotlib
    .venv/bin/python examples/python/combing_sweep.py [--ray local] [--out docs/img/combing-sweep.png]

The scenario is the comb stroke of examples/scenarios/comb-*.toml (24 full-model strands of 20 cm standing
for a 4.75 g tress, the comb entering 1 cm below the roots and stroking down at 0.25 m/s), built here as a
dict read from that file and varied in ``patch.hair_type`` and ``patch.wetness`` (0 dry, 1 soaked; see
docs/wetness.md).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import tomllib

import numpy as np

import coiffure

REPO = pathlib.Path(__file__).resolve().parents[2]
HAIR_TYPES = ["H1", "H2", "GA1", "GC3"]


def comb_stroke(hair_type: str, wetness: float) -> dict:
    """The comb stroke of examples/scenarios/comb-h1.toml (read from that file, so the two never drift apart)
    for another hair type and wetness (0 dry .. 1 soaked)."""
    with open(REPO / "examples" / "scenarios" / "comb-h1.toml", "rb") as f:
        d = tomllib.load(f)
    d["patch"]["hair_type"] = hair_type
    d["patch"]["wetness"] = wetness
    d["name"] = f"comb-{hair_type.lower()}" + ("-wet" if wetness else "")
    return d


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ray", default=None, help='Ray address ("local" starts Ray here); default: in-process')
    ap.add_argument("--out", default=str(REPO / "docs" / "img" / "combing-sweep.png"))
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    wet = True
    levels = [0.0, 1.0]
    scenarios = [comb_stroke(h, w) for w in levels for h in HAIR_TYPES]
    table = coiffure.sweep(scenarios, ray_address=args.ray)
    failed = table[table["error"].notna()]
    if len(failed):
        print(failed[["name", "error"]].to_string(), file=sys.stderr)
        return 1
    cols = ["name", "patch.hair_type"] + (["patch.wetness"] if wet else []) + ["peak_force", "mean_force", "work", "wall_time"]
    print(table[[c for c in cols if c in table.columns]].to_string(index=False))

    # Force traces of the dry strokes (run_scenario gives the arrays) and the sweep's summary.
    fig, (ax_t, ax_b) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1.5, 1]})
    for h in HAIR_TYPES:
        r = coiffure.run_scenario(comb_stroke(h, 0.0 if wet else None))
        ax_t.plot(r["t"], np.linalg.norm(r["force"], axis=1), lw=0.8, label=h)
    ax_t.set_yscale("log")
    ax_t.set_ylim(1e-5, None)
    ax_t.set_xlabel("time since the comb started, s")
    ax_t.set_ylabel("|force on the comb|, N")
    ax_t.set_title("dry comb stroke, 4.75 g tress")
    ax_t.legend(frameon=False)

    x = np.arange(len(HAIR_TYPES))
    width = 0.8 / len(levels)
    for k, w in enumerate(levels):
        rows = table[table["patch.wetness"] == w] if wet else table
        peak = [rows[rows["patch.hair_type"] == h]["peak_force"].iloc[0] for h in HAIR_TYPES]
        label = "dry" if not w else "wet (w = 1)"
        ax_b.bar(x + (k - (len(levels) - 1) / 2) * width, peak, width, label=label)
    # Measured peak combing force of 4.75 g tresses at 0.2-0.3 m/s (J. Soc. Cosmet. Chem. 24, 1973, Table I:
    # 12-13 gf dry, 88-95 gf wet): what the simulation should reach (issue 12).
    ax_b.axhline(0.12, color="C0", ls="--", lw=1, label="measured, dry (0.12 N)")
    ax_b.axhline(0.9, color="C1", ls="--", lw=1, label="measured, wet (0.9 N)")
    ax_b.set_yscale("log")
    ax_b.set_xticks(x, HAIR_TYPES)
    ax_b.set_ylabel("peak force, N")
    ax_b.set_title("sweep: peak combing force" + ("" if wet else "\n(dry only: no patch.wetness key yet)"))
    ax_b.legend(frameon=False)
    fig.tight_layout()
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

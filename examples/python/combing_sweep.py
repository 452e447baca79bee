"""Combing force by surface treatment and hair type, dry and wet, as a sweep; writes docs/img/combing-sweep.png.

    .venv/bin/pip install "./crates/python[ray]" matplotlib
    .venv/bin/python examples/python/combing_sweep.py [--ray local] [--out docs/img/combing-sweep.png]

The scenario is the comb stroke of examples/scenarios/comb-*.toml (24 full-model strands of 20 cm standing
for a 4.75 g tress, the comb entering 1 cm below the roots and stroking down at 0.25 m/s), built here as a
dict read from that file and varied in ``patch.hair_type`` (every preset), ``patch.treatment`` (docs/treatment.md)
and ``patch.wetness`` (0 dry, 1 soaked; docs/wetness.md). It prints the table of docs/python.md (peak force of
every hair type and treatment, dry and wet, and each treatment's peak over virgin hair's against Newman et al.
1973's measured ratios) and plots the ratios and the combing curve (mean force by comb position over each fifth
of the tress, the combing instrument's ``mean_force_fifths_n``).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import tomllib

import numpy as np

import coiffure

REPO = pathlib.Path(__file__).resolve().parents[2]
HAIR_TYPES = ["H1", "H2", "GA1", "GC3", "asian", "caucasian", "african"]
TREATMENTS = ["virgin", "conditioned", "bleached", "bleached-twice"]
# Peak combing force of treated over virgin caucasian tresses, measured (Newman, Cohen and Hayes, J. Soc. Cosmet.
# Chem. 24, 1973; issue 29's acceptance): conditioned 0.8 dry and 0.45 wet, bleached 2.8 and twice 4.3 wet.
MEASURED = {("conditioned", 0.0): 0.8, ("conditioned", 1.0): 0.45, ("bleached", 1.0): 2.8, ("bleached-twice", 1.0): 4.3}


def comb_stroke(hair_type: str, wetness: float, treatment: str = "virgin") -> dict:
    """The comb stroke of examples/scenarios/comb-h1.toml (read from that file, so the two never drift apart)
    for another hair type, wetness (0 dry .. 1 soaked) and surface treatment."""
    with open(REPO / "examples" / "scenarios" / "comb-h1.toml", "rb") as f:
        d = tomllib.load(f)
    d["patch"]["hair_type"] = hair_type
    d["patch"]["wetness"] = wetness
    d["patch"]["treatment"] = treatment
    d["name"] = f"comb-{hair_type.lower()}-{treatment}" + ("-wet" if wetness else "")
    return d


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ray", default=None, help='Ray address ("local" starts Ray here); default: in-process')
    ap.add_argument("--out", default=str(REPO / "docs" / "img" / "combing-sweep.png"))
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    levels = [0.0, 1.0]
    scenarios = [comb_stroke(h, w, t) for w in levels for t in TREATMENTS for h in HAIR_TYPES]
    table = coiffure.sweep(scenarios, ray_address=args.ray)  # shows its progress on stderr
    failed = table[table["error"].notna()]
    if len(failed):
        print(failed[["name", "error"]].to_string(), file=sys.stderr)
        return 1
    table["patch.treatment"] = [s["patch"]["treatment"] for s in scenarios]
    table["patch.wetness"] = [s["patch"]["wetness"] for s in scenarios]

    def peak(h: str, t: str, w: float) -> float:
        row = table[(table["patch.hair_type"] == h) & (table["patch.treatment"] == t) & (table["patch.wetness"] == w)]
        return float(row["combing_peak_n"].iloc[0])

    # The table of docs/python.md: peak N dry / wet; treated over virgin, dry / wet.
    print("| hair type | " + " | ".join(f"{t} peak dry / wet" for t in TREATMENTS) + " | " + " | ".join(f"{t} / virgin dry / wet" for t in TREATMENTS[1:]) + " |")
    print("|---" * (2 * len(TREATMENTS)) + "|")
    for h in HAIR_TYPES:
        cells = [f"{peak(h, t, 0.0):.3f} / {peak(h, t, 1.0):.3f} N" for t in TREATMENTS]
        cells += [f"{peak(h, t, 0.0) / peak(h, 'virgin', 0.0):.2f} / {peak(h, t, 1.0) / peak(h, 'virgin', 1.0):.2f}" for t in TREATMENTS[1:]]
        print(f"| {h} | " + " | ".join(cells) + " |")
    measured = " | ".join(f"{MEASURED.get((t, 0.0), '-')} / {MEASURED.get((t, 1.0), '-')}" for t in TREATMENTS[1:])
    print("| measured (caucasian, Newman 1973) | " + " | ".join("" for _ in TREATMENTS) + " | " + measured + " |")
    print(f"wall time of the sweep's scenarios: {table['wall_time'].sum():.0f} s")

    # Left: treated over virgin peak, every hair type (dots) and the measured ratios (crosses), dry and wet.
    # Right: the combing curve of caucasian hair (mean force by comb position over each fifth), per treatment.
    fig, (ax_r, ax_c) = plt.subplots(1, 2, figsize=(11, 4.2))
    x = np.arange(len(TREATMENTS) - 1)
    labelled = set()

    def once(label: str):
        """The label the first time only (one legend entry per kind of mark)."""
        return None if label in labelled or labelled.add(label) else label

    for k, (w, label) in enumerate([(0.0, "dry"), (1.0, "wet")]):
        off = (k - 0.5) * 0.3
        for i, t in enumerate(TREATMENTS[1:]):
            ratios = [peak(h, t, w) / peak(h, "virgin", w) for h in HAIR_TYPES]
            ax_r.scatter(np.full(len(ratios), x[i] + off), ratios, s=14, color=f"C{k}", label=once(f"simulated, {label} (7 hair types)"))
            if (t, w) in MEASURED:
                ax_r.scatter([x[i] + off], [MEASURED[(t, w)]], marker="x", s=70, color=f"C{k}", label=once(f"measured, {label} (Newman 1973)"))
    ax_r.axhline(1.0, color="grey", lw=0.6)
    ax_r.set_yscale("log")
    ax_r.set_xticks(x, TREATMENTS[1:])
    ax_r.set_ylabel("peak combing force over virgin hair's")
    ax_r.set_title("treatments, 4.75 g tresses at 0.25 m/s")
    ax_r.legend(frameon=False, fontsize=8)
    pos = (np.arange(5) + 0.5) / 5
    for i, t in enumerate(TREATMENTS):
        for w, ls in [(0.0, "-"), (1.0, "--")]:
            row = table[(table["patch.hair_type"] == "caucasian") & (table["patch.treatment"] == t) & (table["patch.wetness"] == w)].iloc[0]
            fifths = [row[f"mean_force_fifths_n.{k}"] for k in range(5)]
            ax_c.plot(pos, [f if f > 0 else np.nan for f in fifths], ls, color=f"C{i}", marker="o", ms=3, label=f"{t}, {'dry' if w == 0 else 'wet'}")
    ax_c.set_yscale("log")
    ax_c.set_xlabel("comb position from the roots / tress length (fifths)")
    ax_c.set_ylabel("mean force by position, N")
    ax_c.set_title("combing curve, caucasian hair")
    ax_c.legend(frameon=False, fontsize=7, ncol=2)
    fig.tight_layout()
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    from PIL import Image  # matplotlib's own dependency: a 64-colour palette keeps the committed PNG small

    Image.open(out).convert("RGB").quantize(64).save(out, optimize=True)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

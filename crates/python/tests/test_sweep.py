"""coiffure.sweep: in-process and on Ray (local mode) give the same table; failures stay in their rows."""

from __future__ import annotations

import pandas as pd
import ray

import coiffure
from test_scenario import small_comb


def four() -> list:
    """Four small comb strokes varying the hair type, one of them with a bad value."""
    scenarios = [small_comb(h) for h in ["H1", "H2", "GA1"]]
    bad = small_comb("GC3")
    bad["patch"]["strands"] = 0  # invalid: reported in its row
    return scenarios + [bad]


def check_table(t):
    assert list(t["scenario"]) == [0, 1, 2, 3]
    assert list(t["patch.hair_type"]) == ["H1", "H2", "GA1", "GC3"]
    assert "patch.strands" in t.columns and "dt" not in t.columns  # only what varies
    assert t["error"].iloc[:3].isna().all()
    assert "strands" in t["error"].iloc[3]
    peak = [c for c in t.columns if c.startswith("peak_force")][0]
    assert (t[peak].iloc[:3] > 0).all() and pd.isna(t[peak].iloc[3])


def test_sweep_in_process_equals_the_single_runs():
    t = coiffure.sweep(four())
    check_table(t)
    peak = [c for c in t.columns if c.startswith("peak_force")][0]
    for i, s in enumerate(four()[:3]):
        assert t[peak].iloc[i] == coiffure.run_scenario(s)["summary"][peak]


def test_sweep_on_ray_local_gives_the_same_table():
    try:
        local = coiffure.sweep(four())
        remote = coiffure.sweep(four(), ray_address="local", workers=2)
    finally:
        ray.shutdown()
    check_table(remote)
    drop = ["wall_time"] + [c for c in local.columns if "wall" in c]
    pd.testing.assert_frame_equal(local.drop(columns=drop), remote.drop(columns=drop))

"""coiffure.sweep: in-process and on Ray (local mode) give the same table; failures stay in their rows."""

from __future__ import annotations

import sys
import types

import numpy as np
import pandas as pd
import pytest
import ray

import coiffure
from test_scenario import short_live_comb, small_comb


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
    peak = "peak_force_n"
    assert (t[peak].iloc[:3] > 0).all() and pd.isna(t[peak].iloc[3])


def test_sweep_in_process_equals_the_single_runs():
    t = coiffure.sweep(four())
    check_table(t)
    peak = "peak_force_n"
    for i, s in enumerate(four()[:3]):
        assert t[peak].iloc[i] == coiffure.run_scenario(s)["summary"][peak]


def test_a_sweep_over_mixed_kinds_has_one_column_per_quantity():
    """Issue 33: a tress (patch) and a `[live]` scenario name their shared quantities alike, so a sweep over both
    gets one column for each (filled in both rows), and no column of an old, unit-less name."""
    t = coiffure.sweep([small_comb("H1"), short_live_comb()], progress=False)
    assert list(t["kind"]) == ["patch", "live"] and t["error"].isna().all()
    for key in ["peak_force_n", "mean_force_n", "contact_steps", "steps", "wall_time_s"]:
        assert t[key].notna().all(), key
    assert (t["peak_force_n"] > 0).all()
    for old in ["peak_force", "mean_force", "work", "clamped_steps", "tress_mass"]:
        assert old not in t.columns, old


def test_sweep_on_ray_local_gives_the_same_table():
    try:
        local = coiffure.sweep(four())
        remote = coiffure.sweep(four(), ray_address="local", workers=2)
    finally:
        ray.shutdown()
    check_table(remote)
    drop = ["wall_time"] + [c for c in local.columns if "wall" in c]
    pd.testing.assert_frame_equal(local.drop(columns=drop), remote.drop(columns=drop))


def three() -> list:
    """Three small comb strokes varying the hair type."""
    return [small_comb(h) for h in ["H1", "H2", "GA1"]]


def test_sweep_reports_each_scenario_done_with_the_time_left():
    # A callable gets (done, total, seconds_left) after each scenario: done counts 1..3 in order, the time
    # left known from the first on and 0 at the end.
    calls = []
    coiffure.sweep(three(), progress=lambda done, total, left: calls.append((done, total, left)), workers=2)
    assert [(d, t) for d, t, _ in calls] == [(1, 3), (2, 3), (3, 3)]
    assert all(left is not None and left >= 0 for _, _, left in calls) and calls[-1][2] == 0


def test_sweep_progress_without_tqdm_writes_lines_and_progress_false_writes_nothing(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "tqdm", None)  # as if tqdm were not installed
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    coiffure.sweep(three())
    lines = [l for l in capsys.readouterr().err.splitlines() if l.startswith("coiffure.sweep:")]
    assert lines[0].startswith("coiffure.sweep: 1/3 scenarios done, ") and lines[0].endswith(" left"), lines
    assert lines[-1] == "coiffure.sweep: 3/3 scenarios done, 0:00 left", lines
    coiffure.sweep(three(), progress=False)
    assert "coiffure.sweep" not in capsys.readouterr().err


def test_sweep_progress_uses_tqdm_where_installed(monkeypatch):
    # A stand-in tqdm module records what the sweep asks of it: a bar of 3, three updates of 1, closed.
    made = []

    class Bar:
        def __init__(self, total, **kw):
            self.total, self.updates, self.closed = total, [], False
            made.append(self)

        def update(self, n):
            self.updates.append(n)

        def close(self):
            self.closed = True

    fake = types.ModuleType("tqdm.auto")
    fake.tqdm = Bar
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", fake)
    coiffure.sweep(three())
    assert len(made) == 1 and made[0].total == 3 and made[0].updates == [1, 1, 1] and made[0].closed


def test_sweep_on_ray_reports_progress_as_results_arrive():
    calls = []
    try:
        coiffure.sweep(three(), ray_address="local", workers=2, progress=lambda d, t, left: calls.append((d, t)))
    finally:
        ray.shutdown()
    assert calls == [(1, 3), (2, 3), (3, 3)]


def test_the_combing_figures_are_columns():
    # The combing rig's figures of summary.json are columns: lists indexed (the five fifths, per stroke), equal
    # to run_scenario's summary and to the profile arrays integrated here.
    two = small_comb("H1")
    two["tool"]["strokes"] = 2
    two["duration"] = None  # the default: both strokes and the return between them
    t = coiffure.sweep([small_comb("H1"), two], progress=False)
    r = coiffure.run_scenario(two)
    s = r["summary"]
    row = t.iloc[1]
    assert row["combing_work_j"] == s["combing_work_j"] > 0
    for k in range(5):
        assert row[f"work_fifths_j.{k}"] == s["work_fifths_j"][k]
        assert row[f"mean_force_fifths_n.{k}"] == s["mean_force_fifths_n"][k]
    for n in range(2):
        assert row[f"per_stroke.combing_work_j.{n}"] == s["per_stroke"]["combing_work_j"][n]
        assert row[f"per_stroke.work_fifths_j.{n}.4"] == s["per_stroke"]["work_fifths_j"][n][4]
    assert pd.isna(t.iloc[0]["per_stroke.combing_work_j.1"]), "one stroke: no second stroke's column value"
    p = r["profile"]
    assert set(np.unique(p["stroke"])) == {1, 2}
    work = 0.0
    for n in (1, 2):
        x, f = p["position_m"][p["stroke"] == n], p["force_n"][p["stroke"] == n]
        w = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.abs(np.diff(x))))
        assert w == pytest.approx(s["per_stroke"]["combing_work_j"][n - 1], rel=1e-12)
        work += w
    assert work == pytest.approx(s["combing_work_j"], rel=1e-12)

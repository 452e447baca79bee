"""coiffure.run_scenario against the command line's files (same engine code, same numbers)."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import coiffure


def small_comb(hair_type: str = "H1", **patch) -> dict:
    """A short comb stroke through a small tress (quick: 4 strands, 0.25 s)."""
    quarter = [1.5707963, 0.0, 0.0]
    return {
        "name": f"small-{hair_type.lower()}",
        "dt": 0.001,
        "settle": 0.05,
        "duration": 0.25,
        "patch": {"hair_type": hair_type, "strands": 4, "length": 0.1, "segments": 6, "root": [0.0, 0.0, 0.3],
                  "extent": [0.008, 0.003], "tress_mass": 1e-3, **patch},
        "tool": {
            "shape": "comb",
            "path": [
                {"t": 0.0, "position": [0.0004, -0.03, 0.29], "rotation": quarter},
                {"t": 0.05, "position": [0.0004, -0.008, 0.29], "rotation": quarter},
                {"t": 0.25, "position": [0.0004, -0.008, 0.22], "rotation": quarter},
            ],
        },
    }


def write_toml(path, d: dict) -> None:
    """A scenario dict as TOML (enough for the dicts of these tests)."""

    def val(v):
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)

    lines, tables = [], []
    for k, v in d.items():
        (tables if isinstance(v, dict) else lines).append((k, v))
    text = "\n".join(f"{k} = {val(v)}" for k, v in lines) + "\n"
    for name, t in tables:
        text += f"\n[{name}]\n" + "\n".join(f"{k} = {val(v)}" for k, v in t.items()) + "\n"
    path.write_text(text)


def assert_same(got, want, key: str) -> None:
    """`got` equals `want` (summary.json values: strings exactly, numbers to 1e-12 relative, dicts and lists entry
    by entry)."""
    if isinstance(want, dict):
        assert set(got) == set(want), key
        for k in want:
            assert_same(got[k], want[k], f"{key}.{k}")
    elif isinstance(want, list):
        assert len(got) == len(want), key
        for i, (g, w) in enumerate(zip(got, want)):
            assert_same(g, w, f"{key}[{i}]")
    elif isinstance(want, str):
        assert got == want, key
    else:
        assert got == pytest.approx(want, rel=1e-12), key


def test_scenario_arrays_equal_the_cli_force_csv(cli, tmp_path):
    scenario = small_comb()
    toml_path = tmp_path / "small.toml"
    write_toml(toml_path, scenario)
    subprocess.run([str(cli), "run", str(toml_path), "--out", str(tmp_path / "cli")], check=True, capture_output=True)
    csv = np.loadtxt(tmp_path / "cli" / "force.csv", delimiter=",", skiprows=1)
    for source in (scenario, toml_path):
        r = coiffure.run_scenario(source)
        steps = round(0.25 / 0.001)
        assert r["kind"] == "patch" and r["name"] == "small-h1"
        assert r["t"].shape == (steps,) and r["contacts"].shape == (steps,)
        for key in ("force", "torque", "tool"):
            assert r[key].shape == (steps, 3) and r[key].dtype == np.float64
        assert r["contacts"].max() > 0, "the comb must touch the hair for the test to mean something"
        # force.csv prints t with 4 decimals and the rest with 7 significant digits: equal to that rounding.
        assert np.allclose(r["t"], csv[:, 0], rtol=0, atol=5e-5)
        got = np.column_stack([r["force"], r["torque"]])
        assert np.all(np.abs(got - csv[:, 1:7]) <= 5e-7 * np.abs(csv[:, 1:7]) + 1e-300)
        assert np.array_equal(r["contacts"], csv[:, 7].astype(np.int64))
        assert np.allclose(r["tool"], csv[:, 8:11], rtol=5e-7, atol=0)
        # The summary is the CLI's summary.json (nested dicts and lists, such as the combing figures per stroke,
        # compared entry by entry).
        summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
        for k, v in summary.items():
            if "wall" not in k:
                assert_same(r["summary"][k], v, k)
        # The combing rig's recording is the CLI's profile.csv (t to 4 decimals, the rest to 7 digits).
        prof = np.loadtxt(tmp_path / "cli" / "profile.csv", delimiter=",", skiprows=1)
        p = r["profile"]
        assert np.array_equal(p["stroke"], prof[:, 0].astype(np.int64)) and np.allclose(p["t"], prof[:, 1], rtol=0, atol=5e-5)
        assert np.allclose(p["position_m"], prof[:, 2], rtol=5e-7, atol=0) and np.allclose(p["force_n"], prof[:, 3], rtol=5e-7, atol=1e-300)
        # Peak force = the largest |force| of the trace.
        peak = r["summary"]["peak_force_n"]
        assert peak == pytest.approx(np.linalg.norm(r["force"], axis=1).max(), rel=1e-12)


def test_nothing_is_written_unless_asked(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    coiffure.run_scenario(small_comb())
    assert list(tmp_path.iterdir()) == []
    coiffure.run_scenario(small_comb(), out=tmp_path / "out")
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert "force.csv" in names and "summary.json" in names


def test_bad_scenarios_raise_value_error_naming_the_key():
    with pytest.raises(ValueError, match="hair_tipe"):
        coiffure.run_scenario({**small_comb(), "patch": {"hair_tipe": "H1"}})
    bad = small_comb()
    bad["dt"] = 0.5
    with pytest.raises(ValueError, match="dt"):
        coiffure.run_scenario(bad)
    with pytest.raises(FileNotFoundError):
        coiffure.run_scenario("/nonexistent/scenario.toml")


def test_global_scenario_gives_rows_and_the_hairstyle():
    r = coiffure.run_scenario({
        "name": "tiny-cut", "duration": 0.05,
        "hairstyle": {"guides": 6, "segments": 4, "render_strands": 50, "render_vertices": 8},
        "action": [{"kind": "cut", "t": 0.01, "point": [0.0, -0.05, -0.08], "normal": [0.0, 0.0, 1.0], "radius": 0.25}],
    })
    assert r["kind"] == "global"
    assert r["t"].shape == (0,) and r["force"].shape == (0, 3)
    g = r["global"]
    assert g["t"].shape == g["mean_tip_z"].shape and g["wetness"].shape == (len(g["t"]), 3)
    assert len(r["hairstyle"]) == 50 and all(s.shape[1] == 3 for s in r["hairstyle"])
    assert r["summary"]["render_strands"] == 50


def short_live_comb() -> dict:
    """A shortened examples/scenarios/live-comb.toml: the live session's cores in lockstep, 2,000 render
    strands, the comb drawn 3 cm down the back of the head."""
    rot = [0.0, 2.2214415, -2.2214415]
    return {
        "name": "short-live-comb",
        "settle": 0.1,
        "duration": 0.3,
        "live": {"render_strands": 2000, "device": "phantom-omni", "hair_type": "caucasian"},
        "tool": {
            "shape": "comb",
            "path": [
                {"t": 0.0, "position": [0.0, -0.118, 0.05], "rotation": rot},
                {"t": 0.3, "position": [0.0, -0.118, 0.02], "rotation": rot},
            ],
        },
    }


def test_live_scenario_equals_the_cli(cli, tmp_path):
    """A `[live]` scenario from Python runs the live session's own cores: the same force trace and summary as
    `coiffure run` on the same TOML (deterministic lockstep; equal to force.csv's printed rounding)."""
    scenario = short_live_comb()
    toml_path = tmp_path / "live.toml"
    write_toml(toml_path, scenario)
    subprocess.run([str(cli), "run", str(toml_path), "--out", str(tmp_path / "cli")], check=True, capture_output=True)
    csv = np.loadtxt(tmp_path / "cli" / "force.csv", delimiter=",", skiprows=1)
    r = coiffure.run_scenario(scenario)
    assert r["kind"] == "live" and r["summary"]["kind"] == "live"
    assert r["force"].shape == (csv.shape[0], 3)
    assert np.all(np.abs(r["force"] - csv[:, 1:4]) <= 5e-7 * np.abs(csv[:, 1:4]) + 1e-300)
    assert np.allclose(r["tool"], csv[:, 8:11], rtol=5e-7, atol=1e-12)
    summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    for k in ("steps", "clamp_steps", "peak_force_n", "max_displacement_m", "final_max_displacement_m"):
        assert r["summary"][k] == pytest.approx(summary[k], rel=1e-12), k
    assert r["summary"]["steps"] > 0

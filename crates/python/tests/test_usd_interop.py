"""USD interoperability with Pixar's usd-core (`pip install usd-core`): a hairstyle written by usd-core as
a DCC tool writes it (cubic B-spline curves in a nested Xform, centimetres, y up) goes through
`coiffure fit` onto the head, and the .usda files Coiffure writes open in usd-core with metres and z up.

Needs `pxr` (usd-core, in requirements-test.txt) and the `coiffure` binary (the `cli` fixture of conftest.py)."""

import json
import math
import os
import subprocess
from pathlib import Path

from pxr import Gf, Sdf, Usd, UsdGeom, Vt

REPO = Path(__file__).resolve().parents[3]


def write_dcc_hairstyle(path):
    """Strands rooted on the upper half of a 10 cm sphere (in cm, y up, the face towards +z and bare), each a
    pinned cubic B-spline of 6 control points hanging down and out; in /character/groom/hair."""
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageMetersPerUnit(stage, UsdGeom.LinearUnits.centimeters)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    root = UsdGeom.Xform.Define(stage, "/character")
    stage.SetDefaultPrim(root.GetPrim())
    UsdGeom.Xform.Define(stage, "/character/groom")
    curves = UsdGeom.BasisCurves.Define(stage, "/character/groom/hair")
    curves.CreateTypeAttr(UsdGeom.Tokens.cubic)
    curves.CreateBasisAttr(UsdGeom.Tokens.bspline)
    curves.CreateWrapAttr(UsdGeom.Tokens.pinned)
    centre = Gf.Vec3f(3.0, 160.0, -2.0)  # the other tool's head centre, cm
    points, counts, roots = [], [], []
    n = 400
    golden = 0.5 * (math.sqrt(5.0) - 1.0)
    for i in range(n):
        up = 0.15 + 0.85 * (i + 0.5) / n  # height of the root on the unit sphere (y)
        phi = 2.0 * math.pi * ((i * golden) % 1.0)
        r = math.sqrt(1.0 - up * up)
        d = Gf.Vec3f(r * math.sin(phi), up, r * math.cos(phi))  # +z is the face
        if d[2] > 0.55 and up < 0.6:
            continue  # the face is bare
        root = centre + 10.0 * d
        roots.append(root)
        out = Gf.Vec3f(d[0], 0.0, d[2])
        for k in range(6):
            points.append(root + 1.2 * k * d * (1.0 if k < 2 else 0.3) + out * (0.4 * k) - Gf.Vec3f(0, 3.0 * k * k / 5.0, 0))
        counts.append(6)
    curves.CreatePointsAttr(Vt.Vec3fArray(points))
    curves.CreateCurveVertexCountsAttr(Vt.IntArray(counts))
    curves.CreateWidthsAttr(Vt.FloatArray([0.008]))
    curves.SetWidthsInterpolation(UsdGeom.Tokens.constant)
    stage.GetRootLayer().Save()
    return len(counts)


def test_a_usd_core_cubic_nested_centimetre_hairstyle_loads_and_fits(cli, tmp_path):
    src = tmp_path / "dcc.usda"
    n = write_dcc_hairstyle(src)
    text = src.read_text()
    assert "bspline" in text and 'metersPerUnit = 0.01' in text and 'upAxis = "Y"' in text
    out = tmp_path / "fitted.usda"
    run = subprocess.run([str(cli), "fit", str(src), str(out), "--json"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    print(report)
    assert report["meters_per_unit"] == 0.01 and report["units_source"] == "metadata"
    assert report["up"] == "+y" and report["orientation_source"] in ("metadata", "detected")
    assert report["front"] == "+z"
    # the roots (the pinned B-splines' first control points) on the scalp
    assert report["root_distance"]["median"] < 0.003, report
    assert report["root_distance"]["p95"] < 0.01, report
    stage = Usd.Stage.Open(str(out))
    prim = stage.GetPrimAtPath("/hair/strands")
    assert len(UsdGeom.BasisCurves(prim).GetCurveVertexCountsAttr().Get()) == n


def test_our_usda_opens_in_usd_core_with_metres_and_z_up(cli, tmp_path):
    src = tmp_path / "dcc.usda"
    n = write_dcc_hairstyle(src)
    out = tmp_path / "ours.usda"
    run = subprocess.run([str(cli), "fit", str(src), str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    stage = Usd.Stage.Open(str(out))
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert stage.GetDefaultPrim().GetPath() == Sdf.Path("/hair")
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/hair/strands"))
    assert curves.GetTypeAttr().Get() == UsdGeom.Tokens.linear
    counts = curves.GetCurveVertexCountsAttr().Get()
    points = curves.GetPointsAttr().Get()
    assert len(counts) == n and sum(counts) == len(points)
    widths = curves.GetWidthsAttr().Get()
    assert len(widths) > 0 and all(0 < w < 0.001 for w in widths)  # metres: hair is tens of micrometres thick
    # in the head frame: every point within 1 m of the head centre
    assert max(max(abs(c) for c in p) for p in points) < 1.0

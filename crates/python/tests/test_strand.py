"""coiffure.Strand against the command line and against independently computed answers.

Physics checks mirror crates/strand/tests/validation.rs: the large-deflection cantilever against a shooting
solution of the elastica (computed here in numpy, not with the Super-Helix code), natural frequencies against
Euler-Bernoulli beam theory. Tolerances are stated next to each assertion."""

from __future__ import annotations

import io
import math
import subprocess

import numpy as np
import pytest

import coiffure

# A heavy H1 cantilever: horizontal root, the major axis horizontal so that it sags by bending about it.
# q L^3 / EI is about 10: the tip drops by about half the length (large deflection).
HEAVY = {
    "length": 0.1,
    "segments": 32,
    "hair_type": "H1",
    "root_position": [0.0, 0.0, 0.0],
    "root_tangent": [1.0, 0.0, 0.0],
    "root_major_axis": [0.0, 1.0, 0.0],
}


def h1() -> dict:
    return next(h for h in coiffure.hair_types() if h["name"] == "H1")


def shooting_tip(ei: float, q: float, length: float, steps: int = 4000) -> tuple[float, float]:
    """Tip (x, z) of the elastica EI theta'' + q (L - s) cos(theta) = 0, theta(0) = 0, theta'(L) = 0 (theta
    below the horizontal), by RK4 and secant iterations on theta'(0). Independent of the Super-Helix code."""
    h = length / steps

    def f(s, y):
        return np.array([y[1], -q * (length - s) * math.cos(y[0]) / ei, math.cos(y[0]), -math.sin(y[0])])

    def run(c):
        y = np.array([0.0, c, 0.0, 0.0])
        for i in range(steps):
            s = i * h
            k1 = f(s, y)
            k2 = f(s + h / 2, y + h / 2 * k1)
            k3 = f(s + h / 2, y + h / 2 * k2)
            k4 = f(s + h, y + h * k3)
            y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return y

    c0, c1 = 0.0, q * length**2 / (2 * ei)  # theta'(0) is between 0 and the linear root curvature
    r0, r1 = run(c0)[1], run(c1)[1]
    for _ in range(30):
        c2 = c1 - r1 * (c1 - c0) / (r1 - r0)
        c0, r0, c1, r1 = c1, r1, c2, run(c2)[1]
        if abs(r1) < 1e-12 * c1:
            break
    y = run(c1)
    return y[2], y[3]


def test_hair_types_are_the_presets_with_units():
    types = coiffure.hair_types()
    assert [t["name"] for t in types][:4] == ["H1", "H2", "GA1", "GC3"]
    t = h1()
    # Table 1: 93.1 um major diameter, ellipticity 1.36, EI 7.59e-9 N m^2, friction 0.64 cN.
    assert t["major_diameter"] == pytest.approx(93.1e-6, rel=1e-12)
    a, b = t["semi_axes"]
    assert a == pytest.approx(93.1e-6 / 2, rel=1e-12) and a / b == pytest.approx(1.36, rel=1e-12)
    # E I_soft = E pi a b^3 / 4 reproduces the measured bending stiffness (1e-12 relative).
    assert t["young_modulus"] * math.pi * a * b**3 / 4 == pytest.approx(7.59e-9, rel=1e-12)
    assert t["friction_force"] == pytest.approx(0.64e-2)
    assert t["linear_density"] == pytest.approx(t["density"] * math.pi * a * b, rel=1e-12)
    assert "Table 1" in t["source"]
    african = next(h for h in types if h["name"] == "african")
    # The natural curl as a helix: radius bend / (twist^2 + bend^2) = 6 mm.
    assert african["rest_bend"] / (african["rest_bend"] ** 2 + african["rest_twist"] ** 2) == pytest.approx(0.006, rel=1e-9)


def test_heavy_cantilever_agrees_with_the_cli_to_1e12(repo, cli, tmp_path):
    spec = tmp_path / "heavy.toml"
    spec.write_text(
        "\n".join(
            [
                'model = "reduced"',
                "length = 0.1",
                "segments = 32",
                'hair_type = "H1"',
                "root_position = [0.0, 0.0, 0.0]",
                "root_tangent = [1.0, 0.0, 0.0]",
                "root_major_axis = [0.0, 1.0, 0.0]",
            ]
        )
    )
    out = subprocess.run([str(cli), "strand", "--spec", str(spec), "--static", "--samples", "33"], capture_output=True, text=True, check=True)
    ref = np.loadtxt(io.StringIO(out.stdout), delimiter=",", skiprows=1)
    for source in (HEAVY, spec, str(spec)):  # a dict, a Path and a str give the same strand
        s = coiffure.Strand.from_spec(source)
        info = s.solve_static()
        assert info["stable"]
        pts = s.centerline(33)
        assert pts.shape == (33, 3)
        # The CLI prints 13 significant digits of metres: 1e-12 m is beyond its rounding only.
        assert np.max(np.abs(pts - ref[:, 1:])) < 1e-12
    assert np.allclose(ref[:, 0], np.linspace(0.0, 0.1, 33), atol=1e-12)


@pytest.mark.parametrize("model", ["reduced", "full"])
def test_heavy_cantilever_matches_the_shooting_solution(model):
    s = coiffure.Strand.from_spec({**HEAVY, "model": model})
    assert s.model == model and s.dofs == (2 if model == "reduced" else 3) * 32
    s.solve_static()
    t = h1()
    a, b = t["semi_axes"]
    ei = t["young_modulus"] * math.pi * a * b**3 / 4
    q = t["linear_density"] * 9.81
    xs, zs = shooting_tip(ei, q, 0.1)
    assert zs < -0.03, "large-deflection regime"
    tip = s.tip
    # Same tolerance as the Rust test with 32 segments: 2e-3 L on the tip position.
    assert math.hypot(tip[0] - xs, tip[2] - zs) < 2e-3 * 0.1
    assert abs(tip[1]) < 1e-12  # no out-of-plane motion
    assert np.allclose(s.centerline(2)[1], tip, atol=1e-15)


@pytest.mark.parametrize("model", ["reduced", "full"])
def test_natural_frequencies_match_euler_bernoulli(model):
    # Without gravity the lowest modes are bending modes: w_n = (beta_n L)^2 sqrt(EI / (rho A L^4)),
    # beta L = 1.8751, 4.6941, about the major axis (E I_soft); the full model also bends about the minor axis
    # (E I_stiff = E pi a^3 b / 4, frequencies higher by the ellipticity). 32 segments: 0.5 % on the first
    # mode of each axis, 1 % on the second (as the Rust test).
    s = coiffure.Strand.from_spec({**HEAVY, "model": model, "length": 0.05, "gravity": [0.0, 0.0, 0.0]})
    t = h1()
    a, b = t["semi_axes"]
    e = t["young_modulus"]
    rigidities = [e * math.pi * a * b**3 / 4] + ([e * math.pi * a**3 * b / 4] if model == "full" else [])
    expected = sorted(
        (bl**2 * math.sqrt(ei / (t["linear_density"] * 0.05**4)), tol)
        for ei in rigidities
        for bl, tol in [(1.875104068711961, 5e-3), (4.694091132974175, 1e-2)]
    )
    w = s.natural_frequencies(len(expected))
    assert w.shape == (len(expected),)
    for n, (exact, tol) in enumerate(expected):
        assert abs(w[n] - exact) < tol * exact, (n, w[n], exact)
    assert len(s.natural_frequencies()) == s.dofs


def test_dynamics_settles_on_the_static_solution():
    # Linearly implicit Euler at 1 ms with damping 0.2 s settles where statics says: tip within 1e-5 L
    # after 3 s (the Rust test's tolerance).
    s = coiffure.Strand.from_spec({**HEAVY, "segments": 16, "damping": 0.2})
    assert s.time == 0.0 and np.all(s.qdot == 0.0)
    s.step(dt=1e-3, steps=3000)
    assert s.time == pytest.approx(3.0, abs=1e-9)
    assert s.qdot.shape == (32,) and np.all(np.isfinite(s.qdot))
    statics = s.copy()
    statics.solve_static()
    assert np.linalg.norm(s.tip - statics.tip) < 1e-5 * 0.1
    # The copy is independent; reset goes back to the rest shape (straight: q = 0).
    s.reset()
    assert s.time == 0.0 and np.all(s.q == s.q_rest) and np.all(s.q == 0.0)


def test_q_and_qdot_are_settable_and_checked():
    s = coiffure.Strand.from_spec({"length": 0.05, "segments": 4})
    s.q = np.arange(8.0)
    assert np.all(s.q == np.arange(8.0))
    with pytest.raises(ValueError, match="8 values"):
        s.qdot = [0.0, 1.0]
    with pytest.raises(ValueError, match="finite"):
        s.q = [0.0] * 7 + [float("nan")]
    s.integrator = "midpoint"
    assert s.integrator == "midpoint"
    with pytest.raises(ValueError, match="euler"):
        s.integrator = "rk4"


def test_bad_specs_name_the_key():
    with pytest.raises(ValueError, match="lenght"):
        coiffure.Strand.from_spec({"lenght": 0.1, "segments": 4})
    with pytest.raises(ValueError, match="hair_type"):
        coiffure.Strand.from_spec({"length": 0.1, "segments": 4, "hair_type": "H9"})
    with pytest.raises(ValueError, match="rest_bend"):
        coiffure.Strand.from_spec({"length": 0.1, "segments": 4, "rest_bend": [1.0, 2.0]})
    with pytest.raises(ValueError, match="length"):
        coiffure.Strand.from_spec({"length": -1.0, "segments": 4})
    with pytest.raises(FileNotFoundError):
        coiffure.Strand.from_spec("/nonexistent/spec.toml")
    with pytest.raises(TypeError):
        coiffure.Strand.from_spec({"length": 0.1, "segments": 4, "gravity": object()})
    with pytest.raises(ValueError, match="dt"):
        coiffure.Strand.from_spec({"length": 0.1, "segments": 4}).step(dt=-1.0)
    # None means "default", numpy values are accepted.
    s = coiffure.Strand.from_spec({"length": np.float32(0.1), "segments": np.int64(4), "hair_type": None, "gravity": np.zeros(3)})
    assert s.length == pytest.approx(0.1, rel=1e-7) and s.segments == 4

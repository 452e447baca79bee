#!/usr/bin/env python3
"""Peer benchmark: Coiffure vs PyElastica on one hair cantilever, side by side.

Run (from the repository root):

    pip install -r bench/requirements.txt
    python bench/peer_pyelastica.py                      # reference + PyElastica + Coiffure
    python bench/peer_pyelastica.py --skip-coiffure      # reference + PyElastica only
    python bench/peer_pyelastica.py --length 0.03        # quicker (about 3x shorter PyElastica run)
    python bench/peer_pyelastica.py --json out.json      # also write the numbers as JSON

The problem: one human hair (type H1: elliptical section, semi-axes a = 46.55 um, b = 34.2 um,
diameter 93.1 um, ellipticity 1.36), horizontal along +x, clamped at the root, sagging under its own
weight (gravity -z, 9.81 m/s^2). It bends about its major axis (a is horizontal, along y), so the
bending stiffness is EI with I = pi a b^3 / 4 and the load per length is q = rho A g, A = pi a b.

Three things are computed and compared:

1. Reference: the inextensible, unshearable large-deflection elastica
       EI theta'' + q (L - s) cos theta = 0,   theta(0) = 0,   theta'(L) = 0
   (theta = downward angle of the tangent), solved by shooting on theta'(0) with solve_ivp (DOP853,
   rtol 1e-12) and brentq; the tip is the integral of (cos theta, -sin theta).
2. PyElastica 1.0 (explicit PositionVerlet Cosserat rod, ~50 elements). Its rods are circular, so it
   gets the equivalent circular section: radius r_eq with pi r_eq^4 / 4 = I (same EI) and density
   rho_eq with rho_eq pi r_eq^2 = rho A (same mass per length). E and G are passed as they are
   (G = 0.9 GPa corresponds to a "Poisson ratio" E/(2G) - 1 = 1.17; PyElastica 1.0 takes
   shear_modulus directly). It starts straight and relaxes to equilibrium with
   AnalyticalLinearDamper(uniform_damping_constant = gamma), gamma = 2 omega_1 (critical damping of
   the first linear bending mode, the slowest one). Wall time excludes numba compilation (a short
   warm-up run is done first).
3. Coiffure through its CLI: a dynamic run (`coiffure strand --spec ... --duration T --dt 0.001
   --samples 2 --trace ...`, tip = last trace row) and a static solve (`--static`). By default its
   air drag is set to the same translational damping rate as PyElastica's (c = gamma rho A), so
   both codes relax the same physical system; `--air-drag` overrides it.

The benchmark figure is wall-clock seconds per simulated second for each code, plus the tip error
|tip - tip_ref| (m) at steady state (and for the static solve), and the ratio
PyElastica / Coiffure of wall time per simulated second.

Choice of the default length L = 0.05 m: the gravity number q L^3 / EI is 1.40, the tip sags
8.5 mm (17 % of L) with a tip angle of 13 degrees, and the geometrically nonlinear part of the sag
(0.2 mm, 2.3 % of it) is far above PyElastica's discretisation error, so the reference genuinely
tests large deflection. At L = 0.03 m the hair barely sags (1.1 mm, tip angle 2.9 deg, nonlinear
part 1.3 um) and L = 0.1 m (63 deg) would be a better large-deflection test, but PyElastica's cost
to reach equilibrium grows like 1/omega_1 ~ L^2: its explicit step is bounded by the shear-rotation
mode of the cross-section, dt < ~ r_eq sqrt(3 rho_eq / (4 G)) ~ 4e-8 s whatever the element count
(measured: 4.3e-8 s stable, 5e-8 s diverges, for 25, 50 and 100 elements), so at L = 0.05 m
relaxing for ~12/omega_1 ~ 0.3 s of simulated time takes ~1e7 steps, i.e. tens of minutes.

Note on PyElastica's tip error: OneEndFixedBC holds the director of the whole first element, whose
centre sits at dl/2, so the discrete clamp acts as if the rod were rotated back by about
kappa_0 dl / 2 (kappa_0 = root curvature). The tip error is therefore first order in dl,
~ kappa_0 (dl / 2) L (measured at L = 0.03 m: 8.9e-5 m with 25 elements, 4.5e-5 m with 50,
2.3e-5 m with 100; at L = 0.05 m with 50 elements: 3.3e-4 m, 3.9 % of the sag).
"""
from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

REPO_ROOT = Path(__file__).resolve().parent.parent
GRAVITY = 9.81


# --------------------------------------------------------------------------------------------------
# Problem definition
# --------------------------------------------------------------------------------------------------
@dataclass
class Hair:
    length: float = 0.05  # m
    semi_a: float = 46.55e-6  # m, major semi-axis (horizontal, along y)
    semi_b: float = 34.2e-6  # m, minor semi-axis (vertical, along z)
    young: float = 3.9e9  # Pa
    shear: float = 0.9e9  # Pa
    density: float = 1300.0  # kg/m^3

    @property
    def area(self) -> float:
        return math.pi * self.semi_a * self.semi_b

    @property
    def second_moment(self) -> float:
        """I about the major axis (bending that sags in z)."""
        return math.pi * self.semi_a * self.semi_b**3 / 4.0

    @property
    def bending_stiffness(self) -> float:
        return self.young * self.second_moment

    @property
    def mass_per_length(self) -> float:
        return self.density * self.area

    @property
    def load_per_length(self) -> float:
        return self.mass_per_length * GRAVITY

    @property
    def r_eq(self) -> float:
        """Radius of the circle with the same I: pi r^4 / 4 = I."""
        return (4.0 * self.second_moment / math.pi) ** 0.25

    @property
    def rho_eq(self) -> float:
        """Density giving the circle the same mass per length."""
        return self.mass_per_length / (math.pi * self.r_eq**2)

    @property
    def poisson_eq(self) -> float:
        return self.young / (2.0 * self.shear) - 1.0

    @property
    def gravity_number(self) -> float:
        return self.load_per_length * self.length**3 / self.bending_stiffness

    @property
    def omega1(self) -> float:
        """First linear bending frequency of the cantilever (rad/s)."""
        return 1.8751040687**2 * math.sqrt(
            self.bending_stiffness / (self.mass_per_length * self.length**4)
        )

    def pyelastica_dt_bound(self) -> float:
        """Step bound from the shear-rotation mode of a Cosserat element, independent of dl.

        omega^2 = alpha_c G A / (rho I) = (4/3) G / rho * 4 / r^2  ->  dt < 2 / omega.
        """
        return self.r_eq * math.sqrt(3.0 * self.rho_eq / (4.0 * self.shear))


# --------------------------------------------------------------------------------------------------
# Reference: shooting solution of the large-deflection elastica
# --------------------------------------------------------------------------------------------------
def reference_tip(hair: Hair) -> dict:
    L, EI, q = hair.length, hair.bending_stiffness, hair.load_per_length

    def shoot(kappa0: float):
        def rhs(s, y):
            theta, dtheta = y[0], y[1]
            return [dtheta, -q * (L - s) * math.cos(theta) / EI, math.cos(theta), -math.sin(theta)]

        return solve_ivp(rhs, (0.0, L), [0.0, kappa0, 0.0, 0.0], method="DOP853",
                         rtol=1e-12, atol=1e-15)

    # theta'(L) < 0 at kappa0 = 0 and >= 0 at the linear root curvature q L^2 / (2 EI) (cos <= 1).
    upper = q * L**2 / (2.0 * EI)
    kappa0 = brentq(lambda k: shoot(k).y[1, -1], 0.0, upper, xtol=1e-15, rtol=1e-15)
    sol = shoot(kappa0)
    theta_l, _, x, z = sol.y[:, -1]
    return {
        "tip": [float(x), 0.0, float(z)],
        "root_curvature": float(kappa0),
        "tip_angle_deg": float(math.degrees(theta_l)),
        "linear_sag": float(-q * L**4 / (8.0 * EI)),
    }


def tip_error(tip, ref) -> float:
    return float(np.linalg.norm(np.asarray(tip, float) - np.asarray(ref, float)))


# --------------------------------------------------------------------------------------------------
# PyElastica
# --------------------------------------------------------------------------------------------------
def build_pyelastica(hair: Hair, n_elements: int, dt: float, gamma: float):
    import elastica as ea

    class Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    sim = Simulator()
    rod = ea.CosseratRod.straight_rod(
        n_elements,
        start=np.zeros(3),
        direction=np.array([1.0, 0.0, 0.0]),
        normal=np.array([0.0, 0.0, 1.0]),
        base_length=hair.length,
        base_radius=hair.r_eq,
        density=hair.rho_eq,
        youngs_modulus=hair.young,
        shear_modulus=hair.shear,
    )
    sim.append(rod)
    sim.constrain(rod).using(
        ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,)
    )
    sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -GRAVITY]))
    sim.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=gamma, time_step=dt)
    sim.finalize()
    return sim, rod


def run_pyelastica(hair: Hair, args, ref_tip, verbose: bool) -> dict:
    from elastica.timestepper.symplectic_steppers import PositionVerlet

    dt = args.pe_dt if args.pe_dt else args.pe_dt_factor * hair.pyelastica_dt_bound()
    gamma = args.pe_damping if args.pe_damping else 2.0 * hair.omega1
    stepper = PositionVerlet()

    # Warm-up: trigger (or load from cache) the numba compilation, not timed.
    t0 = time.perf_counter()
    warm, _ = build_pyelastica(hair, args.elements, dt, gamma)
    t = 0.0
    for _ in range(20):
        t = stepper.step(warm, t, dt)
    warmup_wall = time.perf_counter() - t0
    if verbose:
        print(f"  PyElastica warm-up (numba compile/cache load): {warmup_wall:.1f} s", flush=True)

    sim, rod = build_pyelastica(hair, args.elements, dt, gamma)
    # Relax in chunks of a quarter of 1/omega_1; stop once the tip moves less than settle_tol per
    # chunk (remaining error is then ~4x that for the critically damped first mode) or at max time.
    chunk_steps = max(1, int(round(0.25 / hair.omega1 / dt)))
    min_time = 3.0 / hair.omega1
    max_time = args.pe_max_time if args.pe_max_time else 30.0 / hair.omega1
    settle_tol = args.settle_tol * abs(ref_tip[2])
    t = 0.0
    steps = 0
    prev = rod.position_collection[:, -1].copy()
    history = []
    converged = False
    wall0 = time.perf_counter()
    while t < max_time:
        for _ in range(chunk_steps):
            t = stepper.step(sim, t, dt)
        steps += chunk_steps
        tip = rod.position_collection[:, -1].copy()
        if not np.all(np.isfinite(tip)) or np.max(np.abs(tip)) > 10.0 * hair.length:
            raise RuntimeError(f"PyElastica diverged at t = {t:.3e} s with dt = {dt:.3e} s")
        change = float(np.linalg.norm(tip - prev))
        prev = tip
        wall = time.perf_counter() - wall0
        history.append((float(t), float(tip[0]), float(tip[2]), wall))
        if verbose:
            print(f"  t = {t:8.5f} s  tip = ({tip[0]:.7f}, {tip[2]:.7f}) m  "
                  f"err = {tip_error(tip, ref_tip):.3e} m  change = {change:.2e} m  "
                  f"wall = {wall:7.1f} s", flush=True)
        if t >= min_time and change < settle_tol:
            converged = True
            break
    wall = time.perf_counter() - wall0
    tip = rod.position_collection[:, -1]
    return {
        "code": "PyElastica 1.0.0" if _pe_version() == "1.0.0" else f"PyElastica {_pe_version()}",
        "elements": args.elements,
        "dt": dt,
        "dt_bound_estimate": hair.pyelastica_dt_bound(),
        "damping_constant": gamma,
        "simulated_time": float(t),
        "steps": steps,
        "wall": wall,
        "wall_per_step_us": wall / steps * 1e6,
        "wall_per_sim_s": wall / t,
        "converged": converged,
        "tip": [float(v) for v in tip],
        "tip_error": tip_error(tip, ref_tip),
        "warmup_wall": warmup_wall,
    }


def _pe_version() -> str:
    try:
        from importlib.metadata import version

        return version("pyelastica")
    except Exception:  # pragma: no cover
        return "?"


# --------------------------------------------------------------------------------------------------
# Coiffure
# --------------------------------------------------------------------------------------------------
def coiffure_spec(hair: Hair, segments: int, air_drag: float) -> str:
    return f"""\
model = "reduced"
length = {hair.length!r}
segments = {segments}
semi_axes = [{hair.semi_a!r}, {hair.semi_b!r}]
young_modulus = {hair.young!r}
shear_modulus = {hair.shear!r}
density = {hair.density!r}
rest_twist = 0.0
rest_bend = 0.0
root_position = [0.0, 0.0, 0.0]
root_tangent = [1.0, 0.0, 0.0]
root_major_axis = [0.0, 1.0, 0.0]   # major axis horizontal: the strand bends about it, sags in z
gravity = [0.0, 0.0, {-GRAVITY!r}]
air_drag = {air_drag!r}   # N s / m^2, drag force per unit length per unit velocity
damping = 0.0   # internal damping (relaxation time, s)
"""


def find_coiffure(path_arg: str | None) -> Path:
    binary = Path(path_arg) if path_arg else REPO_ROOT / "target" / "release" / "coiffure"
    if not binary.is_absolute():
        binary = (REPO_ROOT / binary) if not binary.exists() else binary.resolve()
    if binary.exists():
        return binary
    if path_arg:
        raise FileNotFoundError(f"coiffure binary not found at {binary}")
    print(f"  {binary} missing: cargo build --release -p coiffure-server", flush=True)
    cargo = shutil.which("cargo")
    if cargo is None:
        raise FileNotFoundError("cargo not found; build coiffure or pass --coiffure PATH")
    subprocess.run([cargo, "build", "--release", "-p", "coiffure-server"], cwd=REPO_ROOT,
                   check=True)
    if not binary.exists():
        raise FileNotFoundError(f"build finished but {binary} does not exist")
    return binary


def _timed(cmd: list[str]) -> tuple[float, subprocess.CompletedProcess]:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr}")
    return wall, proc


def _last_row(text: str, columns: tuple[str, ...]) -> dict:
    rows = list(csv.DictReader(io.StringIO(text)))
    if not rows:
        raise RuntimeError(f"no CSV rows in output:\n{text[:500]}")
    row = {k.strip(): v for k, v in rows[-1].items() if k is not None}
    missing = [c for c in columns if c not in row]
    if missing:
        raise RuntimeError(f"CSV lacks columns {missing}; header is {list(row)}")
    return {c: float(row[c]) for c in columns}


def run_coiffure(hair: Hair, args, ref_tip, gamma: float, verbose: bool) -> dict:
    binary = find_coiffure(args.coiffure)
    air_drag = args.air_drag if args.air_drag is not None else gamma * hair.mass_per_length
    with tempfile.TemporaryDirectory(prefix="coiffure-bench-") as tmp:
        spec = Path(tmp) / "cantilever.toml"
        spec.write_text(coiffure_spec(hair, args.segments, air_drag))
        trace = Path(tmp) / "trace.csv"
        base = [str(binary), "strand", "--spec", str(spec)]
        dyn_cmd = base + ["--duration", repr(args.duration), "--dt", repr(args.coiffure_dt),
                          "--samples", "2", "--trace", str(trace)]
        zero_cmd = base + ["--duration", "0", "--dt", repr(args.coiffure_dt), "--samples", "2"]
        static_cmd = base + ["--static", "--samples", "2"]
        if verbose:
            print("  " + " ".join(dyn_cmd), flush=True)

        startup, dyn, static = [], [], []
        for _ in range(args.repeat):
            startup.append(_timed(zero_cmd)[0])
            wall, _ = _timed(dyn_cmd)
            dyn.append(wall)
            wall, static_proc = _timed(static_cmd)
            static.append(wall)
        trace_tip = _last_row(trace.read_text(), ("t", "x", "y", "z"))
        static_tip = _last_row(static_proc.stdout, ("s", "x", "y", "z"))

    dyn_wall, startup_wall = min(dyn), min(startup)
    dyn_tip = [trace_tip["x"], trace_tip["y"], trace_tip["z"]]
    st_tip = [static_tip["x"], static_tip["y"], static_tip["z"]]
    return {
        "code": "Coiffure",
        "binary": str(binary),
        "segments": args.segments,
        "dt": args.coiffure_dt,
        "air_drag": air_drag,
        "simulated_time": args.duration,
        "trace_last_t": trace_tip["t"],
        "wall": dyn_wall,
        "startup_wall": startup_wall,
        "wall_per_sim_s": dyn_wall / args.duration,
        "wall_per_sim_s_minus_startup": (dyn_wall - startup_wall) / args.duration,
        "tip": dyn_tip,
        "tip_error": tip_error(dyn_tip, ref_tip),
        "static_wall": min(static),
        "static_tip": st_tip,
        "static_tip_error": tip_error(st_tip, ref_tip),
        "repeat": args.repeat,
    }


# --------------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------------
def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--length", type=float, default=0.05, help="hair length L (m)")
    p.add_argument("--elements", type=int, default=50, help="PyElastica element count")
    p.add_argument("--segments", type=int, default=16, help="Coiffure segment count")
    p.add_argument("--pe-dt", type=float, default=None,
                   help="PyElastica step (s); default pe-dt-factor x the shear-rotation bound")
    p.add_argument("--pe-dt-factor", type=float, default=0.75,
                   help="fraction of r_eq*sqrt(3 rho_eq/(4 G)) used as PyElastica step")
    p.add_argument("--pe-damping", type=float, default=None,
                   help="PyElastica uniform damping constant (1/s); default 2*omega_1")
    p.add_argument("--pe-max-time", type=float, default=None,
                   help="cap on PyElastica simulated time (s); default 30/omega_1")
    p.add_argument("--settle-tol", type=float, default=1e-5,
                   help="stop PyElastica when the tip moves less than this fraction of the "
                        "reference sag during 0.25/omega_1")
    p.add_argument("--coiffure", default=None,
                   help="coiffure binary (default target/release/coiffure, built if missing)")
    p.add_argument("--skip-coiffure", action="store_true", help="run only reference + PyElastica")
    p.add_argument("--skip-pyelastica", action="store_true", help="run only reference + Coiffure")
    p.add_argument("--duration", type=float, default=5.0, help="Coiffure simulated time (s)")
    p.add_argument("--coiffure-dt", type=float, default=0.001, help="Coiffure step (s)")
    p.add_argument("--air-drag", type=float, default=None,
                   help="Coiffure air drag (N s/m^2); default matches PyElastica damping: "
                        "gamma * rho * A")
    p.add_argument("--repeat", type=int, default=3, help="Coiffure timing repeats (min is kept)")
    p.add_argument("--json", default=None, help="write results as JSON to this path")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    return p.parse_args(argv)


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def main(argv=None) -> int:
    args = parse_args(argv)
    verbose = not args.quiet
    hair = Hair(length=args.length)
    gamma = args.pe_damping if args.pe_damping else 2.0 * hair.omega1

    print(f"Cantilever hair: L = {hair.length} m, semi-axes = ({hair.semi_a}, {hair.semi_b}) m, "
          f"E = {hair.young:.3g} Pa, G = {hair.shear:.3g} Pa, rho = {hair.density} kg/m^3")
    print(f"  EI = {hair.bending_stiffness:.6e} N m^2, rho A = {hair.mass_per_length:.6e} kg/m, "
          f"q L^3/EI = {hair.gravity_number:.4f}, omega_1 = {hair.omega1:.3f} rad/s")
    print(f"  PyElastica equivalent circle: r_eq = {hair.r_eq:.6e} m, rho_eq = {hair.rho_eq:.3f} "
          f"kg/m^3, Poisson-equivalent nu = {hair.poisson_eq:.4f}")

    ref = reference_tip(hair)
    rx, _, rz = ref["tip"]
    print(f"Reference (shooting): tip (x, z) = ({rx:.9f}, {rz:.9f}) m, tip angle = "
          f"{ref['tip_angle_deg']:.4f} deg, linear-theory sag = {ref['linear_sag']:.9f} m")

    results = {"problem": {**asdict(hair), "EI": hair.bending_stiffness,
                           "mass_per_length": hair.mass_per_length, "r_eq": hair.r_eq,
                           "rho_eq": hair.rho_eq, "gravity": GRAVITY, "omega1": hair.omega1,
                           "gravity_number": hair.gravity_number},
               "reference": ref,
               "machine": {"platform": platform.platform(), "cpus": os.cpu_count(),
                           "loadavg_start": list(os.getloadavg())}}
    status = 0

    pe = None
    if not args.skip_pyelastica:
        print("PyElastica:", flush=True)
        pe = run_pyelastica(hair, args, ref["tip"], verbose)
        results["pyelastica"] = pe
        if not pe["converged"]:
            print("  warning: PyElastica did not reach the settle tolerance before max time")

    co = None
    if not args.skip_coiffure:
        print("Coiffure:", flush=True)
        try:
            co = run_coiffure(hair, args, ref["tip"], gamma, verbose)
            results["coiffure"] = co
        except (FileNotFoundError, RuntimeError, subprocess.CalledProcessError) as err:
            print(f"  Coiffure part failed: {err}", file=sys.stderr)
            results["coiffure_error"] = str(err)
            status = 2

    results["machine"]["loadavg_end"] = list(os.getloadavg())

    print()
    header = (f"{'code':<18} {'elem/seg':>8} {'dt (s)':>10} {'wall s/sim s':>13} "
              f"{'steady tip err (m)':>19} {'static tip err (m)':>19}")
    print(header)
    print("-" * len(header))
    if pe:
        print(f"{pe['code']:<18} {pe['elements']:>8d} {pe['dt']:>10.3e} "
              f"{pe['wall_per_sim_s']:>13.4g} {pe['tip_error']:>19.3e} {'-':>19}")
    if co:
        print(f"{'Coiffure':<18} {co['segments']:>8d} {co['dt']:>10.3e} "
              f"{co['wall_per_sim_s']:>13.4g} {co['tip_error']:>19.3e} "
              f"{co['static_tip_error']:>19.3e}")
        print(f"  Coiffure process startup (--duration 0): {co['startup_wall']:.4f} s; "
              f"wall s/sim s without it: {co['wall_per_sim_s_minus_startup']:.4g}; "
              f"static solve wall: {co['static_wall']:.4f} s")
    if pe:
        print(f"  PyElastica: {pe['steps']} steps, {pe['wall_per_step_us']:.1f} us/step, "
              f"{pe['simulated_time']:.4f} s simulated in {pe['wall']:.1f} s wall, "
              f"tip = ({pe['tip'][0]:.9f}, {pe['tip'][2]:.9f}) m")
    if pe and co:
        ratio = pe["wall_per_sim_s"] / co["wall_per_sim_s"]
        ratio_net = pe["wall_per_sim_s"] / co["wall_per_sim_s_minus_startup"] \
            if co["wall_per_sim_s_minus_startup"] > 0 else None
        results["ratio_wall_per_sim_s"] = ratio
        results["ratio_wall_per_sim_s_minus_startup"] = ratio_net
        print(f"Ratio PyElastica / Coiffure wall time per simulated second: {ratio:.4g} "
              f"(without Coiffure startup: {fmt(ratio_net, '.4g')})")
    print(f"Load average start/end: {results['machine']['loadavg_start'][0]:.2f} / "
          f"{results['machine']['loadavg_end'][0]:.2f} on {os.cpu_count()} CPUs")

    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n")
        print(f"Wrote {args.json}")
    return status


if __name__ == "__main__":
    sys.exit(main())

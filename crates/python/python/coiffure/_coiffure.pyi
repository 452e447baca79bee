"""Type stubs of the native module ``coiffure._coiffure`` (Rust, PyO3). SI units throughout."""

import os
import threading
from typing import Any, Dict, List, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, os.PathLike[str]]

class SimulationError(RuntimeError):
    """A simulation failed (non-finite state, a solver that did not converge); the message says when and why."""

class HairTypeInfo(TypedDict):
    name: str
    major_diameter: float  # m
    ellipticity: float  # major / minor axis
    semi_axes: List[float]  # [a, b], m
    bending_stiffness: float  # E I about the major axis, N m^2
    young_modulus: float  # Pa
    shear_modulus: float  # Pa
    density: float  # kg/m^3
    linear_density: float  # kg/m
    friction_force: Optional[float]  # measured single-fibre friction, N
    friction_coefficient: float  # Coulomb, against a tool
    curl_radius: Optional[float]  # m (None: straight)
    curl_pitch: Optional[float]  # m
    rest_twist: float  # rad/m
    rest_bend: float  # rad/m
    source: str

def hair_types() -> List[HairTypeInfo]:
    """The hair-type presets (the paper's Table 1 first, then typical Asian, Caucasian, African hair)."""

class StaticResult(TypedDict):
    iterations: int
    stable: bool
    potential: float  # J

class Strand:
    """One Super-Helix hair strand, reduced (2N coordinates) or full (3N). Coordinates are curvatures, rad/m."""

    @staticmethod
    def from_spec(spec: Union[Dict[str, Any], PathLike]) -> "Strand":
        """A strand from a strand spec dict (docs/strand-spec.md keys) or TOML file, at rest at its rest shape."""
    def solve_static(self, tolerance: float = 1e-11, max_iterations: int = 200) -> StaticResult:
        """Static equilibrium under gravity from the current coordinates; sets q (and qdot = 0)."""
    def step(self, dt: float = 1e-3, steps: int = 1) -> None:
        """Advances `steps` steps of `dt` s (GIL released; Ctrl-C stops between steps)."""
    def centerline(self, samples: int = 17) -> npt.NDArray[np.float64]:
        """Centreline at `samples` points evenly spaced in arc length, m, shape (samples, 3)."""
    def natural_frequencies(self, k: Optional[int] = None) -> npt.NDArray[np.float64]:
        """The k lowest natural angular frequencies about the current state, rad/s, ascending."""
    @property
    def q(self) -> npt.NDArray[np.float64]:
        """Generalized coordinates, rad/m: per segment (twist, bend[, bend2])."""
    @q.setter
    def q(self, value: Sequence[float]) -> None: ...
    @property
    def qdot(self) -> npt.NDArray[np.float64]:
        """Their time derivatives, rad/(m s)."""
    @qdot.setter
    def qdot(self, value: Sequence[float]) -> None: ...
    @property
    def q_rest(self) -> npt.NDArray[np.float64]:
        """Rest coordinates, rad/m."""
    @property
    def time(self) -> float:
        """Simulated time, s."""
    @property
    def model(self) -> str:
        """"reduced" or "full"."""
    @property
    def length(self) -> float:
        """Length, m."""
    @property
    def segments(self) -> int: ...
    @property
    def dofs(self) -> int:
        """2N (reduced) or 3N (full)."""
    @property
    def mass(self) -> float:
        """Mass, kg."""
    @property
    def tip(self) -> npt.NDArray[np.float64]:
        """Tip position, m."""
    @property
    def root(self) -> npt.NDArray[np.float64]:
        """Root position, m."""
    @property
    def clamped_steps(self) -> int:
        """Steps whose velocities the safety net scaled down."""
    @property
    def integrator(self) -> str:
        """"euler" (linearly implicit Euler, default) or "midpoint" (implicit midpoint)."""
    @integrator.setter
    def integrator(self, name: str) -> None: ...
    def energy(self) -> float:
        """Total energy (kinetic + gravity + elastic), J."""
    def reset(self) -> None:
        """Back to the rest shape, at rest, at time 0."""
    def copy(self) -> "Strand":
        """An independent copy."""

def load_toml(path: PathLike) -> Dict[str, Any]:
    """A TOML file (strand spec or scenario) as a dict."""

def read_hair_flat(path: PathLike) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]:
    """All points (P, 3) float32 and the point count of each strand."""

def write_hair_flat(path: PathLike, points: npt.NDArray[np.float32], counts: npt.NDArray[np.int64]) -> None:
    """Writes flat points and counts; the format follows the extension."""

def run_scenario(
    scenario: Union[Dict[str, Any], PathLike],
    out: Optional[PathLike] = None,
    base_dir: Optional[PathLike] = None,
    cancel: Optional[threading.Event] = None,
) -> Dict[str, Any]:
    """Runs a scenario in memory (see coiffure.run_scenario); `cancel` (a threading.Event) stops it when set."""

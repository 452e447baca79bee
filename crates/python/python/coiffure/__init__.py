"""Coiffure from Python: Super-Helix hair strands, headless tool scenarios, hair files and parameter sweeps.

Everything calls the same Rust code as the ``coiffure`` command line. SI units throughout (m, kg, s, N, Pa;
strand coordinates are curvatures in rad/m). See docs/python.md.

- :func:`hair_types` -- the hair-type presets (the paper's Table 1 and typical ethnic hair);
- :class:`Strand` -- one strand from a strand spec (dict or TOML path): statics, dynamics, frequencies;
- :func:`run_scenario` -- a scripted tool session or a global-tool scenario, as numpy arrays and a summary;
- :func:`read_hair`, :func:`write_hair` -- ``.hair``, ``.data``, ``.tfx`` and ``.usda`` files;
- :func:`sweep` -- many scenarios in-process (all cores) or on Ray, as a pandas DataFrame.
"""

from ._coiffure import SimulationError, Strand, __version__, hair_types
from ._hair import read_hair, write_hair
from ._scenario import run_scenario
from ._sweep import sweep

__all__ = [
    "SimulationError",
    "Strand",
    "__version__",
    "hair_types",
    "read_hair",
    "run_scenario",
    "sweep",
    "write_hair",
]

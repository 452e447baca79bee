"""Headless scenarios (``coiffure run``) from Python, in memory."""

from __future__ import annotations

import os
from typing import Any, Dict, Optional, Union

from . import _coiffure

Scenario = Union[Dict[str, Any], str, "os.PathLike[str]"]


def run_scenario(
    scenario: Scenario,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    *,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> Dict[str, Any]:
    """Runs a scenario (docs/scenarios.md): a dict with the scenario TOML's structure (``None`` values mean
    "default"), or a path to a scenario file. Every kind runs: a tress with a tool, a global-tool scenario
    (``[[action]]`` / ``[hairstyle]``) and a ``[live]`` scenario.

    Returns a dict of numpy arrays, one row per recorded step: ``t`` (T,) s; ``force`` (T, 3) N and ``torque``
    (T, 3) N m on the tool; ``contacts`` (T,); ``tool`` (T, 3) tool position, m; plus ``summary`` (the contents
    of ``summary.json``), ``kind`` and ``name``. A tress scenario also gives ``profile``, the combing rig's
    recording (``profile.csv``): a dict of arrays ``stroke`` (from 1), ``t`` (s), ``position_m`` (the comb's
    position from the roots along the tress, m) and ``force_n`` (N), one entry per step of each stroke. Nothing is written unless ``out`` names a folder, which then
    receives exactly what ``coiffure run SCENARIO --out DIR`` writes.

    ``base_dir``: where a dict's relative file names (``tool.shape`` files, ``tool.path_file``) are looked up
    (default: the current directory; for a path, the scenario's folder).

    The GIL is released while the scenario runs; Ctrl-C stops it between steps (``KeyboardInterrupt``). Bad
    input raises ``ValueError`` naming the key; a failed simulation raises ``coiffure.SimulationError``.
    """
    return _coiffure.run_scenario(
        scenario if isinstance(scenario, dict) else os.fspath(scenario),
        out=None if out is None else os.fspath(out),
        base_dir=None if base_dir is None else os.fspath(base_dir),
    )

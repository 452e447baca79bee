"""Parameter sweeps: many scenarios, one table.

In-process, the scenarios run on a thread pool (one thread per core): :func:`coiffure.run_scenario` releases
the GIL, so the threads run the Rust code in parallel. On Ray, each scenario is one task (``num_cpus=1``);
``ray_address="local"`` starts Ray on this machine, any other address connects to a running cluster whose
workers have ``coiffure`` installed (``pip install "./crates/python[ray]"``).
"""

from __future__ import annotations

import json
import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Dict, List, Optional, Sequence, Tuple

from . import _coiffure
from ._scenario import Scenario

#: Columns every row of a sweep has, besides the summary and the varying parameters.
BASE_COLUMNS = ("scenario", "name", "kind", "error", "wall_time")


def _load(scenario: Scenario) -> Dict[str, Any]:
    """The scenario as a plain dict (a file is parsed as TOML), for the parameter columns."""
    if isinstance(scenario, dict):
        return scenario
    return _coiffure.load_toml(os.fspath(scenario))


def _flatten(d: Dict[str, Any], prefix: str = "") -> Dict[str, Any]:
    """Nested dicts as dotted keys: {"patch": {"hair_type": "H1"}} -> {"patch.hair_type": "H1"}."""
    out: Dict[str, Any] = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flatten(v, key + "."))
        else:
            out[key] = v
    return out


def _canonical(v: Any) -> str:
    """A comparable text for any parameter value (lists of waypoints included)."""
    try:
        return json.dumps(v, sort_keys=True, default=lambda x: x.tolist() if hasattr(x, "tolist") else str(x))
    except (TypeError, ValueError):
        return repr(v)


def varying_parameters(scenarios: Sequence[Scenario]) -> List[Dict[str, Any]]:
    """For each scenario, the (dotted) parameters whose values are not the same in every scenario of the list
    (a key missing from some scenarios counts as varying, with value None there)."""
    flat = [_flatten(_load(s)) for s in scenarios]
    keys: List[str] = []
    for f in flat:
        keys.extend(k for k in f if k not in keys)
    vary = [k for k in keys if len({_canonical(f.get(k)) for f in flat}) > 1]
    return [{k: f.get(k) for k in vary} for f in flat]


def _run_one(scenario: Scenario, base_dir: Optional[str], cancel: Any = None) -> Dict[str, Any]:
    """Runs one scenario; its summary, or its error as text (never raises, except for Ctrl-C)."""
    started = time.perf_counter()
    try:
        if isinstance(scenario, dict):
            r = _coiffure.run_scenario(scenario, base_dir=base_dir, cancel=cancel)
        else:
            r = _coiffure.run_scenario(os.fspath(scenario), cancel=cancel)
        return {"name": r["name"], "kind": r["kind"], "summary": r["summary"], "error": None, "wall_time": time.perf_counter() - started}
    except KeyboardInterrupt:
        raise
    except Exception as e:  # noqa: BLE001 - a failing scenario is reported in its row
        return {"name": None, "kind": None, "summary": {}, "error": f"{type(e).__name__}: {e}", "wall_time": time.perf_counter() - started}


def _in_process(jobs: Sequence[Scenario], base_dir: str, workers: Optional[int]) -> List[Dict[str, Any]]:
    cancel = threading.Event()
    pool = ThreadPoolExecutor(max_workers=workers or os.cpu_count() or 1, thread_name_prefix="coiffure-sweep")
    futures = [pool.submit(_run_one, s, base_dir, cancel) for s in jobs]
    try:
        return [f.result() for f in futures]
    except KeyboardInterrupt:
        cancel.set()  # the running scenarios stop at their next signal check
        for f in futures:
            f.cancel()
        raise
    finally:
        pool.shutdown(wait=True)


def _on_ray(jobs: Sequence[Scenario], base_dir: str, address: str, workers: Optional[int]) -> List[Dict[str, Any]]:
    try:
        import ray
    except ImportError as e:
        raise ImportError('sweep(ray_address=...) needs Ray: pip install "./crates/python[ray]"') from e
    if not ray.is_initialized():
        if address == "local":
            ray.init(address="local", num_cpus=workers, include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=address, log_to_driver=False)
    task = ray.remote(num_cpus=1)(_run_one)
    refs = [task.remote(s, base_dir) for s in jobs]
    rows = []
    try:
        for ref in refs:
            try:
                rows.append(ray.get(ref))
            except Exception as e:  # noqa: BLE001 - a lost worker is reported in the row
                rows.append({"name": None, "kind": None, "summary": {}, "error": f"{type(e).__name__}: {e}", "wall_time": None})
    except KeyboardInterrupt:
        for ref in refs:
            ray.cancel(ref, force=True)
        raise
    return rows


def _rows(scenarios: Sequence[Scenario], results: Sequence[Dict[str, Any]]) -> Tuple[List[Dict[str, Any]], List[str]]:
    params = varying_parameters(scenarios)
    rows, columns = [], list(BASE_COLUMNS)
    for i, (p, r) in enumerate(zip(params, results)):
        row: Dict[str, Any] = {"scenario": i, "name": r["name"], "kind": r["kind"], "error": r["error"], "wall_time": r["wall_time"]}
        for k, v in p.items():
            row[k] = v
        for k, v in _flatten(r["summary"]).items():
            row[f"summary.{k}" if k in row else k] = v
        for k in row:
            if k not in columns:
                columns.append(k)
        rows.append(row)
    return rows, columns


def sweep(
    scenarios: Sequence[Scenario],
    ray_address: Optional[str] = None,
    *,
    workers: Optional[int] = None,
):
    """Runs every scenario (dicts or paths, as for :func:`coiffure.run_scenario`) and returns a
    ``pandas.DataFrame`` with one row per scenario, in order: ``scenario`` (index in the list), ``name``,
    ``kind``, ``error`` (None, or the exception of a scenario that failed, whose summary columns are then
    empty), ``wall_time`` (s), the parameters that vary across the list (dotted keys such as
    ``patch.hair_type``) and the summary (``summary.json``: e.g. ``peak_force`` N, ``mean_force`` N, ``work``
    J for a tress).

    ``ray_address``: None runs in this process on ``workers`` threads (default: one per core); ``"local"``
    starts Ray on this machine (left running for later sweeps; ``ray.shutdown()`` stops it); any other value
    is the address of a running Ray cluster (``ray.init(address=...)``), whose workers need ``coiffure``.
    If Ray is already initialised it is used as it is. Relative file names in dict scenarios are resolved
    against the current directory; scenario paths are sent as absolute paths.
    """
    try:
        import pandas as pd
    except ImportError as e:
        raise ImportError('coiffure.sweep needs pandas: pip install "./crates/python[ray]" (or pandas)') from e
    scenarios = list(scenarios)
    base_dir = os.getcwd()
    jobs = [s if isinstance(s, dict) else os.path.abspath(os.fspath(s)) for s in scenarios]
    if ray_address is None:
        results = _in_process(jobs, base_dir, workers)
    else:
        results = _on_ray(jobs, base_dir, ray_address, workers)
    rows, columns = _rows(jobs, results)
    return pd.DataFrame(rows, columns=columns)

"""Parameter sweeps: many scenarios, one table.

In-process, the scenarios run on a thread pool (one thread per core): :func:`coiffure.run_scenario` releases
the GIL, so the threads run the Rust code in parallel. On Ray, each scenario is one task (``num_cpus=1``);
``ray_address="local"`` starts Ray on this machine, any other address connects to a running cluster whose
workers have ``coiffure`` installed (``pip install "./crates/python[ray]"``). Either way the sweep reports its
progress as the results arrive (:class:`Progress`).
"""

from __future__ import annotations

import json
import os
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

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


def _flatten_summary(d: Dict[str, Any], prefix: str = "") -> Dict[str, Any]:
    """A summary as columns: nested dicts as dotted keys, lists as indexed dotted keys
    ({"work_fifths_j": [a, b]} -> {"work_fifths_j.0": a, "work_fifths_j.1": b}; a list of lists gives
    "key.i.j")."""
    out: Dict[str, Any] = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, list):
            v = {str(i): x for i, x in enumerate(v)}
        if isinstance(v, dict):
            out.update(_flatten_summary(v, key + "."))
        else:
            out[key] = v
    return out


#: What ``sweep(progress=...)`` takes: True (a progress bar: tqdm where installed, else lines on stderr),
#: False or None (nothing), or a function called with (done, total, seconds_left) after each scenario.
ProgressArg = Union[bool, None, Callable[[int, int, Optional[float]], Any]]


class Progress:
    """A sweep's progress: scenarios done of the total and the time left (the mean time per finished scenario,
    since the sweep started, times the scenarios still to run: the parallel rate, as the results arrive).

    ``report``: True draws a tqdm bar where tqdm is installed, else writes a line to stderr (at most one per
    ``interval`` seconds, and always the first and the last); False or None report nothing; a callable gets
    ``(done, total, seconds_left)`` after each scenario (``seconds_left`` None before the first)."""

    def __init__(self, total: int, report: ProgressArg = True, interval: float = 1.0, stream: Any = None):
        self.total, self.done = total, 0
        self.started = time.perf_counter()
        self.interval, self.stream = interval, stream
        self._last = -float("inf")
        self._bar = None
        self._call: Optional[Callable[[int, int, Optional[float]], Any]] = None
        self._text = False
        if callable(report):
            self._call = report
        elif report:
            try:
                from tqdm.auto import tqdm
            except ImportError:
                self._text = True
            else:
                self._bar = tqdm(total=total, desc="coiffure.sweep", unit="scenario", file=stream)

    def seconds_left(self) -> Optional[float]:
        """Time left, s (None before the first scenario is done)."""
        if self.done == 0:
            return None
        return (time.perf_counter() - self.started) / self.done * (self.total - self.done)

    def line(self) -> str:
        """The text report: e.g. ``coiffure.sweep: 3/8 scenarios done, 0:41 left``."""
        left = self.seconds_left()
        eta = "time left unknown" if left is None else f"{int(left) // 60}:{int(left) % 60:02d} left"
        return f"coiffure.sweep: {self.done}/{self.total} scenarios done, {eta}"

    def update(self, n: int = 1) -> None:
        """``n`` more scenarios are done."""
        self.done += n
        if self._bar is not None:
            self._bar.update(n)
        elif self._call is not None:
            self._call(self.done, self.total, self.seconds_left())
        elif self._text:
            now = time.perf_counter()
            if self.done in (1, self.total) or now - self._last >= self.interval:
                self._last = now
                print(self.line(), file=self.stream or sys.stderr, flush=True)

    def close(self) -> None:
        """Ends the report (closes a tqdm bar)."""
        if self._bar is not None:
            self._bar.close()


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


def _in_process(jobs: Sequence[Scenario], base_dir: str, workers: Optional[int], progress: Progress) -> List[Dict[str, Any]]:
    cancel = threading.Event()
    pool = ThreadPoolExecutor(max_workers=workers or os.cpu_count() or 1, thread_name_prefix="coiffure-sweep")
    futures = [pool.submit(_run_one, s, base_dir, cancel) for s in jobs]
    index = {f: i for i, f in enumerate(futures)}
    rows: List[Any] = [None] * len(futures)
    try:
        for f in as_completed(futures):
            rows[index[f]] = f.result()
            progress.update()
        return rows
    except KeyboardInterrupt:
        cancel.set()  # the running scenarios stop at their next signal check
        for f in futures:
            f.cancel()
        raise
    finally:
        pool.shutdown(wait=True)


def _on_ray(jobs: Sequence[Scenario], base_dir: str, address: str, workers: Optional[int], progress: Progress) -> List[Dict[str, Any]]:
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
    index = {ref: i for i, ref in enumerate(refs)}
    rows: List[Any] = [None] * len(refs)
    pending = list(refs)
    try:
        while pending:  # as the results arrive, in any order
            ready, pending = ray.wait(pending, num_returns=1)
            for ref in ready:
                try:
                    rows[index[ref]] = ray.get(ref)
                except Exception as e:  # noqa: BLE001 - a lost worker is reported in the row
                    rows[index[ref]] = {"name": None, "kind": None, "summary": {}, "error": f"{type(e).__name__}: {e}", "wall_time": None}
                progress.update()
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
        for k, v in _flatten_summary(r["summary"]).items():
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
    progress: ProgressArg = True,
):
    """Runs every scenario (dicts or paths, as for :func:`coiffure.run_scenario`) and returns a
    ``pandas.DataFrame`` with one row per scenario, in order: ``scenario`` (index in the list), ``name``,
    ``kind``, ``error`` (None, or the exception of a scenario that failed, whose summary columns are then
    empty), ``wall_time`` (s), the parameters that vary across the list (dotted keys such as
    ``patch.hair_type``) and the summary (``summary.json``: e.g. ``peak_force_n`` N, ``mean_force_n`` N, ``work_j``
    J, ``combing_work_j`` J for a tress), nested keys dotted and lists indexed (``work_fifths_j.4``, the
    tips' fifth; ``per_stroke.combing_work_j.0``, the first stroke's work).

    ``progress``: True (default) reports the scenarios done of the total and the time left as the results
    arrive (a tqdm bar where tqdm is installed, else a line on stderr at most every second); False turns it
    off; a callable ``f(done, total, seconds_left)`` is called after each scenario instead (:class:`Progress`).

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
    bar = Progress(len(jobs), progress)
    try:
        if ray_address is None:
            results = _in_process(jobs, base_dir, workers, bar)
        else:
            results = _on_ray(jobs, base_dir, ray_address, workers, bar)
    finally:
        bar.close()
    rows, columns = _rows(jobs, results)
    return pd.DataFrame(rows, columns=columns)

"""The runner shared by the experiments: independent units, results kept as they finish.

An experiment is a list of :class:`Unit` (a key, a module-level function, its keyword
arguments). :func:`run_units` runs those whose key is not yet in the experiment's results
file and appends each result as one JSON line the moment it finishes, so a run that is
killed loses nothing finished and a re-run computes only what is missing. The same units
run in this process (``"serial"``), on a local process pool (``"processes"``, the default),
on a local Dask cluster started for the run (``"dask"``) or on a running Dask scheduler
(``"tcp://host:port"``). Every unit runs with one compiled-kernel thread, and its result
depends only on its arguments, so the results are identical whichever runs them.
"""

from __future__ import annotations

import json
import os
import sys
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

__all__ = ["Unit", "run_units", "load_results", "SCHEDULERS"]

SCHEDULERS = ("serial", "processes", "dask")


@dataclass(frozen=True)
class Unit:
    """One independent piece of an experiment: ``func(**kwargs)`` must return JSON-able data."""

    key: str
    func: Callable[..., Any]
    kwargs: dict = field(default_factory=dict)


def _call(func, kwargs):
    """Run one unit with a single compiled-kernel thread (results independent of the machine)."""
    from .._parallel import get_num_threads, set_num_threads

    before = get_num_threads()
    set_num_threads(1)
    try:
        return func(**kwargs)
    finally:
        set_num_threads(before)


def load_results(path) -> dict:
    """``{key: result}`` from a results file; a torn last line (a crash mid-write) is ignored."""
    path = Path(path)
    out = {}
    if not path.exists():
        return out
    with path.open("r", encoding="utf-8") as handle:
        for line in handle:
            if not line.endswith("\n"):
                break  # the process died while writing this line
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                continue
            out[record["key"]] = record["result"]
    return out


class _Appender:
    """Append one JSON line per result with a single ``write`` on an O_APPEND descriptor."""

    def __init__(self, path: Path):
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.exists() and path.stat().st_size:
            with path.open("rb") as handle:  # drop a torn last line left by a crash
                handle.seek(-1, os.SEEK_END)
                torn = handle.read(1) != b"\n"
            if torn:
                lines = path.read_bytes().splitlines(keepends=True)
                tmp = path.with_suffix(path.suffix + ".tmp")
                tmp.write_bytes(b"".join(line for line in lines if line.endswith(b"\n")))
                os.replace(tmp, path)
        self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def add(self, key: str, result) -> None:
        data = (json.dumps({"key": key, "result": result}, separators=(",", ":")) + "\n").encode()
        os.write(self.fd, data)
        os.fsync(self.fd)

    def close(self):
        os.close(self.fd)


def _check_scheduler(scheduler: str) -> str:
    if not isinstance(scheduler, str) or not (scheduler in SCHEDULERS or scheduler.startswith("tcp://")):
        raise ValueError(f"`scheduler` must be one of {', '.join(map(repr, SCHEDULERS))} or 'tcp://host:port'; got {scheduler!r}.")
    return scheduler


def run_units(units, path, *, scheduler: str = "processes", workers: int | None = None, progress: bool = True, desc: str = "") -> dict:
    """Run the units missing from ``path`` and return ``{key: result}`` for all of them.

    Parameters
    ----------
    units : sequence of Unit
        Keys must be unique.
    path : path-like
        The experiment's results file (JSON lines); created if missing.
    scheduler : {'serial', 'processes', 'dask'} or 'tcp://host:port', default='processes'
    workers : int, optional
        Processes (or Dask workers) to start; default: the cores this process may use.
    progress : bool, default=True
        A progress bar on stderr.
    """
    scheduler = _check_scheduler(scheduler)
    units = list(units)
    keys = [u.key for u in units]
    if len(set(keys)) != len(keys):
        raise ValueError("`units` must have unique keys; got duplicates.")
    path = Path(path)
    done = load_results(path)
    todo = [u for u in units if u.key not in done]
    if workers is None:
        from .._parallel import available_cores

        workers = available_cores()
    bar = None
    if progress and todo:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(units), initial=len(units) - len(todo), desc=desc or path.stem, unit="unit", file=sys.stderr, leave=False)
    appender = _Appender(path)

    def finished(key, result):
        done[key] = result
        appender.add(key, result)
        if bar is not None:
            bar.update(1)

    try:
        if not todo:
            pass
        elif scheduler == "serial" or (scheduler == "processes" and workers == 1):
            for unit in todo:
                finished(unit.key, _call(unit.func, unit.kwargs))
        elif scheduler == "processes":
            _run_pool(todo, workers, finished)
        else:
            _run_dask(todo, scheduler, workers, finished)
    finally:
        appender.close()
        if bar is not None:
            bar.close()
    return {key: done[key] for key in keys}


def _run_pool(todo, workers, finished):
    import multiprocessing

    # "spawn" keeps worker processes free of the parent's threads (numba, BLAS pools)
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        pending = {pool.submit(_call, u.func, u.kwargs): u.key for u in todo}
        try:
            while pending:
                ready, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in ready:
                    finished(pending.pop(future), future.result())
        except BaseException:
            for future in pending:
                future.cancel()
            raise


def _run_dask(todo, scheduler, workers, finished):
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise ImportError(
            "The 'dask' schedulers need dask.distributed: pip install 'centrality-vision[dask]'."
        ) from None
    cluster = None
    if scheduler == "dask":
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        futures = {client.submit(_call, u.func, u.kwargs, key=f"cv-{u.key}", pure=False): u.key for u in todo}
        for future in as_completed(futures):
            finished(futures[future], future.result())
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

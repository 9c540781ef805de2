"""The runner shared by the experiments: independent units, results kept as they finish.

An experiment is a list of :class:`Unit` (a label, a module-level function, its keyword
arguments). :func:`run_units` runs those not yet in the experiment's results file and
appends each result as one JSON line the moment it finishes, so a run that is killed loses
nothing finished and a re-run computes only what is missing. The same units run in this
process (``"serial"``), on a local process pool (``"processes"``, the default), on a local
Dask cluster started for the run (``"dask"``) or on a running Dask scheduler
(``"tcp://host:port"``). Every unit runs with one compiled-kernel thread, and its result
depends only on its arguments, so the results are identical whichever runs them.

A stored result is found again by its :func:`unit_id`: the label plus a digest of the
function's qualified name, every keyword argument (seed, sizes, methods, quick, ...), the
package version and a digest of the package's source code. A unit with any other parameter
has another id, so a folder that holds results of another run (another seed, size,
version or code) is never read as this one: those lines stay in the file, unused, and a
note on stderr says how many there are. Each line also carries a checksum of its key and
result: a line that was damaged or edited by hand is recomputed, never used.

Workers die with the process that started them: pool workers and the processes of a
local Dask cluster poll their parent and exit when it is gone (on Linux the pool workers
also get ``PR_SET_PDEATHSIG``), so a run killed with SIGKILL leaves no orphans.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import inspect
import json
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..exceptions import CodeChangedError, InputError

__all__ = ["Unit", "unit_id", "run_units", "load_results", "SCHEDULERS", "MAX_WORKERS"]

SCHEDULERS = ("serial", "processes", "dask")
#: the most processes or Dask workers a run starts (more is a typo: a pool's semaphore is a C int)
MAX_WORKERS = 1024


@dataclass(frozen=True)
class Unit:
    """One independent piece of an experiment: ``func(**kwargs)`` must return JSON-able data.

    ``func`` is best a module-level function: a lambda or a closure (which cannot go to a
    process pool) is keyed by its code and captured values as well as its name.
    ``volatile`` names keyword arguments that do not change the result (a cache folder):
    they are left out of :func:`unit_id`, so that a copied or moved output folder keeps its
    results.
    """

    key: str
    func: Callable[..., Any]
    kwargs: dict = field(default_factory=dict)
    volatile: tuple = ()


def _canonical(value):
    """A JSON-able stand-in for a keyword argument that JSON cannot write, exact enough that two
    different values never share it: an array by its dtype, shape and a digest of its bytes
    (numpy's repr elides the middle of large arrays), a function by its qualified name."""
    import numpy as np

    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        if data.dtype == object:
            return ["ndarray", "object", list(data.shape), [_canonical(v) for v in data.ravel().tolist()]]
        return ["ndarray", data.dtype.str, list(data.shape), hashlib.sha256(data.tobytes()).hexdigest()]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, os.PathLike):
        return ["path", os.fspath(value)]
    if isinstance(value, (set, frozenset)):
        return ["set", sorted(json.dumps(v, sort_keys=True, default=_canonical) for v in value)]
    if isinstance(value, functools.partial):
        return ["partial", _function_name(value.func), _keyed(list(value.args)), _keyed(value.keywords)]
    if inspect.isroutine(value) or inspect.isclass(value):
        return ["function", _function_name(value)]
    if hasattr(value, "get_params"):  # (a class was keyed by its name above)
        # an estimator by its parameters: its repr rounds arrays (an ``init`` transform) to 8 digits
        try:
            params = value.get_params(deep=False)
        except TypeError:
            params = None
        if isinstance(params, dict):
            return ["estimator", type(value).__module__ + "." + type(value).__qualname__, _keyed(params)]
    if dataclasses.is_dataclass(value) or hasattr(value, "__dict__"):
        # an object (a transform) by its state: its repr rounds and elides arrays, or hides state
        state = (
            {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
            if dataclasses.is_dataclass(value)
            else vars(value)
        )
        return ["object", type(value).__module__ + "." + type(value).__qualname__, _keyed(state)]
    text = repr(value)
    if " at 0x" in text:  # an object's default repr: its address, not its value
        raise InputError(
            f"`Unit.kwargs` must hold values a result can be keyed by (JSON data, arrays, paths, module-level "
            f"functions); got {type(value).__name__} {text[:60]}."
        )
    return ["repr", type(value).__qualname__, text]


def _keyed(value):
    """``value`` with every part JSON cannot write replaced by :func:`_canonical`."""
    return json.loads(json.dumps(_string_keyed(value), sort_keys=True, default=_canonical))


def _string_keyed(value):
    """``value`` with every dict that has a key other than a string written as a sorted list of
    ``[key, value]`` pairs: JSON turns keys into strings, so ``{1: x}`` and ``{"1": x}`` would
    share a unit id (and keys of mixed types would not sort)."""
    if isinstance(value, dict):
        if all(isinstance(key, str) for key in value):
            return {key: _string_keyed(item) for key, item in value.items()}
        pairs = [[_keyed(key), _keyed(item)] for key, item in value.items()]
        return ["dict", sorted(pairs, key=lambda pair: json.dumps(pair, sort_keys=True))]
    if isinstance(value, (list, tuple)):
        return [_string_keyed(item) for item in value]
    return value


def _function_name(func):
    """A function's identity in a unit id: its module's import name (also when the module runs
    as ``python -m``) and qualified name; for a lambda or a closure (whose name does not tell two
    apart) also a digest of its code, defaults and captured values."""
    module = getattr(func, "__module__", None) or "?"
    if module == "__main__":  # `python -m package.module`: the name the module has when imported
        spec = getattr(sys.modules.get("__main__"), "__spec__", None)
        module = getattr(spec, "name", None) or module
    name = f"{module}.{getattr(func, '__qualname__', repr(func))}"
    if "<lambda>" not in name and "<locals>" not in name:
        return name
    code = getattr(func, "__code__", None)
    cells = [cell.cell_contents for cell in (getattr(func, "__closure__", None) or ())]
    try:
        body = json.dumps(
            [
                code.co_code.hex() if code is not None else None,
                repr(code.co_consts) if code is not None else None,
                list(code.co_names) if code is not None else None,
                _string_keyed(getattr(func, "__defaults__", None)),
                _string_keyed(cells),
            ],
            sort_keys=True,
            default=_canonical,
        )
    except (InputError, TypeError, ValueError, RecursionError):
        body = f"object {id(func)}"  # nothing stable to key it by: this process's object only
    return [name, hashlib.sha256(body.encode()).hexdigest()]


def unit_id(unit: Unit) -> str:
    """The key under which ``unit``'s result is stored: its label and a digest of everything
    that changes the result (function, keyword arguments, package version and source code).

    Examples
    --------
    >>> a = unit_id(Unit("set/0", max, {"seed": 0}))
    >>> a.startswith("set/0#") and a != unit_id(Unit("set/0", max, {"seed": 1}))
    True
    """
    from .. import __version__
    from .._provenance import code_digest

    kwargs = {k: v for k, v in unit.kwargs.items() if k not in unit.volatile}
    payload = json.dumps(
        [_function_name(unit.func), _string_keyed(kwargs), __version__, code_digest()],
        sort_keys=True,
        default=_canonical,
    )
    return f"{unit.key}#{hashlib.sha256(payload.encode()).hexdigest()[:16]}"


def _watch_parent(parent: int, interval: float = 0.5) -> None:
    """Pool-worker initializer: exit (at once, no clean-up) when process ``parent`` is gone.

    The worker's parent id changes (to init or a subreaper) the moment the parent dies;
    on Linux ``PR_SET_PDEATHSIG`` makes the kernel send SIGKILL even sooner.
    """
    try:
        import ctypes

        ctypes.CDLL(None).prctl(1, 9, 0, 0, 0)  # PR_SET_PDEATHSIG = 1, SIGKILL = 9
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        pass
    if os.getppid() != parent:  # died before we got here
        os._exit(1)

    def loop():
        while os.getppid() == parent:
            time.sleep(interval)
        os._exit(1)

    threading.Thread(target=loop, name="parent-watch", daemon=True).start()


def _pool_worker(parent: int) -> None:
    """Pool-worker initializer: leave Ctrl-C to the parent, and end with it (:func:`_watch_parent`).

    A terminal's Ctrl-C reaches every process of the group. Workers that took it died
    between tasks or sent it back as a task's result, and the parent, shutting the pool
    down, waited on them forever; the parent now ends them itself."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _watch_parent(parent)


def _watch_pid(pid: int, interval: float = 0.5) -> None:
    """In a Dask worker or nanny: exit once the run's main process ``pid`` is gone."""

    def loop():
        while True:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                os._exit(1)
            except PermissionError:
                pass
            time.sleep(interval)

    if not any(t.name == f"run-watch-{pid}" for t in threading.enumerate()):
        threading.Thread(target=loop, name=f"run-watch-{pid}", daemon=True).start()


def _call(func, kwargs):
    """Run one unit with a single compiled-kernel thread (results independent of the machine):
    ``(result, the package's code digest after it ran)``, in the process that ran it."""
    from .. import _provenance
    from .._parallel import num_threads

    with num_threads(1):
        result = func(**kwargs)
    return result, _provenance.current_code_digest()


def _checksum(key: str, result) -> str:
    text = json.dumps([key, result], sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def load_results(path) -> dict:
    """``{unit id: result}`` from a results file (see :func:`unit_id`).

    Only whole lines that hold a record with a string key, a result and that record's
    checksum are read: a torn last line (a crash mid-write), bytes that are not UTF-8 text,
    other JSON and a record edited by hand are skipped (their units are recomputed). The
    checksum guards against damage and stray edits, not forgery: a record whose checksum was
    recomputed after an edit is taken as it stands."""
    return _read_results(path)[0]


def _read_results(path) -> tuple[dict, int]:
    """:func:`load_results` and the number of lines it skipped as damaged."""
    path = Path(path)
    out, damaged = {}, 0
    if not path.exists():
        return out, damaged
    with path.open("rb") as handle:
        for raw in handle:
            damaged += 1  # until the line proves whole
            if not raw.endswith(b"\n"):
                break  # the process died while writing this line
            try:
                record = json.loads(raw.decode("utf-8"))
            except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):  # damage, nested past the parser
                continue
            if not isinstance(record, dict) or not isinstance(record.get("key"), str) or "result" not in record:
                continue
            if record.get("check") != _checksum(record["key"], record["result"]):
                continue
            out[record["key"]] = record["result"]
            damaged -= 1
    return out, damaged


def _check_keys(result, depth: int = 0):
    """Refuse a dict whose keys collide as JSON text (``1`` and ``"1"``, ``True`` and ``"true"``):
    JSON keeps one of them, so the stored result would silently lose the other."""
    if depth > 200:  # (json.dumps refuses deeper data itself)
        return
    if isinstance(result, dict):
        seen = {}
        for key in result:
            text = json.dumps({key: 0})[1:-4]  # the key as JSON writes it (TypeError for a key it cannot)
            if text in seen:
                raise TypeError(f"the keys {seen[text]!r} and {key!r} are the same in JSON")
            seen[text] = key
        values = result.values()
    elif isinstance(result, list | tuple):
        values = result
    else:
        return
    for value in values:
        _check_keys(value, depth + 1)


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

    def add(self, key: str, result):
        """Append ``result`` under ``key`` and return it as it will be read back (tuples become
        lists, dict keys text), so that a run and its resumption hand out the same values."""
        try:
            _check_keys(result)
            stored = json.loads(json.dumps(result))
        except (TypeError, ValueError) as error:
            raise TypeError(
                f"unit {key.partition('#')[0]!r} returned a result that cannot be stored as JSON "
                f"({error}); return dicts, lists, str, int, float, bool or None."
            ) from None
        record = {"key": key, "result": stored, "check": _checksum(key, stored)}
        data = (json.dumps(record, separators=(",", ":")) + "\n").encode()
        os.write(self.fd, data)
        os.fsync(self.fd)
        return stored

    def close(self):
        os.close(self.fd)


def _check_scheduler(scheduler: str) -> str:
    expected = f"`scheduler` must be one of {', '.join(map(repr, SCHEDULERS))} or 'tcp://host:port'"
    if not isinstance(scheduler, str) or not (scheduler in SCHEDULERS or scheduler.startswith("tcp://")):
        raise InputError(f"{expected}; got {scheduler!r}.")
    if scheduler.startswith("tcp://"):
        from urllib.parse import urlsplit

        try:
            parts = urlsplit(scheduler)
            port = parts.port
        except ValueError:
            port = None
        if port is None or not parts.hostname or not 0 < port < 65536:
            raise InputError(f"{expected} with a host and a port in 1..65535; got {scheduler!r}.")
    return scheduler


def run_units(
    units, path, *, scheduler: str = "processes", workers: int | None = None, progress: bool = True, desc: str = ""
) -> dict:
    """Run the units missing from ``path`` and return ``{unit.key: result}`` for all of them.

    Each result is returned as it is stored, in JSON's types (a tuple comes back as a list, a
    dict's keys as strings), whether it was computed now or read from an earlier run; a unit
    must return what JSON can hold.

    A stored result is used only for the unit with the same :func:`unit_id` (same label,
    function, keyword arguments, package version and code); results of other runs kept in the
    same file are left there, unused, and counted in a note on stderr.

    Parameters
    ----------
    units : sequence of Unit
        Keys (labels) must be unique.
    path : path-like
        The experiment's results file (JSON lines); created if missing.
    scheduler : {'serial', 'processes', 'dask'} or 'tcp://host:port', default='processes'
    workers : int, optional
        Processes (or Dask workers) to start; default: the cores this process may use.
    progress : bool, default=True
        A progress bar on stderr.
    """
    scheduler = _check_scheduler(scheduler)
    if workers is not None:
        from .._validation import check_int

        workers = check_int(workers, name="workers", low=1, high=MAX_WORKERS)
    units = list(units)
    keys = [u.key for u in units]
    if len(set(keys)) != len(keys):
        raise InputError(
            f"`units` must have unique keys; got duplicates, e.g. {next(k for k in keys if keys.count(k) > 1)!r}."
        )
    path = Path(path)
    if path.exists() and not path.is_file():
        raise InputError(f"`path` must be a results file (JSON lines); got {str(path)!r}, which is a folder.")
    ids = {u.key: unit_id(u) for u in units}
    from .._provenance import code_digest

    started = code_digest()  # (the digest in every id: a result of other code is not stored under it)
    stored, damaged = _read_results(path)
    done = {key: stored[i] for key, i in ids.items() if i in stored}
    todo = [u for u in units if u.key not in done]
    if damaged:  # (a resume that recomputes work says why)
        print(
            f"{path}: skipped {damaged} damaged line{'' if damaged == 1 else 's'} (a write cut short, or a record "
            "edited by hand); they are left in the file, and a unit of this run whose result was among them is "
            "computed again.",
            file=sys.stderr,
        )
    other = len(set(stored) - set(ids.values()))
    if other:
        print(
            f"{path}: {other} stored result(s) are not units of this run (other seeds, sizes or methods, or "
            f"another package version or code); they are kept in the file and not used. "
            f"Computing {len(todo)} of {len(units)} unit(s).",
            file=sys.stderr,
        )
    if workers is None:
        from .._parallel import available_cores

        workers = available_cores()
    bar = None
    if progress and todo:
        from tqdm.auto import tqdm

        bar = tqdm(
            total=len(units),
            initial=len(units) - len(todo),
            desc=desc or path.stem,
            unit="unit",
            file=sys.stderr,
            leave=False,
        )
    appender = _Appender(path)

    def finished(key, outcome):
        result, digest = outcome
        if digest != started:
            raise CodeChangedError(
                f"The package's files changed during the run: the code digest was {started} when it started "
                f"and {digest} once unit {key!r} was computed, so that result (of other code than the run's "
                f"keys name) was not stored in {str(path)!r}. The {len(done)} result(s) stored before are "
                "kept; run again to compute the rest with the code as it is now."
            )
        done[key] = appender.add(ids[key], result)
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
    pool = ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_pool_worker,
        initargs=(os.getpid(),),
    )
    try:
        pending = {pool.submit(_call, u.func, u.kwargs): u.key for u in todo}
        while pending:
            ready, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in ready:
                finished(pending.pop(future), future.result())
    except BaseException:
        # (an interrupt, or a unit's error): the units still running are given up, not
        # awaited; the finished ones are already in the results file
        workers_left = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in workers_left:
            process.terminate()
        for process in workers_left:
            process.join(5.0)
        raise
    pool.shutdown(wait=True)


# seconds a running scheduler has to answer: Dask's own connect timeout is 30 s, and a
# listener that is not a Dask scheduler (it accepts the connection and never replies to the
# handshake) made Client() wait forever
_CONNECT_SECONDS = 45.0


def _connect(client_class, scheduler: str, seconds: float = _CONNECT_SECONDS):
    """A client of the scheduler at ``scheduler``, or an InputError if it does not answer as a
    Dask scheduler within ``seconds`` (the attempt is left to a daemon thread)."""
    box = {}

    def attempt():
        try:
            box["client"] = client_class(scheduler, timeout=min(30.0, seconds))
        except BaseException as exc:  # anything a wrong peer makes the handshake raise
            box["error"] = exc

    thread = threading.Thread(target=attempt, name="cv-dask-connect", daemon=True)
    thread.start()
    thread.join(seconds)
    if "client" in box:
        return box["client"]
    if thread.is_alive():
        reason = f"no answer within {seconds:g} s (is a Dask scheduler listening there?)"
    else:
        error = box["error"]
        reason = f"{type(error).__name__}: {str(error).strip().splitlines()[0] if str(error).strip() else ''}"
    raise InputError(f"`scheduler` {scheduler!r} could not be reached as a Dask scheduler: {reason}")


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
        client = _connect(Client, scheduler)
    try:
        if cluster is not None:  # its nannies and workers end with this process, even on SIGKILL
            client.run(_watch_pid, os.getpid(), nanny=True)
            client.run(_watch_pid, os.getpid())
        futures = {client.submit(_call, u.func, u.kwargs, key=f"cv-{u.key}", pure=False): u.key for u in todo}
        for future in as_completed(futures):
            finished(futures[future], future.result())
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

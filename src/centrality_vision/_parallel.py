"""Run compiled, GIL-free kernels over chunks of work on a pool of threads.

Why threads and not numba's ``prange``: OpenMP threads spin-wait at the end of a parallel
region, so when another process takes a core (CI, a shared workstation) the region runs at
the pace of its slowest thread while the others burn the remaining CPU; we measured 8x
slower closeness with two threads than with one. Threads of a pool that each take the
next chunk when they finish one leave scheduling to the operating system, balance uneven
chunks, and let a progress bar advance and Ctrl-C stop the work between chunks.
"""

from __future__ import annotations

import contextlib
import os
import threading
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from ._validation import check_int
from .exceptions import InputError

__all__ = ["get_num_threads", "set_num_threads", "run_chunks", "available_cores"]

_ENV = "CENTRALITY_VISION_NUM_THREADS"
_lock = threading.Lock()
_state = {"threads": None, "pool": None, "pool_size": 0}


#: the most threads one may ask for (set_num_threads' bound too)
_MAX_THREADS = 2**62


def _default_threads() -> int:
    env = os.environ.get(_ENV)
    if env:
        try:
            n = int(env)
        except ValueError:
            n = 0
        if not 1 <= n <= _MAX_THREADS:  # (0 and -3 were taken as 1, 10**20 failed later)
            raise InputError(f"`{_ENV}` (environment variable) must be an int in [1, 2^62]; got {env!r}.")
        return n
    return available_cores()


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity where the OS reports one).

    Examples
    --------
    >>> import os
    >>> 1 <= available_cores() <= (os.cpu_count() or 1)
    True
    """
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def get_num_threads() -> int:
    """Threads used by the compiled centralities: :func:`set_num_threads`, else
    ``$CENTRALITY_VISION_NUM_THREADS``, else the cores this process may run on.

    Examples
    --------
    >>> import centrality_vision as cv
    >>> cv.get_num_threads() >= 1
    True
    >>> cv.set_num_threads(2); cv.get_num_threads()
    2
    >>> cv.set_num_threads(None)  # back to the default
    """
    return _state["threads"] or _default_threads()


def set_num_threads(n: int | None) -> None:
    """Set how many threads the compiled centralities use (``None`` restores the default).

    Parameters
    ----------
    n : int >= 1 or None
        Threads for this process from now on. None: back to ``$CENTRALITY_VISION_NUM_THREADS``,
        else the cores this process may run on (:func:`get_num_threads`).

    Examples
    --------
    >>> import centrality_vision as cv
    >>> cv.set_num_threads(1); cv.get_num_threads()
    1
    >>> cv.set_num_threads(None)
    """
    _state["threads"] = None if n is None else check_int(n, name="n", low=1, high=_MAX_THREADS)


@contextlib.contextmanager
def num_threads(n: int | None):
    """Within the block, :func:`set_num_threads` ``(n)``; after it, the setting before (also
    when that was the default, so the environment is not read)."""
    before = _state["threads"]
    set_num_threads(n)
    try:
        yield
    finally:
        _state["threads"] = before


def _pool(size: int) -> ThreadPoolExecutor:
    with _lock:
        if _state["pool"] is None or _state["pool_size"] != size:
            if _state["pool"] is not None:
                _state["pool"].shutdown(wait=False)
            _state["pool"] = ThreadPoolExecutor(max_workers=size, thread_name_prefix="centrality-vision")
            _state["pool_size"] = size
        return _state["pool"]


# chunks of the work: at least 8 (4 per thread on 2 cores), one per 256 units beyond, at most 64
_MIN_CHUNKS, _MAX_CHUNKS, _UNITS_PER_CHUNK = 8, 64, 256


def _bounds(n_items: int, n_chunks: int) -> list[tuple[int, int]]:
    edges = [round(i * n_items / n_chunks) for i in range(n_chunks + 1)]
    return [(lo, hi) for lo, hi in zip(edges[:-1], edges[1:]) if hi > lo]


def run_chunks(
    task, n_items: int, *, progress: bool = False, desc: str = "", weight: int = 1, total: int | None = None
):
    """Call ``task(lo, hi)`` on consecutive chunks of ``range(n_items)``; return the results.

    Results come back in chunk order as a list of ``(lo, hi, result)``. ``weight`` is the
    number of progress units per item (``total`` caps the bar), e.g. 64 sources per group.
    The chunks depend on ``n_items`` and ``weight`` only, never on the thread count (at
    least 8, one per 256 units beyond, at most 64), so that a caller adding the chunks' partial
    sums in chunk order gets the same bits with any number of threads.

    Examples
    --------
    >>> parts = run_chunks(lambda lo, hi: sum(range(lo, hi)), 100)
    >>> len(parts), parts[0], sum(result for _, _, result in parts)
    (8, (0, 12, 66), 4950)
    """
    threads = get_num_threads()
    units = n_items * weight
    n_chunks = min(n_items, max(_MIN_CHUNKS, min(_MAX_CHUNKS, units // _UNITS_PER_CHUNK))) if n_items else 0
    bounds = _bounds(n_items, n_chunks)
    total = units if total is None else total
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, desc=desc, unit="source", leave=False)

    def advance(lo, hi):
        if bar is not None:
            bar.update(min((hi - lo) * weight, total - bar.n))

    results = {}
    try:
        if threads == 1 or len(bounds) == 1:
            for lo, hi in bounds:
                results[lo] = (lo, hi, task(lo, hi))
                advance(lo, hi)
        else:
            pool = _pool(threads)
            pending = {pool.submit(task, lo, hi): (lo, hi) for lo, hi in bounds}
            try:
                while pending:
                    finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                    for future in finished:
                        lo, hi = pending.pop(future)
                        results[lo] = (lo, hi, future.result())
                        advance(lo, hi)
            except BaseException:
                for future in pending:
                    future.cancel()
                raise
    finally:
        if bar is not None:
            bar.close()
    return [results[lo] for lo in sorted(results)]

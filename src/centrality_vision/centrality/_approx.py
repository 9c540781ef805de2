"""Sampling approximations with stated guarantees (hop distances).

- Betweenness: Riondato-Kornaropoulos path sampling, stopped early by an empirical
  Bernstein bound checked at geometric checkpoints. On pixel grids each pair's search is
  pruned to the pixels that can lie on its shortest paths (grid and landmark bounds,
  :func:`._sampling._pruned_bfs`); each thread keeps its work arrays across chunks.
- Closeness and harmonic: Eppstein-Wang source sampling with Hoeffding's bound.

The guarantees are stated on the public functions (:func:`.betweenness`,
:func:`.closeness`, :func:`.harmonic`).
"""

from __future__ import annotations

import math
import queue

import numpy as np

from .._parallel import get_num_threads, run_chunks
from .._seeding import as_generator
from ..exceptions import InputError
from . import _kernels, _sampling

__all__ = ["sample_betweenness", "sample_sources"]

RK_CONSTANT = 0.5  # the universal constant c of the VC-dimension sample bound
# The most pairs betweenness may draw (they are drawn up front, 24 bytes each: 1.1 GiB).
MAX_PAIR_SAMPLES = 5 * 10**7
_GROWTH = 1.5  # checkpoint sizes grow geometrically by this factor
_LANDMARKS = 8  # pixel grids: landmarks whose hop counts bound the distance to a target
_NO_RASTERS = (np.zeros(0, dtype=np.bool_), np.zeros(0, dtype=np.bool_))


def _largest_eccentricity_bound(prep) -> int:
    """Max over components of 2 * (eccentricity of one node of it): at least the diameter."""
    n = prep.n
    dist = np.full(n, -1, dtype=np.int64)
    order = np.empty(n, dtype=np.int64)
    best = 0
    seen = np.zeros(n, dtype=bool)
    for root in range(n):
        if seen[root]:
            continue
        count = _kernels._bfs(prep.indptr, prep.indices, root, dist, order)
        members = order[:count]
        seen[members] = True
        best = max(best, 2 * int(dist[members].max()))
        dist[members] = -1
    return best


def _drain(pool):
    """Every item of a SimpleQueue (no task running), put back."""
    items = []
    while not pool.empty():
        items.append(pool.get())
    for item in items:
        pool.put(item)
    return items


def _grid_guides(grid, reach):
    """Connected-component labels of the padded raster (int32), the hop counts from
    :data:`_LANDMARKS` landmarks chosen farthest-first in the largest component (uint16
    where they fit), and in 2D the raster row by row and column by column: what lets the
    searches skip impossible pairs and bound the distance to a target around holes and
    bends, and the paths of most pairs be counted without a search."""
    from scipy import ndimage

    structure = ndimage.generate_binary_structure(grid.padded.ndim, reach)
    labels, _ = ndimage.label(grid.padded, structure=structure)
    if grid.padded.ndim == 2:  # the raster row by row, and column by column
        rasters = (grid.foreground, np.ascontiguousarray(grid.padded.T).ravel())
    elif len(grid.steps) == 26:  # 3D: the slices are read from the raster itself
        rasters = (grid.foreground, grid.foreground)
    else:
        rasters = _NO_RASTERS
    labels = labels.ravel().astype(np.int32)
    largest = np.argmax(np.bincount(labels)[1:]) + 1
    start = int(np.flatnonzero(labels == largest)[0])
    marks = _sampling.landmark_hops(grid.foreground, grid.offs, _LANDMARKS, start)
    if marks.size == 0 or marks.max() <= np.iinfo(np.uint16).max:
        marks = marks.astype(np.uint16)  # less memory traffic in the searches
    else:
        marks = np.array(marks)  # allocated by NumPy (huge pages), like the searches' arrays
    return labels, marks, rasters


def rk_sample_size(vertex_diameter: int, epsilon: float, delta: float) -> int:
    """Riondato-Kornaropoulos: samples for an ``epsilon`` error with probability ``1 - delta``."""
    vc = math.floor(math.log2(vertex_diameter - 2)) + 1 if vertex_diameter > 3 else 1
    size = RK_CONSTANT * (vc + math.log(1.0 / delta)) / epsilon**2 if epsilon**2 > 0 else math.inf
    return int(math.ceil(size)) if size < 2**62 else 2**62  # (a tiny epsilon: beyond any count)


def _bernstein(hits: np.ndarray, k: int, log_term: float) -> float:
    """Largest two-sided empirical Bernstein radius (Maurer and Pontil 2009, thm. 4) of the
    node frequencies after ``k`` samples; ``log_term`` is ln(4 / per-node failure probability)."""
    p = hits / k
    variance = float(np.max(p * (1.0 - p))) * k / (k - 1)  # the sample variance of a 0/1 variable
    return math.sqrt(2.0 * variance * log_term / k) + 7.0 * log_term / (3.0 * (k - 1))


def sample_betweenness(prep, epsilon: float, delta: float, seed, progress: bool, grid=None):
    """Normalised betweenness estimates (node order of ``prep``) and an info dict; ``(None,
    None)`` where the sample cap reaches the graph's ordered pairs (exact values are cheaper).

    With ``grid`` (a :class:`._grid._Grid` of the same graph) the searches walk the pixel
    grid, and the estimates come in the node order of the graph itself (prepare it
    without reordering).
    """
    n = prep.n
    rng = as_generator(seed)  # validated even when there is nothing to sample
    if n < 3:
        return np.zeros(n), {"samples": 0, "searches": 0, "bound": 0.0, "visited": 0, "retries": 0, "counted": 0}
    # E[hits / k] = b / (n (n - 1)) over ordered pairs; normalised b is that times n / (n - 2).
    target = epsilon * (n - 2) / n
    if prep.directed:
        vertex_diameter = n
    else:
        vertex_diameter = _largest_eccentricity_bound(prep) + 1
    cap = rk_sample_size(vertex_diameter, target, delta / 2)
    if cap >= n * (n - 1):  # more pairs than the graph has: exact values are cheaper
        return None, None
    if cap > MAX_PAIR_SAMPLES:  # (drawn up front: 24 bytes each)
        raise InputError(
            f"`epsilon`={epsilon:g} asks for up to {cap:.3g} sampled pairs on this graph of {n} nodes "
            f"(about {24 * cap / 2**30:.3g} GiB), more than the {MAX_PAIR_SAMPLES:.0e} allowed; use a larger "
            "`epsilon`, or None for exact values."
        )
    checkpoints = []
    k = min(cap, 256)
    while k < cap:
        checkpoints.append(k)
        k = int(math.ceil(k * _GROWTH))
    checkpoints.append(cap)
    log_term = math.log(4.0 * n * len(checkpoints) / (delta / 2))
    s = rng.integers(0, n, size=cap)
    t = (s + 1 + rng.integers(0, n - 1, size=cap)) % n
    pairs = np.stack([s, t], axis=1).astype(np.int64)
    stream = int(rng.integers(0, 2**63 - 1))
    t_indptr, t_indices, _ = prep.transposed()
    offs, foreground = _kernels.NO_GRID
    steps, shape, reach = np.empty((0, 0), dtype=np.int64), np.empty(0, dtype=np.int64), 0
    marks = np.empty((0, 0), dtype=np.int32)
    labels = np.empty(0, dtype=np.int32)
    rasters = _NO_RASTERS
    indptr, indices = prep.indptr, prep.indices
    if grid is not None:
        offs, foreground = grid.offs, grid.foreground
        indptr = t_indptr = np.empty(0, dtype=np.int64)
        indices = t_indices = np.empty(0, dtype=np.int32)
        pairs = grid.raster[pairs]
        steps = np.array(grid.steps, dtype=np.int64)
        shape = np.array(grid.padded.shape, dtype=np.int64)
        reach = int(np.abs(steps).sum(axis=1).max())
        labels, marks, rasters = _grid_guides(grid, reach)
    scratch = queue.SimpleQueue()
    size = foreground.size if grid is not None else n
    for _ in range(max(1, min(get_num_threads(), cap))):
        scratch.put(_sampling.new_scratch(size, foreground, grid is not None))
    done = 0
    bound = math.inf
    visited = 0
    retries = 0
    direct = 0
    for k in checkpoints:

        def task(lo, hi, first=done):
            arrays = scratch.get()  # one thread's work arrays; results do not depend on which
            try:
                return _sampling.sample_paths(
                    indptr,
                    indices,
                    t_indptr,
                    t_indices,
                    pairs,
                    stream,
                    first + lo,
                    first + hi,
                    offs,
                    steps,
                    shape,
                    reach,
                    marks,
                    labels,
                    rasters,
                    arrays,
                )
            finally:
                scratch.put(arrays)

        for _, _, (work, n_retries, n_direct) in run_chunks(
            task, k - done, progress=progress, desc="betweenness samples"
        ):
            visited += work
            retries += n_retries
            direct += n_direct
        done = k
        hits = sum(arrays[-1] for arrays in _drain(scratch))
        bound = _bernstein(hits, k, log_term) if k > 1 else math.inf
        if bound <= target:
            break
    if done == cap:
        bound = min(bound, target)
    if grid is not None:
        hits = hits[grid.raster]
    return hits / done * n / (n - 2), {
        "samples": done,
        "searches": done,
        "bound": bound * n / (n - 2),
        "visited": visited,
        "retries": retries,
        "counted": direct,
    }


def sample_sources(prep, epsilon: float, delta: float, seed, progress: bool, desc: str):
    """Eppstein-Wang: distance sums to every node from ``k`` sampled sources, scaled to n.

    Returns sums of distances and of inverse distances (estimates), the largest sampled
    distance, the exact number of nodes reaching each node, and an info dict.
    """
    from scipy.sparse.csgraph import connected_components

    n = prep.n
    rng = as_generator(seed)
    # (in floats: a tiny epsilon underflows the denominator, and its sample count is not an int)
    spread = 2.0 * (epsilon * (n - 1) / n) ** 2 if n > 1 else 0.0
    k_real = math.log(2.0 * n / delta) / spread if spread > 0 else math.inf
    if not k_real < n:  # sampling would not save anything: exact values
        from ._api import _hop_stats

        return (*_hop_stats(prep.indptr, prep.indices, progress, desc), {"searches": n, "samples": n})
    k = int(math.ceil(k_real))
    sources = np.sort(rng.choice(n, size=k, replace=False)).astype(np.int64)  # RCM order: nearby
    group_ptr = np.arange(0, k + 64, 64, dtype=np.int64)
    group_ptr[-1] = k
    group_ptr = np.unique(group_ptr)

    def task(lo, hi):
        return _kernels.multi_source_stats(prep.indptr, prep.indices, sources, group_ptr, lo, hi)

    parts = [r for _, _, r in run_chunks(task, group_ptr.size - 1, progress=progress, desc=desc, weight=64, total=k)]
    total = sum(p[0] for p in parts) * (n / k)
    inverse = sum(p[1] for p in parts) * (n / k)
    largest = np.max([p[2] for p in parts], axis=0)
    _, labels = connected_components(prep.adjacency, directed=False)
    reached = np.bincount(labels)[labels].astype(np.int64)
    return total, inverse, largest, reached, {"searches": k, "samples": k}

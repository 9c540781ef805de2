"""Compiled kernels (numba) for the sampling approximations and eccentricity bounds.

Random choices come from a counter-based generator (SplitMix64 of the seed, the sample's
index and a step number), so that a sample's outcome does not depend on which thread
draws it or in which chunk: results are identical for any thread count.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import _neighbour, _span

__all__ = ["sample_paths", "uniform"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_RESCALE = 1e200
_BLOCKED = 1 << 40  # grid mode: the distance of background pixels, never a search level


@njit(cache=True, nogil=True, inline="always")
def _mix(z):
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(cache=True, nogil=True, inline="always")
def uniform(seed, sample, step):
    """A uniform float in [0, 1) determined by ``(seed, sample, step)`` alone."""
    z = _mix(np.uint64(seed) + _GOLDEN * np.uint64(sample + 1))
    z = _mix(z + _GOLDEN * np.uint64(step + 1))
    return (z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@njit(cache=True, nogil=True)
def _expand(indptr, indices, offs, grid, frontier, n_front, dist, sigma, other, nxt, visited, n_visited):
    """One breadth-first level of one side; returns (n_next, n_visited, met)."""
    level = dist[frontier[0]] + 1
    n_next = 0
    met = False
    for a in range(n_front):
        v = frontier[a]
        sv = sigma[v]
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            dw = dist[w]
            if dw < 0:
                dist[w] = level
                sigma[w] = sv
                nxt[n_next] = w
                n_next += 1
                visited[n_visited] = w
                n_visited += 1
                if other[w] >= 0:
                    met = True
            elif dw == level:
                sigma[w] += sv
    # Counts of one level share one scale: rescaling them all keeps every ratio.
    top = 0.0
    for a in range(n_next):
        top = max(top, sigma[nxt[a]])
    if top > _RESCALE:
        for a in range(n_next):
            sigma[nxt[a]] /= top
    return n_next, n_visited, met


@njit(cache=True, nogil=True)
def _walk(indptr, indices, offs, grid, start, dist, sigma, seed, sample, step, hits, path_len):
    """Walk from ``start`` down to distance 0, each step to a predecessor drawn with
    probability proportional to its path count; counts the inner nodes in ``hits``."""
    v = start
    while dist[v] > 1:
        total = 0.0
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            if dist[w] == dist[v] - 1:
                total += sigma[w]
        r = uniform(seed, sample, step) * total
        step += 1
        pick = -1
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            if dist[w] == dist[v] - 1:
                pick = w
                r -= sigma[w]
                if r < 0.0:
                    break
        v = pick
        hits[v] += 1
        path_len += 1
    return step, path_len


@njit(cache=True, nogil=True)
def sample_paths(indptr, indices, t_indptr, t_indices, pairs, seed, first, stop, offs, foreground):
    """Riondato-Kornaropoulos samples ``first .. stop - 1``: for each pair ``(s, t)`` a
    shortest path drawn uniformly at random by a balanced bidirectional breadth-first
    search; returns how often each node was an inner node of a drawn path, and the
    number of nodes the searches visited.

    ``t_indptr, t_indices`` is the transposed adjacency (the same arrays when undirected).
    Grid mode when ``offs`` is not empty: nodes are the pixels of the padded raster
    ``foreground`` (undirected; background pixels are never reached).
    """
    grid = offs.shape[0] > 0
    n = foreground.shape[0] if grid else indptr.shape[0] - 1
    hits = np.zeros(n, dtype=np.int64)
    dist_s = np.full(n, -1, dtype=np.int64)
    dist_t = np.full(n, -1, dtype=np.int64)
    if grid:  # background: a distance no level reaches, and "seen" so never entered
        for i in range(n):
            if not foreground[i]:
                dist_s[i] = _BLOCKED
                dist_t[i] = _BLOCKED
    sig_s = np.zeros(n)
    sig_t = np.zeros(n)
    front_s = np.empty(n, dtype=np.int64)
    front_t = np.empty(n, dtype=np.int64)
    nxt = np.empty(n, dtype=np.int64)
    visited = np.empty(2 * n, dtype=np.int64)
    work = 0
    for i in range(first, stop):
        s = pairs[i, 0]
        t = pairs[i, 1]
        dist_s[s] = 0
        sig_s[s] = 1.0
        dist_t[t] = 0
        sig_t[t] = 1.0
        visited[0] = s
        visited[1] = t
        n_visited = 2
        front_s[0] = s
        front_t[0] = t
        ns = 1
        nt = 1
        met = s == t
        meet_side = 0
        while not met and ns > 0 and nt > 0:
            # Expand the side whose frontier has fewer arcs to scan.
            cost_s = ns  # the grid: every pixel has the same offsets to scan
            cost_t = nt
            if not grid:
                cost_s = 0
                for a in range(ns):
                    cost_s += indptr[front_s[a] + 1] - indptr[front_s[a]]
                cost_t = 0
                for a in range(nt):
                    cost_t += t_indptr[front_t[a] + 1] - t_indptr[front_t[a]]
            if cost_s <= cost_t:
                ns, n_visited, met = _expand(
                    indptr, indices, offs, grid, front_s, ns, dist_s, sig_s, dist_t, nxt, visited, n_visited
                )
                front_s[:ns] = nxt[:ns]
                meet_side = 0
            else:
                nt, n_visited, met = _expand(
                    t_indptr, t_indices, offs, grid, front_t, nt, dist_t, sig_t, dist_s, nxt, visited, n_visited
                )
                front_t[:nt] = nxt[:nt]
                meet_side = 1
        work += n_visited
        if met and s != t:
            # The meeting nodes lie on the frontier just expanded; pick one with
            # probability proportional to sigma_s * sigma_t (paths through it).
            front = front_s if meet_side == 0 else front_t
            nf = ns if meet_side == 0 else nt
            total = 0.0
            for a in range(nf):
                w = front[a]
                if dist_s[w] >= 0 and dist_t[w] >= 0:
                    total += sig_s[w] * sig_t[w]
            r = uniform(seed, i, 0) * total
            pick = -1
            for a in range(nf):
                w = front[a]
                if dist_s[w] >= 0 and dist_t[w] >= 0:
                    pick = w
                    r -= sig_s[w] * sig_t[w]
                    if r < 0.0:
                        break
            if pick != s and pick != t:
                hits[pick] += 1
            # Towards s over in-arcs of the forward search, towards t over out-arcs.
            step, _ = _walk(t_indptr, t_indices, offs, grid, pick, dist_s, sig_s, seed, i, 1, hits, 0)
            _walk(indptr, indices, offs, grid, pick, dist_t, sig_t, seed, i, step, hits, 0)
        for q in range(n_visited):
            v = visited[q]
            dist_s[v] = -1
            dist_t[v] = -1
    return hits, work

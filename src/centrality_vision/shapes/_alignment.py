"""Compiled banded alignment of outline profiles (dynamic programming, squared differences)."""

import numpy as np
from numba import njit

__all__ = ["align", "refine"]


@njit(cache=True, nogil=True)
def align(a, b, start, band):  # pragma: no cover - compiled
    """Banded DTW of profile ``a`` against ``b`` read cyclically from ``start``; cost / n.

    Each step adds the squared difference of the two points' profiles; a path may stray
    at most ``band`` points from the diagonal, and must start and end on it.
    """
    n, d = a.shape
    cost = np.full((n + 1, n + 1), np.inf)
    cost[0, 0] = 0.0
    for i in range(1, n + 1):
        lo = max(1, i - band)
        hi = min(n, i + band)
        for j in range(lo, hi + 1):
            jj = (j - 1 + start) % n
            c = 0.0
            for k in range(d):
                x = a[i - 1, k] - b[jj, k]
                c += x * x
            m = cost[i - 1, j - 1]
            if cost[i - 1, j] < m:
                m = cost[i - 1, j]
            if cost[i, j - 1] < m:
                m = cost[i, j - 1]
            cost[i, j] = c + m
    return cost[n, n] / n


@njit(cache=True, nogil=True)
def refine(forward, backward, queries, candidates, shift, side, band, spread, out):  # pragma: no cover - compiled
    """``out[q, t]``: the best alignment of query ``queries[q]`` and shape ``candidates[q, t]``
    within ``spread`` points of the shift (and orientation) the FFT stage found."""
    for q in range(queries.shape[0]):
        a = queries[q]
        for t in range(candidates.shape[1]):
            b = candidates[q, t]
            target = forward[b] if side[a, b] == 0 else backward[b]
            best = np.inf
            for ds in range(-spread, spread + 1):
                v = align(forward[a], target, (shift[a, b] + ds) % forward.shape[1], band)
                if v < best:
                    best = v
            out[q, t] = best

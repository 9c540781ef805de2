"""Nearest-neighbour queries that keep every neighbour tied with a given rank."""

from __future__ import annotations

import numpy as np

__all__ = ["query_with_ties"]


def query_with_ties(tree, queries: np.ndarray, rank: int, rtol: float = 0.0):
    """``(dist, index, tied)`` of each query's nearest points in ``tree`` (a
    :class:`scipy.spatial.cKDTree`), sorted by distance, with every point as near as the
    ``rank``-th (0-based) flagged in ``tied`` (distance at most its ``1 + rtol`` times).

    Which of several equidistant points a k-d tree returns depends on how the tree was
    built, hence on the order of the points: results that must not depend on it take all
    of them. Fetches more neighbours until the last one fetched is not tied (or all are).

    Examples
    --------
    >>> from scipy.spatial import cKDTree
    >>> square = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    >>> dist, index, tied = query_with_ties(cKDTree(square), np.array([[0.5, 0.5]]), 0)
    >>> sorted(index[tied].tolist())  # all four corners are nearest
    [0, 1, 2, 3]
    """
    n = tree.n
    fetch = min(n, max(8, 2 * rank + 2))
    while True:
        dist, index = tree.query(queries, k=[*range(1, fetch + 1)])
        tied = dist <= dist[:, rank : rank + 1] * (1 + rtol)
        if fetch == n or not tied[:, -1].any():
            return dist, index, tied
        fetch = min(n, 2 * fetch)

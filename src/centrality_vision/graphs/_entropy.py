"""Maximum-entropy data-graphs (thesis ch. 6 and 7, SPEC sections 4 and 5).

- :func:`nhdd_graph`: the graphs with the most distinct degrees (n - 1 of them), built by
  Algorithm 6.1.
- :func:`mwme_graph`: the minimum-weight labelling of the connected NHDD graph onto a
  point set (the MWME problem, eq. 6.2).
- :func:`mstme_graph`: the spanning tree minimising weight minus lambda times the entropy
  of its degree distribution (MSTME, eq. 7.1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.spatial.distance import pdist, squareform

from .._parallel import run_chunks
from .._validation import ANY_DIMS, as_points, check_choice, check_float, check_int
from ..exceptions import InputError
from . import _entropy_kernels as _k
from ._pointsets import edges_to_graph

__all__ = ["nhdd_joining", "nhdd_graph", "MWMEResult", "mwme_graph", "MSTMEResult", "mstme_graph"]

#: Largest point set the exact MWME solver accepts (memory grows as 2^n n).
MAX_EXACT = 20


def entropy_of_degrees(degrees) -> float:
    """Entropy in bits of a degree sequence's distribution (eq. 6.1); zeros count."""
    degrees = np.asarray(degrees, dtype=np.int64)
    counts = np.bincount(degrees)
    p = counts[counts > 0] / degrees.size
    return float(-(p * np.log2(p)).sum()) + 0.0


def nhdd_joining(n: int, *, connected: bool = True) -> np.ndarray:
    """Which positions of Algorithm 6.1 join all earlier nodes (the others stay isolated).

    Position ``k`` (0-based) joins iff ``n - 1 - k`` is even for the connected graph, so
    that the last node joins; the complement (one isolated node) swaps the roles.
    """
    n = check_int(n, name="n", low=2)
    k = np.arange(n)
    joining = ((n - 1 - k) % 2 == 0) if connected else ((n - 1 - k) % 2 == 1)
    joining[0] = False  # the first node has nobody to join
    return joining


def nhdd_graph(n: int, /, *, connected: bool = True) -> sparse.csr_array:
    """The graph on ``n`` nodes with ``n - 1`` distinct degrees (Algorithm 6.1).

    Nodes ``0 .. n-1`` are added in order; each is either isolated or joined to all
    earlier nodes, alternating so that the last node joins (connected graph) or stays
    isolated (its complement). Edge ``(i, j)``, ``i < j``, exists iff node ``j`` joins.
    Every such graph has maximum degree entropy, ``log2 n - 2/n`` (Theorems 5 and 6);
    the repeated degree is ``floor(n/2)`` (Lemma 4) and the connected one has
    ``(n(n-1)/2 + floor(n/2)) / 2`` edges (Theorem 4).

    Parameters
    ----------
    n : int >= 3
    connected : bool, default=True
        The connected graph (True) or its complement, which has one isolated node.

    Returns
    -------
    scipy.sparse.csr_array of shape (n, n)
        Unit edge values.

    Examples
    --------
    >>> graph = nhdd_graph(5)
    >>> (graph > 0).sum(axis=1).tolist()  # degrees (1, 2, 2, 3, 4) in some order
    [2, 2, 3, 1, 4]
    """
    n = check_int(n, name="n", low=3)
    joining = nhdd_joining(n, connected=bool(connected))
    cols = np.repeat(np.flatnonzero(joining), np.flatnonzero(joining))
    rows = np.concatenate([np.arange(j) for j in np.flatnonzero(joining)]) if joining.any() else np.array([], int)
    return edges_to_graph(n, rows, cols, lengths=1.0)


def _distance_matrix(points) -> tuple[np.ndarray, np.ndarray]:
    pts = as_points(points, name="points", n_dims=ANY_DIMS, min_points=3, allow_duplicates=False)
    return pts, squareform(pdist(pts))


@dataclass(frozen=True)
class MWMEResult:
    """A minimum-weight maximum-entropy graph of a point set.

    Attributes
    ----------
    graph : scipy.sparse.csr_array
        The connected NHDD graph on the points, Euclidean edge lengths.
    order : ndarray of int
        ``order[k]`` is the point placed at position ``k`` of Algorithm 6.1.
    degrees : ndarray of int
        Degree of every point (row i is point i).
    cost : float
        Total edge length.
    method : str
    """

    graph: sparse.csr_array
    order: np.ndarray
    degrees: np.ndarray
    cost: float
    method: str


def _positions_graph(points: np.ndarray, order: np.ndarray, joining: np.ndarray) -> sparse.csr_array:
    n = order.size
    join_pos = np.flatnonzero(joining)
    rows = order[np.concatenate([np.arange(j) for j in join_pos])]
    cols = order[np.repeat(join_pos, join_pos)]
    return edges_to_graph(n, rows, cols, points)


def mwme_graph(points, /, *, method: str = "local", max_passes: int = 50, progress: bool = False) -> MWMEResult:
    """Minimum-weight maximum-entropy (MWME) graph of a point set (thesis ch. 6).

    Among all ways of laying the connected NHDD graph (:func:`nhdd_graph`) on the points,
    find one of least total Euclidean edge length (eq. 6.2). The result always has
    ``n - 1`` distinct degrees and is connected.

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        At least 3 distinct points.
    method : {"local", "greedy", "exact"}, default="local"
        ``"exact"``: dynamic programming over subsets, the optimum, O(2^n n) time and
        memory, up to 20 points. ``"greedy"``: the thesis' multi-start n1graph
        (Algorithm 6.2), corrected so that it always yields the NHDD graph, O(n^3).
        ``"local"``: the greedy result improved by exchanging the points of two
        positions while the cost drops, O(n^3) per pass.
    max_passes : int, default=50
        Passes of the local search.
    progress : bool, default=False
        Progress bar over the greedy's start points.

    Returns
    -------
    MWMEResult

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.random.default_rng(0).random((9, 2))
    >>> exact = mwme_graph(pts, method="exact")
    >>> sorted(set(exact.degrees.tolist())) == list(range(1, 9))
    True
    >>> mwme_graph(pts, method="greedy").cost >= exact.cost
    True
    """
    method = check_choice(method, ("local", "greedy", "exact"), name="method")
    max_passes = check_int(max_passes, name="max_passes", low=1)
    points, dist = _distance_matrix(points)
    n = points.shape[0]
    joining = nhdd_joining(n)
    if method == "exact":
        if n > MAX_EXACT:
            raise InputError(
                f"`method='exact'` solves up to {MAX_EXACT} points (time and memory grow as 2^n n); "
                f"got {n}. Use method='local'."
            )
        order, cost = _k.mwme_exact(dist, joining)
    else:
        key = dist.sum(axis=1)  # invariant tie-breaker: total distance to all points
        parts = run_chunks(
            lambda lo, hi: _k.mwme_greedy_starts(dist, joining, lo, hi, key), n, progress=progress, desc="mwme starts"
        )
        best_cost, best_start = np.inf, -1
        for _, _, (cost, start) in parts:  # same rule as inside the kernel
            if best_start < 0 or _k._better(cost, key[start], best_cost, key[best_start]):
                best_cost, best_start = cost, start
        order, cost = _k.mwme_greedy_order(dist, joining, best_start, key)
        if method == "local":
            order, cost, _ = _k.mwme_local(dist, joining, order, max_passes)
    order = np.asarray(order, dtype=np.int64)
    graph = _positions_graph(points, order, joining)
    degrees = np.diff(graph.indptr).astype(np.int64)
    return MWMEResult(graph=graph, order=order, degrees=degrees, cost=float(cost), method=method)


@dataclass(frozen=True)
class MSTMEResult:
    """A minimum spanning tree of maximum entropy.

    Attributes
    ----------
    graph : scipy.sparse.csr_array
        The tree, Euclidean (unnormalised) edge lengths.
    weight : float
        Total edge weight in the units of the objective (divided by ``scale``).
    entropy : float
        Degree entropy of the tree, in bits.
    cost : float
        ``weight - lam * entropy``, the objective of eq. 7.1.
    lam : float
    scale : float
        The weights were divided by this (1 when ``normalize=False``).
    method : str
    """

    graph: sparse.csr_array
    weight: float
    entropy: float
    cost: float
    lam: float
    scale: float
    method: str


def mstme_graph(points, /, *, lam: float = 0.5, normalize: bool = True, method: str = "greedy", max_passes: int = 20) -> MSTMEResult:
    """Minimum spanning tree of maximum entropy (MSTME, thesis ch. 7, eq. 7.1).

    Minimises ``W(T) - lam * H(T)`` over spanning trees of the complete Euclidean graph,
    where ``W`` is the total edge weight and ``H`` the entropy of the degree distribution
    over all n nodes. ``lam = 0`` gives the Euclidean minimum spanning tree.

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        At least 3 distinct points.
    lam : float >= 0, default=0.5
        Weight of the entropy term.
    normalize : bool, default=True
        Divide the edge weights by the mean edge length of the Euclidean MST, so that
        ``lam`` means the same at every scale. ``False`` uses raw Euclidean lengths.
    method : {"greedy", "exchange"}, default="greedy"
        ``"greedy"``: Algorithm 7.1, O(n^3) with the entropy change tabulated per pair
        of degrees. ``"exchange"``: the greedy tree improved by edge exchanges (drop a
        tree edge, add the best edge across the cut) while the objective drops.
    max_passes : int, default=20
        Passes of the exchange search.

    Returns
    -------
    MSTMEResult

    Examples
    --------
    Thesis fig. 7.1: four points around a centre, raw weights, lambda = 1.

    >>> star = [[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]]
    >>> tree = mstme_graph(star, lam=1.0, normalize=False)
    >>> round(tree.weight, 2), round(tree.entropy, 2), round(tree.cost, 2)
    (4.41, 1.37, 3.04)
    """
    from scipy.sparse.csgraph import minimum_spanning_tree

    lam = check_float(lam, name="lam", low=0.0)
    method = check_choice(method, ("greedy", "exchange"), name="method")
    max_passes = check_int(max_passes, name="max_passes", low=1)
    if not isinstance(normalize, (bool, np.bool_)):
        raise TypeError(f"`normalize` must be True or False; got {normalize!r}.")
    points, dist = _distance_matrix(points)
    n = points.shape[0]
    scale = 1.0
    if normalize:
        scale = float(minimum_spanning_tree(dist).sum()) / (n - 1)
    weight = dist / scale
    if lam == 0.0:
        tree = sparse.coo_array(minimum_spanning_tree(dist))
        edges = np.stack([tree.row, tree.col], axis=1).astype(np.int64)
    else:
        edges = _k.mstme_greedy(weight, lam)
        if method == "exchange":
            edges, _, _ = _k.mstme_exchange(weight, lam, edges, max_passes)
    graph = edges_to_graph(n, edges[:, 0], edges[:, 1], points)
    total = float(weight[edges[:, 0], edges[:, 1]].sum())
    entropy = entropy_of_degrees(np.diff(graph.indptr))
    return MSTMEResult(graph=graph, weight=total, entropy=entropy, cost=total - lam * entropy, lam=lam, scale=scale, method=method)

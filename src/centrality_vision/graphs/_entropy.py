"""Maximum-entropy data-graphs (thesis ch. 6 and 7).

- :func:`nhdd_graph`: the graphs with the most distinct degrees (n - 1 of them), built by
  Algorithm 6.1.
- :func:`mwme_graph`: the minimum-weight labelling of the connected NHDD graph onto a
  point set (the MWME problem, eq. 6.2).
- :func:`mwme_degrees`: the exact MWME degrees of many small sets at once (local signatures).
- :func:`mstme_graph`: the spanning tree minimising weight minus lambda times the entropy
  of its degree distribution (MSTME, eq. 7.1).

Conventions the code relies on: the entropy (eq. 6.1) is in bits over the degrees of all
n nodes, degree 0 included; every solver sees the distances of the points divided by a
power of two (exact), so results do not depend on the scale of the input and no kernel
ever receives a non-finite weight.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.spatial.distance import pdist, squareform

from .._deprecation import renamed_parameters
from .._parallel import run_chunks
from .._validation import (
    ANY_DIMS,
    as_points,
    as_real_array,
    check_bool,
    check_choice,
    check_float,
    check_int,
    is_real_dtype,
)
from .._warnings import warn
from ..exceptions import InputError
from . import _entropy_kernels as _k
from ._pointsets import edges_to_graph

# mstme_graph's largest lam: lam times an entropy of 64 bits (n < 2^64) stays finite
LAM_MAX = 1e300

__all__ = ["nhdd_joining", "nhdd_graph", "MWMEResult", "mwme_graph", "mwme_degrees", "MSTMEResult", "mstme_graph"]

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

    Parameters
    ----------
    n : int >= 2
        Number of nodes.
    connected : bool, default=True
        The connected graph (True) or its complement (False), as in :func:`nhdd_graph`.

    Returns
    -------
    ndarray of bool, shape (n,)
        True at the positions that join all earlier nodes; position 0 is always False.

    Examples
    --------
    >>> nhdd_joining(5).tolist()
    [False, False, True, False, True]
    >>> nhdd_joining(5, connected=False).tolist()
    [False, True, False, True, False]
    """
    n = check_int(n, name="n", low=2)
    connected = check_bool(connected, name="connected")
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
    n : int in [3, 20000]
        (The graph has about ``n**2 / 4`` edges: 20,000 nodes take some 5 GB.)
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
    # (about n^2 / 4 edges: 10^6 nodes asked numpy for 1.8 TiB)
    n = check_int(n, name="n", low=3, high=_NHDD_MAX_NODES)
    joining = nhdd_joining(n, connected=check_bool(connected, name="connected"))
    cols = np.repeat(np.flatnonzero(joining), np.flatnonzero(joining))
    rows = np.concatenate([np.arange(j) for j in np.flatnonzero(joining)]) if joining.any() else np.array([], int)
    return edges_to_graph(n, rows, cols, lengths=1.0)


#: Smallest ratio of the shortest to the longest distance between points that the entropy
#: graphs accept: below it, squared distances underflow even after rescaling.
MIN_DISTANCE_RATIO = 1e-150
# nhdd_graph: the most nodes (about n^2 / 4 edges, stored twice: 20,000 nodes take some 5 GB)
_NHDD_MAX_NODES = 20_000


@dataclass(frozen=True)
class _Distances:
    """Validated points and their distance matrix, computed on an exactly rescaled copy.

    ``unit`` is the power of two (as an exponent, ``2**exponent``) the points were divided
    by so that every coordinate lies in (-1, 1): squaring differences then neither
    overflows (points near 1e300) nor underflows (points near 1e-300), and the kernels
    only ever see finite, positive distances. Lengths in the caller's units come back
    through :meth:`to_units`, which refuses values that do not fit in float64.
    """

    points: np.ndarray
    scaled: np.ndarray  # distances between the rescaled points
    exponent: int

    def to_units(self, values, what: str):
        with np.errstate(over="ignore"):
            out = np.ldexp(np.asarray(values, dtype=np.float64), self.exponent)
        if not np.all(np.isfinite(out)):
            span = float(np.abs(self.points).max())
            raise InputError(
                f"`points` span too large a range for float64: the {what} overflows "
                f"(coordinates up to {span:.3g}); rescale the points."
            )
        return out


def _distance_matrix(points, *, min_points: int = 3) -> _Distances:
    pts = as_points(points, name="points", n_dims=ANY_DIMS, min_points=min_points, allow_duplicates=False)
    exponent = int(np.frexp(np.abs(pts).max())[1])  # |pts| < 2**exponent
    scaled = squareform(pdist(np.ldexp(pts, -exponent)))  # exact rescaling: a power of two
    off = scaled[~np.eye(pts.shape[0], dtype=bool)]
    if not np.all(np.isfinite(off)) or off.min() <= MIN_DISTANCE_RATIO * off.max():
        ratio = _shortest_distance(np.ldexp(pts, -exponent), scaled) / off.max() if off.max() > 0 else 0.0
        raise InputError(
            "`points` must have distances within a dynamic range float64 can square: the shortest "
            f"distance is {ratio:.3g} times the longest (at least {MIN_DISTANCE_RATIO:g} needed); "
            "rescale or deduplicate the points."
        )
    return _Distances(pts, scaled, exponent)


def _shortest_distance(pts: np.ndarray, distances: np.ndarray) -> float:
    """The shortest distance between two points, exact where ``pdist``'s squares underflow
    (points 1e-200 apart came out 0 apart)."""
    masked = distances + np.diag(np.full(pts.shape[0], np.inf))
    i, j = np.unravel_index(int(np.argmin(masked)), masked.shape)
    diff = pts[i] - pts[j]
    peak = float(np.abs(diff).max())
    return peak * float(np.linalg.norm(diff / peak)) if peak > 0 else 0.0


def _former_solver_name(result) -> str:
    warn(
        f"`{type(result).__name__}.method` is renamed `solver`; the old name will be removed.",
        FutureWarning,
    )
    return result.solver


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
    solver : str
        The solver that laid it (formerly ``method``, which still reads it, with a
        FutureWarning).

    Examples
    --------
    >>> import numpy as np
    >>> result = mwme_graph(np.random.default_rng(0).random((6, 2)), solver="exact")
    >>> result.solver, result.graph.shape, sorted(result.degrees.tolist())
    ('exact', (6, 6), [1, 2, 3, 3, 4, 5])
    >>> bool(np.isclose(result.cost, result.graph.sum() / 2))  # each edge is stored twice
    True
    >>> sorted(result.order.tolist())  # a permutation of the points
    [0, 1, 2, 3, 4, 5]
    """

    graph: sparse.csr_array
    order: np.ndarray
    degrees: np.ndarray
    cost: float
    solver: str

    @property
    def method(self) -> str:
        """The former name of :attr:`solver`."""
        return _former_solver_name(self)


def _precomputed(distances) -> _Distances:
    """A user's distance matrix, checked like points are, rescaled by a power of two."""
    if sparse.issparse(distances):
        distances = distances.toarray()
    if np.ma.is_masked(distances):
        raise TypeError(
            "`points` (metric='precomputed') must be a plain array; got a masked array with masked entries "
            "(the mask would be ignored)."
        )
    try:
        arr = np.asarray(distances)
    except (TypeError, ValueError) as exc:
        raise InputError(f"`points` (metric='precomputed') must be a square distance matrix; got {exc}.") from None
    if not is_real_dtype(arr.dtype, bool_ok=False):
        raise TypeError(
            f"`points` (metric='precomputed') must hold real numbers (not booleans); got dtype {arr.dtype}."
        )
    arr = np.array(arr, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.shape[0] < 3:
        raise InputError(
            f"`points` (metric='precomputed') must be a square matrix of at least 3 rows; got shape {arr.shape}."
        )
    off = ~np.eye(arr.shape[0], dtype=bool)
    problem = None
    if not np.all(np.isfinite(arr)):
        row, col = np.argwhere(~np.isfinite(arr))[0]
        problem = f"entry ({row}, {col}) is {arr[row, col]}"
    elif np.any(np.diag(arr) != 0):
        row = int(np.flatnonzero(np.diag(arr) != 0)[0])
        problem = f"diagonal entry ({row}, {row}) is {arr[row, row]:.6g}"
    elif np.any(arr[off] <= 0):
        row, col = np.argwhere(off & (arr <= 0))[0]
        problem = f"off-diagonal entry ({row}, {col}) is {arr[row, col]:.6g} (distinct points have positive distances)"
    elif not np.allclose(arr, arr.T, rtol=1e-12, atol=0):
        row, col = np.argwhere(~np.isclose(arr, arr.T, rtol=1e-12, atol=0))[0]
        problem = f"entries ({row}, {col}) and ({col}, {row}) differ: {arr[row, col]:.17g} and {arr[col, row]:.17g}"
    if problem is not None:
        raise InputError(
            "`points` (metric='precomputed') must be a finite symmetric matrix with a zero diagonal "
            f"and positive distances off it; {problem}."
        )
    exponent = int(np.frexp(arr.max())[1])
    scaled = np.ldexp(arr, -exponent)
    if scaled[off].min() <= MIN_DISTANCE_RATIO * scaled.max():
        raise InputError(
            f"`points` (metric='precomputed'): the shortest distance must be at least "
            f"{MIN_DISTANCE_RATIO:g} times the longest."
        )
    return _Distances(arr, scaled, exponent)


def _edges_graph(dist: _Distances, rows: np.ndarray, cols: np.ndarray) -> sparse.csr_array:
    """The graph of the given edges, lengths in the caller's units."""
    n = dist.scaled.shape[0]
    return edges_to_graph(n, rows, cols, lengths=dist.to_units(dist.scaled[rows, cols], "edge length"))


def _positions_graph(dist: _Distances, order: np.ndarray, joining: np.ndarray) -> sparse.csr_array:
    join_pos = np.flatnonzero(joining)
    rows = order[np.concatenate([np.arange(j) for j in join_pos])]
    cols = order[np.repeat(join_pos, join_pos)]
    lo, hi = np.minimum(rows, cols), np.maximum(rows, cols)
    return _edges_graph(dist, lo, hi)


@renamed_parameters(max_passes="max_iter", method="solver")
def mwme_graph(
    points, /, *, solver: str = "local", max_iter: int = 50, metric: str = "euclidean", progress: bool = False
) -> MWMEResult:
    """Minimum-weight maximum-entropy (MWME) graph of a point set (thesis ch. 6).

    Among all ways of laying the connected NHDD graph (:func:`nhdd_graph`) on the points,
    find one of least total Euclidean edge length (eq. 6.2). The result always has
    ``n - 1`` distinct degrees and is connected.

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        At least 3 distinct points.
    solver : {"local", "greedy", "exact"}, default="local"
        (Formerly ``method``, which still works.) ``"exact"``: dynamic programming over
        subsets, the optimum, O(2^n n) time and memory, up to 20 points. ``"greedy"``: the thesis' multi-start n1graph
        (Algorithm 6.2), corrected so that it always yields the NHDD graph, O(n^3).
        ``"local"``: the greedy result improved by exchanging the points of two
        positions while the cost drops, O(n^3) per pass.
    max_iter : int >= 1, default=50
        Most passes of the local search (each pass tries every exchange; the search stops
        at the first pass that improves nothing). Formerly ``max_passes``, which still
        works with a FutureWarning.
    metric : {"euclidean", "precomputed"}, default="euclidean"
        ``"precomputed"``: ``points`` is a symmetric (n, n) matrix of positive distances
        (zero diagonal), e.g. the worked example of the thesis' Table 6.1, which is not
        Euclidean.
    progress : bool, default=False
        Progress bar over the greedy's start points.

    Returns
    -------
    MWMEResult

    Notes
    -----
    The solvers run on the points divided by a power of two (exact in floating point),
    so that squared distances neither overflow nor underflow at any scale; sets whose
    shortest distance is below ``1e-150`` times their longest, or whose total edge
    length does not fit in float64, raise :class:`~centrality_vision.exceptions.InputError`.

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.random.default_rng(0).random((9, 2))
    >>> exact = mwme_graph(pts, solver="exact")
    >>> sorted(set(exact.degrees.tolist())) == list(range(1, 9))
    True
    >>> mwme_graph(pts, solver="greedy").cost >= exact.cost
    True
    """
    solver = check_choice(solver, ("local", "greedy", "exact"), name="solver")
    progress = check_bool(progress, name="progress")
    max_iter = check_int(max_iter, name="max_iter", low=1)
    metric = check_choice(metric, ("euclidean", "precomputed"), name="metric")
    distances = _precomputed(points) if metric == "precomputed" else _distance_matrix(points)
    dist = distances.scaled
    n = dist.shape[0]
    joining = nhdd_joining(n)
    if solver == "exact":
        if n > MAX_EXACT:
            raise InputError(
                f"`solver='exact'` solves up to {MAX_EXACT} points (time and memory grow as 2^n n); "
                f"got {n}. Use `solver='local'`."
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
        if solver == "local":
            order, cost, _ = _k.mwme_local(dist, joining, order, max_iter)
    order = np.asarray(order, dtype=np.int64)
    graph = _positions_graph(distances, order, joining)
    degrees = np.diff(graph.indptr).astype(np.int64)
    cost = float(distances.to_units(cost, "total edge length"))
    return MWMEResult(graph=graph, order=order, degrees=degrees, cost=cost, solver=solver)


#: How :func:`mstme_graph` can divide the edge weights (see its ``normalize``).
NORMALIZATIONS = ("tree", "edge", "none")


def mwme_degrees(point_sets, /) -> np.ndarray:
    """Degrees in the exact MWME graph of each of many small point sets of one size.

    The batch form of ``mwme_graph(points, solver="exact").degrees`` for local
    neighbourhoods (as used by :func:`centrality_vision.matching.match`): one validation,
    then the subset dynamic programme per set, without building graphs.

    Parameters
    ----------
    point_sets : array_like of shape (n_sets, n_points, n_dims)
        ``3 <= n_points <= 20``; the points of each set finite and distinct.

    Returns
    -------
    ndarray of int, shape (n_sets, n_points)

    Examples
    --------
    >>> import numpy as np
    >>> sets = np.random.default_rng(0).random((4, 7, 2))
    >>> degrees = mwme_degrees(sets)
    >>> bool(np.all(degrees[1] == mwme_graph(sets[1], solver="exact").degrees))
    True
    """
    # None, text, masked entries: TypeError; sets of different sizes: a named InputError
    arr = as_real_array(point_sets, name="point_sets", shape="one array of shape (n_sets, n_points, n_dims)")
    if arr.ndim != 3 or arr.shape[0] < 1 or not 3 <= arr.shape[1] <= MAX_EXACT or arr.shape[2] not in ANY_DIMS:
        raise InputError(
            f"`point_sets` must have shape (n_sets, n_points, n_dims) with n_sets >= 1, "
            f"3 <= n_points <= {MAX_EXACT} and {ANY_DIMS[0]} <= n_dims <= {ANY_DIMS[-1]}; got shape {arr.shape}."
        )
    n_sets, n, dims = arr.shape
    if arr.dtype != bool:
        finite = np.isfinite(arr).all(axis=(1, 2))
        if not finite.all():
            raise InputError(f"`point_sets[{int(np.argmin(finite))}]` must be finite; got NaN or inf.")
    flat = as_points(arr.reshape(-1, dims), name="point_sets", n_dims=ANY_DIMS).reshape(arr.shape)
    joining = nhdd_joining(n)
    # degree of position k: the joining positions after it, plus all earlier ones if it joins
    later = np.cumsum(joining[::-1])[::-1] - joining
    position_degree = later + np.where(joining, np.arange(n), 0)
    out = np.empty((n_sets, n), dtype=np.int64)
    for b in range(n_sets):
        try:
            dist = _distance_matrix(flat[b]).scaled
        except InputError as exc:  # (its message names `points`: here, one of the sets)
            raise InputError(str(exc).replace("`points`", f"`point_sets[{b}]`", 1)) from None
        order, _ = _k.mwme_exact(dist, joining)
        out[b, order] = position_degree
    return out


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
        The weights were divided by this (1 for ``normalize="none"``).
    solver : str
        Formerly ``method``, which still reads it, with a FutureWarning.
    normalize : str
        ``"tree"``, ``"edge"`` or ``"none"``.
    mst_share : float
        Share of the tree's edges that are not edges of the Euclidean MST (0 when the
        entropy term changed nothing).

    Examples
    --------
    Four points around a centre: the MST is the star (total length 4, the ``scale`` of
    ``normalize="tree"``); the entropy term trades one of its edges for a longer one.

    >>> star = [[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]]
    >>> mst = mstme_graph(star, lam=0.0)
    >>> mst.scale, mst.weight, round(mst.entropy, 3), mst.mst_share
    (4.0, 1.0, 0.722, 0.0)
    >>> tree = mstme_graph(star, lam=1.0)
    >>> round(tree.weight, 3), round(tree.entropy, 3), round(tree.cost, 3), tree.mst_share
    (1.104, 1.371, -0.267, 0.25)
    >>> tree.graph.nnz // 2  # edges of a spanning tree on 5 points
    4
    """

    graph: sparse.csr_array
    weight: float
    entropy: float
    cost: float
    lam: float
    scale: float
    solver: str
    normalize: str = "tree"
    mst_share: float = 0.0

    @property
    def method(self) -> str:
        """The former name of :attr:`solver`."""
        return _former_solver_name(self)


def _normalization(normalize) -> str:
    if isinstance(normalize, (bool, np.bool_)):
        return "tree" if normalize else "none"
    if not isinstance(normalize, str):
        raise TypeError(f"`normalize` must be one of {NORMALIZATIONS} or a bool; got {normalize!r}.")
    return check_choice(normalize, NORMALIZATIONS, name="normalize")


def _edge_keys(n: int, edges: np.ndarray) -> np.ndarray:
    return np.sort(np.minimum(edges[:, 0], edges[:, 1]) * n + np.maximum(edges[:, 0], edges[:, 1]))


@renamed_parameters(max_passes="max_iter", method="solver")
def mstme_graph(
    points, /, *, lam: float = 1.0, normalize="tree", solver: str = "greedy", max_iter: int = 20
) -> MSTMEResult:
    """Minimum spanning tree of maximum entropy (MSTME, thesis ch. 7, eq. 7.1).

    Minimises ``W(T) - lam * H(T)`` over spanning trees of the complete Euclidean graph,
    where ``W`` is the total edge weight and ``H`` the entropy (bits) of the degree
    distribution over all n nodes. ``lam = 0`` gives the Euclidean minimum spanning tree.

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        At least 3 distinct points.
    lam : float in [0, 1e300], default=1.0
        Weight of the entropy term, in the units set by ``normalize`` (at most 1e300, so
        that ``lam`` times an entropy of up to 64 bits stays a float64).
    normalize : {"tree", "edge", "none"} or bool, default="tree"
        What the Euclidean edge lengths are divided by. ``"tree"`` (or True): the total
        length of the Euclidean MST, so the MST weighs 1 and ``lam`` is the share of the
        MST's length one bit of degree entropy is worth: ``lam = 1`` accepts a tree 10%
        longer than the MST for 0.1 bit more entropy. Both terms are then of the same
        order (a tree's entropy is at most ``log2 n`` bits), and the entropy term changes
        about a quarter of the edges of ordinary outlines (26% of the CPD fish at
        ``lam = 1``). ``"edge"``: the mean MST edge length (the MST weighs ``n - 1``):
        one entropy bit is then worth a single edge and the MSTME is the MST on almost
        every point set (0 of the fish's 90 edges change at ``lam = 0.5``).
        ``"none"`` (or False): raw Euclidean lengths (thesis fig. 7.1), scale dependent.
    solver : {"greedy", "exchange"}, default="greedy"
        (Formerly ``method``, which still works.) ``"greedy"``: Algorithm 7.1, O(n^3)
        with the entropy change tabulated per pair of degrees. ``"exchange"``: the greedy
        tree improved by edge exchanges (drop a tree edge, add the best edge across the
        cut) while the objective drops. Equally good edges (to 1e-12 relative) go to the
        pair of smaller total distance to all points, so that the tree does not depend on
        the row order unless that ties too (on small integer grids, 3 of 991 sets gave
        another cost when permuted; 235 when the first edge in row order won).
    max_iter : int >= 1, default=20
        Most passes of the exchange search (it stops at the first pass that improves
        nothing). Formerly ``max_passes``, which still works with a FutureWarning.

    Returns
    -------
    MSTMEResult

    Notes
    -----
    Distances are computed on the points divided by a power of two (exact), so that
    they neither overflow nor underflow at any scale; sets whose shortest distance is
    below ``1e-150`` times their longest raise
    :class:`~centrality_vision.exceptions.InputError`, as does ``normalize="none"`` when
    the raw lengths do not fit in float64.

    Examples
    --------
    Thesis fig. 7.1: four points around a centre, raw weights, lambda = 1.

    >>> star = [[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]]
    >>> tree = mstme_graph(star, lam=1.0, normalize="none")
    >>> round(tree.weight, 2), round(tree.entropy, 2), round(tree.cost, 2)
    (4.41, 1.37, 3.04)
    >>> tree.mst_share  # one of the four edges is not an MST edge
    0.25
    """
    from scipy.sparse.csgraph import minimum_spanning_tree

    lam = check_float(lam, name="lam", low=0.0, high=LAM_MAX)
    solver = check_choice(solver, ("greedy", "exchange"), name="solver")
    max_iter = check_int(max_iter, name="max_iter", low=1)
    normalize = _normalization(normalize)
    distances = _distance_matrix(points)
    dist = distances.scaled
    n = dist.shape[0]
    # A sparse input: scipy turns a dense one into a graph with numpy.ma.masked_values, which
    # drops every distance within 1e-8 of zero (points 1e-8 apart lost their edges).
    mst = sparse.coo_array(minimum_spanning_tree(sparse.csr_array(dist)))
    mst_edges = np.stack([mst.row, mst.col], axis=1).astype(np.int64)
    scaled_scale = {"tree": float(mst.data.sum()), "edge": float(mst.data.sum()) / (n - 1), "none": 1.0}[normalize]
    if normalize == "none":
        weight = distances.to_units(dist, "edge length")
        scale = 1.0
    else:
        weight = dist / scaled_scale
        scale = float(distances.to_units(scaled_scale, "normalising length"))
    if lam == 0.0:
        edges = mst_edges
    else:
        key = weight.sum(axis=1)  # invariant tie-breaker: total distance to all points
        edges = _k.mstme_greedy(weight, lam, key)
        if solver == "exchange":
            edges, _, _ = _k.mstme_exchange(weight, lam, edges, max_iter, key)
    graph = _edges_graph(distances, edges[:, 0], edges[:, 1])
    total = float(weight[edges[:, 0], edges[:, 1]].sum())
    if not np.isfinite(total):
        distances.to_units(np.inf, "total edge length")  # raises
    entropy = entropy_of_degrees(np.diff(graph.indptr))
    share = float(np.mean(~np.isin(_edge_keys(n, edges), _edge_keys(n, mst_edges))))
    return MSTMEResult(
        graph=graph,
        weight=total,
        entropy=entropy,
        cost=total - lam * entropy,
        lam=lam,
        scale=scale,
        solver=solver,
        normalize=normalize,
        mst_share=share,
    )

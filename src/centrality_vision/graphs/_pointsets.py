"""Data-graphs of point sets: Delaunay, Gabriel, EMST, k-NN and complete graphs."""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse
from scipy.spatial import Delaunay, QhullError, cKDTree
from scipy.spatial.distance import pdist, squareform

from .._deprecation import renamed_parameters
from .._validation import ANY_DIMS, as_points, check_int
from ..exceptions import InputError
from ._predicates import delaunay_violations

__all__ = ["delaunay_graph", "gabriel_graph", "emst_graph", "knn_graph", "complete_graph", "edges_to_graph"]


def edges_to_graph(n_nodes: int, rows, cols, points=None, *, lengths=None) -> sparse.csr_array:
    """Symmetric CSR adjacency from undirected edges ``rows[e] -- cols[e]``.

    Edge values are ``lengths`` if given (``lengths[e]`` is edge ``e``'s, or one value for
    all), else the Euclidean distances between ``points``. Self-loops are dropped; a
    repeated edge is kept once, with the length of its first occurrence (not summed).

    Examples
    --------
    >>> edges_to_graph(3, [1, 0], [2, 1], lengths=[5.0, 7.0]).toarray()
    array([[0., 7., 0.],
           [7., 0., 5.],
           [0., 5., 0.]])
    """
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    lo, hi = np.minimum(rows, cols), np.maximum(rows, cols)
    keep = lo != hi
    # (sorted by key; `first` maps each kept edge back to its first occurrence in the input)
    key, first = np.unique(lo[keep] * n_nodes + hi[keep], return_index=True)
    lo, hi = key // n_nodes, key % n_nodes
    if lengths is None:
        lengths = _lengths(points, lo, hi)
    else:
        lengths = np.broadcast_to(np.asarray(lengths, dtype=np.float64), rows.shape)[keep][first]
    graph = sparse.csr_array(
        (np.concatenate([lengths, lengths]), (np.concatenate([lo, hi]), np.concatenate([hi, lo]))),
        shape=(n_nodes, n_nodes),
        dtype=np.float64,
    )
    graph.sort_indices()
    graph.indices = graph.indices.astype(np.int32, copy=False)
    graph.indptr = graph.indptr.astype(np.int32, copy=False)
    return graph


def _unit_scale(points: np.ndarray) -> tuple[np.ndarray, float]:
    """``points / scale`` with ``scale`` a power of two within a factor two of the largest
    absolute coordinate (1 for all-zero input).

    Squared distances of raw coordinates overflow near 1e155 and underflow near 1e-155;
    the graphs here are invariant to scale, so they are built from the scaled points and
    their lengths are scaled back. A power of two divides exactly, so every difference of
    scaled points is the caller's difference, correctly rounded. (Dividing by the largest
    coordinate itself, as before, rounded each point first: a set at offset 1e8 lost about
    8 digits, and equal distances came out 1e-8 apart.)
    """
    peak = float(np.max(np.abs(points), initial=0.0))
    scale = 1.0 if peak == 0.0 else float(np.ldexp(1.0, int(np.frexp(peak)[1]) - 1))
    return points / scale, scale


def _centred(unit: np.ndarray) -> np.ndarray:
    """Scaled points moved to their bounding box's middle, for Qhull.

    Qhull's in-circle tests lose the digits a set's offset from the origin takes: at offset
    1e6 its triangulation of well-separated points was not Delaunay. Where the offset
    dominates, each coordinate is within a factor two of the centre, so the subtraction is
    exact."""
    return unit - (unit.min(axis=0) / 2 + unit.max(axis=0) / 2)


_TINY = 1e-140  # distances (of unit-scaled points) below which squared ones may lose digits


def _robust_norms(diff: np.ndarray) -> np.ndarray:
    """Row norms of ``diff`` without underflow: each row divided by its largest entry first."""
    top = np.max(np.abs(diff), axis=1)
    safe = np.where(top > 0, top, 1.0)
    return top * np.linalg.norm(diff / safe[:, None], axis=1)


def _scaled_lengths(unit_lengths: np.ndarray, scale: float) -> np.ndarray:
    """Lengths in the caller's units; refuses a pair of distinct points whose distance is 0 or inf there."""
    with np.errstate(over="ignore"):
        lengths = unit_lengths * scale
    bad = ~(np.isfinite(lengths) & (lengths > 0))
    if bad.any():
        raise InputError(
            "`points` must have every distance between two of them representable in float64 "
            f"(from about 5e-324 to 1.8e308); got {int(bad.sum())} edge(s) of length "
            f"{'0 (distinct points closer than that)' if np.any(lengths[bad] == 0) else 'inf'}. "
            "Rescale or merge near-duplicate points."
        )
    return lengths


def _lengths(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Euclidean lengths of the edges ``lo[e] -- hi[e]`` without overflow or underflow.

    The points are divided by their largest coordinate and each difference by its largest
    entry before squaring, so no squared distance leaves the float64 range; a length that
    does not fit in float64 in the caller's units is refused (:func:`_scaled_lengths`).
    """
    unit, scale = _unit_scale(points)
    return _scaled_lengths(_robust_norms(unit[lo] - unit[hi]), scale)


def _triangulable_points(points, *, flat: bool = False) -> np.ndarray:
    """Validated float64 points for a Delaunay-based graph: 2D or 3D, D+1 or more, distinct;
    with ``flat`` (graphs that take points on a line or a plane), 2 or more."""
    points = as_points(points, name="points", n_dims=(2, 3), min_points=2 if flat else 3, allow_duplicates=False)
    if not flat and points.shape[0] < points.shape[1] + 1:
        raise InputError(
            f"`points` must have at least {points.shape[1] + 1} points in {points.shape[1]}D; got {points.shape[0]}."
        )
    return points


def _mean_centred(points: np.ndarray) -> np.ndarray:
    """The points less their mean, which lies in their affine span (the bounding box's
    middle need not: for points on a plane in 3D it may lie off the plane). The bounding
    box's middle is taken off first, exactly (see :func:`_centred`): the mean alone, at a
    large offset, rounds away the digits that hold the set, and a line at 1e8 had a second
    dimension of 1e-8 of its extent."""
    centred = _centred(points)
    return centred - centred.mean(axis=0)


def _spread(points: np.ndarray, centred: np.ndarray | None = None) -> np.ndarray:
    """Singular values of the centred points over their largest centred coordinate, largest
    first: the extent along each principal axis, relative to the whole. ``centred``: the
    points' :func:`_mean_centred`, where the caller has it."""
    centred = _mean_centred(points) if centred is None else centred
    return np.linalg.svd(centred / np.abs(centred).max(), compute_uv=False)


def _affine_rank(points: np.ndarray) -> int:
    """The dimension the points span: their principal extents above 1e-12 of the whole and
    above what the rounding of the coordinates themselves can give (16 ulps of the largest
    coordinate, times the square root of the point count), and at least 1 for points not
    all equal. A plane 1e4 from the origin, turned, is 6e-12 of its extent thick from
    rounding alone: taken as 3D, its Delaunay triangulation passed or failed Qhull's
    empty-sphere test by chance."""
    peak = float(np.max(np.abs(points), initial=0.0))
    centred = _mean_centred(points)
    extent = float(np.max(np.abs(centred), initial=0.0))
    if extent == 0.0:
        return 0
    rounding = 16.0 * np.finfo(np.float64).eps * peak * math.sqrt(points.shape[0]) / extent
    # (distinct points a few ulps apart are within rounding of each other: a line, as before)
    return max(int(np.count_nonzero(_spread(points, centred) > max(1e-12, rounding))), 1)


def _triangulation(points: np.ndarray, rank: int, name: str = "points") -> Delaunay:
    """Qhull's Delaunay triangulation of ``points`` (centred), whose uncentred set spans
    ``rank`` dimensions (see :func:`_affine_rank`)."""
    n, dim = points.shape
    if rank < dim:
        what = "collinear" if rank <= 1 else "coplanar"
        # (to within 1e-12 of the extent: ten points in the unit square beside one at 1e300 are)
        raise InputError(
            f"`{name}` must span {dim} dimensions for a Delaunay triangulation; got {n} {what} points (to within "
            "1e-12 of their extent, or the rounding of their coordinates)."
        )
    try:
        tri = Delaunay(points)
    except QhullError as exc:  # numerically degenerate input
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"`{name}` could not be triangulated (degenerate input): {first}") from None
    if getattr(tri, "coplanar", np.empty((0, 3))).shape[0]:
        missing = np.unique(tri.coplanar[:, 0]).tolist()
        raise InputError(
            f"`{name}` has {len(missing)} point(s) left out of the Delaunay triangulation as numerically "
            f"coincident with others (e.g. index {missing[0]}); remove near-duplicates first."
        )
    return tri


def _delaunay_edges(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    unit = _unit_scale(points)[0]
    tri = _triangulation(_centred(unit), _affine_rank(unit))
    # Qhull's floating-point in-circle tests can return a triangulation that is not Delaunay
    # for a tight cluster beside distant points (about 1e-7 of the extent): every facet checked
    failed = delaunay_violations(unit, tri.simplices, tri.neighbors)
    if failed:
        singular = _spread(unit)
        flat = "a line" if points.shape[1] == 2 else "a plane"
        cause = (
            f"happens when the points lie nearly on {flat} (here within {singular[-1] / singular[0]:.1g} of their "
            f"extent; within 1e-12 they count as on it). Project them onto {flat}, or add the missing dimension's "
            "spread."
            if singular[-1] < 1e-6 * singular[0]
            else "happens when some points are very close together relative to the set's extent (about "
            "1e-7 of it). Merge near-duplicate points, or build the graph of each part separately."
        )
        raise InputError(
            f"`points` could not be triangulated reliably: Qhull's Delaunay triangulation fails the "
            f"empty-{'circle' if points.shape[1] == 2 else 'sphere'} test at {failed} facet(s), which {cause}"
        )
    indptr, indices = tri.vertex_neighbor_vertices
    rows = np.repeat(np.arange(points.shape[0]), np.diff(indptr))
    upper = rows < indices
    return rows[upper], indices[upper].astype(np.int64)


def delaunay_graph(points, /) -> sparse.csr_array:
    """Delaunay triangulation of a 2D or 3D point set, as a graph.

    Parameters
    ----------
    points : array_like of shape (n_points, 2) or (n_points, 3)
        At least ``n_dims + 1`` distinct points that are not all collinear (2D) or
        coplanar (3D), to within 1e-12 of their extent or the rounding of their
        coordinates (a turned plane 1e4 from the origin is a plane). Row ``i`` is node ``i``.

    Returns
    -------
    graph : scipy.sparse.csr_array of shape (n_points, n_points)
        Symmetric; stored values are Euclidean edge lengths.

    Notes
    -----
    Computed with Qhull through :class:`scipy.spatial.Delaunay`. For co-circular
    (co-spherical) points the triangulation is not unique and Qhull picks one. Qhull's
    floating-point tests can fail on points very close together relative to the set's
    extent (a cluster about 1e-7 of it): every facet of its triangulation is checked with
    in-sphere tests of certain sign (``graphs._predicates``), and a triangulation that is
    not Delaunay is refused with an :class:`~centrality_vision.exceptions.InputError`
    instead of being returned (so are :func:`gabriel_graph` and :func:`emst_graph`).
    Points co-circular, or a triangle flat, to within the data's precision (16 units in the
    last place of the coordinates, as on a rotated grid) pass either way.

    Examples
    --------
    >>> graph = delaunay_graph([[0, 0], [1, 0], [0, 1], [1, 1.1]])
    >>> graph.nnz // 2  # four sides and one diagonal
    5
    """
    points = _triangulable_points(points)
    rows, cols = _delaunay_edges(points)
    return edges_to_graph(points.shape[0], rows, cols, points)


def _gabriel_mask(points: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """True for the edges whose closed diametral ball holds no other point."""
    points, _ = _unit_scale(points)
    k = min(5, points.shape[0])
    _, idx = cKDTree(points).query(0.5 * (points[rows] + points[cols]), k=k)
    # The nearest points to a midpoint include at least one point other than the edge's two
    # end points, and the nearest such point decides. Point r lies at squared distance
    # (p - r).(q - r) + radius^2 from the midpoint of p and q: from differences, which keep
    # their digits where the midpoint itself would round away those of a tight cluster.
    # A point counts as on the circle (so the edge goes) within the data's own precision:
    # every coordinate moved by 16 units in the last place of the largest of the three
    # points' magnitudes (the co-circular points of a rotated grid), plus the rounding of the
    # differences. A tolerance of 1e-12 of the squared radius also took a point 1e-14 outside,
    # beside an end point, as on it: both edges to a tight pair went, and the graph split.
    other = (idx != rows[:, None]) & (idx != cols[:, None])
    to_p = points[rows][:, None, :] - points[idx]
    to_q = points[cols][:, None, :] - points[idx]
    d_p, d_q = np.sqrt(np.sum(to_p * to_p, axis=2)), np.sqrt(np.sum(to_q * to_q, axis=2))
    size = np.abs(points).max(axis=1)
    magnitude = np.maximum(np.maximum(size[rows], size[cols])[:, None], size[idx])
    tol = 16 * np.finfo(float).eps * (d_p * d_q + magnitude * (d_p + d_q))
    margin = np.where(other, np.sum(to_p * to_q, axis=2) - tol, np.inf).min(axis=1)
    return margin > 0


def gabriel_graph(points, /) -> sparse.csr_array:
    """Gabriel graph: the Delaunay edges whose closed diametral circle (sphere) is empty.

    Edge ``(i, j)`` is kept when no other point lies inside or on the circle that has
    the segment ``i-j`` as a diameter ("on" to within the coordinates' precision, 16 units
    in their last place, so that the co-circular points of a rotated grid count as on it
    whatever their rounding). With this
    closed-ball rule the result does not depend on how Qhull triangulates co-circular
    points, and it is a subgraph of every Delaunay triangulation and a supergraph of every
    Euclidean minimum spanning tree.

    The precision is that of the coordinates as given, so it follows their magnitude, not
    the set's extent: a unit-size set at an offset of 1e12 (where float64 keeps about four
    decimals) treats a point within about 4e-3 of an edge's circle as on it, and drops
    that edge (8 of 67 edges of 40 random points; at an offset of 1e6, points within
    4e-9). Subtract the offset first when the coordinates are exact at that size.

    Parameters
    ----------
    points : array_like of shape (n_points, 2) or (n_points, 3)
        At least 2 distinct points. As for :func:`delaunay_graph`, except that points on
        a line, or in 3D on a plane (to within 1e-12 of their extent or the rounding of
        their coordinates), are accepted (so 2 points, and 3 in 3D): for points exactly on
        a line the graph is the path along it; within the plane, the Gabriel graph there.

    Returns
    -------
    graph : scipy.sparse.csr_array of shape (n_points, n_points)
        Symmetric; stored values are Euclidean edge lengths.

    References
    ----------
    .. [1] K. R. Gabriel and R. R. Sokal, "A new statistical approach to geographic
       variation analysis", Systematic Zoology 18(3), 259-278, 1969.

    Examples
    --------
    >>> gabriel_graph([[0, 0], [2, 0], [1, 0.2]]).nnz // 2  # Delaunay has 3 edges
    2
    """
    points = _triangulable_points(points, flat=True)
    rows, cols = _gabriel_candidates(points)
    keep = _gabriel_mask(points, rows, cols)
    # Within the data's precision a point beside an end point can sit "on" the circles of
    # both edges to a tight pair, and both went (the graph split). The EMST's edges are
    # Gabriel edges in exact arithmetic: they stay.
    tree = _spanning_tree(edges_to_graph(points.shape[0], rows, cols, points))
    in_tree = sparse.csr_array(tree + tree.T)[rows, cols] != 0
    keep = keep | np.asarray(in_tree).ravel()
    return edges_to_graph(points.shape[0], rows[keep], cols[keep], points)


def _spanning_tree(graph: sparse.csr_array) -> sparse.coo_array:
    """The minimum spanning tree of ``graph`` (one triangle of it)."""
    from scipy.sparse.csgraph import minimum_spanning_tree

    return sparse.coo_array(minimum_spanning_tree(graph))


def _gabriel_candidates(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edges that include every Gabriel edge (so every Euclidean MST): the Delaunay edges, or
    for points on a line the path through them in order along it, and for 3D points on a
    plane the Delaunay edges of their coordinates in that plane."""
    unit = _unit_scale(points)[0]
    rank = _affine_rank(unit)
    if rank == points.shape[1]:
        return _delaunay_edges(points)
    # (about the mean: the projection onto the principal axes of points centred off their
    # plane distorted their distances by up to 6%)
    centred = _mean_centred(unit)
    basis = np.linalg.svd(centred, full_matrices=False)[2][:rank]
    along = centred @ basis.T
    if rank == 1:
        return _line_candidates(unit, basis[0])
    return _delaunay_edges(along)


_MAX_LINE_CANDIDATES = 20_000_000


def _line_candidates(unit: np.ndarray, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs that include every Gabriel edge of points within 1e-12 of a line.

    With ``t`` the position along the line and ``h`` the offset across it, a point ``r``
    between ``p`` and ``q`` along the line lies inside their diametral ball when
    ``(t_r - t_p) (t_q - t_r) > (h_r - h_p) . (h_q - h_r)``, which holds once the left side
    exceeds the square of twice the largest offset. Sorted along the line, ``p`` pairs with
    the following points until one between them is inside; the point nearest the middle
    decides (the left side is concave in ``t_r``). Exactly collinear points pair with
    their successor only; a cluster whose offsets are not small against its spacing along
    the line (below the coordinates' precision, say) pairs within itself, where the path in
    order along the line was wrong. ``t`` and ``h`` carry rounding of the order of
    ``eps`` (``unit``'s coordinates are at most 1): both bounds allow for it.
    """
    eps = np.finfo(float).eps
    t = unit @ direction
    across = unit - t[:, None] * direction
    spread = 2.0 * float(np.linalg.norm(across, axis=1).max()) + 16 * eps
    slack = 16 * eps
    order = np.argsort(t, kind="stable")
    ts = t[order]
    n = ts.size
    firsts, seconds = [np.arange(n - 1)], [np.arange(1, n)]
    active = np.arange(n - 2)  # p whose pair with the point `gap` later is still possible
    gap = 2
    count = n - 1
    while active.size:
        last = active + gap
        middle = np.clip(np.searchsorted(ts, 0.5 * (ts[active] + ts[last])), active + 1, last - 1)
        inside = np.zeros(active.size, dtype=bool)
        for r in (np.maximum(middle - 1, active + 1), middle):
            before, after = ts[r] - ts[active] - slack, ts[last] - ts[r] - slack
            inside |= (before > 0) & (after > 0) & (before * after > spread * spread)
        active = active[~inside]
        firsts.append(active)
        seconds.append(active + gap)
        count += active.size
        if count > _MAX_LINE_CANDIDATES:
            raise InputError(
                "`points` lie on a line to within 1e-12 of their extent, but too many of them are closer "
                "together along it than their offsets across it (a cluster below the coordinates' precision?); "
                "build the graph of the cluster separately, or remove near-duplicate points."
            )
        gap += 1
        active = active[active + gap < n]
    first, second = order[np.concatenate(firsts)], order[np.concatenate(seconds)]
    return np.minimum(first, second), np.maximum(first, second)


def emst_graph(points, /) -> sparse.csr_array:
    """Euclidean minimum spanning tree of a 2D or 3D point set.

    Computed as the minimum spanning tree of the Delaunay graph, which contains every
    Euclidean MST (for points within 1e-12 of a line, of the pairs along it that can be
    Gabriel edges; on a plane, of the plane's Delaunay graph). When several
    spanning trees share the minimum weight (equal distances) one of them is returned.

    Parameters
    ----------
    points : array_like of shape (n_points, 2) or (n_points, 3)
        At least 2 distinct points. As for :func:`delaunay_graph`, except that points on
        a line, or in 3D on a plane (to within 1e-12 of their extent or the rounding of
        their coordinates), are accepted (so 2 points, and 3 in 3D): for points exactly on
        a line the tree is the path along it (a cluster across the line below the
        coordinates' precision is joined by its own tree); on a plane, the tree within it.

    Returns
    -------
    graph : scipy.sparse.csr_array of shape (n_points, n_points)
        Symmetric tree with ``n_points - 1`` edges; values are Euclidean lengths.

    Examples
    --------
    >>> tree = emst_graph([[0, 0], [1, 0], [0, 2], [3, 3]])
    >>> tree.nnz // 2, round(float(tree.sum()) / 2, 3)  # 1 + 2 + sqrt(10)
    (3, 6.162)
    """
    points = _triangulable_points(points, flat=True)
    rows, cols = _gabriel_candidates(points)
    tree = _spanning_tree(edges_to_graph(points.shape[0], rows, cols, points))
    return edges_to_graph(points.shape[0], tree.row, tree.col, lengths=tree.data)


@renamed_parameters(k="n_neighbors")
def knn_graph(points, /, *, n_neighbors: int) -> sparse.csr_array:
    """Symmetric k-nearest-neighbour graph.

    Joins every point to its ``n_neighbors`` nearest other points; an edge is kept when
    either end chooses it (union), so every node has degree at least ``n_neighbors``.

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        Distinct points, any dimension.
    n_neighbors : int in [1, n_points - 1]
        Number of neighbours per point (formerly ``k``). Ties in distance are broken by
        the k-d tree.

    Returns
    -------
    graph : scipy.sparse.csr_array of shape (n_points, n_points)
        Symmetric; stored values are Euclidean edge lengths.

    Examples
    --------
    >>> graph = knn_graph([[0, 0], [1, 0], [3, 0], [7, 0]], n_neighbors=1)
    >>> sorted(map(tuple, np.argwhere(graph.toarray() > 0).tolist()))[:3]
    [(0, 1), (1, 0), (1, 2)]
    """
    points = as_points(points, name="points", n_dims=ANY_DIMS, min_points=2, allow_duplicates=False)
    n = points.shape[0]
    k = check_int(n_neighbors, name="n_neighbors", low=1, high=n - 1)
    unit, _ = _unit_scale(points)
    tree = cKDTree(unit)
    distances, idx = tree.query(unit, k=k + 1)
    # The tree compares squared distances, which underflow for points closer than about
    # 1e-154 of the extent: there it may pick wrong neighbours (or not the point itself
    # first). Where the k-th neighbour is that close, choose again among the points within
    # 1e-140 (a radius whose square does not underflow) by their exact distances.
    for i in np.flatnonzero(distances[:, -1] < _TINY):
        near = np.asarray(tree.query_ball_point(unit[i], _TINY), dtype=np.int64)
        lengths = _robust_norms(unit[near] - unit[i])
        idx[i] = near[np.lexsort((near, lengths))[: k + 1]]
    rows = np.repeat(np.arange(n), k + 1)
    cols = idx.ravel()
    return edges_to_graph(n, rows, cols, points)


def complete_graph(points, /) -> sparse.csr_array:
    """Complete graph of a point set, every pair joined by its Euclidean distance.

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        Distinct points, any dimension (memory grows as ``n_points ** 2``).

    Returns
    -------
    graph : scipy.sparse.csr_array of shape (n_points, n_points)

    Examples
    --------
    >>> complete_graph([[0, 0], [3, 0], [0, 4]]).toarray()
    array([[0., 3., 4.],
           [3., 0., 5.],
           [4., 5., 0.]])
    """
    points = as_points(points, name="points", n_dims=ANY_DIMS, min_points=2, allow_duplicates=False)
    unit, scale = _unit_scale(points)
    unit_lengths = pdist(unit)
    close = np.flatnonzero(unit_lengths < _TINY)  # squared differences may have underflowed
    if close.size:
        lo, hi = np.triu_indices(points.shape[0], k=1)
        unit_lengths[close] = _robust_norms(unit[lo[close]] - unit[hi[close]])
    graph = sparse.csr_array(squareform(_scaled_lengths(unit_lengths, scale)))
    graph.sort_indices()
    graph.indices = graph.indices.astype(np.int32, copy=False)
    graph.indptr = graph.indptr.astype(np.int32, copy=False)
    return graph

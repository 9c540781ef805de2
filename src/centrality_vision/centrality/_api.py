"""Public centrality functions (thesis 2.3).

Conventions shared by every function here:

- ``graph`` is a scipy sparse adjacency (any format), a dense array, or a networkx or
  igraph graph. Stored values are edge *lengths*: a dense array's zeros are non-edges,
  a sparse matrix's explicitly stored zeros are edges of length 0 (as in
  :mod:`scipy.sparse.csgraph`), a networkx/igraph edge's ``"weight"`` attribute is its
  length (1 where missing). The diagonal is ignored.
- ``weights`` has one meaning everywhere: ``weights=True`` measures shortest paths by
  the stored lengths, ``weights=False`` (the default, as in the thesis) counts hops. It
  exists on the path centralities only. Degree, eigenvector, PageRank and Katz use the
  stored values as connection *strengths* with ``strengths=True`` (their old
  ``weights=True`` still works, with a :class:`FutureWarning`).
- Directed graphs (an asymmetric matrix, a ``networkx.DiGraph``, a directed igraph
  graph) are accepted by the path centralities, PageRank and Katz, with networkx's
  conventions: closeness and harmonic use distances *to* the node, eccentricity distances
  *from* it, betweenness sums over ordered pairs.
- Disconnected graphs: a node only reaches the nodes of its own component. Distances
  to the other nodes are infinite, so their ``1/d`` terms are 0 and they lie on no
  shortest path; each function states what else it does about it.
- The result is a float64 array of shape ``(n_nodes,)`` in node order (the rows of a
  matrix, ``list(G.nodes)`` of a networkx graph, the vertex ids of an igraph graph), or
  with ``as_dict=True`` a dict ``{node: value}`` keyed by the node labels.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Hashable

import numpy as np
from scipy import sparse

from .._deprecation import renamed_parameters
from .._parallel import run_chunks
from .._validation import GraphInput, as_any_graph, check_bool, check_choice, check_float
from .._warnings import warn
from ..exceptions import InputError
from . import _kernels

__all__ = [
    "CENTRALITIES",
    "PATH_CENTRALITIES",
    "degree",
    "betweenness",
    "edge_betweenness",
    "closeness",
    "harmonic",
    "eccentricity",
    "compute",
    "degree_entropy",
]

#: The centralities built on shortest paths: the ones ``weights=True`` (paths by edge
#: length) changes.
PATH_CENTRALITIES = ("betweenness", "closeness", "harmonic", "eccentricity")

CENTRALITIES = (
    "degree",
    "betweenness",
    "closeness",
    "harmonic",
    "eigenvector",
    "eccentricity",
    "pagerank",
    "katz",
)


# --- shared helpers --------------------------------------------------------------------


class _Prepared:
    """A validated graph as the compiled kernels take it (CSR parts, optionally renumbered)."""

    def __init__(self, graph_input: GraphInput, *, reorder: bool, lengths: bool = True):
        adjacency = graph_input.adjacency
        self.labels = graph_input.labels
        self.directed = graph_input.directed
        self.n = adjacency.shape[0]
        self.perm = None
        if reorder and self.n > 256:
            # Reverse Cuthill-McKee puts neighbours close in memory (1.7x faster Brandes on
            # a randomly numbered Delaunay graph); row i is node perm[i] of the input.
            from scipy.sparse.csgraph import reverse_cuthill_mckee

            pattern = adjacency if not self.directed else (adjacency + adjacency.T).tocsr()
            self.perm = reverse_cuthill_mckee(sparse.csr_matrix(pattern), symmetric_mode=True).astype(np.int64)
            adjacency = adjacency[self.perm][:, self.perm]
            adjacency.sort_indices()
        self.adjacency = adjacency
        self.indptr = adjacency.indptr.astype(np.int64, copy=False)
        self.indices = adjacency.indices.astype(np.int32, copy=False)
        if lengths:
            self.data, self.length_scale = _searchable_lengths(adjacency.data.astype(np.float64, copy=False))
        else:  # hop counts: unit lengths (the stored ones may span more than float64's range)
            self.data, self.length_scale = np.ones(adjacency.data.size), 1.0
        self._classes = False

    def transposed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """CSR parts of the reversed graph (the same arrays when undirected)."""
        if not self.directed:
            return self.indptr, self.indices, self.data
        t = sparse.csr_array(self.adjacency.T)
        t.sort_indices()
        return t.indptr.astype(np.int64), t.indices.astype(np.int32), t.data.astype(np.float64) / self.length_scale

    def classes(self, data=None):
        """``(kind, lengths)`` for the FIFO-queue search when the graph has few distinct
        positive edge lengths (pixel graphs: 1 and sqrt 2), else None."""
        data = self.data if data is None else data
        return _kernels.length_classes(data)

    def unpermute(self, values: np.ndarray) -> np.ndarray:
        if self.perm is None:
            return values
        out = np.empty_like(values)
        out[self.perm] = values
        return out


def _searchable_lengths(data: np.ndarray) -> tuple[np.ndarray, float]:
    """Edge lengths the searches can sum, and the power of two they were divided by.

    Sums of lengths near float64's top overflow (three edges of 1e308: inf, and every
    distance tied) and subnormal lengths have lost digits (1 / d overflows): where the
    largest length is outside [2^-500, 2^500], the lengths are divided by the power of two
    that puts it in [1, 2), exactly, and the searches' distances are scaled back.
    """
    positive = data[data > 0]
    peak = float(positive.max()) if positive.size else 0.0
    if peak == 0.0 or not math.isfinite(peak) or 2.0**-500 <= peak <= 2.0**500:
        return data, 1.0
    scale = math.ldexp(1.0, math.frexp(peak)[1] - 1)
    scaled = data / scale
    if np.any(scaled[data > 0] == 0):
        raise InputError(
            "`graph` must have edge lengths within float64's range of one another (a ratio of about "
            f"1e-308 at most); got lengths from {float(positive.min()):.3g} to {peak:.3g}."
        )
    return scaled, scale


def _scaled_values(adjacency: sparse.csr_array) -> tuple[sparse.csr_array, float]:
    """``adjacency`` with its (non-negative) stored values divided by the power of two of
    :func:`_searchable_lengths`, and that power: sums of values near 1e308 do not
    overflow there, nor inverses of subnormal ones."""
    scaled, unit = _searchable_lengths(adjacency.data.astype(np.float64, copy=False))
    if unit == 1.0:
        return adjacency, 1.0
    return sparse.csr_array((scaled, adjacency.indices, adjacency.indptr), shape=adjacency.shape), unit


def _on_pixel_grid(graph) -> bool:
    """Whether ``graph`` is a :class:`~centrality_vision.graphs.PixelGraph` (2D or 3D) that
    is still exactly the pixel graph of its mask, so the grid kernels may walk the mask."""
    from ..graphs import PixelGraph

    return isinstance(graph, PixelGraph) and graph.mask is not None and graph.matches_mask()


def _octile_grid(graph) -> bool:
    """Whether distances by length on ``graph`` take the octile kernel of ``_octile`` (an
    8-neighbour 2D pixel graph still matching its mask, under 2^21 pixels)."""
    from ._octile import takes

    return _on_pixel_grid(graph) and takes(graph.mask.ndim, int(graph.connectivity), graph.shape[0])


def _prepare(graph, *, reorder: bool = True, allow_directed: bool = True, lengths: bool = True) -> _Prepared:
    """``graph`` checked and laid out for the kernels; ``lengths=False`` (hop counts) gives
    unit edge lengths and leaves the stored ones unread."""
    graph_input = as_any_graph(graph, name="graph", allow_directed=allow_directed)
    return _Prepared(graph_input, reorder=reorder, lengths=lengths)


def _finish(values: np.ndarray, labels, as_dict: bool):
    if not check_bool(as_dict, name="as_dict"):
        return values
    if labels is None:
        return {key: float(v) for key, v in enumerate(values)}
    try:
        result = {key: float(v) for key, v in zip(labels, values)}
    except TypeError:  # igraph vertex names can be any object
        bad = next(label for label in labels if not isinstance(label, Hashable))
        raise TypeError(f"`as_dict` (True) needs hashable node labels; got the label {bad!r}.") from None
    if len(result) != len(labels):  # (a repeated name kept one of its nodes' values)
        repeated = next(label for label, count in Counter(labels).items() if count > 1)
        raise InputError(
            f"`as_dict` (True) needs distinct node labels; the graph names {repeated!r} more than once "
            "(return the array, which follows the node order, instead)."
        )
    return result


def _strengths_option(strengths, weights, function: str) -> bool:
    """``strengths``, honouring the deprecated ``weights`` alias of degree-like measures."""
    if weights is not None:
        weights = check_bool(weights, name="weights")
        if weights:
            warn(
                f"{function}(weights=True) is deprecated: `weights` means edge lengths as distances in "
                f"this package; use {function}(strengths=True) for the stored values as strengths.",
                FutureWarning,  # (as every renamed option: DeprecationWarning is hidden outside __main__)
            )
            return True
    return check_bool(strengths, name="strengths")


def _hop_stats(indptr, indices, progress: bool, desc: str):
    """Per node, over the sources that reach it by arcs: sum of hop distances, sum of
    inverse distances, largest distance, count (itself included). Bit-parallel search
    from groups of 64 nearby sources; every node collects its own sums."""
    members, group_ptr = _kernels.compact_groups(indptr, indices, 64)

    def task(lo, hi):
        return _kernels.multi_source_stats(indptr, indices, members, group_ptr, lo, hi)

    parts = [
        r
        for _, _, r in run_chunks(
            task, group_ptr.size - 1, progress=progress, desc=desc, weight=64, total=indptr.size - 1
        )
    ]
    total, inverse, largest, reached = (np.array(p) for p in parts[0])
    for t, h, e, r in parts[1:]:
        total += t
        inverse += h
        reached += r
        np.maximum(largest, e, out=largest)
    return total, inverse, largest, reached


def _length_stats(indptr, indices, data, progress: bool, desc: str):
    """Per source, by edge length: sum of distances, of inverse distances, largest, reached.

    Graphs with few distinct lengths (pixel graphs) use the exact FIFO-queue search,
    the others Dijkstra with a heap.
    """
    n = indptr.size - 1
    classes = _kernels.length_classes(data)

    def task(lo, hi):
        sources = np.arange(lo, hi, dtype=np.int64)
        if classes is not None:
            return _kernels.class_stats(indptr, indices, classes[0], classes[1], sources, *_kernels.NO_GRID)
        return _kernels.dijkstra_stats(indptr, indices, data, sources)

    parts = [r for _, _, r in run_chunks(task, n, progress=progress, desc=desc)]
    return [np.concatenate(p) for p in zip(*parts)]


def _distance_stats(
    prep: _Prepared, weights: bool, progress: bool, desc: str, inward: bool, grid_graph=None, need_inverse=True
):
    """Per node: sum of distances, sum of inverse distances, eccentricity, nodes reached, and
    the unit of the distances (true distance = returned distance x unit).

    ``inward``: distances to the node (closeness, harmonic); else from it (eccentricity).
    The two coincide on undirected graphs. With lengths, ``grid_graph`` (the same graph,
    given only where :func:`_on_pixel_grid` holds) is searched on the pixel grid, and the
    inverse sums are left at zero unless ``need_inverse`` (they cost a visit per pixel
    there, where the other sums come in closed form).
    """
    if weights and grid_graph is not None:
        from ._grid import grid_length_stats

        # node order of the graph itself, lengths in its units
        return [*grid_length_stats(grid_graph, progress, desc, need_inverse), 1.0]
    if weights:
        # Per-source searches give distances from the source: reverse the arcs for inward.
        indptr, indices, data = prep.transposed() if inward else (prep.indptr, prep.indices, prep.data)
        stats = _length_stats(indptr, indices, data, progress, desc)
    else:
        # The bit-parallel search collects, at each node, distances to it.
        indptr, indices, _ = (prep.indptr, prep.indices, prep.data) if inward else prep.transposed()
        stats = _hop_stats(indptr, indices, progress, desc)
    return [*(prep.unpermute(v) for v in stats), prep.length_scale if weights else 1.0]


def _check_sampling_options(delta, seed) -> None:
    """``delta`` and ``seed`` checked also where ``epsilon`` is None (exact values, which do
    not use them): nonsense there passed unnoticed."""
    from .._seeding import as_generator

    _check_epsilon(1.0, delta)
    as_generator(seed)  # (a Generator is returned as it is, nothing drawn)


def _check_epsilon(epsilon, delta):
    epsilon = check_float(epsilon, name="epsilon", low=0.0, high=1.0)
    if epsilon == 0.0:
        raise InputError("`epsilon` must be in (0, 1] (None for exact values); got 0.0.")
    delta = check_float(delta, name="delta", low=0.0, high=1.0)
    if delta == 0.0 or delta == 1.0:
        raise InputError(f"`delta` must be in (0, 1); got {delta!r}.")
    return epsilon, delta


# --- degree ---------------------------------------------------------------------------


def degree(graph, /, *, strengths: bool = False, normalized: bool = False, as_dict: bool = False, weights=None):
    r"""Degree centrality: the number of neighbours of each node (thesis eq. 2.8).

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
        Adjacency; stored values are edge lengths. Directed graphs count out-arcs.
    strengths : bool, default=False
        If True, sum the stored edge values instead of counting edges (the node strength).
    normalized : bool, default=False
        If True, divide by the largest value, :math:`d(x) / \max_y d(y)` (thesis eq. 2.9),
        so that the most connected node has 1. A graph without edges gives zeros.
    as_dict : bool, default=False
        Return ``{node: value}`` keyed by the node labels.
    weights : bool, optional
        Deprecated alias of ``strengths``.

    Returns
    -------
    ndarray of shape (n,), or dict

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> degree(path)
    array([1., 2., 1.])
    >>> degree(path, normalized=True)
    array([0.5, 1. , 0.5])
    """
    info = as_any_graph(graph, name="graph", allow_directed=True)
    strengths = _strengths_option(strengths, weights, "degree")
    normalized = check_bool(normalized, name="normalized")
    adjacency = info.adjacency
    if strengths:
        # summed at a power-of-two scale, exactly, so that a sum beyond float64 is an error
        # instead of an overflow warning and inf
        scaled, unit = _scaled_values(adjacency)
        with np.errstate(over="ignore"):
            values = np.asarray(scaled.sum(axis=1), dtype=np.float64).ravel() * unit
        if not np.all(np.isfinite(values)):
            raise InputError(
                "`graph` has node strengths beyond float64's largest number (about 1.8e308); rescale its values."
            )
    else:
        values = np.diff(adjacency.indptr).astype(np.float64)
    if normalized:
        top = values.max()
        values = values / top if top > 0 else np.zeros_like(values)
    return _finish(values, info.labels, as_dict)


# --- betweenness ------------------------------------------------------------------------


# betweenness(weights=True) on a pixel graph: the largest spacing ratio at which distinct
# path lengths stay apart by more than its tie tolerance (1e-10 relative)
_TIE_SPACING_RATIO = 1e4


def betweenness(
    graph,
    /,
    *,
    weights: bool = False,
    normalized: bool = False,
    epsilon: float | None = None,
    delta: float = 0.1,
    seed=None,
    progress: bool = False,
    as_dict: bool = False,
    return_info: bool = False,
):
    r"""Betweenness centrality (Freeman; Brandes' algorithm; thesis eq. 2.10).

    .. math:: b(x) = \sum_{\{s, t\},\ s \ne x \ne t} \frac{\sigma_x(s, t)}{\sigma(s, t)}

    over unordered pairs of nodes (ordered pairs on directed graphs), where
    :math:`\sigma(s, t)` is the number of shortest paths between ``s`` and ``t`` and
    :math:`\sigma_x(s, t)` the number of those passing through ``x``. Pairs that do not
    reach each other contribute nothing.

    Exact where other libraries are not: path counts that overflow float64 (long thin
    shapes) are recomputed in log space for that source, and with ``weights=True`` path
    lengths that are equal tie: on graphs with few distinct edge lengths (pixel graphs: 1
    and sqrt 2) distances are kept as integer counts of each length, so ``1 + sqrt 2`` and
    ``sqrt 2 + 1`` are the same number, and lengths computed from two different counts tie
    within a relative ``1e-10``, as two lengths do on other graphs. That is exact on pixel
    graphs with equal spacing (distinct lengths of images up to a million pixels differ by
    about 1e-7 relative) and with spacing ratios up to about 1e4; beyond, distinct lengths
    can differ by less than ``1e-10`` relative and tie (a diagonal step and a step along the
    farther-spaced axis differ by ``1 / (2 ratio^2)``), with a warning on such a pixel
    graph. A zero-length edge counts as
    infinitesimally long: among paths of tied length, only those with the fewest zero-length
    edges are shortest. (Counting every tied path is ill-defined here, since a cycle of
    zero-length edges gives infinitely many; networkx's result then depends on the order its
    search settles nodes at equal distance, and nodes that are interchangeable can differ.)

    On the graph :func:`~centrality_vision.graphs.pixel_graph` returns (hop counts, exact
    values) the searches walk the pixel grid itself, about twice as fast, and a mask that
    mirror or rotation maps onto itself needs one search per orbit of those maps: a disk
    1/8 of the searches, a mask with one mirror axis about 1/2 (``return_info`` reports
    ``"searches"`` and ``"symmetries"``). The values are the same up to rounding.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
        Adjacency; stored values are edge lengths.
    weights : bool, default=False
        Shortest paths by hops (False, the thesis' choice) or by stored edge length.
    normalized : bool, default=False
        If True, divide by the number of pairs not containing the node,
        :math:`(n-1)(n-2)/2` (:math:`(n-1)(n-2)` directed), so values lie in [0, 1]
        (networkx's normalisation).
    epsilon : float in (0, 1], optional
        Approximate instead: with probability at least ``1 - delta`` every node's
        *normalised* value is within ``epsilon`` of the exact one (for ``normalized=False``
        the same bound times :math:`(n-1)(n-2)/2`). Shortest paths between random pairs
        are drawn uniformly (on general graphs by a balanced bidirectional search), as in Riondato and
        Kornaropoulos [2]_; sampling stops at the first checkpoint where an empirical
        Bernstein bound (Maurer and Pontil), union-bounded over nodes and checkpoints,
        holds for every node, and at the latest after the Riondato-Kornaropoulos size
        :math:`\frac{c}{\epsilon^2}(\lfloor \log_2(VD - 2) \rfloor + 1 + \ln\frac{2}{\delta})`
        with :math:`c = 0.5` and the vertex-diameter bound ``VD`` of one search per
        component (``delta`` is split between the two rules). Hop counts only. On a
        pixel graph each pair's search visits only pixels that can lie on one of its
        shortest paths, as an A* search would: a pixel is left out when its hops from the
        source plus a lower bound on its hops to the target exceed the distance, the bound
        being the larger of the unobstructed-grid distance and the landmark bound
        :math:`\max_L |d(L, w) - d(L, t)|` over 8 landmarks chosen farthest-first; a
        search that misses the target (a detour around holes or bends) runs again with a
        larger allowance. On an open region that is the parallelogram of shortest paths
        instead of two balls: on a megapixel silhouette 3.5x fewer visits, 2.7x less time.
        On 2D grids a pair whose distance is the unobstructed one (85% of the pairs on that
        silhouette) needs no search at all: with 8 neighbours its paths advance one column
        (or row) per step, so their counts follow column by column over the band they can
        occupy (the same paths drawn with the same random numbers), another 2x; with 4
        neighbours they are the monotone staircases of the pair's box, counted row by row;
        on 26-neighbour 3D grids they advance one slice per step (1.6x on a 90,000-voxel
        ball with a slot). Where that size reaches the number of ordered pairs
        ``n (n - 1)``, the exact values are computed instead (cheaper, and ``"samples"`` is
        0); sizes beyond 5e7 pairs (drawn up front) are refused: a larger ``epsilon``.
    delta : float in (0, 1), default=0.1
        Failure probability of the approximation.
    seed : int, numpy.random.Generator or None
        Seed of the sampling; the result does not depend on the thread count.
    progress : bool, default=False
        Show a progress bar on stderr.
    as_dict : bool, default=False
        Return ``{node: value}`` keyed by the node labels.
    return_info : bool, default=False
        Also return a dict: ``"samples"`` (paths drawn; 0 when exact), ``"searches"``,
        ``"bound"`` (the guaranteed error of the normalised values, 0 when exact); when
        sampled also ``"visited"`` (nodes the searches visited, and cells counted),
        ``"retries"`` (pixel searches run again with a larger allowance) and ``"counted"``
        (pairs counted without a search).

    Returns
    -------
    ndarray of shape (n,), or dict; with ``return_info`` a tuple ``(values, info)``

    References
    ----------
    .. [1] U. Brandes, "A faster algorithm for betweenness centrality", J. Math.
       Sociology 25(2), 163-177, 2001.
    .. [2] M. Riondato and E. M. Kornaropoulos, "Fast approximation of betweenness
       centrality through sampling", Data Min. Knowl. Disc. 30, 438-475, 2016.

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> betweenness(path)
    array([0., 1., 0.])
    """
    on_grid = _on_pixel_grid(graph)
    weights = check_bool(weights, name="weights")
    if weights and on_grid and graph.spacing is not None:
        spacing = np.asarray(graph.spacing, dtype=float)
        ratio = float(spacing.max() / spacing.min())
        if ratio > _TIE_SPACING_RATIO:
            warn(
                f"betweenness(weights=True): the pixel spacing's ratio is {ratio:.3g}; beyond about "
                f"{_TIE_SPACING_RATIO:g}, path lengths that differ (a diagonal step and a step along the "
                "farther-spaced axis) can tie, and the result is not exact.",
                UserWarning,
            )
    prep = _prepare(graph, reorder=not on_grid, lengths=weights)  # the grid path walks the mask, not these lists
    normalized = check_bool(normalized, name="normalized")
    progress = check_bool(progress, name="progress")
    n = prep.n
    pairs = (n - 1) * (n - 2) / (1 if prep.directed else 2)
    _check_sampling_options(delta, seed)
    if epsilon is not None:
        if weights:
            raise InputError("`epsilon` (approximation) is available for hop counts only; got weights=True.")
        from ._approx import sample_betweenness

        epsilon, delta = _check_epsilon(epsilon, delta)
        from ._grid import _Grid

        grid = _Grid(graph) if on_grid else None
        values, info = sample_betweenness(prep, epsilon, delta, seed, progress, grid=grid)
        if values is not None:
            values = prep.unpermute(values)  # normalised
            if not normalized:
                values = values * pairs
    if epsilon is None or values is None:  # (exact also where sampling would draw more pairs than exist)
        if on_grid:
            from ._grid import grid_betweenness

            values, info = grid_betweenness(graph, weights, progress)
        else:
            values, info = _list_betweenness(prep, weights, progress), {"searches": n}
        values = prep.unpermute(values)
        if not prep.directed:
            values *= 0.5  # every unordered pair was counted from both ends
        if normalized:
            values = values / pairs if n > 2 else np.zeros(n)
        info = {"samples": 0, "bound": 0.0, **info}
    out = _finish(values, prep.labels, as_dict)
    return (out, info) if check_bool(return_info, name="return_info") else out


def _list_betweenness(prep: _Prepared, weights: bool, progress: bool) -> np.ndarray:
    """Ordered-pair betweenness sums (node order of ``prep``) on the adjacency lists."""
    classes = prep.classes() if weights else None

    def task(lo, hi):
        sources = np.arange(lo, hi, dtype=np.int64)
        if classes is not None:
            ones = np.ones(sources.size)
            return _kernels.class_brandes(
                prep.indptr,
                prep.indices,
                classes[0],
                classes[1],
                sources,
                _kernels.TIE_RTOL,
                False,
                False,
                *_kernels.NO_GRID,
                ones,
            )[0]
        return _kernels.brandes(prep.indptr, prep.indices, prep.data, sources, weights, _kernels.TIE_RTOL, False)[0]

    values = np.zeros(prep.n)
    for _, _, part in run_chunks(task, prep.n, progress=progress, desc="betweenness"):
        values += part
    return values


def edge_betweenness(
    graph, /, *, weights: bool = False, normalized: bool = False, progress: bool = False, as_dict: bool = False
):
    r"""Edge betweenness: for each edge, the share of shortest paths through it, summed over pairs.

    .. math:: b(e) = \sum_{\{s, t\}} \frac{\sigma_e(s, t)}{\sigma(s, t)}

    over unordered pairs (ordered on directed graphs), as networkx's
    ``edge_betweenness_centrality``. Path counts are kept as logarithms (exact for any
    graph length); ties as in :func:`betweenness`.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
    weights : bool, default=False
        Shortest paths by hops or by stored edge length.
    normalized : bool, default=False
        If True, divide by :math:`n(n-1)/2` (:math:`n(n-1)` directed), as networkx.
    progress : bool, default=False
        Show a progress bar on stderr.
    as_dict : bool, default=False
        Return ``{(u, v): value}`` keyed by node labels (each undirected edge once, ``u``
        before ``v`` in node order).

    Returns
    -------
    scipy.sparse.csr_array of shape (n, n), or dict
        The value of edge ``u -- v`` at ``[u, v]`` (and ``[v, u]`` when undirected).

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> edge_betweenness(path).toarray()
    array([[0., 2., 0.],
           [2., 0., 2.],
           [0., 2., 0.]])
    """
    weights = check_bool(weights, name="weights")
    prep = _prepare(graph, lengths=weights)
    normalized = check_bool(normalized, name="normalized")
    progress = check_bool(progress, name="progress")
    n = prep.n
    data = prep.data if weights else np.ones_like(prep.data)

    def task(lo, hi):
        return _kernels.brandes_edges(
            prep.indptr, prep.indices, data, np.arange(lo, hi, dtype=np.int64), _kernels.TIE_RTOL
        )

    arcs = np.zeros(prep.indices.size)
    for _, _, part in run_chunks(task, n, progress=progress, desc="edge betweenness"):
        arcs += part
    if not prep.directed:
        # Both arcs of an edge get the mean (each unordered pair was counted from both
        # ends); the structure, zeros included, is the graph's, so the twin arcs align.
        twin = sparse.csr_array(sparse.csr_array((arcs, prep.indices, prep.indptr), shape=(n, n)).T)
        twin.sort_indices()
        arcs = 0.5 * (arcs + twin.data)
    if normalized and n > 1:
        arcs = arcs / (n * (n - 1) / (1 if prep.directed else 2))
    # Back to the input's node numbering, keeping every edge (zeros too).
    coo = sparse.csr_array((arcs, prep.indices, prep.indptr), shape=(n, n)).tocoo()
    rows, cols = coo.row, coo.col
    if prep.perm is not None:
        rows, cols = prep.perm[rows], prep.perm[cols]
    result = sparse.csr_array((coo.data, (rows, cols)), shape=(n, n))
    result.sort_indices()
    if not check_bool(as_dict, name="as_dict"):
        return result
    labels = list(range(n)) if prep.labels is None else prep.labels
    coo = result.tocoo()
    keep = np.ones(coo.nnz, dtype=bool) if prep.directed else coo.row < coo.col
    return {(labels[u], labels[v]): float(x) for u, v, x in zip(coo.row[keep], coo.col[keep], coo.data[keep])}


# --- distance-based ---------------------------------------------------------------------


def closeness(
    graph,
    /,
    *,
    weights: bool = False,
    normalized: bool = True,
    epsilon: float | None = None,
    delta: float = 0.1,
    seed=None,
    progress: bool = False,
    as_dict: bool = False,
    return_info: bool = False,
):
    r"""Closeness centrality: the inverse mean distance to the other nodes.

    .. math:: C(x) = \frac{n - 1}{\sum_{y \ne x} d(y, x)}

    This is the form the thesis' Table 2.1 prints; for the sum of inverse distances
    (its eq. 2.11) see :func:`harmonic`. On directed graphs the distances are those
    *to* ``x`` (networkx's convention).

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
        Adjacency; stored values are edge lengths.
    weights : bool, default=False
        Distances in hops (False) or by stored edge length (exact FIFO-queue search on
        graphs with few distinct lengths, such as pixel graphs; on an 8-neighbour 2D
        :class:`~centrality_vision.graphs.PixelGraph`, with any pixel spacing, the distances of the
        pixels a node sees along straight-then-diagonal paths come in closed form and
        only the rest are searched, which takes about the time of hop counts).
    normalized : bool, default=True
        If True, the formula above. In a disconnected graph a node reached from ``r - 1``
        others gets :math:`\frac{r-1}{n-1} \cdot \frac{r-1}{\sum d}` (Wasserman and
        Faust's correction, networkx's default), which is the formula above when the
        graph is connected. If False, :math:`1 / \sum_y d(y, x)` over the reaching nodes.
        An isolated node gets 0 either way.
    epsilon : float in (0, 1], optional
        Approximate by source sampling (Eppstein and Wang [1]_): ``k`` sources drawn
        without replacement, :math:`k = \lceil \ln(2n/\delta) / (2\epsilon^2) \rceil` (exact
        values when ``k >= n``). With probability at least ``1 - delta``, every node's
        estimated sum of distances, divided by ``n``, is within ``epsilon * D`` of the
        exact one, ``D`` the largest eccentricity (Hoeffding's bound); on a connected
        graph that is the mean distance ``1 / closeness`` within about ``epsilon * D``.
        Hop counts on undirected graphs only.
    delta : float in (0, 1), default=0.1
        Failure probability of the approximation.
    seed : int, numpy.random.Generator or None
        Seed of the source sampling.
    progress : bool, default=False
        Show a progress bar on stderr.
    as_dict : bool, default=False
        Return ``{node: value}`` keyed by the node labels.
    return_info : bool, default=False
        Also return ``{"searches": sources searched, "samples": sampled sources}``.

    Returns
    -------
    ndarray of shape (n,), or dict; with ``return_info`` a tuple ``(values, info)``

    References
    ----------
    .. [1] D. Eppstein and J. Wang, "Fast approximation of centrality", J. Graph
       Algorithms Appl. 8(1), 39-45, 2004.

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> closeness(path)
    array([0.66666667, 1.        , 0.66666667])
    """
    normalized = check_bool(normalized, name="normalized")
    n, total, _, _, reached, unit, info = _inward_sums(
        graph, weights, epsilon, delta, seed, progress, "closeness", False
    )
    values = np.zeros(n)
    ok = total > 0
    with np.errstate(over="ignore"):
        if normalized:
            r = reached[ok] - 1.0
            values[ok] = (r / total[ok]) * (r / (n - 1)) / unit
        else:
            values[ok] = 1.0 / total[ok] / unit
    _check_inverse(values)
    out = _finish(values, info.pop("labels"), as_dict)
    return (out, info) if check_bool(return_info, name="return_info") else out


def _check_inverse(values: np.ndarray) -> None:
    """Refuse inverse distances beyond float64 (edge lengths near its smallest numbers)."""
    if not np.all(np.isfinite(values)):
        raise InputError(
            "`graph` has inverse distances beyond float64's largest number (about 1.8e308) with these "
            "edge lengths (near 1e-308); rescale them."
        )


def _inward_sums(graph, weights, epsilon, delta, seed, progress, desc, need_inverse=True):
    """(n, sum of distances, sum of inverse distances, largest, reached, unit, info) to each
    node (the inverse sums may be zeros unless ``need_inverse``; distances in ``unit``)."""
    weights = check_bool(weights, name="weights")
    on_grid = weights and epsilon is None and _on_pixel_grid(graph)
    prep = _prepare(graph, reorder=not on_grid, lengths=weights)  # the grid search walks the mask, not these lists
    progress = check_bool(progress, name="progress")
    _check_sampling_options(delta, seed)
    if epsilon is not None:
        if weights or prep.directed:
            raise InputError("`epsilon` (approximation) is available for hop counts on undirected graphs only.")
        from ._approx import sample_sources

        epsilon, delta = _check_epsilon(epsilon, delta)
        total, inverse, largest, reached, info = sample_sources(prep, epsilon, delta, seed, progress, desc)
        stats = [*(prep.unpermute(v) for v in (total, inverse, largest, reached)), 1.0]
    else:
        grid_graph = graph if on_grid else None
        stats = _distance_stats(prep, weights, progress, desc, True, grid_graph, need_inverse)
        info = {"searches": prep.n, "samples": 0}
    info["labels"] = prep.labels
    return (prep.n, *stats, info)


def harmonic(
    graph,
    /,
    *,
    weights: bool = False,
    normalized: bool = False,
    epsilon: float | None = None,
    delta: float = 0.1,
    seed=None,
    progress: bool = False,
    as_dict: bool = False,
    return_info: bool = False,
):
    r"""Harmonic centrality: the sum of inverse distances (thesis eq. 2.11).

    .. math:: H(x) = \sum_{y \ne x} \frac{1}{d(y, x)}

    with :math:`1/\infty = 0` for unreachable nodes, so it is well defined on
    disconnected graphs; nodes at distance 0 (zero-length edges) add nothing, as in
    networkx. On directed graphs the distances are those *to* ``x``.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
        Adjacency; stored values are edge lengths.
    weights : bool, default=False
        Distances in hops (False) or by stored edge length.
    normalized : bool, default=False
        If True, divide by ``n - 1`` (values in [0, 1] for hop distances).
    epsilon : float in (0, 1], optional
        Approximate by source sampling (Eppstein and Wang), as for :func:`closeness`:
        with probability at least ``1 - delta`` every node's value divided by ``n - 1``
        is within ``epsilon`` of the exact one (Hoeffding's bound; the terms
        :math:`1/d` lie in [0, 1] for hop counts). Hop counts on undirected graphs only.
    delta : float in (0, 1), default=0.1
        Failure probability of the approximation.
    seed : int, numpy.random.Generator or None
        Seed of the source sampling.
    progress : bool, default=False
        Show a progress bar on stderr.
    as_dict : bool, default=False
        Return ``{node: value}`` keyed by the node labels.
    return_info : bool, default=False
        Also return ``{"searches": sources searched, "samples": sampled sources}``.

    Returns
    -------
    ndarray of shape (n,), or dict; with ``return_info`` a tuple ``(values, info)``

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> harmonic(path)
    array([1.5, 2. , 1.5])
    """
    normalized = check_bool(normalized, name="normalized")
    n, _, inverse, _, _, unit, info = _inward_sums(graph, weights, epsilon, delta, seed, progress, "harmonic")
    with np.errstate(over="ignore"):
        inverse = inverse / unit
    _check_inverse(inverse)
    values = (inverse / (n - 1) if n > 1 else np.zeros(n)) if normalized else inverse
    out = _finish(values, info.pop("labels"), as_dict)
    return (out, info) if check_bool(return_info, name="return_info") else out


def eccentricity(
    graph,
    /,
    *,
    weights: bool = False,
    normalized: bool = False,
    method: str = "auto",
    progress: bool = False,
    as_dict: bool = False,
    return_info: bool = False,
):
    r"""Eccentricity: the largest distance from a node (thesis eq. 2.6).

    .. math:: e(x) = \max_y d(x, y)

    The nodes of smallest eccentricity form the graph centre. In a disconnected graph
    the maximum runs over the nodes the node reaches (strictly it would be infinite,
    which carries no information); an isolated node gets 0.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
        Adjacency; stored values are edge lengths.
    weights : bool, default=False
        Distances in hops (False) or by stored edge length.
    normalized : bool, default=False
        If True, divide by the largest eccentricity (the diameter), so values lie in [0, 1].
    method : {'auto', 'bounds', 'all'}, default='auto'
        ``'bounds'``: Takes and Kosters' exact bounding method [1]_ (undirected graphs):
        each search from a node ``v`` bounds every other node's eccentricity by
        :math:`\max(d(v, w), e(v) - d(v, w)) \le e(w) \le e(v) + d(v, w)`, and searches
        continue, alternately from the node of largest upper and of smallest lower bound,
        until every node's bounds meet. ``'all'``: one search per node (bit-parallel,
        64 sources at a time, for hop counts). ``'auto'``: ``'bounds'`` on undirected
        graphs, by hops giving up for ``'all'`` after ``n / 32`` searches (about the
        cost of the bit-parallel search) and ``'all'`` below 4,096 nodes, by length on
        an 8-neighbour 2D pixel graph giving up after ``n / 16`` searches (about the
        cost of its octile search from every pixel); ``'all'`` on directed graphs. Measured on 2 idle
        cores: a 100,000-pixel silhouette needs 729 searches by hops (4.1 s, against
        21.4 s for 'all') and 523 by length (5.3 s, against one search per node); a
        5,000-point Delaunay graph needs 3,274 by hops (so 'auto' falls back) but 541 by
        length.
    return_info : bool, default=False
        Also return ``{"searches": searches made}``: single-source searches, plus the
        64-source groups of the bit-parallel search by hops.
    progress : bool, default=False
        Show a progress bar on stderr.
    as_dict : bool, default=False
        Return ``{node: value}`` keyed by the node labels.

    Returns
    -------
    ndarray of shape (n,), or dict; with ``return_info`` a tuple ``(values, info)``

    References
    ----------
    .. [1] F. W. Takes and W. A. Kosters, "Computing the eccentricity distribution of
       large graphs", Algorithms 6(1), 100-118, 2013.

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> eccentricity(path)
    array([2., 1., 2.])
    >>> eccentricity(path, method="bounds", return_info=True)[1]["searches"] <= 3
    True
    """
    normalized = check_bool(normalized, name="normalized")
    check_choice(method, ("auto", "bounds", "all"), name="method")
    weights = check_bool(weights, name="weights")
    prep = _prepare(graph, lengths=weights)
    progress = check_bool(progress, name="progress")
    largest = None
    searches = 0
    if method == "auto" and not weights and prep.n < 4096:
        method = "all"  # a few bit-parallel searches: nothing to save
    if method == "bounds" or (method == "auto" and not prep.directed):
        if prep.directed:
            raise InputError("`method='bounds'` needs an undirected graph; got a directed one (use 'all').")
        # 'auto' by hops gives up once the bounds have cost about what the bit-parallel
        # search costs in all (n / 32 single searches): on Delaunay graphs, whose hop
        # eccentricities take few values, the bounds rarely meet. By length on an
        # 8-neighbour 2D pixel graph it gives up after n / 16: the octile search from
        # every pixel costs about that many Dijkstra searches (17 on Kimia silhouettes).
        budget = None
        if method == "auto" and not weights:
            budget = prep.n // 32
        elif method == "auto" and _octile_grid(graph):
            budget = prep.n // 16
        largest, searches = _eccentricity_bounds(prep, weights, budget)
        unit = prep.length_scale if weights else 1.0
        if largest is not None:
            largest = prep.unpermute(largest)
    if largest is None:
        grid_graph = graph if weights and _on_pixel_grid(graph) else None
        *stats, unit = _distance_stats(prep, weights, progress, "eccentricity", False, grid_graph, need_inverse=False)
        largest = stats[2]
        searches += prep.n if weights else int(math.ceil(prep.n / 64))
    with np.errstate(over="ignore"):
        largest = largest * unit
    if np.any(np.isinf(largest)):
        raise InputError(
            "`graph` has distances beyond float64's largest number (about 1.8e308) with these edge "
            "lengths; rescale them."
        )
    if normalized:
        top = largest.max()
        largest = largest / top if top > 0 else np.zeros_like(largest)
    out = _finish(largest, prep.labels, as_dict)
    return (out, {"searches": searches}) if check_bool(return_info, name="return_info") else out


def _eccentricity_bounds(prep: _Prepared, weights: bool, budget: int | None = None):
    """Takes-Kosters bounding: exact eccentricities and the number of searches used
    (None instead of the values when more than ``budget`` searches would be needed)."""
    classes = prep.classes() if weights else None
    kind, lengths = classes if classes is not None else (np.empty(0, dtype=np.int8), np.empty(0))
    values, searches, done = _kernels.eccentricity_bounds(
        prep.indptr,
        prep.indices,
        prep.data,
        kind,
        lengths,
        weights,
        -1 if budget is None else budget,
        1e-9 if weights else 0.0,
    )
    return (values if done else None), int(searches)


# --- dispatch and entropy -----------------------------------------------------------------


@renamed_parameters(name="centrality")
def compute(graph, /, centrality: str, **options):
    """Compute the centrality called ``centrality``; ``options`` go to that function.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
    centrality : {'degree', 'betweenness', 'closeness', 'harmonic', 'eigenvector', 'eccentricity', 'pagerank', 'katz'}
        Formerly ``name``, which still works with a FutureWarning.
    **options
        Keyword arguments of the chosen function (``weights``, ``normalized``, ...).

    Returns
    -------
    values : ndarray of shape (n,)

    Examples
    --------
    >>> from scipy import sparse
    >>> compute(sparse.csr_array([[0, 1], [1, 0]]), "degree")
    array([1., 1.])
    """
    from . import _spectral

    check_choice(centrality, CENTRALITIES, name="centrality")
    function = globals().get(centrality) or getattr(_spectral, centrality)
    try:
        return function(graph, **options)
    except TypeError as exc:
        if "unexpected keyword" in str(exc):
            import inspect

            known = set(inspect.signature(function).parameters)
            unknown = ", ".join(f"`{key}`" for key in options if key not in known) or "an option"
            accepted = _options(function)
            raise TypeError(f"{centrality}() got an unknown option {unknown}; it accepts: {accepted}.") from None
        raise


def _options(function) -> str:
    import inspect

    return ", ".join(p.name for p in inspect.signature(function).parameters.values() if p.kind is p.KEYWORD_ONLY)


def degree_entropy(graph, /) -> float:
    r"""Entropy of the degree distribution, in bits (thesis eq. 6.1).

    .. math:: H = -\sum_v p(v) \log_2 p(v)

    where :math:`p(v)` is the share of the ``n`` nodes whose degree is ``v``; isolated
    nodes count, with degree 0. Edge values are ignored.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
        Undirected (an asymmetric adjacency or a directed graph is refused); self-loops
        are dropped.

    Returns
    -------
    float
        The entropy in bits; 0 when every node has the same degree.

    Examples
    --------
    >>> from scipy import sparse
    >>> star = sparse.csr_array(([1.0] * 8, ([0, 0, 0, 0, 1, 2, 3, 4], [1, 2, 3, 4, 0, 0, 0, 0])), shape=(5, 5))
    >>> round(degree_entropy(star), 2)  # thesis fig. 7.1: the MST star has H = 0.72
    0.72
    """
    from ..graphs._entropy import entropy_of_degrees

    return entropy_of_degrees(np.diff(as_any_graph(graph, name="graph").adjacency.indptr))

"""Public centrality functions (SPEC section 2, thesis 2.3).

Conventions shared by every function here:

- ``graph`` is a symmetric adjacency (any scipy sparse format, or a dense array) whose
  stored values are edge lengths; zero means no edge and the diagonal is ignored.
- ``weights=False`` (the default, as in the thesis) counts hops; ``weights=True`` uses
  the stored lengths as distances (for :func:`degree` and :func:`eigenvector`, as
  connection strengths).
- Disconnected graphs: a node only reaches the nodes of its own component. Distances
  to the other nodes are infinite, so their ``1/d`` terms are 0 and they lie on no
  shortest path; each function states what else it does about it.
- The result is a float64 array of shape ``(n_nodes,)`` aligned with the rows of ``graph``.
"""

from __future__ import annotations


import numpy as np
from scipy import sparse

from .._validation import as_graph, check_choice
from .._parallel import run_chunks
from . import _kernels

__all__ = [
    "CENTRALITIES",
    "degree",
    "betweenness",
    "closeness",
    "harmonic",
    "eigenvector",
    "eccentricity",
    "compute",
    "degree_entropy",
]

CENTRALITIES = ("degree", "betweenness", "closeness", "harmonic", "eigenvector", "eccentricity")

def _csr(graph, *, reorder: bool = False):
    """Validated CSR parts ``(n, indptr, indices, data, perm)`` for the compiled kernels.

    With ``reorder=True`` the nodes are renumbered by reverse Cuthill-McKee, which puts
    neighbours close in memory (1.7x faster Brandes on a randomly numbered Delaunay graph);
    row ``i`` of the result is node ``perm[i]`` of ``graph``. Otherwise ``perm`` is None.
    """
    adjacency = as_graph(graph, name="graph")
    perm = None
    if reorder and adjacency.shape[0] > 256:
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        perm = reverse_cuthill_mckee(adjacency, symmetric_mode=True).astype(np.int64)
        adjacency = adjacency[perm][:, perm]
        adjacency.sort_indices()
    return (
        adjacency.shape[0],
        adjacency.indptr.astype(np.int64, copy=False),
        adjacency.indices.astype(np.int32, copy=False),
        adjacency.data.astype(np.float64, copy=False),
        perm,
    )


def _unpermute(values: np.ndarray, perm) -> np.ndarray:
    if perm is None:
        return values
    out = np.empty_like(values)
    out[perm] = values
    return out


def _check_flag(value, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"`{name}` must be True or False; got {value!r}.")
    return bool(value)


def _distance_stats(graph, weights: bool, progress: bool, desc: str):
    """Per node: sum of distances, sum of inverse distances, eccentricity, nodes reached."""
    n, indptr, indices, data, perm = _csr(graph, reorder=True)
    weights = _check_flag(weights, "weights")
    progress = _check_flag(progress, "progress")
    if weights:
        # One Dijkstra per source; by symmetry a source's sums are its own.
        def task(lo, hi):
            return _kernels.dijkstra_stats(indptr, indices, data, np.arange(lo, hi, dtype=np.int64))

        parts = [r for _, _, r in run_chunks(task, n, progress=progress, desc=desc)]
        stats = [np.concatenate(p) for p in zip(*parts)]
    else:
        # Hop distances: bit-parallel search from groups of 64 nearby sources; every node
        # collects its own sums, so the parts of the groups add up.
        members, group_ptr = _kernels.compact_groups(indptr, indices, 64)

        def task(lo, hi):
            return _kernels.multi_source_stats(indptr, indices, members, group_ptr, lo, hi)

        parts = [r for _, _, r in run_chunks(task, group_ptr.size - 1, progress=progress, desc=desc, weight=64, total=n)]
        total, inverse, largest, reached = (np.array(p) for p in parts[0])
        for t, h, e, r in parts[1:]:
            total += t
            inverse += h
            reached += r
            np.maximum(largest, e, out=largest)
        stats = [total, inverse, largest, reached]
    return (n, *(_unpermute(v, perm) for v in stats))


def degree(graph, /, *, weights: bool = False, normalized: bool = False) -> np.ndarray:
    r"""Degree centrality: the number of neighbours of each node (thesis eq. 2.8).

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n)
        Symmetric adjacency; stored values are edge lengths.
    weights : bool, default=False
        If True, sum the stored edge values instead of counting edges (the node strength).
    normalized : bool, default=False
        If True, divide by the largest value, :math:`d(x) / \max_y d(y)` (thesis eq. 2.9),
        so that the most connected node has 1. A graph without edges gives zeros.

    Returns
    -------
    ndarray of shape (n,)

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> degree(path)
    array([1., 2., 1.])
    >>> degree(path, normalized=True)
    array([0.5, 1. , 0.5])
    """
    adjacency = as_graph(graph, name="graph")
    weights = _check_flag(weights, "weights")
    normalized = _check_flag(normalized, "normalized")
    if weights:
        values = np.asarray(adjacency.sum(axis=1), dtype=np.float64).ravel()
    else:
        values = np.diff(adjacency.indptr).astype(np.float64)
    if normalized:
        top = values.max()
        values = values / top if top > 0 else np.zeros_like(values)
    return values


def betweenness(graph, /, *, weights: bool = False, normalized: bool = False, progress: bool = False) -> np.ndarray:
    r"""Betweenness centrality (Freeman; Brandes' algorithm; thesis eq. 2.10).

    .. math:: b(x) = \sum_{\{s, t\},\ s \ne x \ne t} \frac{\sigma_x(s, t)}{\sigma(s, t)}

    over unordered pairs of nodes, where :math:`\sigma(s, t)` is the number of shortest
    paths between ``s`` and ``t`` and :math:`\sigma_x(s, t)` the number of those passing
    through ``x``. Pairs in different components contribute nothing.

    Exact where other libraries are not: path counts that overflow float64 (long thin
    shapes) are recomputed in log space for that source, and with ``weights=True``
    path lengths that are equal up to rounding (``1 + sqrt 2`` versus ``sqrt 2 + 1``)
    tie, with a relative tolerance of ``1e-10``.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n)
        Symmetric adjacency; stored values are edge lengths.
    weights : bool, default=False
        Shortest paths by hops (False, the thesis' choice) or by stored edge length.
    normalized : bool, default=False
        If True, divide by the number of pairs not containing the node,
        :math:`(n-1)(n-2)/2`, so values lie in [0, 1] (networkx's normalisation).
    progress : bool, default=False
        Show a progress bar on stderr.

    Returns
    -------
    ndarray of shape (n,)

    References
    ----------
    .. [1] U. Brandes, "A faster algorithm for betweenness centrality", J. Math.
       Sociology 25(2), 163-177, 2001.

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> betweenness(path)
    array([0., 1., 0.])
    """
    n, indptr, indices, data, perm = _csr(graph, reorder=True)
    weights = _check_flag(weights, "weights")
    normalized = _check_flag(normalized, "normalized")
    progress = _check_flag(progress, "progress")
    def task(lo, hi):
        return _kernels.brandes(
            indptr, indices, data, np.arange(lo, hi, dtype=np.int64), weights, _kernels.TIE_RTOL, False
        )[0]

    values = np.zeros(n)
    for _, _, part in run_chunks(task, n, progress=progress, desc="betweenness"):
        values += part
    values = 0.5 * _unpermute(values, perm)  # every unordered pair was counted from both ends
    if normalized:
        values = values / ((n - 1) * (n - 2) / 2) if n > 2 else np.zeros(n)
    return values


def closeness(graph, /, *, weights: bool = False, normalized: bool = True, progress: bool = False) -> np.ndarray:
    r"""Closeness centrality: the inverse mean distance to the other nodes.

    .. math:: C(x) = \frac{n - 1}{\sum_{y \ne x} d(x, y)}

    This is the form the thesis' Table 2.1 prints; for the sum of inverse distances
    (its eq. 2.11) see :func:`harmonic`.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n)
        Symmetric adjacency; stored values are edge lengths.
    weights : bool, default=False
        Distances in hops (False) or by stored edge length.
    normalized : bool, default=True
        If True, the formula above. In a disconnected graph a node reaching ``r - 1``
        others gets :math:`\frac{r-1}{n-1} \cdot \frac{r-1}{\sum d}` (Wasserman and
        Faust's correction, networkx's default), which is the formula above when the
        graph is connected. If False, :math:`1 / \sum_y d(x, y)` over the reached nodes.
        An isolated node gets 0 either way.
    progress : bool, default=False
        Show a progress bar on stderr.

    Returns
    -------
    ndarray of shape (n,)

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> closeness(path)
    array([0.66666667, 1.        , 0.66666667])
    """
    normalized = _check_flag(normalized, "normalized")
    n, total, _, _, reached = _distance_stats(graph, weights, progress, "closeness")
    values = np.zeros(n)
    ok = total > 0
    if normalized:
        r = reached[ok] - 1.0
        values[ok] = (r / total[ok]) * (r / (n - 1))
    else:
        values[ok] = 1.0 / total[ok]
    return values


def harmonic(graph, /, *, weights: bool = False, normalized: bool = False, progress: bool = False) -> np.ndarray:
    r"""Harmonic centrality: the sum of inverse distances (thesis eq. 2.11).

    .. math:: H(x) = \sum_{y \ne x} \frac{1}{d(x, y)}

    with :math:`1/\infty = 0` for unreachable nodes, so it is well defined on
    disconnected graphs.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n)
        Symmetric adjacency; stored values are edge lengths.
    weights : bool, default=False
        Distances in hops (False) or by stored edge length.
    normalized : bool, default=False
        If True, divide by ``n - 1`` (values in [0, 1] for hop distances).
    progress : bool, default=False
        Show a progress bar on stderr.

    Returns
    -------
    ndarray of shape (n,)

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> harmonic(path)
    array([1.5, 2. , 1.5])
    """
    normalized = _check_flag(normalized, "normalized")
    n, _, inverse, _, _ = _distance_stats(graph, weights, progress, "harmonic")
    if normalized:
        return inverse / (n - 1) if n > 1 else np.zeros(n)
    return inverse


def eccentricity(graph, /, *, weights: bool = False, normalized: bool = False, progress: bool = False) -> np.ndarray:
    r"""Eccentricity: the largest distance from a node (thesis eq. 2.6).

    .. math:: e(x) = \max_y d(x, y)

    The nodes of smallest eccentricity form the graph centre. In a disconnected graph
    the maximum runs over the node's own component (strictly it would be infinite,
    which carries no information); an isolated node gets 0.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n)
        Symmetric adjacency; stored values are edge lengths.
    weights : bool, default=False
        Distances in hops (False) or by stored edge length.
    normalized : bool, default=False
        If True, divide by the largest eccentricity (the diameter), so values lie in [0, 1].
    progress : bool, default=False
        Show a progress bar on stderr.

    Returns
    -------
    ndarray of shape (n,)

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> eccentricity(path)
    array([2., 1., 2.])
    """
    normalized = _check_flag(normalized, "normalized")
    _, _, _, largest, _ = _distance_stats(graph, weights, progress, "eccentricity")
    if normalized:
        top = largest.max()
        return largest / top if top > 0 else np.zeros_like(largest)
    return largest


def _perron(adjacency: sparse.csr_array) -> tuple[float, np.ndarray]:
    """Largest eigenvalue and its non-negative unit eigenvector, for one connected component."""
    n = adjacency.shape[0]
    if n == 1:
        return 0.0, np.ones(1)
    if n <= 256:
        vals, vecs = np.linalg.eigh(adjacency.toarray())
        lam, vec = vals[-1], vecs[:, -1]
    else:
        from scipy.sparse.linalg import eigsh

        vals, vecs = eigsh(adjacency, k=1, which="LA", v0=np.ones(n), tol=0)
        lam, vec = vals[0], vecs[:, 0]
    vec = np.abs(vec)  # the Perron vector of a connected graph is positive
    return float(lam), vec / np.linalg.norm(vec)


def eigenvector(graph, /, *, weights: bool = False, normalized: bool = True) -> np.ndarray:
    r"""Eigenvector centrality: the leading eigenvector of the adjacency (thesis eq. 2.12).

    The non-negative eigenvector :math:`x` of :math:`A x = \lambda_{max} x`, computed with
    LAPACK or ARPACK (power iteration, as in networkx and rustworkx, fails to converge
    on Delaunay and pixel graphs whose spectral gap is small).

    Disconnected graphs: the eigenvalue problem is solved per component. Only the
    components whose largest eigenvalue equals the graph's (to 1e-9 relative) get
    non-zero values; the others get 0. When several components tie, each gets its unit
    Perron vector weighted by its sum, which is the limit power iteration from the
    all-ones vector reaches (networkx's result).

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n)
        Symmetric adjacency; stored values are edge lengths.
    weights : bool, default=False
        Use the stored values as connection strengths (False: every edge counts 1).
        Note that for data-graphs the stored values are lengths, so longer edges then
        weigh more; pass ``1 / graph`` for affinities.
    normalized : bool, default=True
        If True, scale so that the maximum is 1 (the thesis' Table 2.1). If False, scale
        to unit Euclidean norm (networkx's convention).

    Returns
    -------
    ndarray of shape (n,)

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> eigenvector(path)
    array([0.70710678, 1.        , 0.70710678])
    """
    from scipy.sparse.csgraph import connected_components

    adjacency = as_graph(graph, name="graph")
    weights = _check_flag(weights, "weights")
    normalized = _check_flag(normalized, "normalized")
    if not weights:
        adjacency.data[:] = 1.0  # as_graph returned our own copy
    n = adjacency.shape[0]
    n_comp, labels = connected_components(adjacency, directed=False)
    if n_comp == 1:
        members = [np.arange(n)]
        results = [_perron(adjacency)]
    else:
        order = np.argsort(labels, kind="stable")
        members = np.split(order, np.cumsum(np.bincount(labels, minlength=n_comp))[:-1])
        results = [_perron(adjacency[idx][:, idx]) for idx in members]
    lam_max = max(lam for lam, _ in results)
    values = np.zeros(n)
    for idx, (lam, vec) in zip(members, results):
        if lam >= lam_max - 1e-9 * max(1.0, abs(lam_max)):
            values[idx] = vec * vec.sum()
    scale = values.max() if normalized else np.linalg.norm(values)
    return values / scale


def compute(graph, /, name: str, **options) -> np.ndarray:
    """Compute the centrality called ``name``; ``options`` go to that function.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n)
    name : {'degree', 'betweenness', 'closeness', 'harmonic', 'eigenvector', 'eccentricity'}
    **options
        Keyword arguments of the chosen function (``weights``, ``normalized``, ...).

    Examples
    --------
    >>> from scipy import sparse
    >>> compute(sparse.csr_array([[0, 1], [1, 0]]), "degree")
    array([1., 1.])
    """
    check_choice(name, CENTRALITIES, name="name")
    function = globals()[name]
    try:
        return function(graph, **options)
    except TypeError as exc:
        if "unexpected keyword" in str(exc):
            raise TypeError(f"{name}() got an unknown option; it accepts: {_options(function)}. ({exc})") from None
        raise


def _options(function) -> str:
    import inspect

    return ", ".join(p.name for p in inspect.signature(function).parameters.values() if p.kind is p.KEYWORD_ONLY)


def degree_entropy(graph, /) -> float:
    r"""Entropy of the degree distribution, in bits (thesis eq. 6.1).

    .. math:: H = -\sum_v p(v) \log_2 p(v)

    where :math:`p(v)` is the share of the ``n`` nodes whose degree is ``v``; isolated
    nodes count, with degree 0. Edge values are ignored.

    Examples
    --------
    >>> from scipy import sparse
    >>> star = sparse.csr_array(([1.0] * 8, ([0, 0, 0, 0, 1, 2, 3, 4], [1, 2, 3, 4, 0, 0, 0, 0])), shape=(5, 5))
    >>> round(degree_entropy(star), 2)  # thesis fig. 7.1: the MST star has H = 0.72
    0.72
    """
    from ..graphs._entropy import entropy_of_degrees

    return entropy_of_degrees(np.diff(as_graph(graph, name="graph").indptr))

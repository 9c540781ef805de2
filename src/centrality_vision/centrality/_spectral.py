"""Spectral centralities: eigenvector (thesis eq. 2.12), PageRank and Katz.

These use the stored edge values as connection *strengths* when ``strengths=True``
(every edge counts 1 otherwise); note that the graphs of this package store lengths,
so pass ``1 / graph`` (on the stored entries) for affinities.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse

from .._validation import as_any_graph, check_bool, check_float, check_int
from ..exceptions import InputError
from ._api import _finish, _scaled_values, _strengths_option

__all__ = ["eigenvector", "pagerank", "katz"]


def _collatz_wielandt(adjacency: sparse.csr_array, x: np.ndarray, max_iter: int = 100) -> tuple[float, np.ndarray]:
    """Perron pair of a connected non-negative symmetric matrix by inverse iteration.

    For a positive ``x`` the ratios ``(A x)_i / x_i`` bound the largest eigenvalue from
    below and above (Collatz-Wielandt). Each step solves ``(sigma I - A) y = x`` with
    ``sigma`` the current upper bound, which is above the eigenvalue, so the solution is
    positive and the bound falls towards the eigenvalue at a rate set by
    ``(sigma - lambda_1) / (sigma - lambda_2)``: a few steps even where Lanczos crawls
    (a 10,000-node path has a spectral gap of 3e-7).
    """
    from scipy.sparse.linalg import splu

    n = adjacency.shape[0]
    identity = sparse.identity(n, format="csc")
    hi = np.inf
    settled = 0
    for _ in range(max_iter):
        y = adjacency @ x
        ratio = y / x
        hi, lo = float(ratio.max()), float(ratio.min())
        if hi - lo <= 1e-12 * hi:
            settled += 1
            if settled == 2:  # one more step after the bounds meet refines the vector
                break
        sigma = hi * (1.0 + 1e-14) + 1e-300
        x = splu(sparse.csc_matrix(sigma * identity - adjacency)).solve(x)
        x = np.abs(x) / np.linalg.norm(x)
    return hi, x


def _perron(adjacency: sparse.csr_array) -> tuple[float, np.ndarray]:
    """Largest eigenvalue and its non-negative unit eigenvector, for one connected component.

    Up to 256 nodes LAPACK; above, Lanczos (ARPACK) with a small budget, which converges
    in milliseconds on pixel disks and Delaunay graphs, and where it does not (long thin
    graphs, whose spectral gap is tiny) Collatz-Wielandt inverse iteration. Measured: a
    10,000-node path 0.1 s (Lanczos alone > 90 s), a 3 x 10,000 pixel strip 1.6 s
    (Lanczos > 130 s) on a loaded 2-core machine.
    """
    n = adjacency.shape[0]
    if n == 1:
        return 0.0, np.ones(1)
    if n <= 256:
        vals, vecs = np.linalg.eigh(adjacency.toarray())
        lam, vec = vals[-1], vecs[:, -1]
    else:
        from scipy.sparse.linalg import ArpackNoConvergence, eigsh

        try:
            vals, vecs = eigsh(adjacency, k=1, which="LA", v0=np.ones(n), tol=0, ncv=min(n, 32), maxiter=40)
            lam, vec = vals[0], vecs[:, 0]
        except ArpackNoConvergence:
            lam, vec = _collatz_wielandt(adjacency, np.full(n, 1.0 / np.sqrt(n)))
    vec = np.abs(vec)  # the Perron vector of a connected graph is positive
    return float(lam), vec / np.linalg.norm(vec)


def eigenvector(graph, /, *, strengths: bool = False, normalized: bool = True, as_dict: bool = False, weights=None):
    r"""Eigenvector centrality: the leading eigenvector of the adjacency (thesis eq. 2.12).

    The non-negative eigenvector :math:`x` of :math:`A x = \lambda_{max} x`, computed with
    LAPACK, ARPACK, or, on long thin graphs where ARPACK crawls, inverse iteration with
    Collatz-Wielandt shifts (power iteration, as in networkx and rustworkx, fails to
    converge on Delaunay and pixel graphs whose spectral gap is small). Undirected graphs.

    Disconnected graphs: the eigenvalue problem is solved per component. Only the
    components whose largest eigenvalue equals the graph's (to 1e-9 relative) get
    non-zero values; the others get 0. When several components tie, each gets its unit
    Perron vector weighted by its sum, which is the limit power iteration from the
    all-ones vector reaches (networkx's result).

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
        Symmetric adjacency; stored values are edge lengths.
    strengths : bool, default=False
        Use the stored values as connection strengths (False: every edge counts 1).
        For data-graphs the stored values are lengths, so longer edges then weigh more;
        pass ``1 / graph`` for affinities.
    normalized : bool, default=True
        If True, scale so that the maximum is 1 (the thesis' Table 2.1). If False, scale
        to unit Euclidean norm (networkx's convention).
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
    >>> eigenvector(path)
    array([0.70710678, 1.        , 0.70710678])
    """
    from scipy.sparse.csgraph import connected_components

    info = as_any_graph(graph, name="graph")
    adjacency = info.adjacency
    strengths = _strengths_option(strengths, weights, "eigenvector")
    normalized = check_bool(normalized, name="normalized")
    if not strengths:
        adjacency.data[:] = 1.0  # as_any_graph returned our own copy
    else:
        adjacency.eliminate_zeros()
        # the vector does not depend on the strengths' scale: at unit scale the eigenvalues
        # neither overflow (NaN at 1e308) nor fall under the ties' tolerance (every
        # component kept at 1e-10)
        _to_unit_scale(adjacency)
    n = adjacency.shape[0]
    n_comp, labels = connected_components(adjacency, directed=False)
    from threadpoolctl import threadpool_limits

    # One BLAS thread: the result then does not depend on the core count (LAPACK's eigh in
    # a 1-thread worker and in a many-thread parent differed in the last bits), and ARPACK's
    # small dense steps gain nothing from more (with OpenBLAS threads on a loaded machine
    # they spin: measured 25x slower).
    with threadpool_limits(limits=1):
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
    return _finish(values / scale, info.labels, as_dict)


def _spectral_radius(adjacency: sparse.csr_array) -> float:
    """Largest absolute eigenvalue (LAPACK up to 512 nodes, else ARPACK)."""
    from scipy.sparse.linalg import eigs
    from threadpoolctl import threadpool_limits

    n = adjacency.shape[0]
    with threadpool_limits(limits=1):  # as in eigenvector
        if n <= 512:
            return float(np.abs(np.linalg.eigvals(adjacency.toarray())).max())
        return float(np.abs(eigs(adjacency, k=1, which="LM", return_eigenvectors=False, maxiter=100 * n)).max())


def _to_unit_scale(adjacency: sparse.csr_array) -> int:
    """Divide ``adjacency``'s stored values, in place, by the power of two ``2**shift`` that
    brings the largest ``|value|`` into [0.5, 1), and return ``shift`` (0 without values).
    Only exponents change, so it is exact unless a value falls below float64's normal range."""
    if not adjacency.nnz:
        return 0
    shift = math.frexp(float(np.abs(adjacency.data).max()))[1]
    adjacency.data = np.ldexp(adjacency.data, -shift)
    return shift


def _strength_matrix(graph, strengths, weights, function):
    info = as_any_graph(graph, name="graph", allow_directed=True)
    adjacency = info.adjacency
    if not _strengths_option(strengths, weights, function):
        adjacency.data[:] = 1.0
    return info, adjacency


def pagerank(
    graph,
    /,
    *,
    alpha: float = 0.85,
    strengths: bool = False,
    tol: float = 1e-12,
    max_iter: int = 1000,
    as_dict: bool = False,
):
    r"""PageRank: the stationary distribution of a random surfer who follows an out-edge
    with probability ``alpha`` and jumps to a uniformly random node otherwise.

    .. math:: x = \alpha P^T x + \frac{1 - \alpha}{n} \mathbf{1} + \frac{\alpha}{n} (\text{mass at dangling nodes})

    with :math:`P` the row-normalised adjacency (networkx's ``pagerank`` with its
    defaults; nodes without out-edges spread their mass uniformly). Power iteration,
    which converges at rate ``alpha`` whatever the graph. Values sum to 1. Directed
    graphs are followed along their arcs; an undirected edge is two arcs.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
    alpha : float in [0, 1), default=0.85
        Damping factor.
    strengths : bool, default=False
        Follow arcs in proportion to their stored values (False: uniformly).
    tol : float > 0, default=1e-12
        Stop when the L1 change of an iteration is below ``n * tol``.
    max_iter : int, default=1000
    as_dict : bool, default=False
        Return ``{node: value}`` keyed by the node labels.

    Returns
    -------
    ndarray of shape (n,), or dict

    Examples
    --------
    >>> from scipy import sparse
    >>> star = sparse.csr_array([[0, 1, 1], [1, 0, 0], [1, 0, 0]])
    >>> pagerank(star).round(4)
    array([0.4865, 0.2568, 0.2568])
    """
    info, adjacency = _strength_matrix(graph, strengths, None, "pagerank")
    alpha = check_float(alpha, name="alpha", low=0.0, high=1.0)
    if alpha == 1.0:
        raise InputError("`alpha` must be in [0, 1); got 1.0 (the iteration would not converge).")
    tol = check_float(tol, name="tol", low=0.0, low_open=True)  # (0: a change below 0 never comes)
    max_iter = check_int(max_iter, name="max_iter", low=1)
    n = adjacency.shape[0]
    # the transitions do not depend on the values' scale: computed at a power-of-two scale
    adjacency, _ = _scaled_values(adjacency)  # (CSR, as every graph input is)
    out_strength = np.asarray(adjacency.sum(axis=1)).ravel()
    dangling = out_strength == 0
    # each value over its row's sum, not times the sum's reciprocal (1 / 1e-310 overflows)
    transition = adjacency.copy()
    sums = np.repeat(out_strength, np.diff(adjacency.indptr))
    transition.data = np.divide(adjacency.data, sums, out=np.zeros_like(adjacency.data), where=sums != 0)
    transition_t = sparse.csr_array(transition.T)
    x = np.full(n, 1.0 / n)
    for _ in range(max_iter):
        new = alpha * (transition_t @ x) + (alpha * x[dangling].sum() + 1.0 - alpha) / n
        change = np.abs(new - x).sum()
        x = new
        if change < n * tol:
            break
    else:
        raise InputError(f"pagerank did not converge in `max_iter` = {max_iter} iterations; raise it or `tol`.")
    return _finish(x / x.sum(), info.labels, as_dict)


def katz(
    graph,
    /,
    *,
    alpha: float | None = None,
    beta: float = 1.0,
    strengths: bool = False,
    normalized: bool = True,
    as_dict: bool = False,
):
    r"""Katz centrality: walks into each node, a walk of length ``k`` weighted ``alpha**k``.

    .. math:: x = \alpha A^T x + \beta \mathbf{1}, \quad x = \beta (I - \alpha A^T)^{-1} \mathbf{1}

    solved directly with a sparse LU factorisation (networkx's ``katz_centrality_numpy``;
    no iteration to converge). The series converges, and the values mean what they
    should, only for ``alpha < 1 / lambda_max``; a larger ``alpha`` gives non-positive
    values and an error.

    Parameters
    ----------
    graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph
    alpha : float or None, default=None
        Attenuation; must be below the inverse of the adjacency's largest eigenvalue
        ``lambda_max``. None takes networkx's 0.1 where that converges and
        ``0.9 / lambda_max`` on denser graphs (e.g. a complete graph on more than 11 nodes),
        so the default works on every graph.
    beta : float, default=1.0
        Weight every node gets for itself (must be positive).
    strengths : bool, default=False
        Use the stored values as strengths (False: every edge counts 1).
    normalized : bool, default=True
        If True, scale to unit Euclidean norm (networkx's default).
    as_dict : bool, default=False
        Return ``{node: value}`` keyed by the node labels.

    Returns
    -------
    ndarray of shape (n,), or dict

    Examples
    --------
    >>> from scipy import sparse
    >>> path = sparse.csr_array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    >>> katz(path, alpha=0.5, normalized=False)  # x = 1 + 0.5 * (sum of neighbours)
    array([3., 4., 3.])
    """
    from scipy.sparse.linalg import splu

    info, adjacency = _strength_matrix(graph, strengths, None, "katz")
    n = adjacency.shape[0]
    # Work on the adjacency divided by 2**shift with alpha times 2**shift: the same system,
    # but sums and eigenvalues of strengths near float64's limits neither overflow nor
    # underflow. (_strength_matrix returned our own copy.)
    shift = _to_unit_scale(adjacency)
    rows = np.abs(adjacency).sum(axis=1)
    cols = np.abs(adjacency).sum(axis=0)
    bound = min(rows.max(), cols.max()) if n else 0.0  # bounds lambda_max (scaled)
    with np.errstate(over="ignore"):
        if alpha is None:  # 0.1 unless 0.1 * lambda_max >= 0.9
            alpha = 0.1
            if np.ldexp(0.1 * bound, shift) >= 0.9:
                radius = _spectral_radius(adjacency)
                alpha = 0.1 if np.ldexp(0.1 * radius, shift) < 0.9 else float(np.ldexp(0.9 / radius, -shift))
        alpha = check_float(alpha, name="alpha", low=0.0)
        scaled_alpha = float(np.ldexp(alpha, shift))  # inf for a huge alpha: refused below
    beta = check_float(beta, name="beta", low=0.0)
    if beta == 0.0:
        raise InputError("`beta` must be positive; got 0.0.")
    normalized = check_bool(normalized, name="normalized")
    too_large = n and scaled_alpha * bound >= 1.0
    if too_large:
        radius = _spectral_radius(adjacency)
        too_large = scaled_alpha * radius >= 1.0 - 1e-12
    if too_large:
        with np.errstate(over="ignore", under="ignore"):
            limit = float(np.ldexp(1.0 / radius, -shift))
        raise InputError(
            f"`alpha` must be below 1 / (largest eigenvalue of the adjacency) = {limit:.6g} for Katz centrality; "
            f"got {alpha!r}."
        )
    system = sparse.csc_matrix(sparse.identity(n, format="csc") - scaled_alpha * sparse.csc_matrix(adjacency.T))
    try:
        # x is linear in beta: solved for beta = 1 and scaled after, so that a large beta
        # neither overflows the solve nor (normalised) changes the result
        x = splu(system).solve(np.ones(n))
    except RuntimeError:  # exactly singular: alpha = 1 / an eigenvalue
        x = np.full(n, -1.0)
    if not np.all(np.isfinite(x)) or x.min() <= 0:
        raise InputError(
            f"`alpha` must be below 1 / (largest eigenvalue of the adjacency) for Katz centrality; got {alpha!r}."
        )
    if normalized:
        x = x / x.max()
        x = x / np.linalg.norm(x)
    else:
        with np.errstate(over="ignore"):
            x = x * beta
        if not np.all(np.isfinite(x)):
            raise InputError(
                f"`beta` = {beta!r} puts Katz centralities beyond float64's largest number (about 1.8e308); "
                "take a smaller one, or normalized=True."
            )
    return _finish(x, info.labels, as_dict)

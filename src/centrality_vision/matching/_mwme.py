"""Canonical matching with MWME graphs (thesis 6.5)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .._deprecation import renamed_parameters
from .._validation import as_points, check_bool
from .._warnings import warn
from ..exceptions import InputError, MatchingWarning
from ..graphs import mwme_graph
from ..transforms import SimilarityTransform
from ._common import check_resolution, check_rigid_extents, fit_pairs, normalise, similarity_to_units

__all__ = ["mwme_match"]


@renamed_parameters(method="solver")
def mwme_match(
    moving, fixed, /, *, solver: str = "local", scale: bool = True
) -> tuple[np.ndarray, SimilarityTransform]:
    """Match two point sets through the degrees of their MWME graphs.

    Each set gets its minimum-weight maximum-entropy graph (:func:`~centrality_vision.graphs.mwme_graph`),
    whose ``n`` nodes carry ``n - 1`` distinct degrees: nodes of equal degree correspond.
    The two nodes sharing the degree ``floor(n/2)`` are paired both ways and the
    assignment whose fitted similarity transform leaves the smaller residual wins. The
    matching is exact under similarity transforms whenever both graphs are the same
    optimum: for the exact solver when the optimum is unique (sets with tied optima,
    common on integer grids, can pair the wrong points, whatever the solver), and in
    general position for the deterministic greedy and
    local solvers too (they see only distances, up to scale), as long as the set's
    extent stays within about 1e10 times its smallest spacing (beyond, float64 sums
    cannot tell its orders apart).
    Both sets are centred and divided by a power of two first (exactly), so coordinates
    anywhere in float64's range give finite products and SVD inputs.

    This is the global method: every point moves every degree, so a little noise or a
    resampled outline changes the graphs (see :func:`~centrality_vision.matching.match`
    with ``method="robust"`` for sets with noise, outliers or missing parts).

    When the two graphs are not the same optimum the degrees pair unrelated points. The
    result is then checked against its own transform: a
    :class:`~centrality_vision.exceptions.MatchingWarning` says how many matched pairs are
    not nearest neighbours once the fitted transform is applied (none on a similar copy
    matched right; a symmetric set matched through one of its symmetries is a right match).

    Parameters
    ----------
    moving, fixed : array_like of shape (n_points, n_dims)
        Two sets of the same size, n_dims 2 or 3, at least 3 distinct points each.
    solver : {"local", "greedy", "exact"}, default="local"
        MWME solver (``solver`` of :func:`~centrality_vision.graphs.mwme_graph`; formerly
        ``method``, which :func:`~centrality_vision.matching.match` uses for the matching
        method).
    scale : bool, default=True
        Fit a similarity (True) or a rigid transform (False).

    Returns
    -------
    correspondence : ndarray of int, shape (n_points,)
        ``moving[i]`` matches ``fixed[correspondence[i]]``.
    transform : SimilarityTransform
        Least-squares transform taking ``moving`` onto the matched ``fixed`` points.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> fixed = rng.random((12, 2))
    >>> perm = rng.permutation(12)
    >>> moving = 0.5 * fixed[perm] @ np.array([[0.0, -1.0], [1.0, 0.0]]).T + 3.0
    >>> correspondence, transform = mwme_match(moving, fixed)
    >>> bool(np.all(correspondence == perm)), round(transform.scale, 6)
    (True, 2.0)
    """
    moving = as_points(moving, name="moving", n_dims=(2, 3), min_points=3, allow_duplicates=False)
    fixed = as_points(fixed, name="fixed", n_dims=(2, 3), min_points=3, allow_duplicates=False)
    if moving.shape != fixed.shape:
        raise InputError(
            f"`moving` and `fixed` must have the same shape for MWME matching; got {moving.shape} and {fixed.shape}."
        )
    check_bool(scale, name="scale")
    n = moving.shape[0]
    norm_m, norm_f = normalise(moving), normalise(fixed)
    check_resolution(norm_m.points, "moving", original=moving)
    check_resolution(norm_f.points, "fixed", original=fixed)
    if not scale:  # else both candidates' residuals overflow and the first one wins, right or not
        check_rigid_extents(norm_m, norm_f)
    graph_m = mwme_graph(norm_m.points, solver=solver)
    graph_f = mwme_graph(norm_f.points, solver=solver)
    repeated = n // 2
    by_degree_f = np.full(n, -1, dtype=np.int64)
    for node, deg in enumerate(graph_f.degrees):
        if deg != repeated:
            by_degree_f[deg] = node
    correspondence = np.empty(n, dtype=np.int64)
    for node, deg in enumerate(graph_m.degrees):
        if deg != repeated:
            correspondence[node] = by_degree_f[deg]
    pair_m = np.flatnonzero(graph_m.degrees == repeated)
    pair_f = np.flatnonzero(graph_f.degrees == repeated)
    best = None
    for candidate in (pair_f, pair_f[::-1]):
        trial = correspondence.copy()
        trial[pair_m] = candidate
        rotation, translation, s = fit_pairs(norm_m.points, norm_f.points[trial], scale=scale)
        if not scale:  # a rigid fit in normalised units must undo the unit change
            s = float(np.ldexp(1.0, norm_m.exponent - norm_f.exponent))
            translation = norm_f.points[trial].mean(axis=0) - s * rotation @ norm_m.points.mean(axis=0)
        moved = s * norm_m.points @ rotation.T + translation
        residual = float(np.sum((moved - norm_f.points[trial]) ** 2))
        if best is None or residual < best[0]:
            best = (residual, trial, moved, (rotation, translation, s))
    _, chosen, moved, fit = best
    # the matching is the canonical one only if the two graphs are the same optimum; when they
    # differ (noise, sets that are not similar copies, tied optima) the degrees pair unrelated
    # points, which the fitted transform then contradicts
    nearest = cKDTree(norm_f.points).query(moved)[1]
    disagree = int(np.count_nonzero(nearest != chosen))
    if disagree:
        warn(
            f"mwme_match: {disagree} of {n} matched pairs are not nearest neighbours under the fitted "
            "transform, so the two MWME graphs differ (noise, sets that are not similar copies, or "
            "tied optima on regular grids) and the correspondences are not reliable. "
            "match's `method='robust'` handles noise and missing parts.",
            MatchingWarning,
        )
    return chosen, similarity_to_units(*fit, norm_m, norm_f)

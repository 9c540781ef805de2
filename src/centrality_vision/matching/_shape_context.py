"""Shape context descriptors with Hungarian assignment: the baseline the robust matching is measured against.

Belongie, Malik and Puzicha's shape contexts (PAMI 2002): for every point, a log-polar
histogram of where the other points of its set lie; two points match when their histograms
agree (chi-squared cost); the one-to-one assignment of least total cost is found by the
Hungarian algorithm (:func:`scipy.optimize.linear_sum_assignment`), with dummy partners of
fixed cost so that points may stay unmatched.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree
from scipy.spatial.distance import pdist

from .._neighbours import query_with_ties
from ..transforms import centred

__all__ = ["shape_context", "shape_context_assignment"]

N_RADII = 5
N_ANGLES = 12
R_INNER, R_OUTER = 0.125, 2.0  # radial range in units of the mean pairwise distance
DUMMY_COST = 0.25  # chi-squared cost of leaving a point unmatched (Belongie et al.)


def _tangent_angles(points: np.ndarray, k: int = 5) -> np.ndarray:
    """Angle of each point's local tangent (principal axis of its k nearest neighbours,
    with every point as near as the k-th), its sign chosen so that the set's centroid lies
    on the left (or, where it lies on the tangent's line, behind): a rotation-invariant frame.

    The neighbours tied with the k-th all count: which of them the k-d tree returned
    depended on the order of the points (on grids, 39 of 50 sets turned a tangent when
    their rows were permuted)."""
    k = min(k, points.shape[0] - 1)
    _, index, tied = query_with_ties(cKDTree(points), points, k, rtol=1e-12)
    weight = tied.astype(float)
    centre = np.einsum("nk,nki->ni", weight, points[index]) / weight.sum(axis=1, keepdims=True)
    neigh = (points[index] - centre[:, None]) * weight[:, :, None]
    cov = np.einsum("nki,nkj->nij", neigh, neigh)
    _, vecs = np.linalg.eigh(cov)
    axis = vecs[:, :, -1]
    to_centre = points.mean(axis=0) - points
    left = axis[:, 0] * to_centre[:, 1] - axis[:, 1] * to_centre[:, 0]
    # where the centroid lies on the tangent's line (any point of a collinear set), the sign
    # of ``left`` is rounding's: the tangent points away from the centroid instead
    ahead = np.einsum("ni,ni->n", axis, to_centre)
    on_line = np.abs(left) <= 1e-9 * np.hypot(to_centre[:, 0], to_centre[:, 1])
    axis = np.where(np.where(on_line, ahead > 0, left < 0)[:, None], -axis, axis)
    return np.arctan2(axis[:, 1], axis[:, 0])


def shape_context(points: np.ndarray) -> np.ndarray:
    """Normalised log-polar histograms, shape (n_points, N_RADII * N_ANGLES).

    Radii are in units of the set's mean pairwise distance (scale invariance), angles are
    measured from each point's tangent (rotation invariance).
    """
    n = points.shape[0]
    diff = points[None, :, :] - points[:, None, :]
    radius = np.hypot(diff[..., 0], diff[..., 1]) / pdist(points).mean()
    angle = (np.arctan2(diff[..., 1], diff[..., 0]) - _tangent_angles(points)[:, None]) % (2 * np.pi)
    edges = np.logspace(np.log10(R_INNER), np.log10(R_OUTER), N_RADII + 1)
    r_bin = np.searchsorted(edges, radius) - 1
    a_bin = np.minimum((angle / (2 * np.pi) * N_ANGLES).astype(np.int64), N_ANGLES - 1)
    valid = (r_bin >= 0) & (r_bin < N_RADII) & ~np.eye(n, dtype=bool)
    rows = np.broadcast_to(np.arange(n)[:, None], (n, n))[valid]
    hist = np.zeros((n, N_RADII * N_ANGLES))
    np.add.at(hist, (rows, r_bin[valid] * N_ANGLES + a_bin[valid]), 1.0)
    return hist / np.maximum(hist.sum(axis=1, keepdims=True), 1.0)


_CHUNK_VALUES = 1 << 22  # histogram bins per temporary block (32 MB of float64)


def _chi2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Chi-squared costs between the rows of ``a`` and of ``b``, in blocks of rows of ``a``
    so that the temporaries stay near 32 MB each (all pairs at once took 1.7 GB for 1000
    points against 1000); each row's sum is the same as without blocks."""
    out = np.empty((a.shape[0], b.shape[0]))
    step = max(1, _CHUNK_VALUES // max(1, b.size))
    for start in range(0, a.shape[0], step):
        block = a[start : start + step, None, :]
        num = (block - b[None, :, :]) ** 2
        den = block + b[None, :, :]
        out[start : start + step] = 0.5 * np.sum(np.divide(num, den, out=np.zeros_like(num), where=den > 0), axis=2)
    return out


_TIE_BREAK = 1e-9


def _radial(points: np.ndarray) -> np.ndarray:
    """Each point's distance to the set's centroid over the mean such distance."""
    radius = np.hypot(*centred(points)[1].T)
    return radius / max(float(radius.mean()), np.finfo(float).tiny)


def shape_context_assignment(moving: np.ndarray, fixed: np.ndarray) -> tuple[np.ndarray, dict]:
    """One-to-one assignment of least chi-squared cost, dummies at ``DUMMY_COST``.

    Returns ``correspondence`` (moving -> fixed, -1 for a dummy) and diagnostics:
    ``mean_cost``, the mean chi-squared cost of the matched pairs (None when every point
    went to a dummy).
    """
    cost = _chi2(shape_context(moving), shape_context(fixed))
    m, f = cost.shape
    padded = np.full((m + f, f + m), DUMMY_COST)
    # Costs of counted histograms tie exactly (several assignments of one total), and the
    # Hungarian algorithm then picks by row order: permuting the inputs changed the pairs
    # (13 of 100 noisy sets). A tie goes to the pairs whose distances to their set's
    # centroid, in units of the set's mean, are closest in the squared sense: invariant to
    # order, pose and scale, and too small (1e-9) to overturn a real difference of counted
    # costs. (Not the absolute difference: its sum is the same for both ways of pairing
    # two and two points on either side of each other, and 8 of the 100 still tied.)
    padded[:m, :f] = cost + _TIE_BREAK * (_radial(moving)[:, None] - _radial(fixed)[None, :]) ** 2
    padded[m:, f:] = 0.0  # dummy-to-dummy is free
    rows, cols = linear_sum_assignment(padded)
    correspondence = np.full(m, -1, dtype=np.int64)
    real = (rows < m) & (cols < f)
    correspondence[rows[real]] = cols[real]
    mean_cost = float(cost[rows[real], cols[real]].mean()) if real.any() else None
    return correspondence, {"mean_cost": mean_cost}

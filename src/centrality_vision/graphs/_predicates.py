"""A check that a triangulation is Delaunay, with in-sphere tests of certain sign.

Qhull decides its in-circle tests in floating point on lifted coordinates, so a set whose
points lie far apart relative to some of their spacings (a tight cluster beside distant
points, about 1e-7 of the set's extent) can come back as a triangulation that is not
Delaunay, without an error. :func:`delaunay_violations` tests every interior facet: the
far vertex of the neighbouring simplex must not lie strictly inside the simplex's
circumsphere (a triangulation whose every facet passes is Delaunay, by Delaunay's lemma).

Each test is a small determinant evaluated in floating point by permutation expansion
about the far vertex, with a bound on its rounding error (Shewchuk's filter idea). Its sign
is certain when the value exceeds that bound and also the change that moving every
coordinate by ``_DATA_ULPS`` units in the last place of its point's magnitude could make
(a first-order bound from the cofactors): coordinates are data, already rounded by the
arithmetic that made them. The same holds for the simplex's orientation. A facet fails when,
seen from either of its two simplices, the far vertex is certainly inside. Anything less
than certain passes: the points are co-spherical, or the simplex flat, to within the
precision of the data, and either triangulation is Delaunay as far as float64 can tell.
Measured: every square of a rotated grid is co-circular, and three points of one of its
rows collinear, only to within a few units in the last place; on 6 of 297 rotated grids
Qhull returned facets that failed the test on the floats as given (in the four examined,
every such facet a triangle flat to within one unit in the last place), while the facets
Qhull gets wrong beside a tight cluster (1e-5 to 1e-9 of the extent) fail it by 2e4 to
4e7 units.
"""

from __future__ import annotations

import itertools

import numpy as np

_EPS = 2.0**-53
# relative error bounds of the expansions below, on the sum of their terms' magnitudes:
# generous over the derivation (about 35 eps for the 4 x 4 lifted determinant: one
# rounding in each difference, five in a lift, three in a product of four, 23 in the sum;
# about 10 eps for the 3 x 3 orientation)
_IN_BOUND, _ORIENT_BOUND = 64 * _EPS, 16 * _EPS
# below this a term may have lost digits to underflow: not certain
_TINY = 1e-290
# the precision of the data: a test whose sign moving each coordinate by this many units in
# the last place (of its point's largest coordinate) could change is not certain
_DATA_ULPS = 16


def _signed_permutations(size: int) -> list[tuple[tuple[int, ...], int]]:
    out = []
    for perm in itertools.permutations(range(size)):
        inversions = sum(perm[i] > perm[j] for i in range(size) for j in range(i + 1, size))
        out.append((perm, -1 if inversions % 2 else 1))
    return out


_PERMUTATIONS = {size: _signed_permutations(size) for size in (1, 2, 3, 4)}


def _expand(matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Determinants of a stack of small matrices, and the sums of their terms' magnitudes."""
    det = np.zeros(matrices.shape[0])
    magnitude = np.zeros(matrices.shape[0])
    for perm, sign in _PERMUTATIONS[matrices.shape[-1]]:
        term = matrices[:, 0, perm[0]].copy()
        for row in range(1, len(perm)):
            term *= matrices[:, row, perm[row]]
        det += sign * term
        magnitude += np.abs(term)
    return det, magnitude


def _cofactor_bound(matrices: np.ndarray, errors: np.ndarray) -> np.ndarray:
    """``sum_ij |C_ij| errors_ij`` (C: cofactors): to first order, the most the determinants
    change when each entry moves by at most ``errors_ij``."""
    size = matrices.shape[-1]
    bound = np.zeros(matrices.shape[0])
    for i in range(size):
        rows = np.delete(matrices, i, axis=1)
        for j in range(size):
            bound += np.abs(_expand(np.delete(rows, j, axis=2))[0]) * errors[:, i, j]
    return bound


def _certainly_inside(corners: np.ndarray, far: np.ndarray) -> np.ndarray:
    """True where ``far[i]`` lies inside the circumsphere of the simplex ``corners[i]``, beyond
    rounding and beyond the data's precision (see the module notes)."""
    dim = corners.shape[2]
    diff = corners - far[:, None, :]
    lifted_rows = np.concatenate([diff, np.sum(diff * diff, axis=2)[:, :, None]], axis=2)
    lifted, lifted_size = _expand(lifted_rows)
    edges = corners[:, 1:, :] - corners[:, :1, :]
    orient, orient_size = _expand(edges)
    certain = np.abs(lifted) > _IN_BOUND * lifted_size + _TINY
    certain &= np.abs(orient) > _ORIENT_BOUND * orient_size + _TINY
    certain &= np.sign(lifted) * np.sign(orient) == _INSIDE[dim]
    candidates = np.flatnonzero(certain)
    if candidates.size:
        # each point known to within _DATA_ULPS units in the last place of its magnitude
        corner_error = _DATA_ULPS * _EPS * np.abs(corners[candidates]).max(axis=2)
        row_error = corner_error + _DATA_ULPS * _EPS * np.abs(far[candidates]).max(axis=1)[:, None]
        lifted_error = np.repeat(row_error[:, :, None], dim + 1, axis=2)
        lifted_error[:, :, dim] = 2 * row_error * np.sum(np.abs(diff[candidates]), axis=2) + dim * row_error**2
        edge_error = np.repeat((corner_error[:, 1:] + corner_error[:, :1])[:, :, None], dim, axis=2)
        # twice the first-order bounds: a margin for the second-order terms and their own rounding
        firm = np.abs(lifted[candidates]) > 2 * _cofactor_bound(lifted_rows[candidates], lifted_error)
        firm &= np.abs(orient[candidates]) > 2 * _cofactor_bound(edges[candidates], edge_error)
        certain[candidates[~firm]] = False
    return certain


def _inside_sign(dim: int) -> float:
    """The sign of (lifted x orientation determinant) for a point inside: from the unit simplex."""
    unit = np.vstack([np.zeros(dim), np.eye(dim)])[None]
    diff = unit - unit[0].mean(axis=0)[None, None, :]
    lifted = _expand(np.concatenate([diff, np.sum(diff * diff, axis=2)[:, :, None]], axis=2))[0][0]
    return float(np.sign(lifted * _expand(unit[:, 1:, :] - unit[:, :1, :])[0][0]))


_INSIDE = {dim: _inside_sign(dim) for dim in (2, 3)}


def delaunay_violations(points: np.ndarray, simplices: np.ndarray, neighbors: np.ndarray) -> int:
    """The number of interior facets of a triangulation that certainly fail the empty-sphere test.

    ``points`` (n, D) with D = 2 or 3; ``simplices`` (T, D + 1) and ``neighbors`` (T, D + 1)
    as in :class:`scipy.spatial.Delaunay` (``neighbors[t, k]``: the simplex across the facet
    opposite vertex ``k``, -1 on the hull). A facet fails when the far vertex of either
    simplex lies inside the other's circumsphere by more than the rounding of the test and
    the data's precision; co-spherical points and flat simplices, exactly or to within
    that, pass.
    """
    simplex, side = np.nonzero(neighbors >= 0)
    other = neighbors[simplex, side]
    far = simplices[other, np.argmax(neighbors[other] == simplex[:, None], axis=1)]
    failed = _certainly_inside(points[simplices[simplex]], points[far])
    # each facet is seen from both sides; it fails once
    facets = np.unique(np.sort(np.column_stack([simplex[failed], other[failed]]), axis=1), axis=0)
    return int(facets.shape[0])

"""What the matching methods share: the result type, unit normalisation, transform algebra."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from ..exceptions import InputError
from ..graphs._entropy import MIN_DISTANCE_RATIO
from ..transforms import SimilarityTransform, least_squares_similarity

__all__ = ["MatchResult", "Normalised", "normalise", "similarity_to_units", "assign_nearest"]


@dataclass(frozen=True, eq=False)
class MatchResult:
    """Correspondences from ``moving`` to ``fixed`` and the similarity transform they give.

    Unpacks as ``correspondence, transform = match(moving, fixed)``, and indexes as that
    pair (``result[0]`` is ``correspondence``, as from :func:`mwme_match`). Two results compare
    (``==``) and hash by identity; compare their arrays to compare what they hold.

    Attributes
    ----------
    correspondence : ndarray of int, shape (n_moving,)
        ``moving[i]`` matches ``fixed[correspondence[i]]``; -1 where ``moving[i]`` has no
        partner (an outlier, or a part missing from ``fixed``).
    transform : SimilarityTransform
        The fitted transform taking ``moving`` onto ``fixed``.
    method : str
    n_matched : int
        Number of moving points with a partner.
    info : dict
        Method-specific diagnostics (e.g. the number of similarity hypotheses tried, the
        inlier count of the best one); for reading, not for computing.

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.matching import match
    >>> rng = np.random.default_rng(0)
    >>> fixed = rng.random((10, 2))
    >>> perm = rng.permutation(10)
    >>> moving = 0.5 * fixed[perm] @ np.array([[0.0, -1.0], [1.0, 0.0]]).T + 3.0
    >>> result = match(moving, fixed, method="mwme")
    >>> result.method, result.n_matched, round(result.transform.scale, 6)
    ('mwme', 10, 2.0)
    >>> correspondence, transform = result  # unpacks as a pair
    >>> result[1] is transform
    True
    >>> bool(np.array_equal(correspondence, perm))
    True
    >>> bool(np.allclose(transform(moving), fixed[correspondence]))
    True
    """

    correspondence: np.ndarray
    transform: SimilarityTransform
    method: str
    n_matched: int
    info: dict = field(default_factory=dict, compare=False)

    def __iter__(self):
        yield self.correspondence
        yield self.transform

    def __len__(self) -> int:
        return 2

    def __getitem__(self, index):
        return (self.correspondence, self.transform)[index]


@dataclass(frozen=True)
class Normalised:
    """Points centred and divided by powers of two (exact), so that every product and sum
    of squares the matching forms stays finite, whatever the input's scale:
    ``x = 2^first (2^second points + centre)``."""

    points: np.ndarray
    centre: np.ndarray
    first: int
    second: int

    @property
    def exponent(self) -> int:
        return self.first + self.second


def normalise(points: np.ndarray) -> Normalised:
    """Centre ``points`` and bring their coordinates into (-1, 1) by exact powers of two."""
    first = int(np.frexp(np.abs(points).max())[1])
    scaled = np.ldexp(points, -first)
    centre = scaled.mean(axis=0)
    centre = centre + (scaled - centre).mean(axis=0)  # second pass: accurate far from the origin
    centred = scaled - centre
    peak = np.abs(centred).max()
    second = int(np.frexp(peak)[1]) if peak > 0 else 0
    return Normalised(np.ldexp(centred, -second), centre, first, second)


#: Smallest distance between two points, relative to the set's diameter, that matching accepts:
#: below it the local graphs' squared distances underflow (the graphs' own limit)
MIN_RELATIVE_SPACING = MIN_DISTANCE_RATIO


def check_resolution(points: np.ndarray, name: str, *, original: np.ndarray) -> None:
    """Refuse a set whose closest points coincide, or nearly, once centred and scaled to
    (-1, 1) (``points``, from :func:`normalise`); ``original``: the set as given, for the message.

    "Nearly" is the graphs' limit: the closest pair within :data:`MIN_RELATIVE_SPACING` of the
    set's diameter, here its bounding box's diagonal (at least the diameter: a set accepted
    here is accepted by the graphs the matchers build on it)."""
    dist, index = cKDTree(points).query(points, k=2)
    row = int(np.argmin(dist[:, 1]))
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    spacing = float(dist[row, 1]) / diagonal if diagonal > 0 else 0.0
    if spacing > MIN_RELATIVE_SPACING:
        return
    other = int(index[row, 1]) if index[row, 1] != row else int(index[row, 0])  # ties at 0: either order
    i, j = sorted((row, other))
    if spacing == 0.0:  # distinct as given (duplicates are refused before), equal once centred
        step = np.abs(original[i] - original[j])
        gap = float(step.max() * np.linalg.norm(step / step.max()))  # no underflow of tiny squares
        magnitude = float(np.abs(original).max())
        ratio = gap / magnitude
        relative = f"{ratio:.1e}" if ratio > 0 else "below 1e-308"  # (the quotient can underflow)
        raise InputError(
            f"`{name}`: rows {i} and {j} are {gap:.3g} apart, at coordinates up to {magnitude:.3g} in size "
            f"(a relative spacing of {relative}); once the set is centred, float64 (resolution about "
            "2e-16 of that size) cannot tell them apart. Drop one of them, or, if the whole set lies far from "
            "the origin, subtract a point near it from all coordinates first."
        )
    raise InputError(
        f"`{name}` has points closer than {MIN_RELATIVE_SPACING:g} times its diameter "
        f"(rows {i} and {j}: {spacing:.3g} of it): float64 cannot tell them apart at this dynamic range; "
        "rescale or deduplicate the points."
    )


def similarity_to_units(rotation, translation, scale, moving: Normalised, fixed: Normalised) -> SimilarityTransform:
    """The transform in the caller's units from ``f = s R m + t`` fitted between normalised sets.

    Substituting ``x = 2^a_m (2^b_m m + c_m)`` and ``y = 2^a_f (2^b_f f + c_f)`` gives
    ``y = s 2^(e_f - e_m) R x + 2^a_f (2^b_f t - 2^(b_f - b_m) s R c_m + c_f)``; every power of
    two is applied with ``ldexp``, so nothing overflows before the final values, which
    must fit in float64.
    """
    rotation = np.asarray(rotation, dtype=float)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):  # checked below, with a named error
        s = float(np.ldexp(scale, fixed.exponent - moving.exponent))
        inner = (
            np.ldexp(np.asarray(translation, dtype=float), fixed.second)
            - np.ldexp(scale * (rotation @ moving.centre), fixed.second - moving.second)
            + fixed.centre
        )
        translation_units = np.ldexp(inner, fixed.first)
    if not (np.isfinite(s) and s > 0 and np.all(np.isfinite(translation_units))):
        raise InputError(
            "`moving` and `fixed` differ in scale or position beyond float64: the fitted transform "
            "overflows; rescale them."
        )
    return SimilarityTransform(rotation, translation_units, s)


def fit_pairs(moving: np.ndarray, fixed: np.ndarray, *, scale: bool = True):
    """Least-squares ``(R, t, s)`` between paired, finite, normalised rows."""
    return least_squares_similarity(moving, fixed, scale=scale)


def assign_nearest(moved: np.ndarray, fixed_tree: cKDTree, radius: float) -> np.ndarray:
    """Each moved point's nearest fixed point, or -1 when it is farther than ``radius``."""
    dist, index = fixed_tree.query(moved)
    return np.where(dist <= radius, index, -1).astype(np.int64)


#: With ``scale=False``, the largest ratio (as a power of two) between the extents of the two
#: sets: beyond it squared distances of the unscaled set overflow float64.
MAX_RIGID_EXPONENT = 300


def check_rigid_extents(norm_m: Normalised, norm_f: Normalised) -> None:
    """Refuse a rigid fit (``scale=False``) between sets whose extents differ beyond
    :data:`MAX_RIGID_EXPONENT` powers of two."""
    gap = abs(norm_m.exponent - norm_f.exponent)
    if gap > MAX_RIGID_EXPONENT:
        raise InputError(
            f"`scale=False` needs `moving` and `fixed` of comparable extent; their extents differ by a factor "
            f"2^{gap} (more than 2^{MAX_RIGID_EXPONENT}), so a rigid transform cannot bring one onto the other "
            "(and its squared distances overflow); use `scale=True`."
        )

"""One entry point for point-set matching: ``match(moving, fixed, method=...)``."""

from __future__ import annotations

import numpy as np

from .._deprecation import renamed_parameters
from .._validation import as_points, check_bool, check_choice, check_float, check_int
from .._warnings import warn
from ..exceptions import InputError, MatchingWarning
from ..transforms import RigidTransform, SimilarityTransform
from ._common import (
    MatchResult,
    check_resolution,
    check_rigid_extents,
    fit_pairs,
    normalise,
    similarity_to_units,
)

__all__ = ["METHODS", "match"]


def _rigid_if_unscaled(transform, scale) -> SimilarityTransform:
    """A :class:`RigidTransform` when ``scale`` is False (the fitted scale is then exactly 1)."""
    if scale or isinstance(transform, RigidTransform) or transform.scale != 1.0:
        return transform
    return RigidTransform(transform.rotation, transform.translation)


#: The methods :func:`match` offers.
METHODS = ("robust", "mwme", "shape-context")


# a similarity that explains this much more of the sets than the rigid fit, at a scale this
# far from 1, means the sets are not congruent and the rigid pairs are unreliable
_SCALED_CONSENSUS, _SCALED_RATIO = 1.1, 1.05


def _warn_unless_pairs_agree(moving, partners, rot, t, s) -> None:
    """Shape contexts pair points by their descriptors alone: on a symmetric set (a regular
    polygon, a grid) several pairings tie and the assignment may mix them, and the
    least-squares pose of mixed pairs shrinks towards the centroid (an exact copy of an
    octagon at scale 0.5 came back at 0.125). Say so when the pose brings the pairs less
    than halfway together: their residuals hold more than half the partners' spread
    (under noise or resampling the pairs are off by a few sampling steps, a few percent)."""
    residual = float(np.sum((s * moving @ rot.T + t - partners) ** 2))
    spread = float(np.sum((partners - partners.mean(axis=0)) ** 2))
    if residual > 0.5 * spread:
        warn(
            f"shape-context matching: the transform fitted to the {moving.shape[0]} matched pairs leaves "
            f"{min(residual / max(spread, np.finfo(float).tiny), 99.0):.0%} of the fixed partners' spread "
            "unexplained: many pairs join unrelated points (a symmetric set, whose pairings tie; noise, clutter "
            "or missing parts that change the descriptors), and the transform, fitted to them all, is not "
            "reliable. match's `method='robust'` scores poses on all points.",
            MatchingWarning,
        )


def _three_d(points) -> bool:
    """Whether ``points`` has the shape of a 3D point set (for a hint in an error)."""
    try:
        shape = np.shape(points)
    except ValueError:  # ragged
        return False
    return len(shape) == 2 and shape[1] == 3


def _warn_if_scaled(info: dict) -> None:
    ratio, rigid, similar = info["similarity_scale"], info["refined_consensus"], info["similarity_consensus"]
    if similar > _SCALED_CONSENSUS * rigid and max(ratio, 1 / ratio) > _SCALED_RATIO:
        warn(
            f"The sets seem to differ in scale: a similarity transform of scale {ratio:.3g} brings "
            f"{similar:g} points into agreement where the rigid fit brings {rigid:g}. A rigid "
            "transform cannot align them and its correspondences are not reliable; use `scale=True`.",
            MatchingWarning,
        )


@renamed_parameters(n_neighbours="n_neighbors", outlier_weight="w", mwme_method="mwme_solver")
def match(
    moving,
    fixed,
    /,
    *,
    method: str = "robust",
    scale: bool = True,
    n_neighbors: int = 8,
    n_candidates: int = 6,
    refine: str = "icp",
    w: float = 0.3,
    mwme_solver: str = "local",
) -> MatchResult:
    """Correspondences from ``moving`` to ``fixed`` and the similarity transform between them.

    Parameters
    ----------
    moving, fixed : array_like of shape (n_points, 2)
        Point sets, possibly of different sizes, with outliers or missing parts (except for
        ``method="mwme"``); at least 4 distinct points each. ``"mwme"`` also takes 3D sets.
    method : {"robust", "mwme", "shape-context"}, default="robust"
        ``"robust"``: MWME graphs of every point's neighbourhood as rotation- and
        scale-invariant signatures, one similarity hypothesis per likely pair, the
        hypothesis most points agree with (a one-pair RANSAC scored on all points), refined
        by trimmed nearest-neighbour fits (and CPD with ``refine="cpd"``); each moving point
        then takes its nearest fixed point within two sampling steps, else -1 (see
        :mod:`centrality_vision.matching._robust`).
        ``"mwme"``: the thesis' global MWME matching (:func:`mwme_match`): exact under
        similarity transforms of the same points, but needs sets of equal size and breaks
        under noise or resampling (a ``MatchingWarning`` then says so).
        ``"shape-context"``: the baseline: Belongie et al.'s log-polar shape contexts
        (angles from each point's tangent), chi-squared costs and a one-to-one Hungarian
        assignment (:func:`scipy.optimize.linear_sum_assignment`) with dummy partners
        of cost 0.25 for unmatched points; the transform is fitted to the pairs, and a
        ``MatchingWarning`` says when it leaves more than half the partners' spread
        unexplained (symmetric sets, whose pairings tie; on the matching benchmark's
        outlines it warned for 10 of 68 resampled copies, 49 of 68 at noise 0.02). The
        assignment is square in ``m + f`` points: memory grows as ``(m + f)^2`` and time
        as ``(m + f)^3`` (measured on 2 cores: 1.4 s and 0.3 GB for 1000 points against
        1000, 3.3 s and 0.4 GB for 2000 against 2000).
    scale : bool, default=True
        Fit a similarity (True) or a rigid transform (False; the result's ``transform`` is
        then a :class:`~centrality_vision.transforms.RigidTransform`). A rigid fit of sets
        that differ in scale pairs unrelated points; ``"robust"`` then also scores the
        similarity hypotheses and a ``MatchingWarning`` says so when one at a scale more than
        5% from 1 brings 10% more points into agreement (measured: copies scaled by 0.7, 1.1
        and 1.5 warn; 30 rigid copies with noise up to 0.02 and up to a third missing do not).
    n_neighbors : int in [3, 19], default=8
        ``"robust"``: neighbours in each local MWME graph. Each signature is an exact
        MWME graph of ``n_neighbors + 1`` points, whose cost doubles with every
        neighbour: two 40-point sets take about 0.3 s at 8 and 20 s at 19 (measured
        on 2 cores).
    n_candidates : int >= 1, default=6
        ``"robust"``: likely partners (hence hypotheses) per moving point.
    refine : {"icp", "cpd"}, default="icp"
        ``"robust"``: the refinement after consensus: trimmed nearest-neighbour similarity
        fits alone, or followed by similarity CPD with outlier weight ``w``.
        CPD suits whole sets: its mixture, centred on the moving points, is pulled towards
        fixed points that have no partner, so a part missing from ``moving`` skews the pose.
    w : float in [0, 1), default=0.3
        The CPD outlier weight for ``refine="cpd"`` (``w`` of
        :class:`~centrality_vision.registration.RigidCPD`). When CPD's pose brings fewer than 3/4 as
        many points into agreement as the consensus pose it started from (a collapse: weights
        near 1 let CPD shrink the set onto a few points), the consensus pose is kept and a
        ``MatchingWarning`` says so; ``info["cpd_kept"]`` records which was kept.
    mwme_solver : {"local", "greedy", "exact"}, default="local"
        ``"mwme"``: the MWME solver (``solver`` of
        :func:`~centrality_vision.matching.mwme_match`; formerly ``mwme_method``).

    Returns
    -------
    MatchResult
        Unpacks as ``correspondence, transform``: ``moving[i]`` matches
        ``fixed[correspondence[i]]`` (-1: unmatched), and ``transform`` takes ``moving``
        onto ``fixed``.

    Notes
    -----
    .. versionchanged:: 0.1.0
       ``n_neighbours`` and ``outlier_weight`` are now ``n_neighbors`` and ``w``, the
       estimators' names; the former names still work, with a FutureWarning.

    Examples
    --------
    A rotated, scaled and shifted outline, resampled elsewhere along the contour, with a
    third of it missing and 20 outliers added:

    >>> import numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    >>> outline = lambda u: np.c_[np.cos(u) * (1 + 0.3 * np.cos(3 * u)), np.sin(u) * (1 + 0.3 * np.cos(3 * u))]
    >>> fixed = outline(t)
    >>> angle = 1.0
    >>> rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    >>> kept = outline(t[:55] + 0.5 * (t[1] - t[0]))
    >>> noise = np.random.default_rng(0).uniform(-1.5, 1.5, (20, 2))
    >>> moving = 2.0 * np.vstack([kept, noise]) @ rot.T + [5.0, -3.0]
    >>> result = match(moving, fixed)
    >>> round(result.transform.scale, 2)
    0.5
    >>> truth = result.transform(moving[:55])
    >>> bool(np.all(np.linalg.norm(fixed[result.correspondence[:55]] - truth, axis=1) < t[1]))
    True
    """
    method = check_choice(method, METHODS, name="method")
    check_bool(scale, name="scale")
    # every option is checked whatever the method, so a typo is caught before it matters
    mwme_solver = check_choice(mwme_solver, ("local", "greedy", "exact"), name="mwme_solver")
    n_neighbors = check_int(n_neighbors, name="n_neighbors", low=3, high=19)
    n_candidates = check_int(n_candidates, name="n_candidates", low=1)
    refine = check_choice(refine, ("icp", "cpd"), name="refine")
    w = check_float(w, name="w", low=0.0, high=1.0, high_open=True)
    if method == "mwme":
        from ..graphs._entropy import MAX_EXACT
        from ._mwme import mwme_match

        moving_arr = as_points(moving, name="moving", n_dims=(2, 3), min_points=3, allow_duplicates=False)
        if mwme_solver == "exact" and moving_arr.shape[0] > MAX_EXACT:
            raise InputError(
                f"`mwme_solver='exact'` solves sets of up to {MAX_EXACT} points (time and memory grow as 2^n n); "
                f"`moving` has {moving_arr.shape[0]}. Use `mwme_solver='local'` or `mwme_solver='greedy'`."
            )
        correspondence, transform = mwme_match(moving_arr, fixed, solver=mwme_solver, scale=bool(scale))
        transform = _rigid_if_unscaled(transform, scale)
        return MatchResult(correspondence, transform, method, int(moving_arr.shape[0]), {"mwme_solver": mwme_solver})
    try:
        moving = as_points(moving, name="moving", n_dims=(2,), min_points=4, allow_duplicates=False)
        fixed = as_points(fixed, name="fixed", n_dims=(2,), min_points=4, allow_duplicates=False)
    except InputError as exc:
        if any(_three_d(points) for points in (moving, fixed)):
            raise InputError(f"{exc} method={method!r} matches 2D sets; method='mwme' matches 3D ones.") from None
        raise
    norm_m, norm_f = normalise(moving), normalise(fixed)
    for name, norm in (("moving", norm_m), ("fixed", norm_f)):
        check_resolution(norm.points, name, original=moving if name == "moving" else fixed)
    if not scale:
        check_rigid_extents(norm_m, norm_f)
    # scale 1 in the caller's units (used by rigid fits only; with scale=True it may overflow)
    unit_ratio = 1.0 if scale else float(np.ldexp(1.0, norm_m.exponent - norm_f.exponent))
    if method == "robust":
        from ._robust import robust_pose

        rot, t, s, correspondence, info = robust_pose(
            norm_m.points,
            norm_f.points,
            n_neighbors=n_neighbors,
            n_candidates=n_candidates,
            refine=refine,
            scale=bool(scale),
            unit_ratio=unit_ratio,
            w=w,
        )
    else:
        from ._shape_context import shape_context_assignment

        correspondence, info = shape_context_assignment(norm_m.points, norm_f.points)
        pairs = correspondence >= 0
        if pairs.sum() < 2:
            warn(
                f"shape-context matching paired {int(pairs.sum())} point(s): too few to fit a transform; the "
                "transform returned only maps the centre of `moving` onto that of `fixed` and means nothing.",
                UserWarning,
            )
            rot, t, s = np.eye(2), np.zeros(2), 1.0
        else:
            rot, t, s = fit_pairs(norm_m.points[pairs], norm_f.points[correspondence[pairs]], scale=bool(scale))
        if not scale:
            s = unit_ratio
            if pairs.sum() >= 2:
                t = norm_f.points[correspondence[pairs]].mean(axis=0) - s * rot @ norm_m.points[pairs].mean(axis=0)
        if pairs.sum() >= 2:
            _warn_unless_pairs_agree(norm_m.points[pairs], norm_f.points[correspondence[pairs]], rot, t, s)
    transform = _rigid_if_unscaled(similarity_to_units(rot, t, s, norm_m, norm_f), scale)
    if method == "robust" and not scale:
        _warn_if_scaled(info)
    if method == "robust" and refine == "cpd" and not info["cpd_kept"]:
        warn(
            f"`refine='cpd'` with `w={w:g}` ended in a pose that brings "
            f"{info['cpd_consensus']:g} points into agreement where the consensus pose it started from "
            f"brings {info['refined_consensus']:g}: CPD's result was dropped and the consensus pose kept. "
            "A lower `w` lets CPD refine it.",
            MatchingWarning,
        )
    return MatchResult(correspondence, transform, method, int(np.sum(correspondence >= 0)), info)

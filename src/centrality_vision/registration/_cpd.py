"""Coherent Point Drift: rigid/similarity, affine and non-rigid, on one shared EM loop.

Conventions every variant shares:

* ``fit(moving, fixed)``: the moving set Y (M x D) is transformed onto the fixed set X
  (N x D); points are rows, a transform maps ``y -> L y + t`` as ``Y @ L.T + t``.
* The E-step is CPD's (Myronenko and Song 2010): a Gaussian mixture with one component of
  variance sigma2 per transformed moving point and a uniform outlier component of weight
  ``w``, ``P(m | x_n) = exp(-|x_n - T(y_m)|^2 / 2 sigma2) / (sum_k exp(...) + c)`` with
  ``c = (2 pi sigma2)^(D/2) w / (1 - w) M / N``, computed in log space.
* D is the dimension the sets span: a set with no extent along some direction (an outline
  with ``z = 0`` in 3D, a plane, a line; a principal side below 1/1000 of its longest) is a
  set of fewer dimensions, and where the two sets together (each centred) span only d of
  the coordinates' D dimensions the mixture is a density within d dimensions: ``c`` and
  the objective take d, and sigma2 is the residual per spanned dimension (the M-steps'
  ``sum P |x - T(y)|^2 / (Np d)``). A 2D problem lifted into any plane of 3D then registers
  as it does in 2D (with D = 3, sigma2 was 2/3 of the residual in the plane, and w='auto'
  read the narrower fit as outliers: the fish with 20 clutter points, lifted, collapsed).
  Sets that span more together than apart (two lines at an angle, planes at an angle, a 3D
  blob onto a line) keep the larger d: their residual off each other is real. The cut at
  1/1000 is sharp: a planar scan 1/100 thick is a 3D set, whose sigma2 averages the
  residual over all three coordinates, 2/3 of the residual in its plane. w='auto''s box
  floors its thin side at the Gaussians' width (see :func:`_box_sides`): rigid fits of
  such scans with clutter find the pose as the flat ones do. What remains is the narrower
  sigma2: a non-rigid fit of such a scan is regularised less than the flat one, and a
  rigid w='auto' fit whose model does not fit the data (a rigid fit of the bent CPD fish
  with clutter, 1/1000 thick) reads the residual as outliers and collapses, as the flat
  one did before d was taken; a remedy is a separate variance across the thin direction.
* ``normalize=True`` (the default): inside ``fit`` each set is centred on its own mean and
  both are divided by one common factor, the RMS distance of all M + N points to their
  set's mean, so the EM runs on sets of unit RMS radius whatever the caller's units and
  offset. ``beta``, ``lam``, ``sigma2`` (the initial variance) and ``w`` are read in that
  frame, which makes their defaults unit-free; every fitted transform, point set, variance
  and history entry is mapped back to the caller's units. Because the sets start with their
  means on top of each other, the initial pose is "centroids aligned" rather than the
  identity (pass ``init=`` to start elsewhere); a similarity or affine fit also starts at
  the ratio of the sets' RMS radii as its scale, as CPD's separate normalisation of each
  set does, so sets in different units (metres and centimetres) register. The
  k-nearest-neighbour E-step
  (``n_neighbors``) trusts the caller's pose instead: both sets are centred on the fixed
  set's mean and divided by the moving set's RMS radius alone, so that clutter in the
  fixed set does not widen ``beta`` (on the fish with as many uniform outliers as points,
  mean error 0.0104 against 0.0127 with the radius of both sets).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, replace

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from .._seeding import as_generator
from .._validation import ANY_DIMS, as_points, check_bool, check_choice, check_float, check_int, counted
from .._warnings import warn
from ..exceptions import CollapseWarning, ConvergenceWarning, InputError
from ..transforms import (
    AffineTransform,
    NonRigidTransform,
    RigidTransform,
    SimilarityTransform,
    _centred,
    centred,
    power_of_two_scale,
    proper_rotation,
    rms_radius,
)
from ._estep import (
    E_STEP_METHODS,
    PRECISIONS,
    CentralityPrior,
    EStepPlanner,
    _e_step,
    dense_posterior,
    fixed_to_moving,
    knn_posterior,
    knn_posterior_matrix,
)
from ._mstep import LowRankKernel, affine_m_step, gaussian_kernel, kernel_times, nonrigid_m_step, rigid_m_step

__all__ = ["RigidCPD", "AffineCPD", "NonRigidCPD", "IterationInfo", "Snapshots", "initial_sigma2", "alignment_error"]

# sigma2 below this fraction of the data's spread means the sets coincide: stop, converged.
_SIGMA2_FLOOR = 1e-14
#: The smallest extent of unnormalised data: sigma2, of the order of its square, must stay
#: above the 1e-280 that keeps 1 / (2 sigma2) finite.
_UNNORMALIZED_MIN_SPAN = 1e-135
# The common scale factor must keep sigma2 = scale^2 sigma2_normalised representable; the
# normalised sigma2 can reach about 1e12 (a fixed set up to _FRAME_RATIO times the moving set's
# radius), hence 1e145 rather than 1e154.
_SCALE_RANGE = (1e-145, 1e145)
# With ``moving_scale`` the frame's scale is the moving set's RMS radius unless the fixed
# set's is this many times larger (then both sets' radius: the coordinates stay moderate).
_FRAME_RATIO = 1e6
# A transformed moving set whose RMS radius falls below this fraction of both sets' radii
# has collapsed to a blob.
_COLLAPSE_RADIUS = 0.05
# ... or when the matched mass Np ends below this fraction of the (1 - w) min(M, N) expected.
_COLLAPSE_MATCHED = 0.25
# ... or below this fraction of D matched points (D fix a pose in D dimensions).
_COLLAPSE_MATCHED_DIMS = 0.75
# ... or, under w="auto" (whose estimate follows the matched mass, so expects what it gets),
# below this fraction of min(M, N): exact similarity copies in a wrong basin ended with 3 to 5
# of 20 to 60 points matched exactly and w_ at 0.85 to 0.9, "converged"; sound fits with twice
# as many outliers as points match 0.9 to 1 of the moving set.
_COLLAPSE_MATCHED_AUTO = 0.15
# ... or, in a fit that converged, when the Gaussians' RMS radius sqrt(D sigma2) ends this many
# times the transformed moving set's: each Gaussian spans the whole set, which explains the
# fixed set as one blob. Measured on 52 failed similarity and affine fits (2D outlines and the
# bunny; moving sets with a missing part and far outliers of their own): 20 end above 2.5
# times, up to 55. Sound fits end below 1.5 times (1.4 with Gaussian noise of the shape's own
# RMS radius per axis), and fits with noise 1.5 times that radius, whose rotation is still
# within 10 degrees, at up to 2.25 times.
_COLLAPSE_SPREAD = 2.5
# accelerate: an extrapolated sigma2 stays within this factor of the plain step's.
_SIGMA_JUMP = 0.25
# A given sigma2 may be at most this many times the sets' own spread (beyond, every posterior
# is already uniform, and its products overflow).
_SIGMA2_MAX = 1e10
# The largest landmark_weight: the pinned pairs' residual grows about as the weight times
# float64's rounding (1e-11 of the extent at 1e6; 2e-5 at 1e12, and 1e100 gave a
# scale of 3.6e16 reported as converged).
_LANDMARK_WEIGHT_MAX = 1e6
# A principal side below this share of a set's longest is a direction the set does not
# span (see _model_dims).
_THIN_SIDE = 1e-3
# w="auto": a side of the outlier box up to _BOX_FLOORED_SIDE of the longest is floored at
# the Gaussians' width, one from there to _BOX_THIN_SIDE at a floor falling to 0 (see
# _box_sides); longer sides are the set's extent.
_BOX_FLOORED_SIDE, _BOX_THIN_SIDE = 0.1, 0.2
# w="auto": start and bounds of the estimated outlier fraction.
_AUTO_W_START, _AUTO_W_MAX = 0.1, 0.9
# ... and the most the E-step's w may take from it (odds of 1e12 to 1)
_AUTO_W_E_MAX = 1.0 - 1e-12
# What one EM run of ``_run`` sets: w='auto' keeps one of two runs.
_FITTED = (
    "transform_",
    "moving_transformed_",
    "sigma2_",
    "n_iter_",
    "converged_",
    "w_",
    "history_",
    "fixed_to_moving_",
    "posteriors_",
    "_posterior_state",
)


@dataclass(frozen=True)
class IterationInfo:
    """What a ``callback`` receives after each E-step (iteration 0 is the initial state).

    Everything is in the caller's units (also under ``normalize=True``).

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.registration import RigidCPD
    >>> y = np.random.default_rng(0).random((20, 2))
    >>> seen = []
    >>> def watch(info):
    ...     seen.append(info)
    ...     return info.iteration == 3  # True stops the fit
    >>> reg = RigidCPD(callback=watch).fit(y, y + 0.1)
    >>> [info.iteration for info in seen], reg.n_iter_, reg.converged_
    ([0, 1, 2, 3], 3, False)
    >>> sigma2 = [info.sigma2 for info in seen]
    >>> sigma2 == sorted(sigma2, reverse=True), seen[-1].moving_transformed.shape
    (True, (20, 2))
    >>> type(seen[-1].transform).__name__, seen[-1].error  # error needs ``true_moving``
    ('SimilarityTransform', None)
    """

    iteration: int
    transform: object
    moving_transformed: np.ndarray
    sigma2: float
    objective: float
    error: float | None


class Snapshots:
    """A ``callback`` that keeps the moving set at chosen iterations (for thesis figs. 5.4, 5.5, 5.7).

    ``frames`` maps each recorded iteration to a copy of the moving points; the final state is
    always kept too, so a method that converged early still has a last frame.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((30, 2))
    >>> snaps = Snapshots([0, 2])
    >>> reg = RigidCPD(tol=1e-3, callback=snaps).fit(y, y + 0.1)
    >>> sorted(snaps.frames)[:2]
    [0, 2]
    """

    def __init__(self, iterations):
        if isinstance(iterations, (str, bytes)) or not hasattr(iterations, "__iter__"):
            raise TypeError(f"`iterations` must be a sequence of ints; got {iterations!r}.")
        self.iterations = {check_int(i, name="iterations[i]", low=0) for i in iterations}
        self.frames = {}
        self._last = None

    def __call__(self, info: IterationInfo):
        if self._last is not None and self._last not in self.iterations:
            self.frames.pop(self._last, None)  # an earlier "last" frame that was not asked for
        self.frames[info.iteration] = info.moving_transformed
        self._last = info.iteration


def initial_sigma2(moving, fixed) -> float:
    """CPD's starting variance ``sum_mn |x_n - y_m|^2 / (D M N)``, in O((M + N) D).

    Parameters
    ----------
    moving : array_like of shape (M, D)
        The moving set (CPD's Y), D from 1 to 64.
    fixed : array_like of shape (N, D)
        The fixed set (CPD's X), of the same D.

    Returns
    -------
    float
        The mean squared distance over all (moving, fixed) pairs, divided by D.

    Raises
    ------
    InputError
        When that value is beyond float64 (rescale the sets).

    Examples
    --------
    >>> initial_sigma2([[0.0, 0.0]], [[3.0, 4.0]])
    12.5

    (A fit starts from this value times ``D / d`` where the sets span only ``d`` of the D
    dimensions; see the module docstring.)
    """
    moving = as_points(moving, name="moving", n_dims=ANY_DIMS)
    fixed = as_points(fixed, name="fixed", n_dims=(moving.shape[1],))
    sigma2 = _initial_sigma2(moving, fixed)
    if not math.isfinite(sigma2):
        raise InputError(
            "`moving` and `fixed` must lie close enough for their mean squared distance to fit in "
            "float64; it is beyond float64. Rescale the sets (the estimators do so themselves with normalize=True)."
        )
    return sigma2


def _initial_sigma2(moving, fixed) -> float:
    """:func:`initial_sigma2` of checked arrays (a fit calls it three times); inf where the
    value is beyond float64. The sets are divided by a power of two (exactly) so that no
    intermediate square overflows."""
    centre = centred(fixed)[0]
    with np.errstate(over="ignore", invalid="ignore"):
        x, y = fixed - centre, moving - centre
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            return math.inf
        unit = max(power_of_two_scale(x), power_of_two_scale(y))
        x, y = x / unit, y / unit
        n_fixed, n_moving, n_dims = x.shape[0], y.shape[0], x.shape[1]
        total = n_moving * np.sum(x * x) + n_fixed * np.sum(y * y) - 2.0 * x.sum(axis=0) @ y.sum(axis=0)
        sigma2 = float(total / (n_dims * n_moving * n_fixed)) * unit * unit
    return sigma2 if math.isfinite(sigma2) else math.inf


def alignment_error(true_moving, moving_transformed) -> float:
    """``|X - T(Y)|``: the Frobenius norm over known correspondences (thesis figs. 5.3, 5.6, 5.8).

    Parameters
    ----------
    true_moving : array_like of shape (M, D)
        Where each moving point truly belongs in the fixed frame (D from 1 to 64).
    moving_transformed : array_like of shape (M, D)
        The transformed moving points, row ``i`` paired with row ``i`` of ``true_moving``.

    Returns
    -------
    float
        ``sqrt(sum |true_moving - moving_transformed|^2)`` over all rows, in the caller's units.

    Examples
    --------
    >>> alignment_error([[0.0, 0.0], [1.0, 1.0]], [[0.0, 0.0], [1.0, 2.0]])
    1.0
    """
    a = as_points(true_moving, name="true_moving", n_dims=ANY_DIMS)
    b = as_points(moving_transformed, name="moving_transformed", n_dims=(a.shape[1],))
    if a.shape != b.shape:
        raise InputError(f"`true_moving` must have the shape of the moving set {b.shape}; got {a.shape}.")
    unit = max(power_of_two_scale(a), power_of_two_scale(b))  # exact: no square can overflow
    with np.errstate(over="ignore"):
        error = float(np.linalg.norm(a / unit - b / unit)) * unit
    if not math.isfinite(error):
        raise InputError("The alignment error between `true_moving` and `moving_transformed` is beyond float64.")
    return error


def nearest_score(estimator, moving, fixed) -> float:
    """``score`` of a fitted registration estimator: minus the mean distance from each fixed
    point to its nearest point of ``estimator.transform_(moving)``, in the caller's units."""
    from scipy.spatial import cKDTree

    check_is_fitted(estimator, "transform_")
    moved = estimator.transform_(as_points(moving, name="moving", n_dims=ANY_DIMS))
    fixed = as_points(fixed, name="fixed", n_dims=(moved.shape[1],))
    unit = max(power_of_two_scale(moved), power_of_two_scale(fixed))  # exact: no square overflows
    mean = float(np.mean(cKDTree(moved / unit).query(fixed / unit, k=1)[0])) * unit
    if not math.isfinite(mean):
        raise InputError("The mean distance from `fixed` to the transformed `moving` is beyond float64.")
    return -mean


# --------------------------------------------------------------------- the normalised frame
def _start_within_reach(frame, init, moving_n: np.ndarray, name: str):
    """``init`` in the normalised frame, checked to keep the moving set within reach.

    The normalised frame has unit radius: a start that puts the moving set more than
    ``_SCALE_RANGE[1]`` radii away would overflow sigma2 and the M-step's moments (CPD), or
    every nearest-neighbour distance (ICP)."""
    try:
        with np.errstate(all="ignore"):
            start = frame.linear_in(init)
            reach = float(np.max(np.abs(start(moving_n)))) if moving_n.size else 0.0
    except InputError:  # the transform's result overflows float64
        reach = math.inf
    if not reach <= _SCALE_RANGE[1]:
        raise InputError(
            f"`{name}` must bring the moving set within {_SCALE_RANGE[1]:g} radii of the fixed set "
            f"(the data's scale); it maps it {reach:.3g} radii away. Check its scale and translation."
        )
    return start


@dataclass(frozen=True)
class _Frame:
    """``y_n = (y - moving_centre) / scale`` and ``x_n = (x - fixed_centre) / scale``."""

    moving_centre: np.ndarray
    fixed_centre: np.ndarray
    scale: float

    @staticmethod
    def of(
        moving: np.ndarray,
        fixed: np.ndarray,
        normalize: bool,
        *,
        same_centre: bool = False,
        moving_scale: bool = False,
        posed: np.ndarray | None = None,
    ):
        """The frame and both sets in it (without ``normalize``: a translation only, scale 1).

        The common scale is the RMS radius of all M + N points about their centres, or
        with ``moving_scale`` the moving set's alone (the model's: clutter or missing parts
        of the fixed set then do not change what ``beta`` means), except where the moving
        set is one point repeated, or the fixed set's radius or the moving set's distance from
        the fixed set's centre exceeds ``_FRAME_RATIO`` times the moving set's radius (then
        the RMS radius of both about the fixed set's centre, so that no coordinate can
        overflow). With ``moving_scale`` the moving set is taken where the start puts it:
        ``posed`` (the caller's pose when None).
        ``same_centre`` centres both sets on the fixed set's mean (a start pose unchanged).
        """
        if not normalize:
            with np.errstate(over="ignore", invalid="ignore"):
                span = float(
                    np.max(
                        np.maximum(moving.max(axis=0), fixed.max(axis=0))
                        - np.minimum(moving.min(axis=0), fixed.min(axis=0))
                    )
                )
            largest = max(float(np.max(np.abs(moving))), float(np.max(np.abs(fixed))))
            if not max(span, largest) <= _SCALE_RANGE[1]:
                # (squared distances and coordinates, and so sigma2 and the M-step's moments,
                # would overflow to inf)
                raise InputError(
                    f"`moving` and `fixed` must have coordinates at most {_SCALE_RANGE[1]:g} in absolute "
                    f"value with `normalize=False` (their squares must fit in float64); got "
                    f"{max(span, largest):.3g}. Use normalize=True."
                )
            if 0.0 < span < _UNNORMALIZED_MIN_SPAN:
                # (sigma2 then falls below the floor kept for 1 / (2 sigma2): the fit stopped at
                # the start pose as if the sets coincided, "converged")
                raise InputError(
                    f"`moving` and `fixed` must span at least {_UNNORMALIZED_MIN_SPAN:g} with "
                    f"`normalize=False` (their squared distances must stay normal floats); got "
                    f"{span:.3g}. Use normalize=True."
                )
        mu_x, xc = _centred(fixed, "fixed")
        if not normalize:
            # Both sets are still moved by one common translation, the fixed set's mean: that
            # keeps every parameter in the caller's units and the caller's pose as the start,
            # but the M-step's moments then do not cancel far from the origin (the fish at an
            # offset of 1e8: rigid CPD stopped after one iteration 3.8 off, non-rigid 0.63).
            return _Frame(mu_x, mu_x, 1.0), _shifted(moving, mu_x), xc
        if same_centre:
            mu_y = mu_x
            yc = _shifted(moving, mu_x)
        else:
            mu_y, yc = _centred(moving, "moving")
        sized = yc  # the moving set as the scale sees it
        r_moving = r_fixed = 0.0
        if moving_scale:  # the moving set's radius about its own mean
            r_moving, r_fixed = rms_radius(moving), rms_radius(fixed)
            # (where the start puts it: far from the fixed set's centre, its coordinates in
            # units of its own radius could overflow when squared)
            sized = _shifted(moving if posed is None else posed, mu_x)
        if (
            moving_scale
            and r_moving > 0.0
            and r_fixed <= _FRAME_RATIO * r_moving
            and float(np.max(np.abs(sized))) <= _FRAME_RATIO * r_moving
        ):
            scale = r_moving
        else:
            unit = max(power_of_two_scale(sized), power_of_two_scale(xc))
            total = float(np.sum((sized / unit) ** 2) + np.sum((xc / unit) ** 2))
            scale = unit * math.sqrt(total / (moving.shape[0] + fixed.shape[0]))
        if scale == 0.0:
            scale = 1.0  # every point of both sets is the same point: only a translation is left
        elif not _SCALE_RANGE[0] <= scale <= _SCALE_RANGE[1]:
            raise InputError(
                f"`moving` and `fixed` must have an RMS radius between {_SCALE_RANGE[0]:g} and {_SCALE_RANGE[1]:g} "
                f"(their variance must fit in float64); got {scale:.3g}."
            )
        return _Frame(mu_y, mu_x, scale), yc / scale, xc / scale

    @property
    def identity(self) -> bool:
        return self.scale == 1.0 and not np.any(self.moving_centre) and not np.any(self.fixed_centre)

    def points_out(self, points_n: np.ndarray) -> np.ndarray:
        """Points of the normalised fixed frame in the caller's units."""
        return points_n if self.identity else points_n * self.scale + self.fixed_centre

    def fixed_in(self, points: np.ndarray) -> np.ndarray:
        return points if self.identity else (points - self.fixed_centre) / self.scale

    def true_in(self, true_moving):
        """``true_moving`` in the normalised frame (None stays None), refused by name when it
        lies so far from the data that the errors recorded against it would overflow."""
        if true_moving is None:
            return None
        with np.errstate(over="ignore", invalid="ignore"):
            true_n = self.fixed_in(true_moving)
            reach = float(np.max(np.abs(true_n))) if true_n.size else 0.0
        if not reach <= _SCALE_RANGE[1]:
            raise InputError(
                f"`true_moving` must lie within {_SCALE_RANGE[1]:g} radii of the fixed set (the data's scale); it "
                f"reaches {reach:.3g} radii. Check its units."
            )
        return true_n

    def linear_in(self, transform):
        """A caller-units similarity or affine transform as a map of the normalised frame."""
        linear = (
            transform.scale * transform.rotation if isinstance(transform, SimilarityTransform) else transform.linear
        )
        translation = (linear @ self.moving_centre + transform.translation - self.fixed_centre) / self.scale
        if isinstance(transform, RigidTransform):
            return RigidTransform(transform.rotation, translation)
        if isinstance(transform, SimilarityTransform):
            return SimilarityTransform(transform.rotation, translation, transform.scale)
        return AffineTransform(linear, translation)

    def linear_out(self, transform_n):
        """The inverse of :meth:`linear_in`."""
        if self.identity:
            return transform_n
        is_similarity = isinstance(transform_n, SimilarityTransform)
        linear = transform_n.scale * transform_n.rotation if is_similarity else transform_n.linear
        translation = self.scale * transform_n.translation + self.fixed_centre - linear @ self.moving_centre
        if isinstance(transform_n, RigidTransform):
            return RigidTransform(transform_n.rotation, translation)
        if is_similarity:
            return SimilarityTransform(transform_n.rotation, translation, transform_n.scale)
        return AffineTransform(transform_n.linear, translation)


def _shifted(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """``points - centre`` computed on power-of-two-scaled values (it cannot overflow)."""
    unit = max(power_of_two_scale(points), power_of_two_scale(centre[None, :]))
    return ((points / unit) - (centre / unit)) * unit


def _as_landmarks(landmarks, n_moving: int, n_fixed: int) -> np.ndarray | None:
    """``landmarks`` as an (L, 2) int64 array of in-range index pairs (None when empty).

    Integer entries, or floats with integral values, are accepted; bools, text, None, NaN,
    fractions and ragged pairs are refused by name, and the range is checked before any cast
    (an index beyond int64 is an out-of-range index, not an overflow)."""
    if landmarks is None:
        return None
    shape = "a sequence of integer (moving_index, fixed_index) pairs, shape (L, 2)"
    if isinstance(landmarks, (str, bytes)):
        raise TypeError(f"`landmarks` must be {shape}; got text {landmarks!r}.")
    if np.ma.is_masked(landmarks):  # (tolist() below made its masked entries None)
        raise TypeError(f"`landmarks` must be {shape}; got a masked array with masked entries.")
    if isinstance(landmarks, (dict, set, frozenset)) or not hasattr(landmarks, "__len__"):
        # (numpy wraps these in a 0-d object array: the message spoke of shape ())
        raise TypeError(f"`landmarks` must be {shape}; got a value of type {type(landmarks).__name__}.")
    try:
        # nested lists as objects: a bool beside ints is seen as a bool, not cast to the int 1
        arr = landmarks if isinstance(landmarks, np.ndarray) else np.asarray(landmarks, dtype=object)
    except (TypeError, ValueError):
        raise InputError(f"`landmarks` must be {shape}; got {landmarks!r}.") from None
    if arr.size == 0:
        return None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InputError(f"`landmarks` must be {shape}; got shape {arr.shape}.")
    entries = arr.ravel().tolist()
    for value in entries:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise TypeError(f"`landmarks` must hold integer indices; got {value!r} of type {type(value).__name__}.")
        if not isinstance(value, numbers.Integral) and not (math.isfinite(value) and float(value).is_integer()):
            raise InputError(f"`landmarks` must hold integer indices; got {value!r}.")
    pairs = [(int(a), int(b)) for a, b in zip(entries[0::2], entries[1::2], strict=True)]
    for column, name, size in ((0, "moving", n_moving), (1, "fixed", n_fixed)):
        outside = [pair[column] for pair in pairs if not 0 <= pair[column] < size]
        if outside:
            raise InputError(f"`landmarks` {name} indices must be in [0, {size}); got {outside[0]}.")
    arr = np.array(pairs, dtype=np.int64)
    if np.unique(arr[:, 0]).size != arr.shape[0]:
        raise InputError("`landmarks` must pin each moving point at most once; got a repeated moving index.")
    # two moving points pinned to one fixed point: no transform puts them both there (a rigid
    # fit ended 0.36 apart, "converged")
    pinned = {}  # fixed index -> the moving point pinned to it
    for i, j in pairs:
        if j in pinned:
            raise InputError(
                f"`landmarks` must pin each fixed point at most once; got fixed index {j} for moving points "
                f"{pinned[j]} and {i}."
            )
        pinned[j] = i
    return arr


#: The range of NonRigidCPD's ``beta`` and ``lam``: beta^2 (and lam's products) must be
#: representable in float64.
KERNEL_RANGE = (1e-150, 1e150)


def _principal_sides(points: np.ndarray) -> np.ndarray:
    """Sides of the points' bounding box in their principal axes (the covariance's eigenvectors).

    The box of ``w="auto"``'s uniform outlier density (see :func:`_box_sides`). Taken along the
    principal axes rather than the coordinate axes, so that the estimate does not depend on how
    the sets are oriented: the axis-aligned box of a set rotated by 45 degrees has up to twice
    the volume (a fuzz run found ``w_`` 0.83 for a long thin set with 20% clutter and 1e-10 for
    the same sets rotated together)."""
    return _principal_axes(points)[1]


def _principal_axes(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points' principal axes (the centred covariance's eigenvectors, as columns) and
    their bounding box's sides along them."""
    centred_points = points - points.mean(axis=0)
    _, axes = np.linalg.eigh(centred_points.T @ centred_points)
    return axes, np.ptp(centred_points @ axes, axis=0)


def _span_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """``(centre, basis)`` of the affine span of ``points``: their mean, and their principal
    axes whose sides are not thin, as columns (None when they span every direction).

    What ``accelerate`` extrapolates a linear map on, with the image of the centre in place
    of the translation. On the directions a set does not span the map does not move its
    points, and the M-steps leave it undetermined (a rotation's block off a plane in 4D jumps
    between iterations, an affine map's column off it starts at the identity's and drops to
    0). Extrapolated with the rest, such entries set the jump's length: a fish lifted into 4D
    took 35 iterations instead of the 2D fit's 18 and ended 1.1e-2 from it. The translation
    moves with the map by the set's offset from the origin: extrapolated itself, a jump
    depended on where the origin lies (``normalize=False``: an affine fit 5 units from the
    origin took 57 iterations, and the same fit lifted into 3D, extrapolated about the
    centre, 33)."""
    axes, sides = _principal_axes(points)
    keep = ~_thin(sides)
    if keep.all():
        return points.mean(axis=0), None
    keep[np.argmax(sides)] = True  # (a set of equal points: one direction)
    return points.mean(axis=0), axes[:, keep]


def _is_line(basis: np.ndarray | None) -> bool:
    """Whether a :func:`_span_frame` basis is one direction."""
    return basis is not None and basis.shape[1] == 1


def _off_span_kept(on_span: np.ndarray, matrix: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """The D x D map that takes the ``basis`` columns (a set's span, see :func:`_span_frame`)
    as ``on_span`` (D x k, flattened) does and acts as ``matrix`` off the span."""
    return on_span.reshape(matrix.shape[0], basis.shape[1]) @ basis.T + matrix - (matrix @ basis) @ basis.T


def _box_sides(sides: np.ndarray, sigma2: float, model_dims: int) -> np.ndarray:
    """Sides of the uniform outlier density's box in the mixture's ``model_dims`` dimensions
    at variance ``sigma2``: the ``model_dims`` longest of the fixed set's principal ``sides``,
    one up to :data:`_BOX_FLOORED_SIDE` of the longest at least the width ``sqrt(2 pi sigma2)``
    of CPD's Gaussians, and from there to :data:`_BOX_THIN_SIDE` at least a share of it that
    falls linearly to 0 (a floor cut off at the tenth made the box, and the fit, jump there:
    sides 0.0999999999 and 0.1000000001 of the longest gave boxes up to 25 times apart).

    The box of a flat fixed set in a mixture of its own dimension is its area. Along a side
    shorter than the Gaussians' width, a Gaussian centred in the set has density about
    ``1 / sqrt(2 pi sigma2)`` at every fixed point, and a box of that width gives the uniform
    density the same factor. With a side of 0 the uniform density was unbounded and took
    every point as an outlier (the fish with ``z = 0`` added and 20 clutter points ended
    with ``w_`` 0.9 and nothing matched). Floored only below 1/1000 of the longest side, a
    scan 1/100 thick kept a box 1/100 thick while sigma2 was far wider: rigid w='auto' fits
    of such cluttered scans ended 0.25 to 0.7 off in 5 to 7 of 40 (now none). Sides over a
    fifth of the longest are the set's extent, as before: floored at the width too,
    the early steps' wider box cost the k-NN w='auto' fits of the registration suite's
    occlusion family up to 30% in mean error; floored at no more than a tenth of the
    longest (which is continuous), the thin scans failed as before. The floor falls off
    above a tenth, not below it: falling from a twentieth to a tenth, rigid fits of
    cluttered scans 0.095 thick failed in 4 of 20 (none at the full floor); falling from a
    tenth to a fifth, scans 0.12 thick fail in none of 20 (4 with the floor cut off at a
    tenth). The floor acts only while the Gaussians are wider than the side (the first
    steps); on shapes 15 and 40 times longer than wide, with clutter or a third occluded,
    fits were as good or as bad as with the floor below 1/1000 (20 seeds each)."""
    width = max(math.sqrt(2.0 * math.pi * sigma2), 1e-300)
    longest_side = float(np.max(sides))
    share = sides / longest_side if longest_side > 0 else np.zeros_like(sides)  # (a one-point set)
    floor = width * np.clip((_BOX_THIN_SIDE - share) / (_BOX_THIN_SIDE - _BOX_FLOORED_SIDE), 0.0, 1.0)
    longest = np.argsort(-sides, kind="stable")[:model_dims]
    return np.where(floor > 0, np.maximum(sides, floor), sides)[np.sort(longest)]


def _thin(sides: np.ndarray) -> np.ndarray:
    """Which of a box's sides are below :data:`_THIN_SIDE` of its longest: directions the set
    does not span (a planar set in 3D)."""
    return sides <= _THIN_SIDE * float(np.max(sides))


def _model_dims(moving: np.ndarray, fixed: np.ndarray) -> int:
    """The dimension of CPD's mixture for these sets: what they span together, a set's span
    being the number of its principal sides longer than :data:`_THIN_SIDE` of its longest
    (at least 1); see the module docstring.

    Together: the span of both sets, each centred and of unit RMS radius, stacked (two lines
    at an angle span a plane: taken as 1D, a non-rigid fit of one onto the other read the
    distance off the line as the Gaussians' width and ended 0.42 off, "converged"), and at
    least each set's own span (a blob far smaller than a line it is fitted onto)."""
    own = [max(int(np.sum(~_thin(_principal_sides(points)))), 1) for points in (moving, fixed)]
    unit = [centred(points)[1] / (rms_radius(points) or 1.0) for points in (moving, fixed)]
    both = int(np.sum(~_thin(_principal_sides(np.vstack(unit)))))
    return max(*own, both)


def _weight_of_odds(odds: float) -> float:
    """The weight ``odds / (1 + odds)`` of an outlier term, at most :data:`_AUTO_W_E_MAX`
    (odds beyond 1e12 round the weight to 1, where CPD's constant would divide by 0)."""
    return min(odds / (1.0 + odds), _AUTO_W_E_MAX)


def _check_prior(prior, n_moving: int, n_fixed: int, name: str) -> None:
    """A :class:`CentralityPrior` whose arrays fit the sets and whose numbers are finite."""
    if not isinstance(prior, CentralityPrior):
        raise TypeError(f"`{name}` must be a CentralityPrior or None; got {prior!r} of type {type(prior).__name__}.")
    for field, size in (("log_weight", n_moving), ("moving_centrality", n_moving), ("fixed_centrality", n_fixed)):
        values = np.asarray(getattr(prior, field))
        if values.shape != (size,) or not np.issubdtype(values.dtype, np.floating) or not np.all(np.isfinite(values)):
            raise InputError(
                f"`{name}`.{field} must be {size} finite floats (one per point); got {values.dtype} of shape "
                f"{values.shape}."
            )
    for field in ("inv2phi2", "strength"):
        value = getattr(prior, field)
        if not isinstance(value, numbers.Real) or not math.isfinite(value) or value < 0:
            raise InputError(f"`{name}`.{field} must be a finite number >= 0; got {value!r}.")


def _with_landmarks(post, fixed, landmarks, weight):
    """The E-step statistics with each landmark pair added as a correspondence of mass ``weight``."""
    i, j = landmarks[:, 0], landmarks[:, 1]
    p1 = post.p1.copy()
    pt1 = post.pt1.copy()
    px = post.px.copy()
    np.add.at(p1, i, weight)
    np.add.at(pt1, j, weight)
    np.add.at(px, i, weight * fixed[j])
    return replace(post, p1=p1, pt1=pt1, px=px, n_p=post.n_p + weight * landmarks.shape[0])


def _data_sigma2(post, fixed, moved) -> float:
    """``sum_mn P_mn |x_n - T(y_m)|^2 / (Np D)`` from the statistics of the un-augmented ``P``."""
    x_px = float(post.pt1 @ np.einsum("ij,ij->i", fixed, fixed))
    y_py = float(post.p1 @ np.einsum("ij,ij->i", moved, moved))
    return (x_px - 2.0 * float(np.sum(moved * post.px)) + y_py) / (post.n_p * fixed.shape[1])


class _CPD(BaseEstimator):
    """The EM loop shared by every CPD variant (and by GPD, which adds a prior)."""

    _init_kinds: tuple = (RigidTransform, SimilarityTransform, AffineTransform)

    def __init__(
        self,
        *,
        w=0.0,
        max_iter=150,
        tol=1e-5,
        sigma2=None,
        normalize=True,
        init=None,
        landmark_weight=10.0,
        method="auto",
        n_neighbors=None,
        precision="float64",
        accelerate=False,
        callback=None,
        progress=False,
        random_state=None,
    ):
        self.w = w
        self.max_iter = max_iter
        self.tol = tol
        self.sigma2 = sigma2
        self.normalize = normalize
        self.init = init
        self.landmark_weight = landmark_weight
        self.method = method
        self.n_neighbors = n_neighbors
        self.precision = precision
        self.accelerate = accelerate
        self.callback = callback
        self.progress = progress
        self.random_state = random_state

    # ----------------------------------------------------------------- parameters
    def _check_common(self):
        name = type(self).__name__
        if not (isinstance(self.w, str) and self.w == "auto"):
            if isinstance(self.w, str):
                raise InputError(f"`{name}.w` must be a number in [0, 1) or 'auto'; got {self.w!r}.")
            check_float(self.w, name=f"{name}.w", low=0.0, high=1.0, high_open=True)
        check_int(self.max_iter, name=f"{name}.max_iter", low=0)
        check_float(self.tol, name=f"{name}.tol", low=0.0)
        if self.sigma2 is not None:
            check_float(self.sigma2, name=f"{name}.sigma2", low=0.0, low_open=True)
        check_float(
            self.landmark_weight, name=f"{name}.landmark_weight", low=0.0, low_open=True, high=_LANDMARK_WEIGHT_MAX
        )
        check_choice(self.method, E_STEP_METHODS, name=f"{name}.method")
        check_choice(self.precision, PRECISIONS, name=f"{name}.precision")
        check_bool(self.accelerate, name=f"{name}.accelerate")
        if self.n_neighbors is not None:
            check_int(self.n_neighbors, name=f"{name}.n_neighbors", low=1)
            if self.method not in ("auto", "dense"):
                raise InputError(
                    f"`{name}.n_neighbors` runs its own E-step; `method` must be 'auto' or 'dense' with it, "
                    f"got {self.method!r}."
                )
        if self.callback is not None and not callable(self.callback):
            raise TypeError(f"`{name}.callback` must be callable or None; got {self.callback!r}.")
        check_bool(self.normalize, name=f"{name}.normalize")
        check_bool(self.progress, name=f"{name}.progress")
        if self.random_state is not None:
            as_generator(self.random_state, name=f"{name}.random_state")
        init = self.init
        if (
            init is not None
            and not (isinstance(init, str) and init == "global")
            and not isinstance(init, self._init_kinds)
        ):
            kinds = ", ".join(k.__name__ for k in self._init_kinds)
            raise TypeError(f"`{name}.init` must be None, 'global' or a {kinds}; got {init!r}.")

    def _check_params(self):  # variant-specific checks
        pass

    # ----------------------------------------------------------------- variant hooks
    def _init_state(self, moving, fixed, start):
        """The state of iteration 0; ``start`` is the initial transform in the normalised frame or None."""
        raise NotImplementedError

    def _m_step(self, post, moving, fixed, state, sigma2):
        raise NotImplementedError

    def _penalty(self, state) -> float:
        return 0.0

    def _make_transform(self, state, moving, frame: _Frame):
        """The transform of ``state`` in the caller's units."""
        raise NotImplementedError

    def _apply(self, state, moving):
        return state(moving)

    def _rounding_note(self, moving) -> str | None:
        """Why ``transform_`` may not reproduce ``moving_transformed_`` to rounding, or None."""
        return None

    def _vector(self, state) -> np.ndarray:
        """The parameters of ``state`` as one vector (what ``accelerate`` extrapolates)."""
        raise NotImplementedError

    def _from_vector(self, vector, state):
        """``(state, T(Y))`` from an extrapolated vector, projected back onto the model."""
        raise NotImplementedError

    # ----------------------------------------------------------------- the loop
    def fit(self, moving, fixed, *, true_moving=None, landmarks=None, prior=None):
        """Register ``moving`` (Y, M x D) onto ``fixed`` (X, N x D); returns ``self``.

        Parameters
        ----------
        moving, fixed : array_like of shape (M, D) and (N, D)
            Neither is modified.
        true_moving : array_like of shape (M, D), optional
            Where each moving point truly belongs in the fixed frame; when given,
            ``history_["error"]`` holds ``|true_moving - T(Y)|`` per iteration.
        landmarks : sequence of (i, j) pairs, optional
            Moving point ``i`` corresponds to fixed point ``j``. Each pair enters every
            M-step as an extra correspondence of mass ``landmark_weight * Np / L`` (``Np``
            the posterior mass of the data, ``L`` the number of pairs), added to the
            posterior (a constrained E-step in the spirit of the extended CPD of Golyanik
            et al. 2016); sigma2 is still estimated from the data alone. Three landmarks
            take the fish rotated by 150 degrees, where plain CPD falls into a wrong basin,
            to the right pose.
        prior : CentralityPrior or callable, optional
            The hook GPD uses: a log prior on the (moving, fixed) pairs added to the E-step
            (thesis eq. 5.10), or ``prior(sigma2_ratio) -> CentralityPrior | None`` called
            before each E-step with the current sigma2 over the initial one (a schedule).

        Returns
        -------
        self : RigidCPD, AffineCPD or NonRigidCPD
        """
        self._check_common()
        self._check_params()
        moving, fixed, true_moving = self._validate(moving, fixed, true_moving)
        landmarks = _as_landmarks(landmarks, moving.shape[0], fixed.shape[0])
        if prior is not None and not (isinstance(prior, CentralityPrior) or callable(prior)):
            raise TypeError(f"`prior` must be a CentralityPrior, a callable or None; got {prior!r}.")
        if isinstance(prior, CentralityPrior):
            _check_prior(prior, moving.shape[0], fixed.shape[0], "prior")
        frame, moving_n, fixed_n = self._frame(moving, fixed)
        true_n = frame.true_in(true_moving)
        start = self._start(moving_n, fixed_n, frame)
        run = (moving, moving_n, fixed_n, frame, true_n, start, landmarks, prior)
        if not isinstance(self.w, str):
            notes, _, _ = self._run(*run, hold=False)
        else:
            notes = self._fit_auto_w(run)
        for message, category in notes:
            warn(message, category)
        return self

    def _fit_auto_w(self, run) -> list:
        """w='auto': two EM runs; returns the kept run's warnings. The first holds ``w`` at its
        start until EM settles and estimates it from then on; the second estimates it from
        the first step. A run that collapsed, or whose estimate ended at its bound, loses to
        one that did not; otherwise the run of higher likelihood is kept. A callback that
        stops a run ends the fit with that run; an exception leaves the estimator as it was.

        (Estimated from the first step alone, the share climbs while sigma2 is still large,
        where the tails of any set look like outliers, and the pose follows the inliers it
        leaves: exact copies turned by 20 to 40 degrees ended 4 to 23 degrees off in 6 of 20
        similarity and 10 of 20 affine fits, "converged", with ``w_`` up to 0.6; held, each
        was exact. Held alone, an affine fit stretches towards clutter and a non-rigid one
        towards an occluded part, where the estimate from the first step does not: kept
        only where it alone would have been, the held run doubled the registration suite's
        error on dog1 with 40% occluded. The likelihood alone is no judge of a run that
        explains a few fixed points tightly and calls the rest outliers: with ``w`` free it
        grows without bound there, and such runs won over exact ones.)"""
        before = {name: self.__dict__[name] for name in _FITTED if name in self.__dict__}
        try:
            held_notes, objective, halted = self._run(*run, hold=True)
            if halted:  # the callback stopped the fit
                return held_notes
            held = {name: getattr(self, name) for name in _FITTED}
            held_order = self._run_order(held_notes, objective)
            notes, objective, halted = self._run(*run, hold=False)
            if halted or self._run_order(notes, objective) < held_order:
                return notes
        except BaseException:  # (a callback raised, or Ctrl-C): no half-kept fit
            for name in _FITTED:
                self.__dict__.pop(name, None)
            self.__dict__.update(before)
            raise
        self.__dict__.update(held)
        return held_notes

    def _run_order(self, notes, objective) -> tuple:
        """How w='auto' orders its runs (lower is kept): collapsed last, then an estimate at
        its bound, then by the objective."""
        collapsed = any(issubclass(category, CollapseWarning) for _, category in notes)
        return (collapsed, self.w_ >= _AUTO_W_MAX, objective)

    def _frame(self, moving, fixed):
        """``(frame, moving_n, fixed_n)``: the normalised frame ``fit`` runs in, and both sets in it."""
        # The k-NN model trusts the start: the moving set keeps the caller's pose relative to
        # the fixed set (``_start`` turns it into a translation of the normalised frame). Each
        # set is still centred on its own mean: a pose that brings a far moving set onto the
        # fixed one then cancels no large coordinates (the field's rounding grew with them).
        if self.n_neighbors is None:
            return _Frame.of(moving, fixed, bool(self.normalize))
        posed = None
        if isinstance(self.init, (SimilarityTransform, AffineTransform)):
            try:
                with np.errstate(all="ignore"):
                    posed = self.init(moving)
            except InputError:  # another dimension, or beyond float64: `_start` names it
                posed = None
        try:
            return _Frame.of(moving, fixed, bool(self.normalize), moving_scale=True, posed=posed)
        except InputError:
            if posed is None:
                raise
            # the sets are fine where they are (else this raises their own error): the start
            # put the moving set out of reach, which `init` is to blame for
            _Frame.of(moving, fixed, bool(self.normalize), moving_scale=True)
            with np.errstate(all="ignore"):
                reach = float(np.max(np.abs(posed - fixed.mean(axis=0)))) / max(rms_radius(moving), 1e-300)
            raise InputError(
                f"`{type(self).__name__}.init` must bring the moving set within {_SCALE_RANGE[1]:g} radii of the "
                f"fixed set (the data's scale); it maps it {reach:.3g} radii away. Check its scale and translation."
            ) from None

    def _validate(self, moving, fixed, true_moving):
        moving = as_points(moving, name="moving", n_dims=ANY_DIMS)
        fixed = as_points(fixed, name="fixed", n_dims=ANY_DIMS)
        if fixed.shape[1] != moving.shape[1]:
            raise InputError(
                "`moving` and `fixed` must have the same number of dimensions; "
                f"got {moving.shape[1]} and {fixed.shape[1]}."
            )
        if true_moving is not None:
            true_moving = as_points(true_moving, name="true_moving", n_dims=(moving.shape[1],))
            if true_moving.shape != moving.shape:
                raise InputError(
                    f"`true_moving` must have the shape of `moving` {moving.shape}; got {true_moving.shape}."
                )
        return moving, fixed, true_moving

    def _start(self, moving_n, fixed_n, frame):
        """The initial transform in the normalised frame (None: the variant's identity)."""
        init = self.init
        if init is None:
            if self.n_neighbors is None or np.array_equal(frame.moving_centre, frame.fixed_centre):
                return None
            # the caller's pose (see `_frame`)
            dim = moving_n.shape[1]
            return frame.linear_in(RigidTransform(np.eye(dim), np.zeros(dim)))
        dim = moving_n.shape[1]
        if isinstance(init, str):  # "global"
            from ._pose import global_pose_search

            # what the search needs and a plain fit does not, named with the option (radii in
            # the caller's units, not the normalised frame's)
            name = f"`{type(self).__name__}.init`='global'"
            if dim not in (2, 3):
                raise InputError(f"{name} searches rotations in 2D and 3D; got {dim}D sets.")
            if min(moving_n.shape[0], fixed_n.shape[0]) < 3:
                raise InputError(
                    f"{name} needs at least 3 points in each set; got {moving_n.shape[0]} moving and "
                    f"{fixed_n.shape[0]} fixed."
                )
            radii = rms_radius(moving_n) * frame.scale, rms_radius(fixed_n) * frame.scale
            if min(radii) <= 0:
                raise InputError(
                    f"{name} needs at least two distinct points in each set; got RMS radii {radii[0]:.3g} "
                    f"(moving) and {radii[1]:.3g} (fixed)."
                )
            scale = bool(getattr(self, "scale", True))
            w = _AUTO_W_START if isinstance(self.w, str) else float(self.w)
            return global_pose_search(moving_n, fixed_n, scale=scale, w=w, random_state=self.random_state)
        linear = init.linear if isinstance(init, AffineTransform) else init.rotation
        name = f"{type(self).__name__}.init"
        if linear.shape != (dim, dim):
            raise InputError(f"`{name}` must be a {dim}D transform; got a {linear.shape[0]}D one.")
        return _start_within_reach(frame, init, moving_n, name)

    def _run(self, moving, moving_n, fixed, frame, true_n, start, landmarks, prior, *, hold):
        """One EM run from ``start``; sets the fitted attributes and returns ``(warnings,
        final objective, stopped by the callback)``. ``hold`` (w='auto' only): ``w`` held at
        its start, CPD's weight, until EM settles; estimated from then on."""
        n_fixed, n_dims = fixed.shape
        # the mixture's dimension: what the sets span (see the module docstring)
        model_dims = _model_dims(moving_n, fixed)
        per_dim = n_dims / model_dims  # the spreads and M-steps divide by D; sigma2 is per spanned dimension
        # the largest coordinate whose rounding the moving points carry, in the frame's units:
        # far from the origin the caller's coordinates round by more than the centred
        # points show, and the M-steps must not take that rounding for spread
        self._peak = float(np.max(np.abs(moving))) / frame.scale
        spread_fixed = _initial_sigma2(fixed, fixed)
        spread = max(spread_fixed, _initial_sigma2(moving_n, moving_n))
        spread = 1.0 if spread <= 0 else max(spread, 1e-280)  # keeps 1 / (2 floor) finite
        # sigma2 measures residuals among the fixed points: its floor follows their spread (a
        # fixed set 1e6 times smaller than the moving set stopped at a tenth of its radius)
        floor = _SIGMA2_FLOOR * (max(spread_fixed, 1e-280) if spread_fixed > 0 else spread)
        floor *= per_dim
        state = self._init_state(moving_n, fixed, start)
        moving_t = self._apply(state, self._work)
        sigma2 = _initial_sigma2(moving_t, fixed) * per_dim if self.sigma2 is None else float(self.sigma2)
        if self.sigma2 is not None and not sigma2 <= _SIGMA2_MAX * spread:  # (1e300 overflowed)
            unit = "" if frame.scale == 1.0 else " in the normalised frame"
            raise InputError(
                f"`{type(self).__name__}.sigma2` must be at most {_SIGMA2_MAX:g} times the sets' own "
                f"spread ({_SIGMA2_MAX * spread:.3g}{unit}); got {self.sigma2!r}."
            )
        sigma2 = max(sigma2, floor)
        sigma2_start = sigma2
        auto_w = isinstance(self.w, str)
        w_fraction = _AUTO_W_START if auto_w else float(self.w)
        holding, released, halted = auto_w and hold, False, False
        # w="auto" estimates the fraction of outliers under a uniform density over the fixed
        # set's bounding box; CPD's E-step takes the weight of a density 1/N instead.
        sides = _principal_sides(fixed) if auto_w else None
        history = {"objective": [], "sigma2": [], "error": [], "method": [], "w": []}
        # the objective in the caller's units: plus the density's Jacobian
        units = n_fixed * model_dims * math.log(frame.scale)
        converged = False
        stopped = None
        previous = None
        current_prior = None
        planner = EStepPlanner()  # method='auto': the E-step path by timing, per fit
        e_step = self._e_step_of(fixed, planner, model_dims)
        # accelerate: the last EM iterates as vectors, and a pending extrapolated jump
        # (the plain step to fall back on, and the objective the jump must not exceed)
        squarem = bool(self.accelerate) and landmarks is None and not auto_w and not callable(prior)
        self._jump_frame = _span_frame(self._work) if squarem else None
        chain, pending, jumped = [], None, False
        bar = None
        if self.progress:
            from tqdm.auto import tqdm

            bar = tqdm(total=self.max_iter, desc=type(self).__name__, unit="iter", leave=False)
        try:
            iteration = 0
            while True:
                current_prior = prior
                if callable(prior):
                    current_prior = prior(sigma2 / sigma2_start)
                    if current_prior is not None:
                        _check_prior(current_prior, moving.shape[0], fixed.shape[0], "prior(sigma2_ratio)")
                w_e = (
                    _box_weight(w_fraction, n_fixed, _box_sides(sides, sigma2, model_dims))
                    if auto_w and not holding
                    else w_fraction
                )
                planner.hold = pending is not None  # a jump's E-step: no probing
                post = e_step(moving_t, sigma2, w_e, current_prior)
                objective = post.neg_log_likelihood + self._penalty(state)
                jumped = pending is not None
                if pending is not None:
                    fallback, limit = pending
                    pending = None
                    if not objective <= limit + 1e-12 * abs(limit):  # the jump did worse: the plain step
                        state, moving_t, sigma2 = fallback
                        continue
                error = None if true_n is None else float(np.linalg.norm(true_n - moving_t))
                history["objective"].append(objective + units)
                history["sigma2"].append(sigma2)
                history["error"].append(error)
                history["method"].append(post.method)
                history["w"].append(w_fraction)
                if self.callback is not None:
                    info = IterationInfo(
                        iteration,
                        self._make_transform(state, moving, frame),
                        frame.points_out(moving_t),
                        sigma2 * frame.scale**2,
                        objective + units,
                        None if error is None else error * frame.scale,
                    )
                    if _stops(self.callback(info)):
                        halted = True
                        break
                # (after a jump the change is not an EM step's: it does not say EM has stalled)
                if (
                    previous is not None
                    and not jumped
                    and abs(objective - previous) <= self.tol * max(abs(objective), 1e-300)
                ):
                    if not holding:
                        converged = True
                        break
                    # settled under the held w: estimated from here on (the objective changes
                    # with it: no comparison across the switch)
                    holding, released = False, True
                if iteration > 0 and sigma2 <= floor:
                    converged = True  # the sets coincide to rounding error (checked below)
                    break
                if iteration >= self.max_iter:
                    break
                if post.n_p <= 1e-12 * n_fixed:
                    stopped = (
                        f"every fixed point was explained by the outlier term at iteration {iteration} "
                        f"(sigma2={sigma2 * frame.scale**2:.3g}, w={w_e:.3g}); stopped. "
                        "Try a smaller `w` or a larger `sigma2`."
                    )
                    break
                previous = None if released else objective
                released = False
                m_post = (
                    post
                    if landmarks is None
                    else _with_landmarks(
                        post, fixed, landmarks, float(self.landmark_weight) * post.n_p / landmarks.shape[0]
                    )
                )
                previous_state = state
                new_state, new_moving_t, new_sigma2 = self._m_step(m_post, self._work, fixed, state, sigma2)
                if landmarks is not None:
                    new_sigma2 = _data_sigma2(post, fixed, new_moving_t)
                new_sigma2 *= per_dim
                if not np.all(np.isfinite(new_moving_t)):
                    stopped = (
                        f"the M-step of iteration {iteration + 1} gave non-finite points; "
                        "stopped at the last finite state."
                    )
                    break
                moving_t_used, sigma2_used = moving_t, sigma2
                state, moving_t, sigma2 = new_state, new_moving_t, new_sigma2
                if not math.isfinite(sigma2) or sigma2 <= floor:
                    sigma2 = floor
                if squarem:
                    if chain is None:
                        chain = []  # the step after a jump steadies it; the next cycle starts from its result
                    else:
                        if not chain:
                            chain.append(np.append(self._vector(previous_state), sigma2_used))
                        chain.append(np.append(self._vector(state), sigma2))
                        if len(chain) == 3:
                            jump = self._extrapolate(chain, state, floor)
                            chain = []
                            if jump is not None:
                                pending = ((state, moving_t, sigma2), objective)
                                state, moving_t, sigma2 = jump
                                chain = None
                                if _is_line(self._jump_frame[1]):
                                    # A line's pose is held only by where its points lie along
                                    # it: under a variance below what the jumped pose leaves
                                    # (the M-step's for that pose, under the last posteriors)
                                    # each point locks onto its nearest and the line stays
                                    # turned (3,000 random rigid, similarity and affine
                                    # problems: 19 ended over 1.5x plain EM's error, 12 of
                                    # them on 1,352 lines; with this floor none, at 1.15x the
                                    # E-steps, 0.7x plain EM's; a floor of half that
                                    # variance left 3)
                                    pose = _data_sigma2(m_post, fixed, moving_t) * per_dim
                                    if math.isfinite(pose):
                                        sigma2 = max(sigma2, pose)
                if auto_w and not holding:
                    # from CPD's posterior: a centrality prior's histogram weights lower the
                    # inlier mass and would inflate the estimate
                    n_p = post.n_p if current_prior is None else e_step(moving_t_used, sigma2_used, w_e, None).n_p
                    w_fraction = _w_estimate(n_p, n_fixed)
                iteration += 1
                if bar is not None:
                    bar.update(1)
                    bar.set_postfix(sigma2=f"{sigma2 * frame.scale**2:.3g}")
        finally:
            if bar is not None:
                bar.close()
        final_objective = history["objective"][-1]
        if holding:  # (the sets coincided, or max_iter or the callback came, before EM settled)
            # the estimate, and the final posteriors under it: w_, posteriors_ and posterior()
            # agree, and the run is scored as the other one is; from CPD's posterior, as in the loop
            n_p = post.n_p if current_prior is None else e_step(moving_t, sigma2, w_fraction, None).n_p
            w_fraction = _w_estimate(n_p, n_fixed)
            w_e = _box_weight(w_fraction, n_fixed, _box_sides(sides, sigma2, model_dims))
            post = e_step(moving_t, sigma2, w_e, current_prior)
            final_objective = post.neg_log_likelihood + self._penalty(state) + units
        name = type(self).__name__
        notes = []
        if stopped is not None:
            notes.append((f"{name}: {stopped}", ConvergenceWarning))
        elif not converged and iteration >= self.max_iter and self.max_iter > 0 and self.tol > 0:
            notes.append(
                (
                    f"{name} stopped at `max_iter={self.max_iter}` before the relative change of the "
                    f"objective fell below `tol={self.tol}`.",
                    ConvergenceWarning,
                )
            )
        collapse = self._collapse(
            moving_n, fixed, moving_t, w_fraction, post, model_dims, sigma2 if converged else None
        )
        if collapse is not None:
            notes.append((f"{name}: {collapse}", CollapseWarning))
            converged = False
        scale2 = frame.scale**2
        self.transform_ = self._make_transform(state, moving, frame)
        self.moving_transformed_ = frame.points_out(moving_t)
        rounding = self._rounding_note(moving)
        if rounding is not None:
            notes.append((f"{name}: {rounding}", UserWarning))
        self.sigma2_ = float(sigma2 * scale2)
        self.n_iter_ = iteration
        self.converged_ = converged
        self.w_ = float(w_fraction)
        self.history_ = {
            "objective": np.array(history["objective"]),
            "sigma2": np.array(history["sigma2"]) * scale2,
            "error": None if true_n is None else np.array(history["error"]) * frame.scale,
            "method": history["method"],
            "w": np.array(history["w"]),
        }
        if post.best is None:  # the E-steps skip it (a third of an E-step): once, for the last state
            post = replace(
                post, best=fixed_to_moving(moving_t, fixed, sigma2, w_e, current_prior, model_dims=model_dims)
            )
        self.fixed_to_moving_ = post.best
        self.posteriors_ = (
            post
            if frame.identity
            else replace(
                post,
                px=post.px * frame.scale + post.p1[:, None] * frame.fixed_centre,
                neg_log_likelihood=post.neg_log_likelihood + units,
            )
        )
        # the normalised state, for posterior(): c depends on sigma2 in the frame's units
        self._posterior_state = (moving_t, fixed, sigma2, w_e, current_prior, model_dims)
        return notes, final_objective, halted

    def _extrapolate(self, chain, state, floor):
        """SQUAREM's jump from the iterates ``t0, t1, t2`` (parameters then sigma2):
        ``(state, T(Y), sigma2)``, or None when it would not move or leaves the model."""
        t0, t1, t2 = chain
        r = t1 - t0
        v = t2 - 2.0 * t1 + t0
        norm_v = float(np.linalg.norm(v))
        if norm_v == 0.0:
            return None
        a = min(-float(np.linalg.norm(r)) / norm_v, -1.0)
        if a == -1.0:
            return None  # the jump is the plain step itself
        jump = t0 - 2.0 * a * r + a * a * v
        if not np.all(np.isfinite(jump)):
            return None
        try:
            new_state, moving_t = self._from_vector(jump[:-1], state)
        except (InputError, ValueError, np.linalg.LinAlgError):
            return None
        if not np.all(np.isfinite(moving_t)):
            return None
        # sigma2 along the same path in log space (EM shrinks it geometrically), never
        # below SIGMA_JUMP times the plain step's: a variance that jumps far below the
        # data's freezes the fit in a worse optimum (measured on the registration suite)
        logs = np.log(np.maximum([t0[-1], t1[-1], t2[-1]], floor))
        log_jump = logs[0] - 2.0 * a * (logs[1] - logs[0]) + a * a * (logs[2] - 2.0 * logs[1] + logs[0])
        sigma2 = float(np.exp(np.clip(log_jump, logs[2] + math.log(_SIGMA_JUMP), logs[2] - math.log(_SIGMA_JUMP))))
        return new_state, moving_t, max(sigma2, floor)

    def _e_step_of(self, fixed, planner, model_dims=None):
        """``e_step(moving_t, sigma2, w, prior) -> Posteriors`` of this fit: CPD's or the k-NN
        model's, for a mixture in ``model_dims`` dimensions (what the sets span; see the
        module docstring): ``w`` is that mixture's, and so is the objective."""
        if self.n_neighbors is None:
            # (``best`` from the last state only: see the end of _run)
            memo = {}  # the dense path's sorted fixed points, kept over the fit
            return lambda moving_t, sigma2, w, prior: _e_step(
                moving_t,
                fixed,
                sigma2,
                w,
                prior,
                method=self.method,
                planner=planner,
                precision=self.precision,
                want_best=False,
                memo=memo,
                fgt_fallback=True,
                model_dims=model_dims,
            )
        from scipy.spatial import cKDTree

        tree = cKDTree(fixed)
        k = int(self.n_neighbors)
        return lambda moving_t, sigma2, w, prior: knn_posterior(
            moving_t, fixed, sigma2, w, prior, k=k, tree=tree, model_dims=model_dims
        )

    def _collapse(self, moving_n, fixed, moving_t, w, post, model_dims, sigma2=None) -> str | None:
        """Why the result is not a registration, or None. ``model_dims``: the mixture's
        dimension; ``sigma2``: the final variance of a fit that converged (a fit stopped early
        is already warned of)."""
        one_point = one_point_fixed(moving_n, fixed)
        if one_point is not None:
            return one_point
        radius_y, radius_x, radius_t = rms_radius(moving_n), rms_radius(fixed), rms_radius(moving_t)
        # (normalize=True is suggested only where it is off: the command line always has it on)
        # (a smaller w only where there is one to lower; w='auto' can be given a value instead)
        auto = isinstance(self.w, str)
        tries = ["normalize=True"] if not self.normalize else []
        tries += ["a fixed `w`"] if auto else ["a smaller `w`"] if w > 0 else []
        tries.append("a starting pose (`init`)")
        advice = "Try " + (", ".join(tries[:-1]) + ", or " if len(tries) > 1 else "") + tries[-1] + "."
        if min(radius_y, radius_x) > 0 and radius_t < _COLLAPSE_RADIUS * min(radius_y, radius_x):
            return (
                f"the transformed moving set collapsed (RMS radius {radius_t / radius_y:.3g} of the moving set's); "
                f"the result is not a registration. {advice}"
            )
        expected = (1.0 - w) * min(moving_n.shape[0], fixed.shape[0])
        # fewer matched points than dimensions leave the pose undetermined (two points in 3D: any
        # rotation about their axis), whatever w expects (w='auto' can rise to its bound)
        needed = _needed_points(fixed.shape[1], moving_n.shape[0], fixed.shape[0])
        share = _COLLAPSE_MATCHED_AUTO * min(moving_n.shape[0], fixed.shape[0]) if auto else 0.0
        if post.n_p < max(_COLLAPSE_MATCHED * expected, needed, share):
            why = (
                f"w='auto' estimated {w:.3g}, and a registration matches at least {_COLLAPSE_MATCHED_AUTO:.0%} of "
                "the smaller set"
                if post.n_p < share
                else f"about {expected:.3g} expected with w={w:.3g}, and {fixed.shape[1]} in {fixed.shape[1]}D "
                "fix a pose"
            )
            return (
                f"only {post.n_p:.3g} of {fixed.shape[0]} fixed points were matched at the end (the rest taken as "
                f"outliers; {why}); the result is not a registration. {advice}"
            )
        # the fixed set explained by fewer moving points than fix a pose: a fixed set far smaller
        # than the moving set under a rigid model (other units) sat on 1 of 91, "converged"
        p1 = np.asarray(post.p1, dtype=float)
        used = float(np.sum(p1)) ** 2 / float(np.sum(p1 * p1)) if np.sum(p1 * p1) > 0 else 0.0
        if min(radius_y, radius_x) > 0 and used < _needed_points(fixed.shape[1], moving_n.shape[0], fixed.shape[0]):
            return (
                f"the fixed set was explained by about {used:.3g} of the {moving_n.shape[0]} moving points (each "
                "fixed point's nearest moving points are the same few): the result is not a registration. Is the "
                "fixed set in other units than the moving set? A transform with a scale (`scale=True`, affine) "
                "fits that; otherwise try a starting pose (`init`)."
            )
        spread = math.sqrt(model_dims * sigma2) if sigma2 is not None else 0.0
        if min(radius_y, radius_x) > 0 and spread > _COLLAPSE_SPREAD * radius_t:
            return (
                f"the fit ended with Gaussians {spread / radius_t:.3g} times as wide as the transformed moving "
                f"set (RMS radius {radius_t / radius_x:.3g} of the fixed set's): it explains the fixed set as "
                "one blob, and the result is not a registration. Either the moving set shrank onto the fixed "
                "set's centre (its own outliers, or parts the fixed set lacks, pull it there: remove them, or "
                "give a starting pose with `init`) or the fixed set is mostly noise."
            )
        return None

    # ----------------------------------------------------------------- results
    def transform(self, points) -> np.ndarray:
        """Apply the fitted transform to new points."""
        check_is_fitted(self, "transform_")
        return self.transform_(points)

    def score(self, moving, fixed) -> float:
        """Minus the mean distance from each fixed point to its nearest transformed moving point.

        Larger is better; in the caller's units. It lets scikit-learn's model selection
        (e.g. ``GridSearchCV(..., cv=[(index, index)])`` on sets of equal size) rank settings.
        """
        return nearest_score(self, moving, fixed)

    def posterior(self) -> np.ndarray:
        """The full posterior matrix ``P`` (M x N) of the final state; ``P[m, n] = P(m | x_n)``.

        Memory is M x N doubles, so it refuses sets above 50 million pairs; the fitted
        ``posteriors_`` (its row and column sums) and ``fixed_to_moving_`` are always there.
        """
        check_is_fitted(self, "transform_")
        moving_t, fixed, sigma2, w, prior, model_dims = self._posterior_state
        if moving_t.shape[0] * fixed.shape[0] > 50_000_000:
            raise InputError(
                "posterior() builds an M x N matrix; "
                f"M x N = {moving_t.shape[0] * fixed.shape[0]:,} exceeds 50,000,000. "
                "Use `fixed_to_moving_` or `posteriors_` instead."
            )
        if self.n_neighbors is not None:
            return knn_posterior_matrix(
                moving_t, fixed, sigma2, w, prior, k=int(self.n_neighbors), model_dims=model_dims
            )
        return dense_posterior(moving_t, fixed, sigma2, w, prior, model_dims=model_dims)

    @property
    def correspondence_(self) -> np.ndarray:
        """Deprecated alias of ``fixed_to_moving_`` (for each fixed point, its moving point)."""
        check_is_fitted(self, "fixed_to_moving_")
        warn(
            f"`{type(self).__name__}.correspondence_` is deprecated; use `fixed_to_moving_` (same values: for each "
            "fixed point the most probable moving point, -1 for an outlier).",
            FutureWarning,
        )
        return self.fixed_to_moving_


_COMMON_PARAMETERS = """w : float in [0, 1) or 'auto', default=0
        Weight of the uniform outlier component (CPD's w), read in the normalised frame
        (under ``normalize=False`` CPD's own constant, whose weight changes with the units:
        a fixed w of 0.2 on a scan in km ended 2.8 degrees off where in m it gave 0.4, and in
        mm it collapsed; 'auto' does not depend on them). 0 trusts every fixed point; use
        0.1 - 0.3 when the fixed set has clutter or the moving set has parts the fixed set
        lacks (the larger the share of such points, the larger w). CPD models outliers in
        the fixed set only: when both sets have parts the other lacks (two partial scans),
        fits can end tens of degrees off without a warning. On two bunny scans that each
        lack a different 20% (20 seeds, ``benchmarks/partial_overlap.py``), from the true
        pose 45% of fits end within 5 degrees with w=0.2, 95% with 'auto' and 100% with
        ``ICP(trim=0.3)``; turned by up to 180 degrees, ``init='global'`` with 'auto'
        finds the pose in 90% of them. 'auto' estimates it during EM: the fraction of fixed points that are
        outliers under a uniform density over the fixed set's bounding box (along its
        principal axes, so that it does not depend on the sets' orientation; of a flat set
        in 3D, the area it spans: see the module docstring), updated as
        ``1 - Np / N`` after each E-step (CPD's posterior, also under GPD), from 0.1 and at
        most 0.9 (the estimate is ``w_``). EM runs twice: with ``w`` held at CPD's 0.1 until
        it settles, then estimated, and estimated from the first step. A run that collapsed
        (see ``converged_``) or whose estimate ended at 0.9 loses to one that did not;
        otherwise the run of higher likelihood is kept (``n_iter_`` and ``history_`` are its
        own, ``history_["w"]`` the share each of its E-steps used). A ``callback`` sees both
        runs; one that stops a run ends the fit with it. The two runs cost about twice the
        former single run and 1.4 to 9 times a fixed ``w`` (2D rigid, 10,000 points with 20%
        clutter: 10.5 s against 1.2 s; the estimate slows convergence). Estimated from the
        first step alone, the share climbs while sigma2 is large, where the tails of any set
        look like outliers, and exact copies turned by 30 degrees ended in a wrong pose; held
        alone, an affine or non-rigid fit leans towards clutter. It is the maximum-likelihood fraction
        for the chosen transform model: exact on rigid data with clutter, high when the model
        cannot fit the data (a similarity on a bent shape reads the bent parts as outliers).
        Measured on the bunny (1,000 points, 20% missing, clutter 10%; 5 seeds): rotation
        error 1.66 degrees with w=0, 0.000 with 0.1, 0.3 and 'auto' (estimate 0.111, the true
        clutter fraction; ``benchmarks/outlier_weight.py``). On clean non-rigid data it
        matches 0 (face under a smooth warp: error 0.0026 with both; 0.043 when it was
        estimated from the first step only), and with clutter it is the best setting (the
        face with as many outliers as points: 0.0060, against 0.23 with 0 and with 0.1;
        ``outlier_weight.py --models``). It is not the default because of that cost.
    max_iter : int, default=150
        Maximum number of M-steps.
    tol : float, default=1e-5
        Tolerance on the relative change of the objective.
    sigma2 : float, optional
        Initial variance (in the normalised frame under ``normalize=True``); by default
        ``sum |x_n - T0(y_m)|^2 / (D M N)`` for the starting pose T0. At most 1e10 times
        the sets' own spread (their larger ``sum |x_i - x_j|^2 / (D N^2)``).
    normalize : bool, default=True
        Run EM on both sets centred and divided by their common RMS radius (see the module
        notes; the moving set's radius alone under ``n_neighbors``); results are
        equivariant under translating or scaling both inputs. False runs in the caller's
        units, where ``sigma2`` (and a non-rigid ``beta``) are in those units, on both sets shifted by the
        fixed set's mean (the pose is kept; results are equivariant under translation).
    init : None, transform or 'global', default=None
        The starting pose: None (centroids aligned under ``normalize``, else the identity),
        a transform in the caller's units, or 'global' (a rotation search over the whole
        sphere, ``registration._pose.global_pose_search``, seeded by ``random_state``).
    landmark_weight : float in (0, 1e6], default=10.0
        Mass of the ``landmarks`` given to :meth:`fit`: together they weigh this many times
        the data's posterior mass. The default pins landmarks the data agree with (on the
        fish, true pairs end within 1e-3 of each other); pairs the data pull elsewhere are
        held less tightly: two pairs each one outline point off ended 0.022 and 0.012 apart
        at 10, 0.0024 and 0.0013 at 100, 2e-4 and 1e-4 at 1,000 (in units of the fish's
        extent, about 3). Use about 0.1 - 1 for uncertain landmarks.
    method : {'auto', 'dense', 'truncated', 'fgt'}, default='auto'
        E-step path: every pair's score ('dense'; from 256 moving points the exponentials
        only over the band of moving points, sorted along one axis, that can hold a term
        above exp(-36.8)/M of the row's largest); for each fixed point only the moving
        points whose term is above that ('truncated', a cell grid); both equal every term's
        sum to rounding; a fast Gauss transform ('fgt', about 1e-8 of the total weight; CPD only,
        not GPD; 2D and 3D; an E-step whose sigma2 is too small for its grid, or whose
        expansion is predicted to cost over 10 times every pair's exponential (above 2^20
        pairs), takes the exact truncated path, as ``history_["method"]`` records; in 3D its expansion costs
        far more than in 2D: 15 E-steps on 3,000 points took 6.7 s against dense's 0.22 s,
        and 4,500 bunny points, now all truncated, 1.4 s against 0.37 s, where the expansion
        had not finished in 90 s; in 2D, 20,000 points: 2.3 s against 7.1 s). 'auto' takes the fastest by
        timing the paths during the fit (``registration._estep.EStepPlanner``; always dense
        below 2^20 pairs). Timing
        decides, so above 2^20 pairs two fits of one problem may take different paths and
        differ at rounding level (measured: 1e-12 at 2,000 points; up to the FGT's 1e-8 where
        it is chosen); pass 'dense' or 'truncated' for results bit-identical across runs and
        for any number of this library's threads. (The M-step's solves and products go
        through NumPy's BLAS, whose own thread count can change the last bits: 1e-14 at
        700 points between OpenBLAS on 1 and 2 threads.)
    n_neighbors : int, optional
        None (default): CPD's model, every moving point may explain every fixed point.
        An int k: the k-nearest-neighbour model (the E-step of biocpd, our own code): each
        moving point may explain only its k nearest fixed points, found again at every
        E-step (see ``registration._estep.knn_posterior``); clutter far from the shape is
        nobody's neighbour and is ignored whatever ``w``. It trusts the start, so under
        ``normalize`` both sets are centred on the fixed set's mean (the caller's pose, or
        ``init``, is the start, not "centroids aligned") and divided by the moving set's
        RMS radius, so that clutter does not widen ``beta``: use it when the sets start
        roughly aligned, not for large rotations. k >= N is the dense model. Measured
        (``benchmarks/registration_suite.py``, Chui-Rangarajan families, 100 pairs per
        level, non-rigid, k=10): fish with as many uniform outliers as points, mean error
        0.205 dense, 0.0104 with k=10, 0.0044 with k=10 and w='auto'; 30% occluded, 0.124
        dense, 0.050 with k=10; clean and noisy levels within a few percent of dense. Where
        the start is far from the answer it is worse: the CPD fish pair 0.051 against 0.0061
        dense (``outlier_weight.py --models``), the fish rotated by 45 degrees with clutter
        75% success against 100%.
    precision : {'float64', 'float32'}, default='float64'
        'float32' takes the dense E-step's exponentials in float32 (scores, maxima and sums
        stay in float64): each posterior within 1.1e-5 of its float64 value relative, plus
        ``3.4e-38 (M + 1)`` (derived in ``registration._estep.PRECISIONS``). Measured on
        uniform 2D points, one E-step: 1.15-1.4x faster than float64 at 1,000 to 10,000
        points. The truncated, FGT and ``n_neighbors`` E-steps ignore it.
    accelerate : bool, default=False
        Squared extrapolation of the EM iterates (SQUAREM, Varadhan and Roland 2008): after
        every two EM steps the transform parameters jump along the extrapolated path,
        ``t0 - 2 a r + a^2 v`` with ``r = t1 - t0``, ``v = t2 - 2 t1 + t0`` and
        ``a = -|r| / |v|`` (at most -1), projected back onto the model (a proper rotation
        by SVD), and sigma2 along the same path in log space, kept within 4x of the plain
        step's (a variance that jumps far below the data's froze fits in worse optima);
        the jump is kept only if the E-step there is no worse than the last plain one,
        else the plain step is taken. 1.8-2.8x fewer E-steps at 1,000-3,000 points, rigid
        and non-rigid (``benchmarks/registration.py``); on the 44 family/levels of
        ``benchmarks/registration_suite.py`` (non-rigid, 100 pairs each) its mean error is
        plain EM's (ratio 0.87-1.03, median 1.00) with the same success rate. A rejected
        jump costs one E-step more. A rigid or affine map is extrapolated with the image of
        the moving set's centre in place of its translation, so that a jump does not depend
        on where the origin lies (with ``normalize=False``, rigid fits of the fish 30 units
        from the fixed set took 163 E-steps over 10 seeds, against 216 with the translation
        itself extrapolated). On a set short of full span (a plane in 3D, a line) the map
        is extrapolated on the set's span only, where it is determined. On a line, a jump's
        sigma2 is at least the M-step's for the jumped pose: a line's pose is held only by
        where its points lie along it, and a jump that left sigma2 below that kept 12 of
        1,352 random lines turned. Over 3,000 random rigid, similarity and affine problems
        (flat, nearly flat and line sets turned in random planes; 375 spanning every
        direction) an accelerated fit ended over 1.5 times as far from the truth as plain
        EM in 7: 6 nearly flat or nearly straight (3e-3 of their extent thick or less), and
        one of the 375 (0.066 from the truth against 0.042).
        Not used with ``w='auto'``, ``landmarks`` or a scheduled GPD prior (the EM map then
        changes between steps); off by default so that iteration counts are CPD's own.
    callback : callable, optional
        Called with an :class:`IterationInfo` after each E-step; return ``True`` (or
        ``numpy.True_``, as a comparison gives) to stop.
    progress : bool, default=False
        Show a progress bar on stderr.
    random_state : int, Generator or None, default=None
        Seed of ``init='global'``."""

_COMMON_ATTRIBUTES = """transform_ : transform
        In the caller's units.
    moving_transformed_ : ndarray of shape (M, D)
    sigma2_ : float
        Final variance, in the caller's units.
    n_iter_ : int
        Number of M-steps taken.
    converged_ : bool
        The objective's relative change fell below ``tol`` (or the sets coincide); False on
        ``max_iter``, on a stop for non-finite values and when the result collapsed (a
        :class:`~centrality_vision.exceptions.CollapseWarning` is issued then).
    w_ : float
        The outlier weight used at the end (``w``, or the estimate of ``w='auto'``).
    history_ : dict
        ``objective``, ``sigma2``, ``error`` (None without ``true_moving``) and ``w``: entry
        ``k`` for the state after ``k`` M-steps, in the caller's units; ``method`` the
        E-step path of each.
    fixed_to_moving_ : ndarray of shape (N,)
        For each fixed point the most probable moving point, -1 for an outlier
        (``correspondence_`` is its deprecated alias).
    posteriors_ : Posteriors
        The E-step statistics of the final state (``px`` and the likelihood in the caller's units)."""


def _stops(answer) -> bool:
    """Whether a callback's answer asks the fit to stop: ``True`` or ``numpy.True_`` (what a
    comparison returns); None, False and anything else go on."""
    return isinstance(answer, (bool, np.bool_)) and bool(answer)


def _w_estimate(n_p: float, n_fixed: int) -> float:
    """w='auto''s share of outliers from the posterior's inlier mass ``n_p``: ``1 - Np / N``,
    within [0, :data:`_AUTO_W_MAX`]."""
    return min(max(1.0 - n_p / n_fixed, 0.0), _AUTO_W_MAX)


def _box_weight(w_fraction: float, n_fixed: int, box_sides: np.ndarray) -> float:
    """CPD's outlier weight (of a density 1/N) for w='auto''s share ``w_fraction`` of a uniform
    density over a box with sides ``box_sides`` (see :func:`_box_sides`)."""
    if w_fraction <= 0:
        return w_fraction
    box, odds_per_volume = float(np.prod(box_sides)), w_fraction / (1.0 - w_fraction) * n_fixed
    odds = odds_per_volume / box if 0.0 < box < math.inf else math.inf
    if odds < math.inf:
        # (a nearly flat fixed set has a box of almost no volume: the odds can pass 1e16)
        return _weight_of_odds(odds)
    # a volume or odds past float's range, in logs: one fixed point in 46 dimensions has a
    # box of 46 sides of the Gaussians' width at the variance floor, which rounded to 0
    # (ZeroDivisionError), and a box of 1e-310 gave odds of inf and a NaN weight
    log_odds = math.log(odds_per_volume) - float(np.sum(np.log(box_sides)))
    return _weight_of_odds(math.exp(min(log_odds, 100.0)))  # (odds past 1e12 give the bound)


def _needed_points(n_dims: int, n_moving: int, n_fixed: int) -> float:
    """The fewest moving points (a participation count of the matched mass) that a fit may
    explain the fixed set by: three quarters of min(D, M, N)."""
    return _COLLAPSE_MATCHED_DIMS * min(n_dims, n_moving, n_fixed)


def _radius_ratio(estimator, moving_n: np.ndarray, fixed_n: np.ndarray) -> float:
    """The start scale of a similarity or affine fit without ``init``: the ratio of the sets'
    RMS radii, as CPD's own normalisation of each set to unit variance gives. (At scale 1, a
    moving set 100 times larger than the fixed set, as in metres against centimetres,
    shrank past it and collapsed.) The k-NN model and ``normalize=False`` keep the caller's
    pose: 1."""
    if estimator.n_neighbors is not None or not estimator.normalize:
        return 1.0
    radius_y, radius_x = rms_radius(moving_n), rms_radius(fixed_n)
    return radius_x / radius_y if radius_x > 0 and radius_y > 0 else 1.0


def one_point_fixed(moving: np.ndarray, fixed: np.ndarray) -> str | None:
    """Why no registration is possible when ``fixed`` is one point (repeated) and ``moving``
    is spread (every model shrinks, or turns at random, onto the point); None otherwise."""
    if rms_radius(fixed) > 0 or rms_radius(moving) == 0:
        return None
    n = fixed.shape[0]
    copies = "a single point" if n == 1 else f"one point repeated {n} times"
    return (
        f"`fixed` is {copies}, onto which no transform of the spread moving set is determined; the result "
        "is not a registration."
    )


def _span(points: np.ndarray) -> int:
    """How many dimensions the points span about their mean (the rank of the centred set).

    A direction counts when the centred set's singular value along it exceeds what the
    rounding of the coordinates themselves can give (a few ulps of the largest, times the
    square root of the point count): a line 100 units from the origin is a line, not a thin
    plane of rounding errors."""
    unit = points / power_of_two_scale(points)  # (the mean of coordinates near 1e308 overflowed)
    centred = unit - unit.mean(axis=0)
    values = np.linalg.svd(centred, compute_uv=False)
    eps = np.finfo(np.float64).eps
    rounding = 16.0 * eps * float(np.abs(unit).max()) * math.sqrt(points.shape[0])
    tol = max(rounding, float(values.max(initial=0.0)) * max(points.shape) * eps, np.finfo(float).tiny)
    return int(np.count_nonzero(values > tol))


def warn_rotation_spans(moving: np.ndarray, fixed: np.ndarray, who: str = "") -> None:
    """Warn when ``moving`` or ``fixed`` does not determine a rotation (they take points not
    all on one point in 2D, on one line in 3D, in one (D - 2)-dimensional flat in D): the fit
    still runs, but its turn about the degenerate set is arbitrary. (One fixed point under a
    spread moving set is the collapse :func:`one_point_fixed` names.)"""
    dim = moving.shape[1]
    rank = _span(moving)
    shape = {2: "point", 3: "line"}.get(dim, f"{dim - 2}-dimensional flat")
    if rank < dim - 1:
        warn(
            f"{who}`moving` spans {rank} of {dim} dimensions ({counted(moving.shape[0], 'point')}): a rotation is not "
            f"determined by it (it takes points not all on one {shape}); `transform_` is right on `moving` only.",
            UserWarning,
        )
    rank = _span(fixed)
    if 0 < rank < dim - 1:
        warn(
            f"{who}`fixed` spans {rank} of {dim} dimensions ({counted(fixed.shape[0], 'point')}): a rotation onto it "
            f"is not determined (it takes points not all on one {shape}); the turn about it is arbitrary, not a "
            "registration.",
            UserWarning,
        )


class RigidCPD(_CPD):
    """Rigid (``scale=False``) or similarity (``scale=True``) Coherent Point Drift.

    EM on a Gaussian mixture centred on the transformed moving points with an outlier
    component of weight ``w`` (the module notes give the posterior). Stops when the relative
    change of the objective ``-sum_n log(sum_m exp(-|x_n - T(y_m)|^2 / 2 sigma2) + c) + N D/2 log sigma2``
    between two E-steps is at most ``tol``, after ``max_iter`` M-steps, or when sigma2
    reaches 1e-14 of the fixed set's spread (the sets coincide).

    Moving points that do not determine a rotation (one point repeated, or in 3D points on
    one line) are still aligned, but ``transform_`` is then right on them only, and a
    :class:`UserWarning` says so.

    Parameters
    ----------
    scale : bool, default=True
        Estimate an isotropic scale (similarity) or not (rigid).
    {common}

    Attributes
    ----------
    {attributes}

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((40, 2))
    >>> r = np.array([[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]])
    >>> x = 1.5 * y @ r.T + [0.2, -0.1]
    >>> reg = RigidCPD(scale=True, tol=1e-10).fit(y, x)
    >>> round(reg.transform_.scale, 6), bool(np.allclose(reg.moving_transformed_, x, atol=1e-6))
    (1.5, True)
    >>> far = RigidCPD(scale=True, tol=1e-10).fit(1e6 * y + 3e8, 1e6 * x + 3e8)  # other units, far away
    >>> bool(np.allclose(far.transform_.rotation, reg.transform_.rotation, atol=1e-9))
    True
    """

    _init_kinds = (RigidTransform, SimilarityTransform)

    def __init__(
        self,
        *,
        scale=True,
        w=0.0,
        max_iter=150,
        tol=1e-5,
        sigma2=None,
        normalize=True,
        init=None,
        landmark_weight=10.0,
        method="auto",
        n_neighbors=None,
        precision="float64",
        accelerate=False,
        callback=None,
        progress=False,
        random_state=None,
    ):
        super().__init__(
            w=w,
            max_iter=max_iter,
            tol=tol,
            sigma2=sigma2,
            normalize=normalize,
            init=init,
            landmark_weight=landmark_weight,
            method=method,
            n_neighbors=n_neighbors,
            precision=precision,
            accelerate=accelerate,
            callback=callback,
            progress=progress,
            random_state=random_state,
        )
        self.scale = scale

    def _check_params(self):
        check_bool(self.scale, name="RigidCPD.scale")
        if not self.scale and isinstance(self.init, SimilarityTransform) and not isinstance(self.init, RigidTransform):
            if self.init.scale != 1.0:
                raise InputError(f"`RigidCPD.init` must have scale 1 when scale=False; got {self.init.scale!r}.")

    def _init_state(self, moving, fixed, start):
        self._work = moving
        dim = moving.shape[1]
        if start is None:
            return (
                SimilarityTransform(np.eye(dim), np.zeros(dim), _radius_ratio(self, moving, fixed))
                if self.scale
                else RigidTransform(np.eye(dim), np.zeros(dim))
            )
        if self.scale:
            return SimilarityTransform(start.rotation, start.translation, start.scale)
        return RigidTransform(start.rotation, start.translation)

    def _validate(self, moving, fixed, true_moving):
        moving, fixed, true_moving = super()._validate(moving, fixed, true_moving)
        warn_rotation_spans(moving, fixed)
        return moving, fixed, true_moving

    def _m_step(self, post, moving, fixed, state, sigma2):
        transform, sigma2 = rigid_m_step(post, moving, fixed, scale=bool(self.scale), peak=self._peak)
        return transform, transform._apply(moving), sigma2

    def _vector(self, state):
        # the rotation on the moving set's span and the image of its centre (see _span_frame)
        scale = [state.scale] if self.scale else []
        centre, basis = self._jump_frame
        scaled = (state.scale if self.scale else 1.0) * state.rotation
        on_span = state.rotation if basis is None else state.rotation @ basis
        return np.concatenate([on_span.ravel(), scaled @ centre + state.translation, scale])

    def _from_vector(self, vector, state):
        dim = state.translation.shape[0]
        scale = max(float(vector[-1]), 1e-300) if self.scale else 1.0
        centre, basis = self._jump_frame
        size = dim * (dim if basis is None else basis.shape[1])
        if basis is None:
            rotation = proper_rotation(vector[:size].reshape(dim, dim))[0]
        else:  # off the span, the state's rotation
            rotation = proper_rotation(_off_span_kept(vector[:size], state.rotation, basis))[0]
        translation = vector[size : size + dim] - scale * rotation @ centre
        if self.scale:
            new = SimilarityTransform._trusted(rotation, translation, scale)
        else:
            new = RigidTransform._trusted(rotation, translation)
        return new, new._apply(self._work)

    def _make_transform(self, state, moving, frame):
        return frame.linear_out(state)


class AffineCPD(_CPD):
    """Affine Coherent Point Drift.

    Parameters
    ----------
    {common}

    Attributes
    ----------
    {attributes}

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((40, 3))
    >>> a = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.1], [0.1, 0.0, 1.2]])
    >>> reg = AffineCPD(tol=1e-12).fit(y, y @ a.T + 0.3)
    >>> bool(np.allclose(reg.transform_.linear, a, atol=1e-6))
    True

    Moving points that do not span every dimension (fewer than D + 1, or all on one line
    in 2D or one plane in 3D, within the rounding of their coordinates: a line 1e8 from the
    origin is a line) do not determine the linear map: the fit still aligns them,
    but ``transform_`` is then right on them only (its linear part is the least-norm one,
    collapsed across the missing directions), and a :class:`UserWarning` says so.
    """

    def _validate(self, moving, fixed, true_moving):
        moving, fixed, true_moving = super()._validate(moving, fixed, true_moving)
        dim, rank = moving.shape[1], _span(moving)
        if rank < dim:
            warn(
                f"`moving` spans {rank} of {dim} dimensions ({counted(moving.shape[0], 'point')}): an affine transform "
                f"is not determined by it (it takes at least {dim + 1} points, not all on one "
                f"{'line' if dim == 2 else 'hyperplane'}); `transform_` is right on `moving` only.",
                UserWarning,
            )
        rank = _span(fixed)
        if 0 < rank < dim:  # (one point: the collapse one_point_fixed names)
            warn(
                f"`fixed` spans {rank} of {dim} dimensions ({counted(fixed.shape[0], 'point')}): an affine map onto it "
                f"flattens the moving set into it (it takes at least {dim + 1} points, not all on one "
                f"{'line' if dim == 2 else 'hyperplane'}); `transform_` is singular, not a registration.",
                UserWarning,
            )
        return moving, fixed, true_moving

    def _init_state(self, moving, fixed, start):
        self._work = moving
        dim = moving.shape[1]
        if start is None:
            return AffineTransform(_radius_ratio(self, moving, fixed) * np.eye(dim), np.zeros(dim))
        linear = start.linear if isinstance(start, AffineTransform) else start.scale * start.rotation
        return AffineTransform(linear, start.translation)

    def _m_step(self, post, moving, fixed, state, sigma2):
        transform, sigma2 = affine_m_step(post, moving, fixed, peak=self._peak)
        return transform, transform(moving), sigma2

    def _vector(self, state):
        # the map on the moving set's span and the image of its centre (see _span_frame)
        centre, basis = self._jump_frame
        on_span = state.linear if basis is None else state.linear @ basis
        return np.concatenate([on_span.ravel(), state.linear @ centre + state.translation])

    def _from_vector(self, vector, state):
        dim = state.translation.shape[0]
        centre, basis = self._jump_frame
        size = dim * (dim if basis is None else basis.shape[1])
        if basis is None:
            linear = vector[:size].reshape(dim, dim)
        else:  # off the span, the state's map
            linear = _off_span_kept(vector[:size], state.linear, basis)
        new = AffineTransform(linear, vector[-dim:] - linear @ centre)
        return new, new(self._work)

    def _make_transform(self, state, moving, frame):
        return frame.linear_out(state)


class NonRigidCPD(_CPD):
    """Non-rigid Coherent Point Drift: a motion-coherent displacement field.

    ``T(Y) = Y + G C`` with ``G[i, j] = exp(-|y_i - y_j|^2 / (2 beta^2))`` and coefficients
    ``C`` (W in the CPD paper), regularised by ``lam / 2 tr(C^T G C)`` (added to the
    objective). With ``init=`` the field acts on ``init(Y)`` (the pose is kept, not refined).
    ``transform_`` is a :class:`NonRigidTransform` that can move any point.

    Parameters
    ----------
    beta : float, default=2.0
        Width of the Gaussian kernel (in the normalised frame under ``normalize=True``, where
        the sets have unit RMS radius; in the caller's units otherwise).
    lam : float, default=2.0
        Strength of the smoothness regularisation (lambda of the CPD paper). It acts
        as ``lam * sigma2``, so an exact fit, whose sigma2 shrinks to nothing, is nearly
        unregularised at a small ``lam``: the field's coefficients then grow until its
        values carry visible rounding, and a :class:`UserWarning` says so when it exceeds
        1e-6 of the moving set's RMS radius (exact copies: at ``lam=1e-8``, not at 1e-5).
    low_rank : int, 'auto' or None, default='auto'
        Number of eigenpairs of ``G`` kept (the CPD paper's fast variant, O(M K^2) per
        iteration instead of an O(M^3) solve). None solves exactly; 'auto' is exact up to
        500 moving points; above, it keeps as many eigenpairs as make the kernel exact to
        1e-12 of its trace (34 for the default beta), up to the largest of 50,
        ``ceil(sqrt(M))`` and ``min(M / 4, 2000, 5e7 / M)``. Where those leave more than
        1e-6 of the trace out (a narrow kernel), up to 5,000 points are solved exactly
        (above 2,000 with a :class:`UserWarning`: an O(M^3) solve at every step, about a
        second a step on 4,500 points) and more get a
        :class:`~centrality_vision.exceptions.ConvergenceWarning`, as does a number that
        leaves that much out.
    {common}

    Attributes
    ----------
    {attributes}

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((50, 2))
    >>> x = y + 0.05 * np.sin(3 * y[:, ::-1])
    >>> reg = NonRigidCPD(beta=1.0, lam=0.5, tol=1e-8).fit(y, x)
    >>> bool(np.linalg.norm(reg.moving_transformed_ - x) < 0.1 * np.linalg.norm(y - x))
    True

    Clutter: 50 points in a far cluster are nobody's nearest neighbour under the k-NN model,
    which registers as if they were absent; the dense model with ``w=0`` is pulled towards them.

    >>> clutter = np.random.default_rng(1).normal(size=(50, 2)) * 0.05 + [3.0, 3.0]
    >>> knn = NonRigidCPD(beta=1.0, lam=0.5, tol=1e-8, n_neighbors=10).fit(y, np.vstack([x, clutter]))
    >>> dense = NonRigidCPD(beta=1.0, lam=0.5, tol=1e-8).fit(y, np.vstack([x, clutter]))
    >>> float(knn.posteriors_.pt1[50:].sum()), bool(np.abs(knn.moving_transformed_ - x).max() < 0.01)
    (0.0, True)
    >>> bool(np.abs(dense.moving_transformed_ - x).max() > 0.1)
    True
    """

    def __init__(
        self,
        *,
        beta=2.0,
        lam=2.0,
        low_rank="auto",
        w=0.0,
        max_iter=150,
        tol=1e-5,
        sigma2=None,
        normalize=True,
        init=None,
        landmark_weight=10.0,
        method="auto",
        n_neighbors=None,
        precision="float64",
        accelerate=False,
        callback=None,
        progress=False,
        random_state=None,
    ):
        super().__init__(
            w=w,
            max_iter=max_iter,
            tol=tol,
            sigma2=sigma2,
            normalize=normalize,
            init=init,
            landmark_weight=landmark_weight,
            method=method,
            n_neighbors=n_neighbors,
            precision=precision,
            accelerate=accelerate,
            callback=callback,
            progress=progress,
            random_state=random_state,
        )
        self.beta = beta
        self.lam = lam
        self.low_rank = low_rank

    def _check_params(self):
        low, high = KERNEL_RANGE
        beta = check_float(self.beta, name="NonRigidCPD.beta", low=0.0, low_open=True)
        if not low <= beta <= high:
            raise InputError(
                f"`NonRigidCPD.beta` must be between 1e-150 and 1e150 (beta^2 must be representable); got {beta!r}."
            )
        lam = check_float(self.lam, name="NonRigidCPD.lam", low=0.0, low_open=True)
        if not low <= lam <= high:
            raise InputError(f"`NonRigidCPD.lam` must be between 1e-150 and 1e150; got {lam!r}.")
        if not (self.low_rank is None or (isinstance(self.low_rank, str) and self.low_rank == "auto")):
            check_int(self.low_rank, name="NonRigidCPD.low_rank", low=1)

    def _rank(self, n_moving: int):
        if self.low_rank is None:
            return None
        if isinstance(self.low_rank, str):  # 'auto'
            if n_moving <= _AUTO_EXACT_UP_TO:
                return None
            # the factorisation stops once it is exact to 1e-12 of G's trace (34 columns for
            # beta 2 in the normalised frame, 2D or 3D); a narrow kernel needs more, up to a
            # quarter of the points and at most 2,000 columns or 50 million entries of L
            room = min(n_moving // 4, 2000, 50_000_000 // n_moving)
            rank = max(50, math.ceil(math.sqrt(n_moving)), room)
            return None if rank >= n_moving - 1 else rank
        if self.low_rank >= n_moving - 1:
            return None  # ARPACK needs k < n; a full-rank "approximation" is the exact kernel
        return int(self.low_rank)

    def _init_state(self, moving, fixed, start):
        # the field acts on the pre-mapped moving points; the pre-map is kept for transform_
        self._pre = start
        self._work = moving if start is None else start(moving)
        n_moving = moving.shape[0]
        rank = self._rank(n_moving)
        beta = float(self.beta)
        work = self._work
        kernel = gaussian_kernel(work, work, beta) if rank is None else LowRankKernel(work, beta, rank)
        lost = kernel.residual_trace / n_moving if rank is not None else 0.0
        if lost > _LOW_RANK_LOSS:
            if isinstance(self.low_rank, str) and n_moving <= _AUTO_EXACT_FALLBACK:
                kept = len(kernel.values)
                kernel = gaussian_kernel(work, work, beta)  # too narrow a kernel to pay off
                if n_moving > _AUTO_EXACT_SLOW:
                    warn(
                        f"`beta={self.beta!r}` is too narrow for the low-rank kernel ({kept} "
                        f"eigenpairs leave {lost:.2g} of its trace out), so `low_rank='auto'` solves the exact "
                        f"{n_moving:,} x {n_moving:,} system at every EM step (O(M^3): on 4,500 points, about "
                        "a second a step). Pass `low_rank=None` to choose this, or a larger `beta`.",
                        UserWarning,
                    )
            else:
                warn(
                    f"`low_rank={self.low_rank!r}`: the {len(kernel.values)} eigenpairs kept leave {lost:.2g} of the "
                    "kernel's trace out, so the motion field is smoother than the model asks; pass a larger "
                    "low_rank (None: the exact kernel) or a larger `beta`.",
                    ConvergenceWarning,
                )
        return {"kernel": kernel, "coefficients": np.zeros_like(moving), "g_term": 0.0}

    def _apply(self, state, moving):
        return moving.copy()

    def _penalty(self, state) -> float:
        # tr(W^T G W), kept by the step that made W (it had G W at hand)
        return 0.5 * self.lam * state["g_term"]

    def _m_step(self, post, moving, fixed, state, sigma2):
        coefficients, moved, sigma2, g_term = nonrigid_m_step(post, moving, fixed, state["kernel"], self.lam, sigma2)
        return {"kernel": state["kernel"], "coefficients": coefficients, "g_term": g_term}, moved, sigma2

    def _vector(self, state):
        return state["coefficients"].ravel()

    def _from_vector(self, vector, state):
        kernel = state["kernel"]
        coefficients = vector.reshape(state["coefficients"].shape)
        field = kernel_times(kernel, coefficients)
        g_term = float(np.sum(coefficients * field))
        return {"kernel": kernel, "coefficients": coefficients, "g_term": g_term}, self._work + field

    def _rounding_note(self, moving):
        # a field value is a sum of kernel values (at most 1) times the coefficients: its
        # rounding is about eps times their sum, which the measured gaps between transform_
        # and moving_transformed_ followed within a factor 3 (exact copies: 2e-9 of the RMS
        # radius at lam 2, 5e-5 at lam 1e-8, 5e-2 at lam 1e-12)
        # (and only beyond what the result's own coordinates round off: a field that carries
        # the set 1e12 away sums to 1e12 with nothing cancelling)
        eps = np.finfo(float).eps
        radius = rms_radius(moving)
        rounding = eps * float(np.abs(self.transform_.coefficients).sum(axis=0).max())
        own = 16 * eps * float(np.abs(self.moving_transformed_).max())
        if not rounding > max(_FIELD_ROUNDING * radius, own):
            return None
        return (
            f"the field's coefficients sum to {rounding / eps:.1e}, so its values carry "
            f"rounding of about {rounding / radius:.0e} of the moving set's RMS radius (`transform_` and "
            "`moving_transformed_` may differ by that much): the fit interpolates almost without smoothing, "
            f"as happens when sigma2 shrinks to nothing at a small `lam` ({self.lam:g}). A larger `lam` or "
            "`beta` gives a field that rounding does not disturb."
        )

    def _make_transform(self, state, moving, frame):
        kernel, coefficients = state["kernel"], state["coefficients"]
        centres = self._work
        if isinstance(kernel, LowRankKernel):
            # the low-rank field as kernel weights on the pivots: equal to the fitted
            # displacement at every moving point (weights G Q Q^T W matched it only up to the
            # part of G outside the kept eigenvectors, which is not small at a low rank)
            pivots, coefficients = kernel.pivot_field(coefficients)
            centres = centres[pivots]
        pre = self._pre
        if frame.identity and pre is None:
            return NonRigidTransform(centres, coefficients, self.beta)
        # v = s * pre_n((y - mu_y) / s) = L (y - mu_y) + s t_n, and T(y) = mu_x + v + field(v):
        # the field scales with s, and its arguments stay as small as in the fit
        linear = translation = None
        if pre is not None:
            linear = pre.linear if isinstance(pre, AffineTransform) else pre.scale * pre.rotation
            translation = frame.scale * pre.translation
        return NonRigidTransform(
            frame.scale * centres,
            frame.scale * coefficients,
            frame.scale * float(self.beta),
            linear=linear,
            translation=translation,
            input_origin=frame.moving_centre,
            output_origin=frame.fixed_centre,
        )


# NonRigidCPD warns when its field's rounding exceeds this share of the moving set's RMS radius
_FIELD_ROUNDING = 1e-6

# low_rank='auto': exact up to this many moving points; above, the low-rank kernel unless it
# leaves more than _LOW_RANK_LOSS of G's trace (the mean diagonal residual, a bound on its
# spectral-norm error over M) out, when up to _AUTO_EXACT_FALLBACK points are solved exactly
# and more get a warning (as does a low_rank given as a number)
_AUTO_EXACT_UP_TO = 500
_AUTO_EXACT_FALLBACK = 5000
# ... and that fallback warns above this many (4,500 points took 65 s for 60 steps)
_AUTO_EXACT_SLOW = 2000
_LOW_RANK_LOSS = 1e-6


for _cls in (RigidCPD, AffineCPD, NonRigidCPD):
    _cls.__doc__ = _cls.__doc__.replace("{common}", _COMMON_PARAMETERS).replace("{attributes}", _COMMON_ATTRIBUTES)
del _cls

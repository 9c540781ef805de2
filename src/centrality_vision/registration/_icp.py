"""Iterative Closest Point (Besl and McKay 1992; Chen and Medioni 1992) with a k-d tree.

Point-to-point updates are closed form (SVD, proper rotation); point-to-plane updates solve
the linearised problem for a small rotation and a translation and compose it with the
current pose. Pairs can be limited by a maximum distance and trimmed (Chetverikov et al.'s
trimmed ICP: the worst fraction dropped at each iteration).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from .._deprecation import FORMER, former_parameter, renamed_parameters
from .._parallel import get_num_threads
from .._validation import ANY_DIMS, as_points, check_bool, check_choice, check_float, check_int
from .._warnings import warn
from ..exceptions import CollapseWarning, ConvergenceWarning, InputError
from ..transforms import RigidTransform, SimilarityTransform, least_squares_similarity, power_of_two_scale
from ._cpd import (
    IterationInfo,
    _Frame,
    _start_within_reach,
    _stops,
    nearest_score,
    one_point_fixed,
    warn_rotation_spans,
)

__all__ = ["ICP", "estimate_normals"]

METRICS = ("point_to_point", "point_to_plane")
# A mean squared residual below this (sets of unit RMS radius) is rounding error: converged
# (or below the rounding the caller's coordinates carry into the normalised frame, if larger).
_COINCIDE = 1e-26


@renamed_parameters(k="n_neighbors")
def estimate_normals(points, *, n_neighbors: int = 10) -> np.ndarray:
    """Unit normals by local PCA: for each point, the direction of least variance of its
    ``n_neighbors`` nearest neighbours (itself included). The sign is arbitrary.

    Parameters
    ----------
    points : array_like of shape (n_points, 2) or (n_points, 3)
        At least ``n_dims`` points.
    n_neighbors : int >= n_dims, default=10
        Neighbours per point (``k`` is its former name); at most ``n_points`` are used. A point whose neighbours are
        one point repeated (or, in 3D, lie on one line) has no normal; a
        :class:`UserWarning` counts such points.

    Returns
    -------
    ndarray of shape (n_points, n_dims)
        One unit normal per row of ``points``.

    Examples
    --------
    >>> import numpy as np
    >>> g = np.stack(np.meshgrid(np.arange(5.0), np.arange(5.0)), -1).reshape(-1, 2)
    >>> plane = np.c_[g, np.zeros(25)]  # the plane z = 0
    >>> bool(np.allclose(np.abs(estimate_normals(plane, n_neighbors=6)[:, 2]), 1.0))
    True
    """
    points = as_points(points, name="points", n_dims=(2, 3), min_points=2)
    dim = points.shape[1]
    if points.shape[0] < dim:
        raise InputError(
            f"`points` must have at least {dim} points in {dim}D (a normal needs {dim}); got {points.shape[0]}."
        )
    # a line through 2 points has a normal in 2D; a plane takes 3 in 3D
    k = min(check_int(n_neighbors, name="n_neighbors", low=dim), points.shape[0])
    # normals do not depend on scale: a power-of-two scale to unit size is exact, and keeps
    # the k-d tree's squared distances from overflowing past 1e154 (it then reported no
    # neighbours) or underflowing below 1e-154
    points = points / power_of_two_scale(points)
    _, neighbours = cKDTree(points).query(points, k=k, workers=get_num_threads())
    patches = points[neighbours]  # (n, k, D)
    patches = patches - patches.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", patches, patches)
    values, vectors = np.linalg.eigh(cov)  # ascending eigenvalues
    # a neighbourhood of one point (duplicates), or one line in 3D, has no normal: its
    # least-variance direction is any of two or more
    # (the coordinates are of unit size here, so rounding of the patch means leaves variances
    # near k eps^2: copies of one point do not average back to it exactly)
    floor = np.maximum(_FLAT_PATCH * values[:, -1], k * (8 * np.finfo(float).eps) ** 2)
    undetermined = int(np.count_nonzero(values[:, 1] <= floor))
    if undetermined:
        warn(
            f"estimate_normals: {undetermined} of {points.shape[0]} points have neighbourhoods of one point"
            f"{' or one line' if dim == 3 else ''} (their {k} nearest points), so their normals are arbitrary; "
            "deduplicate the points or raise `k`.",
            UserWarning,
        )
    return np.ascontiguousarray(vectors[:, :, 0])


#: A neighbourhood whose second-least variance is at most this fraction of its largest has
#: no normal (double rounding of unit-scale coordinates is far below it).
_FLAT_PATCH = 1e-20


def _small_rotation(omega: np.ndarray, n_dims: int) -> np.ndarray:
    """The rotation of angle vector ``omega`` (a scalar angle in 2D, Rodrigues in 3D)."""
    if n_dims == 2:
        a = float(omega[0])
        return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    angle = float(np.linalg.norm(omega))
    if angle == 0.0:
        return np.eye(3)
    axis = omega / angle
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


#: A motion whose singular value in the point-to-plane system is below this fraction of the
#: largest moves no point off its plane: the fixed set leaves it free (a plane, a line).
_FREE_MOTION = 1e-8


def _point_to_plane_step(current: np.ndarray, targets: np.ndarray, normals: np.ndarray):
    """``(R, t, free)`` minimising ``sum (n_i . (R p_i + t - q_i))^2`` linearised in the rotation;
    ``free`` counts the motions the normals do not constrain (the minimum-norm solution leaves
    them at zero)."""
    n_dims = current.shape[1]
    centre = current.mean(axis=0)
    p = current - centre  # rotate about the centroid: better conditioned
    if n_dims == 2:
        rot_part = (p[:, 0] * normals[:, 1] - p[:, 1] * normals[:, 0])[:, None]
    else:
        rot_part = np.cross(p, normals)
    a = np.hstack([rot_part, normals])
    b = np.einsum("ij,ij->i", targets - current, normals)
    solution, _, _, singular = np.linalg.lstsq(a, b, rcond=None)
    free = a.shape[1] - int(np.count_nonzero(singular > _FREE_MOTION * singular.max(initial=0.0)))
    n_rot = 1 if n_dims == 2 else 3
    rotation = _small_rotation(solution[:n_rot], n_dims)
    translation = solution[n_rot:] + centre - rotation @ centre
    return rotation, translation, free


class ICP(BaseEstimator):
    """Iterative Closest Point: match each moving point to its nearest fixed point, refit.

    Each iteration pairs every transformed moving point with its closest fixed point (k-d
    tree), keeps the pairs within ``max_distance`` and drops the ``trim`` fraction with the
    largest distances, and solves for the pose: the least-squares rigid (or similarity,
    ``scale=True``) transform of the kept moving points onto their partners in closed form
    (``metric='point_to_point'``), or the rigid motion minimising the squared distances to
    the partners' tangent planes (``'point_to_plane'``, normals of the fixed set by local
    PCA over ``normal_neighbors`` neighbours). Stops when the relative change of the objective
    (the mean squared residual of the kept pairs) is at most ``tol``, or after ``max_iter``
    updates. ICP converges to the nearest local minimum: start it close (``init=``).

    The work is done on both sets centred on the fixed set's mean and divided by their
    common RMS radius (the start pose is unchanged by this), so huge or tiny coordinates
    neither overflow nor lose precision; results are in the caller's units.

    Parameters
    ----------
    scale : bool, default=False
        Also fit an isotropic scale (point-to-point only). It is held at the start's until
        the rigid fit settles, then fitted: a least-squares scale on wrong nearest-neighbour
        pairs shrinks the set (a copy shifted by its own radius ended at scale 0.49, a
        turned one at 0.07).
    max_iter : int, default=100
    tol : float, default=1e-6
    max_distance : float, optional
        Pairs farther apart than this (in the caller's units) are ignored.
    trim : float in [0, 1), default=0
        Fraction of the pairs with the largest distances ignored at each iteration; set it
        to about the share of moving points that have no partner (overlap 80% -> 0.2).
    metric : {'point_to_point', 'point_to_plane'}, default='point_to_point'
        With a flat (3D) or straight (2D) fixed set, point-to-plane leaves the motions along it
        free: a :class:`~centrality_vision.exceptions.ConvergenceWarning` then says so.
    normal_neighbors : int >= 3, default=10
        Neighbours for the normals of ``metric='point_to_plane'`` (the point itself
        included; :func:`estimate_normals` takes 2, enough in 2D only).
    init : RigidTransform or SimilarityTransform, optional
        Starting pose (identity by default).
    callback : callable, optional
        Called with an :class:`IterationInfo` (``objective`` = mean squared residual,
        ``sigma2`` = NaN) after each matching; return ``True`` (or ``numpy.True_``) to stop.
    k_normals : deprecated
        The former name of ``normal_neighbors``; it still works, with a FutureWarning, and
        will be removed.

    Attributes
    ----------
    transform_, moving_transformed_, n_iter_, converged_ : as for :class:`RigidCPD`
    history_ : dict
        ``objective`` (mean squared residual of the kept pairs), ``n_pairs`` (pairs kept)
        and ``error`` per iteration.
    moving_to_fixed_ : ndarray of shape (M,)
        For each moving point its nearest fixed point (-1 where it was not kept).
    fixed_to_moving_ : ndarray of shape (N,)
        For each fixed point the nearest transformed moving point (``correspondence_`` is
        its deprecated alias).

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((200, 2))
    >>> angle = 0.1
    >>> r = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    >>> icp = ICP(tol=1e-12).fit(y, y @ r.T + 0.02)
    >>> bool(np.allclose(icp.transform_.rotation, r, atol=1e-8))
    True
    """

    def __init__(
        self,
        *,
        scale=False,
        max_iter=100,
        tol=1e-6,
        max_distance=None,
        trim=0.0,
        metric="point_to_point",
        normal_neighbors=10,
        init=None,
        callback=None,
        k_normals=FORMER,
    ):
        self.scale = scale
        self.max_iter = max_iter
        self.tol = tol
        self.max_distance = max_distance
        self.trim = trim
        self.metric = metric
        self.normal_neighbors = normal_neighbors
        self.init = init
        self.callback = callback
        self.k_normals = k_normals

    def _check_params(self):
        check_bool(self.scale, name="ICP.scale")
        check_int(self.max_iter, name="ICP.max_iter", low=0)
        check_float(self.tol, name="ICP.tol", low=0.0)
        if self.max_distance is not None:
            check_float(self.max_distance, name="ICP.max_distance", low=0.0, low_open=True)
        check_float(self.trim, name="ICP.trim", low=0.0, high=1.0, high_open=True)
        check_choice(self.metric, METRICS, name="ICP.metric")
        neighbors, name = former_parameter(self, "k_normals", "normal_neighbors")
        neighbors = check_int(neighbors, name=name, low=3)
        if self.metric == "point_to_plane" and self.scale:
            raise InputError("`ICP.scale=True` needs metric='point_to_point'; point-to-plane fits a rigid motion.")
        if self.init is not None and not isinstance(self.init, SimilarityTransform):
            raise TypeError(f"`ICP.init` must be None or a RigidTransform/SimilarityTransform; got {self.init!r}.")
        if self.callback is not None and not callable(self.callback):
            raise TypeError(f"`ICP.callback` must be callable or None; got {self.callback!r}.")
        return neighbors

    def fit(self, moving, fixed, *, true_moving=None):
        """Register ``moving`` onto ``fixed``; returns ``self``. See :meth:`RigidCPD.fit`.

        Parameters
        ----------
        moving : array_like of shape (M, D)
            The set to transform, at least D + 1 points (D from 1 to 64; 2 or 3 for
            ``metric='point_to_plane'``). Not modified.
        fixed : array_like of shape (N, D)
            The set it is brought onto, of the same D (at least D points for
            ``metric='point_to_plane'``). Not modified.
        true_moving : array_like of shape (M, D), optional
            Where each moving point truly belongs; ``history_["error"]`` then holds
            ``|true_moving - T(Y)|`` per iteration (None otherwise).

        Returns
        -------
        self : ICP

        Examples
        --------
        A rotated copy with a fifth of its points replaced by far clutter; ``trim=0.2``
        ignores the worst fifth of the pairs:

        >>> import numpy as np
        >>> y = np.random.default_rng(0).random((30, 2))
        >>> r = np.array([[np.cos(0.1), -np.sin(0.1)], [np.sin(0.1), np.cos(0.1)]])
        >>> x = np.vstack([(y @ r.T + 0.02)[:24], np.random.default_rng(1).random((6, 2)) + 3.0])
        >>> icp = ICP(tol=1e-12, trim=0.2).fit(y, x)
        >>> icp.converged_, bool(np.allclose(icp.transform_.rotation, r))
        (True, True)
        >>> icp.moving_to_fixed_[22:26].tolist(), int(icp.history_["n_pairs"][-1])  # -1: not kept
        ([22, 23, -1, -1], 24)
        """
        normal_neighbors = self._check_params()
        moving = as_points(moving, name="moving", n_dims=ANY_DIMS)
        fixed = as_points(fixed, name="fixed", n_dims=(moving.shape[1],))
        if true_moving is not None:
            true_moving = as_points(true_moving, name="true_moving", n_dims=(moving.shape[1],))
            if true_moving.shape != moving.shape:
                raise InputError(
                    f"`true_moving` must have the shape of `moving` {moving.shape}; got {true_moving.shape}."
                )
        dim = moving.shape[1]
        if moving.shape[0] < dim + 1:
            raise InputError(
                f"`moving` must have at least {dim + 1} points for ICP in {dim}D (a pose needs {dim + 1} pairs); "
                f"got {moving.shape[0]}."
            )
        if self.metric == "point_to_plane" and dim not in (2, 3):
            raise InputError(f"`ICP.metric='point_to_plane'` needs 2D or 3D points; got {dim}D.")
        if self.metric == "point_to_plane" and fixed.shape[0] < dim:
            raise InputError(
                f"`fixed` must have at least {dim} points for metric='point_to_plane' (a normal needs {dim}); "
                f"got {fixed.shape[0]}."
            )
        frame, moving_n, fixed_n = _Frame.of(moving, fixed, True, same_centre=True)
        warn_rotation_spans(moving, fixed, "ICP: ")  # (after the frame's errors: no warning before one)
        true_n = frame.true_in(true_moving)
        # the normalised coordinates carry the rounding of the caller's (an offset of 1e4
        # leaves ~1e-12 of a unit radius): residuals below it are rounding error too
        peak = max(float(np.max(np.abs(moving))), float(np.max(np.abs(fixed)))) / frame.scale
        coincide = max(_COINCIDE, (np.finfo(float).eps * peak) ** 2)
        max_d = None if self.max_distance is None else float(self.max_distance) / frame.scale
        normals = estimate_normals(fixed_n, n_neighbors=normal_neighbors) if self.metric == "point_to_plane" else None
        tree = cKDTree(fixed_n)
        if self.init is None:
            transform = (
                SimilarityTransform(np.eye(dim), np.zeros(dim))
                if self.scale
                else RigidTransform(np.eye(dim), np.zeros(dim))
            )
        else:
            if self.init.rotation.shape != (dim, dim):
                raise InputError(f"`ICP.init` must be a {dim}D transform; got a {self.init.rotation.shape[0]}D one.")
            if not self.scale and self.init.scale != 1.0:
                raise InputError(f"`ICP.init` must have scale 1 when scale=False; got {self.init.scale!r}.")
            transform = _start_within_reach(frame, self.init, moving_n, "ICP.init")  # (an IndexError beyond)
            if not self.scale:
                transform = RigidTransform(transform.rotation, transform.translation)
        moving_t = transform(moving_n)
        objectives, errors, n_pairs = [], [], []
        previous = None
        converged = False
        stopped = None
        iteration = 0
        scale2 = frame.scale**2
        keep = np.ones(moving_n.shape[0], dtype=bool)
        last = None  # the previous iterate: (transform, moving_t, partner, keep)
        # scale=True: the scale is held at the start's until the rigid fit settles (fitted on
        # wrong pairs it shrinks the set: a copy shifted by half its radius ended at 0.87, by
        # its radius at 0.49, and a turned one at 0.07, all "converged")
        holding = bool(self.scale)
        free = 0  # motions the last point-to-plane step left unconstrained
        while True:
            dist, partner = tree.query(moving_t, k=1, workers=get_num_threads())
            keep = self._kept(dist, max_d)
            if self.metric == "point_to_plane":
                residual = np.einsum("ij,ij->i", moving_t - fixed_n[partner], normals[partner])
                residual2 = residual * residual
            else:
                residual2 = dist * dist
            if np.count_nonzero(keep) < dim + 1:
                if last is None:
                    kept_by_distance = np.count_nonzero(self._kept(dist, max_d, trim=False))
                    if kept_by_distance >= dim + 1:  # the trimming took the rest
                        raise InputError(
                            f"`trim={self.trim}` leaves {int(np.count_nonzero(keep))} of {dist.shape[0]} pairs "
                            f"(at least {dim + 1} are needed); lower it."
                        )
                    raise InputError(
                        f"`max_distance={self.max_distance}` leaves ICP only {int(np.count_nonzero(keep))} "
                        f"pairs at the start (at least {dim + 1} are needed); start closer (`init`) or raise "
                        "`max_distance`."
                    )
                # the last step moved the pairs out of reach: its iterate is dropped, the one
                # before (which had pairs) is the result
                stopped = (
                    f"only {int(np.count_nonzero(keep))} pairs within `max_distance={self.max_distance}` "
                    f"after trimming at iteration {iteration}; stopped at the iterate before, the last "
                    "with enough pairs. Start closer (`init`) or raise `max_distance`."
                )
                transform, moving_t, partner, keep = last
                iteration -= 1
                break
            objective = float(np.mean(residual2[keep]))
            error = None if true_n is None else float(np.linalg.norm(true_n - moving_t)) * frame.scale
            objectives.append(objective * scale2)
            errors.append(error)
            n_pairs.append(int(np.count_nonzero(keep)))
            if self.callback is not None:
                info = IterationInfo(
                    iteration,
                    frame.linear_out(transform),
                    frame.points_out(moving_t),
                    float("nan"),
                    objective * scale2,
                    error,
                )
                if _stops(self.callback(info)):
                    break
            settled = previous is not None and abs(previous - objective) <= self.tol * max(previous, 1e-300)
            if settled and holding:  # the rigid fit has settled: now the scale too
                holding, settled, previous = False, False, None
            if objective <= coincide or settled:
                converged = True
                break
            if iteration >= self.max_iter:
                break
            previous = objective
            last = (transform, moving_t, partner, keep)
            if self.metric == "point_to_plane":
                rotation, translation, free = _point_to_plane_step(
                    moving_t[keep], fixed_n[partner[keep]], normals[partner[keep]]
                )
                transform = RigidTransform(
                    rotation @ transform.rotation, rotation @ transform.translation + translation
                )
            elif holding:
                held = transform.scale
                rotation, translation, _ = least_squares_similarity(
                    held * moving_n[keep], fixed_n[partner[keep]], scale=False
                )
                transform = SimilarityTransform(rotation, translation, held)
            else:
                rotation, translation, s = least_squares_similarity(
                    moving_n[keep], fixed_n[partner[keep]], scale=bool(self.scale)
                )
                transform = (
                    SimilarityTransform(rotation, translation, s)
                    if self.scale
                    else RigidTransform(rotation, translation)
                )
            moving_t = transform(moving_n)
            iteration += 1
        # every moving point pairs with the one fixed point: the rotation is arbitrary (and a
        # scale shrinks to 0), yet the residual stops changing
        one_point = one_point_fixed(moving_n, fixed_n)
        if one_point is not None:
            converged = False
            warn(f"ICP: {one_point}", CollapseWarning)
        if free:
            # (a planar or linear fixed set: the pose slid freely along it and came back
            # "converged" at the start's position, 0.05 off on a shifted plane)
            warn(
                f"ICP: the fixed set's normals leave {free} of the {3 if dim == 2 else 6} rigid motions free (a "
                "flat or straight fixed set): the pose along them is the start's, not a fit. Use "
                "`metric='point_to_point'`.",
                ConvergenceWarning,
            )
        if stopped is not None:
            warn(f"ICP: {stopped}", ConvergenceWarning)
        elif not converged and iteration >= self.max_iter and self.max_iter > 0 and self.tol > 0:
            warn(
                f"ICP stopped at `max_iter={self.max_iter}` before meeting `tol={self.tol}`.",
                ConvergenceWarning,
            )
        self.transform_ = frame.linear_out(transform)
        self.moving_transformed_ = frame.points_out(moving_t)
        self.n_iter_ = iteration
        self.converged_ = converged
        self.history_ = {
            "objective": np.array(objectives),
            "n_pairs": np.array(n_pairs),
            "error": None if true_moving is None else np.array(errors),
        }
        self.moving_to_fixed_ = np.where(keep, partner, -1)
        self.fixed_to_moving_ = cKDTree(moving_t).query(fixed_n, k=1, workers=get_num_threads())[1]
        return self

    def _kept(self, dist: np.ndarray, max_d: float | None, *, trim: bool = True) -> np.ndarray:
        keep = np.ones(dist.shape[0], dtype=bool) if max_d is None else dist <= max_d
        if trim and self.trim > 0:
            n_drop = int(math.floor(self.trim * dist.shape[0]))
            if n_drop > 0:
                worst = np.argsort(dist, kind="stable")[dist.shape[0] - n_drop :]
                keep[worst] = False
        return keep

    def transform(self, points) -> np.ndarray:
        """Apply the fitted transform to new points.

        Parameters
        ----------
        points : array_like of shape (n_points, D)
            Points in the moving set's frame, D as in :meth:`fit`.

        Returns
        -------
        ndarray of shape (n_points, D)
            ``transform_(points)``.

        Examples
        --------
        >>> import numpy as np
        >>> y = np.random.default_rng(0).random((30, 2))
        >>> r = np.array([[np.cos(0.1), -np.sin(0.1)], [np.sin(0.1), np.cos(0.1)]])
        >>> icp = ICP(tol=1e-12).fit(y, y @ r.T + 0.02)
        >>> icp.transform([[0.0, 0.0], [1.0, 0.0]]).round(3)  # r @ p + 0.02
        array([[0.02 , 0.02 ],
               [1.015, 0.12 ]])
        """
        check_is_fitted(self, "transform_")
        return self.transform_(points)

    def score(self, moving, fixed) -> float:
        """Minus the mean distance from each fixed point to its nearest transformed moving point.

        Larger is better; in the caller's units, as the CPD estimators' ``score``, so that
        scikit-learn's model selection (e.g. ``GridSearchCV(ICP(), {"trim": [0, 0.1]},
        cv=[(index, index)])`` on sets of equal size) ranks ICP's settings too.

        Examples
        --------
        >>> import numpy as np
        >>> y = np.random.default_rng(0).random((30, 2))
        >>> icp = ICP(tol=1e-12).fit(y, y + 0.02)
        >>> abs(icp.score(y, y + 0.02)) < 1e-9  # every fixed point met
        True
        """
        return nearest_score(self, moving, fixed)

    @property
    def correspondence_(self) -> np.ndarray:
        """Deprecated alias of ``fixed_to_moving_``."""
        check_is_fitted(self, "fixed_to_moving_")
        warn(
            "`ICP.correspondence_` is deprecated; use `fixed_to_moving_` (same values) or `moving_to_fixed_`.",
            FutureWarning,
        )
        return self.fixed_to_moving_

"""Iterative Closest Point (Besl and McKay 1992) with a k-d tree and a closed-form update."""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial import cKDTree

from .._parallel import get_num_threads
from .._validation import ANY_DIMS, as_points, check_float, check_int
from ..exceptions import ConvergenceWarning, InputError
from ..transforms import RigidTransform, SimilarityTransform, least_squares_similarity
from ._cpd import IterationInfo

__all__ = ["ICP"]


def _fit(source, target, scale: bool):
    """Least-squares rigid/similarity transform taking ``source`` rows onto ``target`` rows."""
    rotation, translation, s = least_squares_similarity(source, target, scale=scale)
    return SimilarityTransform(rotation, translation, s) if scale else RigidTransform(rotation, translation)


class ICP:
    """Iterative Closest Point: match each moving point to its nearest fixed point, refit.

    Each iteration pairs every transformed moving point with its closest fixed point (k-d
    tree) and solves the least-squares rigid (or similarity, ``scale=True``) transform of the
    original moving set onto those partners in closed form (SVD, proper rotation). Stops when
    the relative change of the mean squared distance is at most ``tol``, or after
    ``max_iter`` updates. ICP converges to the nearest local minimum: start it close.

    Parameters
    ----------
    scale : bool, default=False
    max_iter : int, default=100
    tol : float, default=1e-6
    callback : callable, optional
        Called with an :class:`IterationInfo` (``objective`` = mean squared distance,
        ``sigma2`` = NaN) after each matching; return ``True`` to stop.

    Attributes
    ----------
    transform_, moving_transformed_, n_iter_, converged_ : as for :class:`RigidCPD`
    history_ : dict
        ``objective`` (mean squared closest-point distance) and ``error`` per iteration.
    correspondence_ : ndarray of shape (N,)
        For each fixed point the nearest transformed moving point.

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.transforms import random_rotation
    >>> y = np.random.default_rng(0).random((200, 2))
    >>> angle = 0.1
    >>> r = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    >>> icp = ICP(tol=1e-12).fit(y, y @ r.T + 0.02)
    >>> bool(np.allclose(icp.transform_.rotation, r, atol=1e-8))
    True
    """

    def __init__(self, *, scale=False, max_iter=100, tol=1e-6, callback=None):
        self.scale = scale
        self.max_iter = max_iter
        self.tol = tol
        self.callback = callback

    def __repr__(self) -> str:
        return f"ICP(scale={self.scale!r}, max_iter={self.max_iter!r}, tol={self.tol!r}, callback={self.callback!r})"

    def fit(self, moving, fixed, *, true_moving=None):
        """Register ``moving`` onto ``fixed``; returns ``self``. See :meth:`RigidCPD.fit`."""
        if not isinstance(self.scale, (bool, np.bool_)):
            raise TypeError(f"`ICP.scale` must be a bool; got {self.scale!r}.")
        check_int(self.max_iter, name="ICP.max_iter", low=0)
        check_float(self.tol, name="ICP.tol", low=0.0)
        if self.callback is not None and not callable(self.callback):
            raise TypeError(f"`ICP.callback` must be callable or None; got {self.callback!r}.")
        moving = as_points(moving, name="moving", n_dims=ANY_DIMS)
        fixed = as_points(fixed, name="fixed", n_dims=(moving.shape[1],))
        if true_moving is not None:
            true_moving = as_points(true_moving, name="true_moving", n_dims=(moving.shape[1],))
            if true_moving.shape != moving.shape:
                raise InputError(f"`true_moving` must have the shape of `moving` {moving.shape}; got {true_moving.shape}.")
        dim = moving.shape[1]
        tree = cKDTree(fixed)
        transform = SimilarityTransform(np.eye(dim), np.zeros(dim)) if self.scale else RigidTransform(np.eye(dim), np.zeros(dim))
        moving_t = moving.copy()
        objectives, errors = [], []
        previous = None
        converged = False
        iteration = 0
        while True:
            dist, partner = tree.query(moving_t, k=1, workers=get_num_threads())
            objective = float(np.mean(dist * dist))
            error = None if true_moving is None else float(np.linalg.norm(true_moving - moving_t))
            objectives.append(objective)
            errors.append(error)
            if self.callback is not None:
                if self.callback(IterationInfo(iteration, transform, moving_t.copy(), float("nan"), objective, error)) is True:
                    break
            if objective == 0.0 or (previous is not None and abs(previous - objective) <= self.tol * max(previous, 1e-300)):
                converged = True
                break
            if iteration >= self.max_iter:
                break
            previous = objective
            transform = _fit(moving, fixed[partner], bool(self.scale))
            moving_t = transform(moving)
            iteration += 1
        if not converged and iteration >= self.max_iter and self.max_iter > 0 and self.tol > 0:
            warnings.warn(f"ICP stopped at max_iter={self.max_iter} before meeting tol={self.tol}.", ConvergenceWarning, stacklevel=2)
        self.transform_ = transform
        self.moving_transformed_ = moving_t
        self.n_iter_ = iteration
        self.converged_ = converged
        self.history_ = {"objective": np.array(objectives), "error": None if true_moving is None else np.array(errors)}
        self.correspondence_ = cKDTree(moving_t).query(fixed, k=1, workers=get_num_threads())[1]
        return self

    def transform(self, points) -> np.ndarray:
        """Apply the fitted transform to new points."""
        if not hasattr(self, "transform_"):
            raise InputError("This ICP is not fitted yet; call fit(moving, fixed) first.")
        return self.transform_(points)

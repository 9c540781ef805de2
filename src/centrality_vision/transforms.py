"""Geometric transforms of point sets and their least-squares fits.

Frozen dataclasses, callable on points of shape (n_points, n_dims); ``.matrix`` is the
homogeneous (D+1) x (D+1) matrix and ``.inverse()`` the inverse transform. Rotations are
proper (det R = +1). Used by matching and registration alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validation import as_points
from .exceptions import InputError

__all__ = ["SimilarityTransform", "fit_similarity"]


@dataclass(frozen=True)
class SimilarityTransform:
    """``x -> scale * rotation @ x + translation``.

    Attributes
    ----------
    rotation : ndarray of shape (D, D)
        Proper rotation (orthogonal, determinant +1).
    translation : ndarray of shape (D,)
    scale : float
        Positive; 1 for a rigid transform.

    Examples
    --------
    >>> import numpy as np
    >>> t = SimilarityTransform(np.array([[0.0, -1.0], [1.0, 0.0]]), np.array([1.0, 0.0]), 2.0)
    >>> t(np.array([[1.0, 0.0]]))
    array([[1., 2.]])
    >>> np.allclose(t.inverse()(t(np.eye(2))), np.eye(2))
    True
    """

    rotation: np.ndarray
    translation: np.ndarray
    scale: float = 1.0

    def __post_init__(self):
        rotation = np.array(self.rotation, dtype=float)
        translation = np.array(self.translation, dtype=float).ravel()
        dim = rotation.shape[0]
        if rotation.shape != (dim, dim) or translation.shape != (dim,):
            raise InputError(
                f"`rotation` must be (D, D) and `translation` (D,); got {rotation.shape} and {translation.shape}."
            )
        if not np.isfinite(self.scale) or self.scale <= 0:
            raise InputError(f"`scale` must be a finite number > 0; got {self.scale!r}.")
        rotation.setflags(write=False)
        translation.setflags(write=False)
        object.__setattr__(self, "rotation", rotation)
        object.__setattr__(self, "translation", translation)
        object.__setattr__(self, "scale", float(self.scale))

    @property
    def matrix(self) -> np.ndarray:
        """Homogeneous matrix of shape (D+1, D+1)."""
        dim = self.rotation.shape[0]
        out = np.eye(dim + 1)
        out[:dim, :dim] = self.scale * self.rotation
        out[:dim, dim] = self.translation
        return out

    def __call__(self, points) -> np.ndarray:
        points = as_points(points, name="points", n_dims=(self.rotation.shape[0],))
        return self.scale * points @ self.rotation.T + self.translation

    def inverse(self) -> "SimilarityTransform":
        rotation = self.rotation.T
        return SimilarityTransform(rotation, -(rotation @ self.translation) / self.scale, 1.0 / self.scale)


def fit_similarity(source, target, *, scale: bool = True) -> SimilarityTransform:
    """Least-squares similarity (or rigid) transform taking ``source`` onto ``target``.

    Minimises ``sum |s R x_i + t - y_i|^2`` over proper rotations (Umeyama's closed form).

    References
    ----------
    .. [1] S. Umeyama, "Least-squares estimation of transformation parameters between two
       point patterns", IEEE PAMI 13(4), 376-380, 1991.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(0).random((10, 2))
    >>> angle = 0.3
    >>> r = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    >>> t = fit_similarity(x, 2 * x @ r.T + 1)
    >>> round(t.scale, 6), np.allclose(t.rotation, r)
    (2.0, True)
    """
    source = as_points(source, name="source", n_dims=(2, 3), min_points=2)
    target = as_points(target, name="target", n_dims=(source.shape[1],), min_points=2)
    if source.shape != target.shape:
        raise InputError(f"`source` and `target` must have the same shape; got {source.shape} and {target.shape}.")
    mu_s, mu_t = source.mean(axis=0), target.mean(axis=0)
    xs, xt = source - mu_s, target - mu_t
    u, sv, vt = np.linalg.svd(xt.T @ xs)
    d = np.ones(source.shape[1])
    d[-1] = np.sign(np.linalg.det(u @ vt)) or 1.0
    rotation = (u * d) @ vt
    var = np.sum(xs**2)
    s = float(np.sum(sv * d) / var) if scale and var > 0 else 1.0
    return SimilarityTransform(rotation, mu_t - s * rotation @ mu_s, s if s > 0 else 1.0)

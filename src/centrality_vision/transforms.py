"""Geometric transforms of point sets and their least-squares fits.

Frozen dataclasses, callable on points of shape (n_points, n_dims); ``.matrix`` is the
homogeneous (D+1) x (D+1) matrix and ``.inverse()`` the inverse transform. Rotations are
proper (det R = +1). Used by matching and registration alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._deprecation import renamed_parameters
from ._validation import as_points, as_real_array, check_bool, check_float, check_int
from .exceptions import InputError

__all__ = [
    "RigidTransform",
    "SimilarityTransform",
    "AffineTransform",
    "NonRigidTransform",
    "fit_similarity",
    "least_squares_similarity",
    "proper_rotation",
    "random_rotation",
    "centred",
    "power_of_two_scale",
    "rms_radius",
]


def _real_array(value, name: str) -> np.ndarray:
    """``value`` as a new float64 array, or an error naming ``name`` (None, text, complex)."""
    return np.array(as_real_array(value, name=name), dtype=float)


def _frozen(array, name: str = "array") -> np.ndarray:
    array = _real_array(array, name)
    array.setflags(write=False)
    return array


def _finite_result(points: np.ndarray, what: str) -> np.ndarray:
    """``points`` if finite; else a named error (the transform took them beyond float64)."""
    if not np.all(np.isfinite(points)):
        raise InputError(
            f"`points` mapped by this {what} leave the float64 range (inf or NaN in the result); "
            "rescale the points or the transform."
        )
    return points


class _ArrayEquality:
    """Equality and hash by value for the frozen transforms (their fields hold arrays)."""

    def _fields(self) -> tuple:
        return tuple(getattr(self, f) for f in self.__dataclass_fields__)

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return all(
            (a is None and b is None)
            or (a is not None and b is not None and np.array_equal(np.asarray(a), np.asarray(b)))
            for a, b in zip(self._fields(), other._fields())
        )

    def __hash__(self):
        # "+ 0.0" turns -0.0 into 0.0: equal values (np.array_equal) must hash alike, and an
        # inverse's translation of an identity is -0.0
        parts = [type(self).__name__]
        for value in self._fields():
            parts.append(None if value is None else (np.shape(value), (np.asarray(value) + 0.0).tobytes()))
        return hash(tuple(parts))

    def __setstate__(self, state: dict) -> None:
        # pickle and deepcopy restore the fields without __post_init__: keep the arrays read-only
        for name, value in state.items():
            if isinstance(value, np.ndarray):
                value = value.copy()
                value.setflags(write=False)
            object.__setattr__(self, name, value)


@dataclass(frozen=True, eq=False)
class SimilarityTransform(_ArrayEquality):
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
        rotation = _real_array(self.rotation, "rotation")
        translation = _real_array(self.translation, "translation").ravel()
        dim = rotation.shape[0] if rotation.ndim == 2 else -1
        if dim < 1 or rotation.shape != (dim, dim) or translation.shape != (dim,):
            raise InputError(
                f"`rotation` must be (D, D) and `translation` (D,) with D >= 1; "
                f"got {rotation.shape} and {translation.shape}."
            )
        scale = check_float(self.scale, name="scale", low=0.0, low_open=True)
        if not np.all(np.isfinite(rotation)) or not np.all(np.isfinite(translation)):
            raise InputError("`rotation` and `translation` must be finite; got NaN or inf.")
        with np.errstate(all="ignore"):  # a huge matrix overflows here: inf is then the named error
            off = float(np.max(np.abs(rotation @ rotation.T - np.eye(dim))))
            det = float(np.linalg.det(rotation))
        if not off <= 1e-8 or det < 0:
            raise InputError(
                "`rotation` must be a proper rotation (orthogonal, det +1); got max |R R^T - I| "
                f"{off:.3g} and det {det:.6g}."
            )
        rotation.setflags(write=False)
        translation.setflags(write=False)
        object.__setattr__(self, "rotation", rotation)
        object.__setattr__(self, "translation", translation)
        object.__setattr__(self, "scale", scale)

    @classmethod
    def _trusted(cls, rotation: np.ndarray, translation: np.ndarray, scale: float = 1.0):
        """The transform without the checks of the constructor, for a rotation that is proper
        by construction (an M-step's SVD): the checks cost more than a small M-step itself."""
        out = object.__new__(cls)
        rotation = np.array(rotation, dtype=float)
        translation = np.array(translation, dtype=float)
        rotation.setflags(write=False)
        translation.setflags(write=False)
        object.__setattr__(out, "rotation", rotation)
        object.__setattr__(out, "translation", translation)
        object.__setattr__(out, "scale", float(scale))
        return out

    def _apply(self, points: np.ndarray) -> np.ndarray:
        """``__call__`` on points already checked (a float64 array of shape (n, D))."""
        return self.scale * points @ self.rotation.T + self.translation

    @property
    def matrix(self) -> np.ndarray:
        """Homogeneous matrix of shape (D+1, D+1).

        Examples
        --------
        >>> import numpy as np
        >>> t = SimilarityTransform(np.array([[0.0, -1.0], [1.0, 0.0]]), np.array([1.0, 0.0]), 2.0)
        >>> t.matrix
        array([[ 0., -2.,  1.],
               [ 2.,  0.,  0.],
               [ 0.,  0.,  1.]])
        """
        dim = self.rotation.shape[0]
        out = np.eye(dim + 1)
        out[:dim, :dim] = self.scale * self.rotation
        out[:dim, dim] = self.translation
        return out

    def __call__(self, points) -> np.ndarray:
        with np.errstate(over="ignore", invalid="ignore"):
            out = self._apply(as_points(points, name="points", n_dims=(self.rotation.shape[0],)))
        return _finite_result(out, type(self).__name__)

    def inverse(self) -> SimilarityTransform:
        """The transform taking ``self(x)`` back to ``x``.

        Returns
        -------
        SimilarityTransform
            Rotation ``rotation.T``, translation ``-rotation.T @ translation / scale`` and
            scale ``1 / scale``.

        Raises
        ------
        InputError
            When ``1 / scale`` or that translation is beyond float64.
        """
        rotation = self.rotation.T
        with np.errstate(over="ignore", invalid="ignore"):
            translation, scale = -(rotation @ self.translation) / self.scale, 1.0 / self.scale
        if not (np.all(np.isfinite(translation)) and np.isfinite(scale)):
            raise InputError(
                f"`scale` and `translation` must have an inverse within float64; got `scale` "
                f"{self.scale:.3g} and `translation` up to {np.abs(self.translation).max():.3g}."
            )
        return SimilarityTransform(rotation, translation, scale)


@dataclass(frozen=True, eq=False)
class RigidTransform(SimilarityTransform):
    """``x -> rotation @ x + translation``: a :class:`SimilarityTransform` with scale 1.

    Examples
    --------
    >>> import numpy as np
    >>> t = RigidTransform(np.array([[0.0, -1.0], [1.0, 0.0]]), np.array([1.0, 0.0]))
    >>> t(np.array([[1.0, 0.0]]))
    array([[1., 1.]])
    >>> t.inverse()(t(np.array([[3.0, 4.0]])))
    array([[3., 4.]])
    """

    scale: float = 1.0

    def __post_init__(self):
        if not (isinstance(self.scale, (int, float, np.integer, np.floating)) and self.scale == 1.0):
            raise InputError(f"`scale` of a RigidTransform must be 1; got {self.scale!r}.")
        super().__post_init__()

    def inverse(self) -> RigidTransform:
        """The transform taking ``self(x)`` back to ``x``.

        Returns
        -------
        RigidTransform
            Rotation ``rotation.T`` and translation ``-rotation.T @ translation``.
        """
        rotation = self.rotation.T
        return RigidTransform(rotation, -(rotation @ self.translation))


@dataclass(frozen=True, eq=False)
class AffineTransform(_ArrayEquality):
    """``x -> linear @ x + translation``.

    Attributes
    ----------
    linear : ndarray of shape (D, D)
    translation : ndarray of shape (D,)

    Examples
    --------
    >>> import numpy as np
    >>> t = AffineTransform(np.array([[2.0, 1.0], [0.0, 1.0]]), np.array([0.0, 1.0]))
    >>> t(np.array([[1.0, 1.0]]))
    array([[3., 2.]])
    >>> t.inverse()(np.array([[3.0, 2.0]]))
    array([[1., 1.]])
    """

    linear: np.ndarray
    translation: np.ndarray

    def __post_init__(self):
        linear = _frozen(self.linear, "linear")
        translation = _frozen(np.ravel(_real_array(self.translation, "translation")), "translation")
        dim = linear.shape[0] if linear.ndim == 2 else -1
        if dim < 1 or linear.shape != (dim, dim) or translation.shape != (dim,):
            raise InputError(
                f"`linear` must be (D, D) and `translation` (D,) with D >= 1; "
                f"got {linear.shape} and {translation.shape}."
            )
        if not (np.all(np.isfinite(linear)) and np.all(np.isfinite(translation))):
            raise InputError("`linear` and `translation` must be finite; got NaN or inf.")
        object.__setattr__(self, "linear", linear)
        object.__setattr__(self, "translation", translation)

    @property
    def matrix(self) -> np.ndarray:
        """Homogeneous matrix of shape (D+1, D+1).

        Examples
        --------
        >>> import numpy as np
        >>> t = AffineTransform(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([1.0, 1.0]))
        >>> t.matrix
        array([[2., 0., 1.],
               [0., 4., 1.],
               [0., 0., 1.]])
        """
        dim = self.linear.shape[0]
        out = np.eye(dim + 1)
        out[:dim, :dim] = self.linear
        out[:dim, dim] = self.translation
        return out

    def __call__(self, points) -> np.ndarray:
        points = as_points(points, name="points", n_dims=(self.linear.shape[0],))
        with np.errstate(over="ignore", invalid="ignore"):
            out = points @ self.linear.T + self.translation
        return _finite_result(out, "AffineTransform")

    def inverse(self) -> AffineTransform:
        """The inverse map; raises ``InputError`` when ``linear`` is singular.

        Examples
        --------
        >>> import numpy as np
        >>> t = AffineTransform(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([1.0, 1.0]))
        >>> inv = t.inverse()
        >>> inv.linear, inv.translation
        (array([[0.5 , 0.  ],
               [0.  , 0.25]]), array([-0.5 , -0.25]))
        >>> inv(t([[3.0, 5.0]]))
        array([[3., 5.]])
        >>> AffineTransform(np.array([[1.0, 2.0], [0.5, 1.0]]), np.zeros(2)).inverse()  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        centrality_vision.exceptions.InputError: `linear` must be invertible for the inverse transform; ...
        """
        if np.linalg.cond(self.linear) > 1e14:
            raise InputError(
                "`linear` must be invertible for the inverse transform; got a singular matrix "
                f"(cond {np.linalg.cond(self.linear):.3g})."
            )
        inv = np.linalg.inv(self.linear)
        with np.errstate(over="ignore", invalid="ignore"):
            translation = -(inv @ self.translation)
        if not (np.all(np.isfinite(inv)) and np.all(np.isfinite(translation))):
            raise InputError("`linear` must have an inverse within float64; the inverse transform leaves its range.")
        return AffineTransform(inv, translation)


@dataclass(frozen=True, eq=False)
class NonRigidTransform(_ArrayEquality):
    """CPD's motion-coherent displacement field after an optional affine pre-map.

    ``z -> p + v + sum_m W[m] exp(-|v - c_m|^2 / (2 beta^2))`` with
    ``v = linear @ (z - o) + translation``, where ``o`` is ``input_origin`` and ``p`` is
    ``output_origin`` (``v = z`` and ``p = 0`` when every optional part is None). The field
    is defined everywhere, so it can be applied to points other than the ones it was fitted
    on. It has no closed-form inverse.

    The two origins keep the field's arguments near zero: CPD fits the field on centred
    sets, and the kernel sums cancel terms whose weights can be 1e5 times the displacement.
    Data far from the origin (coordinates of 1e8 and a displacement of 0.1) would otherwise
    lose the field to the rounding of ``v``.

    Attributes
    ----------
    control_points : ndarray of shape (M, D)
        The kernel centres ``c_m``, in the frame of ``v`` (the fitted moving points after the
        pre-map, less ``output_origin``; after a low-rank fit, the pivots of its kernel's
        factorisation among them).
    coefficients : ndarray of shape (M, D)
        ``W`` of the CPD paper (for a low-rank fit, the weights on those pivots).
    beta : float
        Width of the Gaussian kernel.
    linear : ndarray of shape (D, D), optional
        Linear part of the pre-map (identity when None).
    translation : ndarray of shape (D,), optional
        Translation of the pre-map (zero when None).
    input_origin : ndarray of shape (D,), optional
        ``o``, subtracted from the points before the pre-map (zero when None).
    output_origin : ndarray of shape (D,), optional
        ``p``, added to the result (zero when None).

    Examples
    --------
    >>> import numpy as np
    >>> t = NonRigidTransform(np.zeros((1, 2)), np.array([[1.0, 0.0]]), beta=1.0)
    >>> t(np.array([[0.0, 0.0], [10.0, 0.0]])).round(6)
    array([[ 1.,  0.],
           [10.,  0.]])
    >>> shifted = NonRigidTransform(np.zeros((1, 2)), np.array([[1.0, 0.0]]), beta=1.0, translation=[5.0, 0.0])
    >>> shifted(np.array([[-5.0, 0.0]])).round(6)
    array([[1., 0.]])

    The same field about a point far from the origin, in centred form:

    >>> far = NonRigidTransform(
    ...     np.zeros((1, 2)), np.array([[1.0, 0.0]]), beta=1.0, input_origin=[1e8, 0.0], output_origin=[1e8, 0.0]
    ... )
    >>> far(np.array([[1e8, 0.0]])) - [1e8, 0.0]
    array([[1., 0.]])
    """

    control_points: np.ndarray
    coefficients: np.ndarray
    beta: float
    linear: np.ndarray | None = None
    translation: np.ndarray | None = None
    input_origin: np.ndarray | None = None
    output_origin: np.ndarray | None = None

    def __post_init__(self):
        control = _frozen(self.control_points, "control_points")
        coefficients = _frozen(self.coefficients, "coefficients")
        if control.ndim != 2 or coefficients.shape != control.shape or 0 in control.shape:
            raise InputError(
                "`control_points` and `coefficients` must both be (M, D) with M, D >= 1; "
                f"got {control.shape} and {coefficients.shape}."
            )
        if not (np.all(np.isfinite(control)) and np.all(np.isfinite(coefficients))):
            raise InputError("`control_points` and `coefficients` must be finite; got NaN or inf.")
        beta = check_float(self.beta, name="beta", low=0.0, low_open=True)
        dim = control.shape[1]
        vectors = ("translation", "input_origin", "output_origin")
        for name in ("linear", *vectors):
            value = getattr(self, name)
            if value is None:
                continue
            shape = (dim,) if name in vectors else (dim, dim)
            value = _real_array(value, name)
            value = _frozen(np.reshape(value, -1) if name in vectors else value, name)
            if value.shape != shape or not np.all(np.isfinite(value)):
                raise InputError(f"`{name}` must be a finite array of shape {shape}; got shape {value.shape}.")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "control_points", control)
        object.__setattr__(self, "coefficients", coefficients)
        object.__setattr__(self, "beta", beta)

    def _pre(self, points: np.ndarray) -> np.ndarray:
        out = points if self.input_origin is None else points - self.input_origin
        out = out if self.linear is None else out @ self.linear.T
        return out if self.translation is None else out + self.translation

    def _field(self, v: np.ndarray) -> np.ndarray:
        out = np.empty_like(v)
        step = max(1, 2**22 // max(1, self.control_points.shape[0]))
        for lo in range(0, v.shape[0], step):
            block = v[lo : lo + step]
            # distances in units of beta before squaring: no beta**2 to underflow (0/0) or overflow
            z = (block[:, None, :] - self.control_points[None, :, :]) / self.beta
            out[lo : lo + step] = np.exp(-0.5 * np.sum(z * z, axis=2)) @ self.coefficients
        return out

    def displacement(self, points) -> np.ndarray:
        """The displacement ``T(z) - z`` at each row of ``points``, in blocks of rows.

        It is summed as ``(p - z) + v + field(v)``: far from the origin, near ``p``, no
        coordinate's rounding enters it.

        Parameters
        ----------
        points : array_like of shape (n_points, D)
            D is the dimension of ``control_points``.

        Returns
        -------
        ndarray of shape (n_points, D)
            ``self(points) - points``.

        Examples
        --------
        One kernel of width 1 at the origin pushing by (1, 0): the push fades with distance.

        >>> import numpy as np
        >>> t = NonRigidTransform(np.zeros((1, 2)), np.array([[1.0, 0.0]]), beta=1.0)
        >>> points = np.array([[0.0, 0.0], [1.0, 0.0], [10.0, 0.0]])
        >>> t.displacement(points).round(3)  # exp(-1/2) = 0.607 at distance beta
        array([[1.   , 0.   ],
               [0.607, 0.   ],
               [0.   , 0.   ]])
        >>> bool(np.allclose(t.displacement(points), t(points) - points))
        True
        """
        points = as_points(points, name="points", n_dims=(self.control_points.shape[1],))
        with np.errstate(over="ignore", invalid="ignore"):
            v = self._pre(points)
            start = -points if self.output_origin is None else self.output_origin - points
            moved = start + v + self._field(v)  # each finite, their sum need not be
        return _finite_result(moved, "NonRigidTransform's displacement")

    def __call__(self, points) -> np.ndarray:
        points = as_points(points, name="points", n_dims=(self.control_points.shape[1],))
        with np.errstate(over="ignore", invalid="ignore"):
            v = self._pre(points)
            out = v + self._field(v)
            if self.output_origin is not None:
                out += self.output_origin
        return _finite_result(out, "NonRigidTransform")


def random_rotation(n_dims: int, seed=None) -> np.ndarray:
    """A uniformly distributed proper rotation matrix of shape (n_dims, n_dims).

    Parameters
    ----------
    n_dims : int in [1, 1000]
    seed : int, numpy.random.Generator or None, default=None
        Seed of the draw; ``None`` draws fresh entropy.

    Returns
    -------
    ndarray of shape (n_dims, n_dims)
        Orthogonal, determinant +1.

    Examples
    --------
    >>> import numpy as np
    >>> r = random_rotation(3, seed=0)
    >>> bool(np.allclose(r @ r.T, np.eye(3))), round(float(np.linalg.det(r)), 12)
    (True, 1.0)
    """
    from ._seeding import as_generator

    n_dims = check_int(n_dims, name="n_dims", low=1, high=1000)
    rng = as_generator(seed)
    q, r = np.linalg.qr(rng.standard_normal((n_dims, n_dims)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


@renamed_parameters(source="moving", target="fixed")
def fit_similarity(moving, fixed, *, scale: bool = True) -> SimilarityTransform:
    """Least-squares similarity (or, with ``scale=False``, a :class:`RigidTransform`) taking
    ``moving`` onto ``fixed``, row ``i`` onto row ``i``.

    Minimises ``sum |s R x_i + t - y_i|^2`` over proper rotations (Umeyama's closed form).

    Parameters
    ----------
    moving, fixed : array_like of shape (n_points, 2) or (n_points, 3)
        Paired points (at least 2 rows), ``moving[i]`` to go onto ``fixed[i]``.
    scale : bool, default=True
        Fit the scale ``s`` (a :class:`SimilarityTransform`), or keep ``s = 1`` (a
        :class:`RigidTransform`).

    Returns
    -------
    SimilarityTransform or RigidTransform

    Raises
    ------
    InputError
        When the fit is undetermined: all rows of ``moving`` (or of ``fixed``) equal, so that
        any rotation fits as well as any other; or, with ``scale=True``, when no positive
        scale beats scale 0 (``fixed`` uncorrelated with every rotation of ``moving``, as
        for a symmetric set and its mirror image).

    Notes
    -----
    .. versionchanged:: 0.1.0
       The points are ``moving`` and ``fixed``, as everywhere in the package; the former
       names ``source`` and ``target`` still work, with a FutureWarning.

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
    check_bool(scale, name="scale")
    moving = as_points(moving, name="moving", n_dims=(2, 3), min_points=2)
    fixed = as_points(fixed, name="fixed", n_dims=(moving.shape[1],), min_points=2)
    if moving.shape != fixed.shape:
        raise InputError(f"`moving` and `fixed` must have the same shape; got {moving.shape} and {fixed.shape}.")
    for name, points in (("moving", moving), ("fixed", fixed)):
        if np.all(points == points[0]):
            raise InputError(
                f"`{name}` must hold at least two distinct points (the rotation is undetermined "
                f"otherwise); got {points.shape[0]} equal rows."
            )
    rotation, translation, s, fitted = _least_squares_similarity(moving, fixed, scale=scale)
    if scale and not fitted:
        raise InputError(
            "The least-squares scale between `moving` and `fixed` is 0: no rotation of `moving` "
            "correlates with `fixed` (a symmetric set and its mirror image?). Fit with scale=False."
        )
    return SimilarityTransform(rotation, translation, s) if scale else RigidTransform(rotation, translation)


def _finite_array(values, name: str, *, ndim: int | None = 2) -> np.ndarray:
    """``values`` as a finite float64 array (of ``ndim`` dimensions), or a named error.

    The public helpers below check their input once with it and then run their unchecked
    kernels (``_unit``, ``_centred``), which call each other without checking again."""
    arr = as_real_array(values, name=name).astype(np.float64, copy=False)
    if ndim is not None and arr.ndim != ndim:
        raise InputError(f"`{name}` must be a {ndim}D array; got shape {arr.shape}.")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"`{name}` must be finite; got NaN or inf.")
    return arr


def proper_rotation(cross: np.ndarray) -> tuple[np.ndarray, float]:
    """The proper rotation R maximising ``tr(cross^T R)``, and that maximum.

    SVD ``cross = U S V^T``; the sign of the last singular vector is flipped when
    ``det(U V^T) < 0`` (Umeyama's correction), so det R = +1 even for reflected data.
    A non-finite ``cross`` raises :class:`InputError` (LAPACK's SVD can loop on inf).

    Parameters
    ----------
    cross : array_like of shape (D, D)
        A square, finite matrix with D >= 1, e.g. the cross-covariance ``fixed.T @ moving``
        of two centred point sets.

    Returns
    -------
    rotation : ndarray of shape (D, D)
        Orthogonal, determinant +1.
    trace : float
        ``tr(cross^T rotation)``, the maximum.

    Examples
    --------
    >>> r, trace = proper_rotation(np.diag([2.0, 1.0]))
    >>> r, trace
    (array([[1., 0.],
           [0., 1.]]), 3.0)
    """
    cross = as_real_array(cross, name="cross").astype(np.float64, copy=False)  # (a TypeError for text, complex)
    if cross.ndim != 2 or cross.shape[0] != cross.shape[1] or cross.size == 0:
        raise InputError(f"`cross` must be a square (D, D) matrix; got shape {cross.shape}.")
    if not np.all(np.isfinite(cross)):
        raise InputError(
            "`cross` (the cross-covariance of two point sets) must be finite; got NaN or inf "
            "(coordinates too large for their products to fit in float64?)."
        )
    u, sv, vt = np.linalg.svd(cross)
    c = np.ones(cross.shape[0])
    c[-1] = 1.0 if np.linalg.det(u @ vt) >= 0 else -1.0
    return (u * c) @ vt, float(np.sum(sv * c))


def power_of_two_scale(points: np.ndarray) -> float:
    """A power of two within a factor 2 of the largest absolute coordinate (1 for all zeros).

    Dividing by it is exact in floating point and brings every coordinate into [-2, 2], so
    that products and sums of squares stay finite (even for coordinates near 1e308).

    Parameters
    ----------
    points : array_like
        Finite real numbers, of any shape.

    Returns
    -------
    float
        ``2**e`` with ``2**e <= max |points| < 2**(e + 1)``; 1.0 when every value is 0 or
        there are none.

    Examples
    --------
    >>> power_of_two_scale(np.array([[3.0, -5.0]])), power_of_two_scale(np.zeros((2, 2)))
    (4.0, 1.0)
    """
    return _unit(_finite_array(points, "points", ndim=None))


def _unit(points: np.ndarray) -> float:
    peak = float(np.max(np.abs(points))) if points.size else 0.0
    if peak == 0.0:
        return 1.0
    return float(np.ldexp(1.0, int(np.frexp(peak)[1]) - 1))


def rms_radius(points: np.ndarray) -> float:
    """The RMS distance of the rows from their mean, without overflow near 1e308 (0 for no rows).

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        Finite.

    Returns
    -------
    float
        ``sqrt(mean_i |points[i] - mean|^2)``.

    Examples
    --------
    >>> rms_radius(np.array([[1e300, 0.0], [-1e300, 0.0]]))
    1e+300
    """
    points = _finite_array(points, "points")
    if points.shape[0] == 0:
        return 0.0
    unit, _, rows = _centred_scaled(points)  # (in units of a power of two: nothing overflows)
    inner = _unit(rows)
    return unit * (inner * math.sqrt(float(np.sum((rows / inner) ** 2)) / rows.shape[0]))


def centred(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(mean, points - mean)`` with the mean corrected by a second pass.

    The correction keeps the centred coordinates accurate when the points sit far from the
    origin (e.g. a shape of size 1 at offset 1e8); the points are pre-divided by a power of
    two so that the sum cannot overflow.

    Parameters
    ----------
    points : array_like of shape (n_points, n_dims)
        Finite, at least one row.

    Returns
    -------
    mean : ndarray of shape (n_dims,)
    centred : ndarray of shape (n_points, n_dims)
        ``points - mean``.

    Examples
    --------
    >>> mean, c = centred(np.array([[1e8, 0.0], [1e8 + 2.0, 2.0]]))
    >>> mean.tolist(), c.tolist()
    ([100000001.0, 1.0], [[-1.0, -1.0], [1.0, 1.0]])
    """
    points = _finite_array(points, "points")
    if points.shape[0] == 0:
        raise InputError("`points` must hold at least one row; got none.")
    return _centred(points)


def _centred_scaled(points: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """``(unit, mean, centred)`` with ``mean`` and ``centred`` in units of ``unit`` (a power
    of two: both within [-4, 4], whatever the coordinates)."""
    unit = _unit(points)
    scaled = points / unit
    mean = scaled.mean(axis=0)
    mean = mean + (scaled - mean).mean(axis=0)
    return unit, mean, scaled - mean


def _centred(points: np.ndarray, name: str = "points") -> tuple[np.ndarray, np.ndarray]:
    unit, mean, rows = _centred_scaled(points)
    with np.errstate(over="ignore"):
        out = rows * unit
    if not np.isfinite(out).all():
        # (points at +-1.7e308 lie 3.4e308 apart: their offsets from the mean are no floats)
        axis = int(np.argmax(np.ptp(points / unit, axis=0)))
        raise InputError(
            f"`{name}` must span less than float64's largest number (1.8e308) along each axis, so that its "
            f"centred coordinates exist; got axis {axis} from {points[:, axis].min():.3g} to "
            f"{points[:, axis].max():.3g}."
        )
    return mean * unit, out


@renamed_parameters(source="moving", target="fixed")
def least_squares_similarity(
    moving: np.ndarray, fixed: np.ndarray, *, scale: bool
) -> tuple[np.ndarray, np.ndarray, float]:
    """``(rotation, translation, s)`` minimising ``sum |s R x_i + t - y_i|^2`` for paired rows
    (``s = 1`` without ``scale``, or when the sets are degenerate); inputs must be finite.

    Each centred set is divided by a power of two within a factor 2 of its largest
    coordinate before the cross-covariance is formed, so coordinates up to the float64
    limit give finite products (no inf reaches the SVD).

    Parameters
    ----------
    moving, fixed : array_like of shape (n_points, D)
        Finite paired points (at least 1 row), ``moving[i]`` to go onto ``fixed[i]``.
    scale : bool
        Fit ``s`` (True), or keep ``s = 1``.

    Returns
    -------
    rotation : ndarray of shape (D, D)
        Proper rotation ``R``.
    translation : ndarray of shape (D,)
        ``t``.
    s : float
        Positive scale: 1 without ``scale``, or when the centred ``moving`` is all zeros or
        the best rotation's trace is not positive.

    Examples
    --------
    >>> moving = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> quarter_turn = np.array([[0.0, -1.0], [1.0, 0.0]])
    >>> rotation, translation, s = least_squares_similarity(moving, 2 * moving @ quarter_turn.T + [3, 4], scale=True)
    >>> np.allclose(rotation, quarter_turn), np.allclose(translation, [3, 4]), round(s, 12)
    (True, True, 2.0)
    """
    check_bool(scale, name="scale")
    return _least_squares_similarity(moving, fixed, scale=scale)[:3]


def _least_squares_similarity(moving, fixed, *, scale: bool) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """:func:`least_squares_similarity` and whether its scale was fitted (False where it fell
    back to 1: no scale asked for, a ``moving`` without spread, or a best trace not positive)."""
    moving, fixed = _finite_array(moving, "moving"), _finite_array(fixed, "fixed")
    if moving.shape != fixed.shape or moving.shape[0] == 0:
        raise InputError(
            f"`moving` and `fixed` must be paired rows of one shape (n >= 1, D); got {moving.shape} and {fixed.shape}."
        )
    mu_s, xs = _centred(moving, "moving")
    mu_t, xt = _centred(fixed, "fixed")
    a, b = _unit(xs), _unit(xt)
    xs, xt = xs / a, xt / b
    rotation, trace = proper_rotation(xt.T @ xs)
    var = float(np.sum(xs * xs))
    fitted = scale and var > 0 and trace > 0
    s = (trace / var) * (b / a) if fitted else 1.0
    if not np.isfinite(s) or s <= 0:
        raise InputError(f"The least-squares scale between `moving` and `fixed` is not representable (got {s!r}).")
    translation = mu_t - s * rotation @ mu_s
    if not np.all(np.isfinite(translation)):
        raise InputError("The least-squares translation between `moving` and `fixed` overflows float64.")
    return rotation, translation, s, fitted

"""Coarse-to-fine CPD for very large point sets (a million points and more).

CPD's E-step touches every pair of points (or, truncated, every pair within a few sigma), so
a full-resolution fit of N = 10^6 points costs far more than one of 10^4. The transform,
however, has few parameters (rigid, affine) or is smooth at the scale ``beta`` (non-rigid),
so a random subsample pins it down: :class:`MultiscaleCPD` registers a seeded subsample
exactly, then refines on larger subsamples, each level starting from the previous level's
transform at the variance of its residuals on the new level's points (the mean squared
distance of each fixed point to its nearest transformed moving point, at most the previous
level's final sigma2), with a few EM iterations each, and finally applies the transform to
every point.

* Rigid, similarity and affine: each level passes the transform as ``init=`` to the next.
* Non-rigid: each level registers the subsample as warped by the previous levels, so the
  result is the composition of the levels' displacement fields. Each field
  ``v(z) = sum_m g(z, c_m) w_m`` is first compressed onto the pivots of a pivoted Cholesky
  factorisation of its kernel (the Nystrom form, :func:`._lowrank.nystrom_field`), so that
  applying it to N points costs O(N K) with K in the tens or hundreds instead of O(N M).

Memory is O(N) for the final application plus what the levels need (each is an ordinary
CPD fit on its subsample).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from .._deprecation import FORMER, former_parameter
from .._seeding import as_generator
from .._validation import ANY_DIMS, as_points, check_int
from ..exceptions import ConvergenceWarning, InputError
from ..transforms import NonRigidTransform, RigidTransform
from ._cpd import _model_dims
from ._estep import _nearest
from ._lowrank import PivotedCholesky, nystrom_field

#: MultiscaleCPD's refine_max_iter default
_REFINE_MAX_ITER = 10

__all__ = ["MultiscaleCPD", "ComposedTransform", "compress_field"]


@dataclass(frozen=True)
class ComposedTransform:
    """``z -> transforms[-1](... transforms[0](z))``.

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.transforms import RigidTransform
    >>> t = ComposedTransform((RigidTransform(np.eye(2), np.array([1.0, 0.0])),) * 2)
    >>> t(np.zeros((1, 2)))
    array([[2., 0.]])
    """

    transforms: tuple

    def __post_init__(self):
        if isinstance(self.transforms, (str, bytes)) or not hasattr(self.transforms, "__iter__"):
            raise TypeError(f"`transforms` must be a sequence of transforms; got {self.transforms!r}.")
        bad = [t for t in self.transforms if not callable(t)]
        if bad:
            raise TypeError(f"`transforms` must hold callable transforms; got {bad[0]!r}.")
        object.__setattr__(self, "transforms", tuple(self.transforms))

    def __call__(self, points):
        out = as_points(points, name="points", n_dims=ANY_DIMS)
        for transform in self.transforms:
            out = transform(out)
        return out


def compress_field(transform: NonRigidTransform, *, max_rank=1000, tol=1e-12) -> NonRigidTransform:
    """The same displacement field on at most ``max_rank`` of its kernel centres.

    ``G ~ L L^T`` on the centres by pivoted Cholesky (pivots S); the field's values at the
    centres, ``G W``, become ``G[:, S] a`` with ``a = L[S]^-T L^T W``: equal up to the
    residual trace of the factorisation (at most ``tol * M`` per unit of ``|W|``) there,
    and a Gaussian-kernel field of the same width everywhere.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> c = rng.random((400, 2))
    >>> t = NonRigidTransform(c, 0.01 * rng.standard_normal((400, 2)), beta=0.5)
    >>> small = compress_field(t)
    >>> small.control_points.shape[0] < 100, bool(np.abs(small(c) - t(c)).max() < 1e-8)
    (True, True)
    """
    if not isinstance(transform, NonRigidTransform):
        raise TypeError(f"`transform` must be a NonRigidTransform; got {type(transform).__name__}.")
    control = np.asarray(transform.control_points)
    pc = PivotedCholesky(control, transform.beta, max_rank=max_rank, tol=tol)
    centres, coefficients = nystrom_field(control, pc.pivots, pc.factor, np.asarray(transform.coefficients))
    return NonRigidTransform(
        centres,
        coefficients,
        transform.beta,
        linear=transform.linear,
        translation=transform.translation,
        input_origin=transform.input_origin,
        output_origin=transform.output_origin,
    )


def _clone(estimator):
    try:
        from sklearn.base import clone

        return clone(estimator)
    except Exception:  # an estimator without scikit-learn's get_params(deep=...)
        return type(estimator)(**estimator.get_params())


class MultiscaleCPD(BaseEstimator):
    """Coarse-to-fine registration of large sets with any CPD estimator (see the module docstring).

    Parameters
    ----------
    estimator : RigidCPD, AffineCPD or NonRigidCPD
        The registration to run at every level (cloned; its parameters are kept, except
        ``init``, ``sigma2`` and, after the first level, ``max_iter``).
    sizes : sequence of int, default=(5000, 20000)
        Points per set at each level, increasing; a level at least as large as a set uses
        all of it (the full-resolution fit). Levels above the sets' sizes are skipped. The
        first level does the global work (sigma2 from the sets' spread down), so it is kept
        small; the last level's size bounds the cost of the rest. The first level must
        still resolve the deformation: on 20,000 bunny-shaped 3D points under a smooth
        non-rigid warp, a first level of 2,000 points ended at RMS error 3.8e-2 (5,000:
        1.7e-3, as a plain full-resolution fit, 1.6e-3, in 8 s instead of 22 s).
        Measurements at 10^5 and 10^6 points: ``benchmarks/registration_large.py``.
    refine_max_iter : int, default=10
        ``max_iter`` of every level after the first.
    random_state : int, Generator or None, default=0
        Seed of the subsamples, as the CPD estimators take it (None: fresh entropy; a
        Generator is drawn from, so two fits with one Generator take other subsamples).
    refine_iter : deprecated
        The former name of ``refine_max_iter`` (the package's iteration limit is
        ``max_iter``); it still works, with a FutureWarning, and will be removed.

    Attributes
    ----------
    transform_ : transform
        The fitted transform, applicable to any points: the last level's for rigid and
        affine, a :class:`ComposedTransform` of the levels' fields for non-rigid.
    moving_transformed_ : ndarray of shape (M, D)
        Every moving point transformed.
    levels_ : list of dict
        Per level: ``n_moving``, ``n_fixed``, ``n_iter``, ``converged``, ``sigma2`` and ``seconds``.
    sigma2_ : float
        The last level's final sigma2.

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.registration import RigidCPD
    >>> y = np.random.default_rng(0).random((3000, 2))
    >>> r = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    >>> reg = MultiscaleCPD(RigidCPD(tol=1e-8), sizes=(300, 3000), refine_max_iter=30).fit(y, y @ r.T + 0.1)
    >>> error = np.abs(reg.moving_transformed_ - (y @ r.T + 0.1)).max()
    >>> [level["n_moving"] for level in reg.levels_], bool(error < 1e-6)
    ([300, 3000], True)
    """

    def __init__(
        self,
        estimator,
        *,
        sizes=(5_000, 20_000),
        refine_max_iter=_REFINE_MAX_ITER,
        random_state=0,
        refine_iter=FORMER,
    ):
        self.estimator = estimator
        self.sizes = sizes
        self.refine_max_iter = refine_max_iter
        self.random_state = random_state
        self.refine_iter = refine_iter

    def _check(self):
        from ._cpd import AffineCPD, NonRigidCPD, RigidCPD

        if not isinstance(self.estimator, (RigidCPD, AffineCPD, NonRigidCPD)):
            raise TypeError(
                f"`MultiscaleCPD.estimator` must be a RigidCPD, AffineCPD or NonRigidCPD; got {self.estimator!r}."
            )
        try:
            if isinstance(self.sizes, (str, bytes, bytearray, dict, set, frozenset)):
                raise TypeError  # iterable, but not a sequence of sizes (bytes iterate as ints)
            sizes = [check_int(s, name="MultiscaleCPD.sizes[i]", low=2) for s in self.sizes]
        except TypeError:
            raise TypeError(f"`MultiscaleCPD.sizes` must be a sequence of ints; got {self.sizes!r}.") from None
        if not sizes or sorted(sizes) != sizes or len(set(sizes)) != len(sizes):
            raise InputError(f"`MultiscaleCPD.sizes` must be non-empty and strictly increasing; got {self.sizes!r}.")
        refine, name = former_parameter(self, "refine_iter", "refine_max_iter")
        refine = check_int(refine, name=name, low=1)
        as_generator(self.random_state, name="MultiscaleCPD.random_state")  # checked before any work
        return sizes, isinstance(self.estimator, NonRigidCPD), refine

    def fit(self, moving, fixed):
        """Register ``moving`` (M x D) onto ``fixed`` (N x D); returns ``self``. Neither is modified.

        Parameters
        ----------
        moving : array_like of shape (M, D)
            The set to transform, D from 1 to 64; each level registers a subsample of it.
        fixed : array_like of shape (N, D)
            The set it is brought onto, of the same D.

        Returns
        -------
        self : MultiscaleCPD
            With ``transform_``, ``moving_transformed_`` (all M points), ``levels_`` and ``sigma2_``.

        Examples
        --------
        A subsample of 30 points first, then all 60:

        >>> import numpy as np
        >>> from centrality_vision.registration import RigidCPD
        >>> y = np.random.default_rng(0).random((60, 2))
        >>> r = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
        >>> reg = MultiscaleCPD(RigidCPD(tol=1e-8), sizes=(30, 60)).fit(y, y @ r.T + 0.1)
        >>> [(level["n_moving"], level["n_fixed"], level["converged"]) for level in reg.levels_]
        [(30, 30, True), (60, 60, True)]
        >>> reg.moving_transformed_.shape, bool(np.allclose(reg.moving_transformed_, y @ r.T + 0.1))
        ((60, 2), True)
        """
        sizes, nonrigid, refine_max_iter = self._check()
        moving = as_points(moving, name="moving", n_dims=ANY_DIMS)
        fixed = as_points(fixed, name="fixed", n_dims=(moving.shape[1],))
        rng = as_generator(self.random_state, name="MultiscaleCPD.random_state")
        largest = max(moving.shape[0], fixed.shape[0])
        # every level up to the first that covers both sets whole
        levels = [s for s in sizes if s < largest] + [s for s in sizes if s >= largest][:1]
        fields = []
        transform = None
        sigma2 = None
        self.levels_ = []
        for i, size in enumerate(levels):
            start = time.perf_counter()
            sub_moving = _subsample(moving, size, rng)
            sub_fixed = _subsample(fixed, size, rng)
            est = _clone(self.estimator)
            if nonrigid and fields:
                sub_moving = ComposedTransform(tuple(fields))(sub_moving)
            if i > 0:
                est.max_iter = refine_max_iter
                # a refinement starts where the previous level ended: the last transform, or for
                # non-rigid the warped subsample as it lies (the identity; without an init a
                # normalised fit would centre it on the fixed set's mean, a jump wherever
                # clutter or missing parts move that mean)
                dim = moving.shape[1]
                est.init = RigidTransform(np.eye(dim), np.zeros(dim)) if nonrigid else transform
                moved = sub_moving if nonrigid else transform(sub_moving)
                est.sigma2 = _start_sigma2(est, moved, sub_moving, sub_fixed, sigma2)
            with warnings.catch_warnings():
                # a level is a starting point or a bounded refinement: stopping at its max_iter is
                # the plan, recorded in levels_ ("converged"), not a warning
                warnings.filterwarnings("ignore", message=".*max_iter", category=ConvergenceWarning)
                est.fit(sub_moving, sub_fixed)
            sigma2 = float(est.sigma2_)
            if nonrigid:
                fields.append(compress_field(est.transform_))
            else:
                transform = est.transform_
            self.levels_.append(
                {
                    "n_moving": sub_moving.shape[0],
                    "n_fixed": sub_fixed.shape[0],
                    "n_iter": int(est.n_iter_),
                    "converged": bool(est.converged_),
                    "sigma2": sigma2,
                    "seconds": time.perf_counter() - start,
                }
            )
        self.transform_ = ComposedTransform(tuple(fields)) if nonrigid else transform
        self.moving_transformed_ = self.transform_(moving)
        self.sigma2_ = sigma2
        return self

    def transform(self, points):
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
        >>> from centrality_vision.registration import RigidCPD
        >>> y = np.random.default_rng(0).random((60, 2))
        >>> r = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
        >>> reg = MultiscaleCPD(RigidCPD(tol=1e-8), sizes=(30, 60)).fit(y, y @ r.T + 0.1)
        >>> reg.transform([[0.0, 0.0], [1.0, 0.0]]).round(3)  # r @ p + 0.1
        array([[0.1  , 0.1  ],
               [1.055, 0.396]])
        """
        check_is_fitted(self, "transform_")
        return self.transform_(as_points(points, name="points", n_dims=ANY_DIMS))


def _start_sigma2(est, moved, sub_moving, sub_fixed, previous):
    """The variance a refinement level starts at, in the units its fit reads ``sigma2`` in.

    The previous level's final variance reflects that level's sampling (its nearest
    neighbours are farther apart); at the current pose on this level's denser points the
    residuals are smaller. The start is the mean squared distance of each fixed point to
    its nearest transformed moving point, per dimension the sets span, capped by the
    previous level's variance (so that a refinement never starts coarser than the level
    before it).
    """
    d2 = _nearest(moved, sub_fixed)[0]
    sigma2 = min(float(np.mean(d2)) / _model_dims(moved, sub_fixed), previous)
    scale = est._frame(sub_moving, sub_fixed)[0].scale  # the normalised frame under ``normalize``
    return max(sigma2, np.finfo(float).tiny) / scale**2


def _subsample(points, size, rng):
    if size >= points.shape[0]:
        return points
    return points[np.sort(rng.choice(points.shape[0], size, replace=False))]

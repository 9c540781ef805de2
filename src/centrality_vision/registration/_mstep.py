"""CPD's M-steps [1]_: pure functions of the E-step statistics, returning a transform and sigma2.

Notation as in the paper: ``mu_x = X^T P^T 1 / Np``, ``mu_y = Y^T P 1 / Np``,
``A = (X - mu_x)^T P^T (Y - mu_y) = (P X)^T Y - Np mu_x mu_y^T`` (D x D). Points are rows,
so a transform maps ``y -> L y + t`` as ``Y @ L.T + t``.

References
----------
.. [1] A. Myronenko and X. Song, "Point set registration: coherent point drift",
   IEEE TPAMI 32(12), 2262-2275, 2010, figs. 2-4.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import linalg

from ..transforms import AffineTransform, RigidTransform, SimilarityTransform, proper_rotation
from ._estep import Posteriors
from ._lowrank import weighted_gram

__all__ = ["rigid_m_step", "affine_m_step", "nonrigid_m_step", "kernel_times", "gaussian_kernel", "LowRankKernel"]


@njit(nogil=True, cache=True, fastmath={"contract", "reassoc"})
def _dot(a, b, shift_b):
    """``sum_i a[i] (b[i] - shift_b)`` over 1-D arrays (one vectorised loop)."""
    total = 0.0
    for i in range(a.shape[0]):
        total += a[i] * (b[i] - shift_b)
    return total


@njit(nogil=True, cache=True, fastmath={"contract", "reassoc"})
def _weighted_dot(weights, a, shift_a, b, shift_b):
    """``sum_i weights[i] (a[i] - shift_a) (b[i] - shift_b)`` over 1-D arrays (one vectorised loop)."""
    total = 0.0
    for i in range(a.shape[0]):
        total += weights[i] * (a[i] - shift_a) * (b[i] - shift_b)
    return total


@njit(nogil=True, cache=True)
def _centred_moments(p1, pt1, px, moving, fixed, n_p):
    """``mu_x``, ``mu_y``, ``A = (P X)^T (Y - mu_y)``, ``tr(Xh^T d(P^T 1) Xh)`` and
    ``Yh^T d(P1) Yh`` (D x D): the coordinates transposed once, then each entry one
    vectorised pass.

    ``A`` is taken about ``mu_y`` alone: it equals ``(X - mu_x)^T P^T (Y - mu_y)`` because
    ``(P X)^T 1 = Np mu_x``, and every product is of centred values, so points far from the
    origin lose no digits to cancellation.
    """
    n_dims = moving.shape[1]
    xt = np.ascontiguousarray(fixed.T)
    yt = np.ascontiguousarray(moving.T)
    pxt = np.ascontiguousarray(px.T)
    mu_x = np.empty(n_dims)
    mu_y = np.empty(n_dims)
    for k in range(n_dims):
        mu_x[k] = _dot(pt1, xt[k], 0.0) / n_p
        mu_y[k] = _dot(p1, yt[k], 0.0) / n_p
    x_px = 0.0
    for k in range(n_dims):
        x_px += _weighted_dot(pt1, xt[k], mu_x[k], xt[k], mu_x[k])
    a = np.empty((n_dims, n_dims))
    y_py = np.empty((n_dims, n_dims))
    for i in range(n_dims):
        for j in range(n_dims):
            a[i, j] = _dot(pxt[i], yt[j], mu_y[j])
            y_py[i, j] = _weighted_dot(p1, yt[i], mu_y[i], yt[j], mu_y[j]) if j >= i else y_py[j, i]
    return mu_x, mu_y, a, x_px, y_py


def _moments(post: Posteriors, moving: np.ndarray, fixed: np.ndarray):
    """``(Np, mu_x, mu_y, A, tr(Xh^T d(P^T 1) Xh), Yh^T d(P1) Yh)``; see :func:`_centred_moments`."""
    mu_x, mu_y, a, x_px, y_py = _centred_moments(post.p1, post.pt1, post.px, moving, fixed, post.n_p)
    return post.n_p, mu_x, mu_y, a, x_px, y_py


def _spread_floor(moving: np.ndarray, n_p: float, peak: float | None = None) -> float:
    """The weighted spread ``Yh^T d(P1) Yh`` that rounding alone gives a set of one repeated
    point: its deviations from the weighted mean are a few ulps of its coordinates, or of
    ``peak``, the largest coordinate whose rounding they carry (the caller's, before the
    normalised frame centred them). A spread at or below it is none (a one-point moving set
    away from the origin, as the k-NN frame leaves it, made the similarity's scale 8e15 and
    the affine map 1.6e7; a line 1e8 from the origin, seen as a thin plane, an affine map of
    5e7)."""
    largest = max(float(np.max(np.abs(moving), initial=0.0)), 0.0 if peak is None else float(peak))
    return n_p * (8.0 * np.finfo(np.float64).eps * largest) ** 2


def rigid_m_step(post: Posteriors, moving: np.ndarray, fixed: np.ndarray, *, scale: bool = True, peak=None):
    """Rigid (``scale=False``) or similarity M-step: ``(transform, sigma2)``; ``peak``: see
    :func:`_spread_floor`.

    The rotation is the proper one closest to ``A`` (SVD with the last singular vector's sign
    fixed so that det R = +1); ``s = tr(A^T R) / tr(Yh^T d(P1) Yh)``.
    """
    n_p, mu_x, mu_y, a, x_px, y_py = _moments(post, moving, fixed)
    n_dims = moving.shape[1]
    rotation, tr_ar = proper_rotation(a)
    y_py = float(np.trace(y_py))
    s = tr_ar / y_py if scale and y_py > n_dims * _spread_floor(moving, n_p, peak) and tr_ar > 0 else 1.0
    sigma2 = (x_px - 2 * s * tr_ar + s * s * y_py) / (n_p * n_dims)
    translation = mu_x - s * rotation @ mu_y
    kind = SimilarityTransform if scale else RigidTransform
    return kind._trusted(rotation, translation, s if scale else 1.0), float(sigma2)


def affine_m_step(post: Posteriors, moving: np.ndarray, fixed: np.ndarray, *, peak=None):
    """Affine M-step: ``B = A (Yh^T d(P1) Yh)^-1``; returns ``(transform, sigma2)``.

    A singular ``Yh^T d(P1) Yh`` (collinear moving points) takes the minimum-norm solution;
    directions whose spread is within rounding (see :func:`_spread_floor` for ``peak``) count
    as singular.
    """
    n_p, mu_x, mu_y, a, x_px, y_py = _moments(post, moving, fixed)
    n_dims = moving.shape[1]
    top = float(np.linalg.norm(y_py, 2))
    floor = _spread_floor(moving, n_p, peak)
    if top <= floor:  # no spread beyond rounding in any direction: the least-norm map is 0
        linear = np.zeros((n_dims, n_dims))
    else:  # (directions of rounding-level spread cut like exactly singular ones)
        rcond = max(floor / top, n_dims * np.finfo(np.float64).eps)
        linear = np.linalg.lstsq(y_py.T, a.T, rcond=rcond)[0].T
    sigma2 = (x_px - float(np.sum(a * linear))) / (n_p * n_dims)
    return AffineTransform(linear, mu_x - linear @ mu_y), float(sigma2)


def gaussian_kernel(a: np.ndarray, b: np.ndarray, beta: float) -> np.ndarray:
    """``G[i, j] = exp(-|a_i - b_j|^2 / (2 beta^2))``.

    The squared distances are summed from the differences (scipy's ``cdist``), not as
    ``|a|^2 + |b|^2 - 2 a.b``, which cancels where the coordinates are large against the
    distances: at an offset of 1e8 (``normalize=False``) the fitted ``transform_`` and
    ``moving_transformed_`` disagreed by 3.2, and with ``beta=1e-8`` the kernel's diagonal
    came out exp(-0.5) instead of 1. (Also 5-7x faster in 2D at 2,000-5,000 points.)
    """
    from scipy.spatial.distance import cdist

    sq = cdist(a, b, "sqeuclidean")
    sq *= -1.0 / (2.0 * beta * beta)
    return np.exp(sq, out=sq)


class LowRankKernel:
    """``G ~ Q diag(values) Q^T`` with orthonormal ``Q`` of at most ``rank`` columns.

    Built by pivoted Cholesky (:func:`._lowrank.low_rank_eigh`: O(M rank^2), no M x M matrix;
    its spectral-norm error is at most the residual trace, which stops it early once below
    1e-12 M). Measured against ARPACK's ``eigsh`` (the rank largest exact eigenpairs) on
    uniform 2D points, extent 3, beta 2: 25x faster at 1,000 points, at a spectral error
    of 1.2e-8 instead of 2.2e-9 (``|G|`` ~ 300). ``seed`` is kept for compatibility; the
    factorisation is deterministic.
    """

    def __init__(self, moving: np.ndarray, beta: float, rank: int, seed: int = 0):
        from ._lowrank import _low_rank_eigh_parts

        self.values, self.vectors, self._cholesky, self._basis = _low_rank_eigh_parts(moving, beta, rank)
        self.vectors_t = np.ascontiguousarray(self.vectors.T)  # Q^T, for weighted_gram

    @property
    def residual_trace(self) -> float:
        """``trace(G - L L^T)``: a bound on the approximation's spectral-norm error."""
        return float(self._cholesky.residual_trace)

    def pivot_field(self, coefficients: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The field ``Q diag(values) Q^T W`` as Gaussian-kernel weights on the pivots alone.

        With ``Q = L V diag(values)^-1/2``, ``Q diag(values) Q^T W = L (V V^T L^T W)``, and
        ``L`` is the Nystrom factor ``G[:, S] C^-T`` (see :func:`._lowrank.nystrom_field`):
        the field ``v(z) = sum_{s in S} g(z, y_s) a_s`` equals the fitted displacement at
        every moving point and is defined everywhere. Returns ``(pivots, a)``.
        """
        from ._lowrank import pivot_weights

        factor, basis, pivots = self._cholesky.factor, self._basis, self._cholesky.pivots
        projected = basis @ (basis.T @ (factor @ coefficients))  # V V^T L^T W (K x D)
        return pivots, pivot_weights(factor, pivots, projected)

    def apply(self, w: np.ndarray) -> np.ndarray:
        """``G w`` (M x D, C-ordered)."""
        return _low_rank_times(self.vectors_t, self.values, np.ascontiguousarray(w, dtype=float))


def kernel_times(kernel, w: np.ndarray) -> np.ndarray:
    """``G w`` for the dense ``G`` or a :class:`LowRankKernel`."""
    return kernel.apply(w) if isinstance(kernel, LowRankKernel) else kernel @ w


def nonrigid_m_step(post: Posteriors, moving: np.ndarray, fixed: np.ndarray, kernel, lam: float, sigma2: float):
    """Non-rigid M-step: solve ``(d(P1) G + lam sigma2 I) W = P X - d(P1) Y``.

    ``kernel`` is the dense ``G`` (exact) or a :class:`LowRankKernel` (the Woodbury form of
    the CPD paper's section 5). Returns ``(W, T(Y), sigma2_new, tr(W^T G W))``; the last is
    the smoothness penalty's trace, from the ``G W`` the step computes anyway.
    """
    ls2 = lam * sigma2
    if isinstance(kernel, LowRankKernel):
        inner = weighted_gram(kernel.vectors_t, post.p1)
        # (one compiled call for the rest: 175 -> ~95 us at 1,000 points and rank 44, where
        # a dozen small NumPy calls cost more than their arithmetic)
        w, moved, sigma2_new, g_term = _low_rank_step(
            kernel.vectors_t, kernel.values, inner, post.p1, post.px, post.pt1, moving, fixed, ls2, post.n_p
        )
        return w, moved, sigma2_new, g_term
    n_dims = moving.shape[1]
    p1 = post.p1
    rhs = post.px - p1[:, None] * moving
    system = p1[:, None] * kernel
    system[np.diag_indices_from(system)] += ls2
    # LAPACK's gesv: the LU solve of scipy.linalg.solve without its condition estimate, whose
    # "ill-conditioned" warning would fire on most fits (a Gaussian G is ill-conditioned by
    # nature; lam sigma2 I is what regularises it)
    _, _, w, info = linalg.lapack.dgesv(system, rhs, overwrite_a=True, overwrite_b=False)
    if info != 0:
        # singular: lam sigma2 has underflowed beside moving points with no posterior mass
        # (P1 = 0) or repeated moving points (equal rows of G); the least-squares solution
        system = p1[:, None] * kernel
        system[np.diag_indices_from(system)] += ls2
        w = linalg.lstsq(system, rhs, check_finite=False)[0]
    field = kernel @ w
    moved = moving + field
    # (traces as flat dot products: 2.8 us against 5.1 us for a product and a sum, 1,000 x 2)
    x_px = float(post.pt1 @ np.einsum("ij,ij->i", fixed, fixed))
    y_py = float(p1 @ np.einsum("ij,ij->i", moved, moved))
    tr_pxy = float(np.ravel(moved) @ np.ravel(post.px))
    sigma2_new = (x_px - 2 * tr_pxy + y_py) / (post.n_p * n_dims)
    return w, moved, float(sigma2_new), float(np.ravel(w) @ np.ravel(field))


@njit(nogil=True, cache=True, fastmath={"contract", "reassoc", "nsz"})
def _low_rank_step(qt, values, inner, p1, px, pt1, moving, fixed, ls2, n_p):
    """The low-rank M-step after its Gram matrix ``inner = Q^T d(P1) Q`` (modified here).

    Woodbury gives ``W = (R - d(P1) Q z) / ls2`` with ``(inner + ls2 diag(1 / values)) z =
    Q^T R``, ``R = P X - d(P1) Y``; but that difference cancels as ``ls2 = lam sigma2``
    shrinks (at sigma2 ~ 1e-10 its rounding, amplified by ``1 / ls2``, moved the fit by 1e-4
    between BLAS thread counts). Only ``Q^T W`` enters the model, and the same system gives
    ``Q^T W = diag(1 / values) z`` exactly, so without any difference: the field
    ``G W = Q diag(values) Q^T W = Q z``, the penalty ``tr(W^T G W) = sum z^2 / values``, and
    ``W = Q diag(1 / values) z`` (the coefficients with that ``Q^T W`` and no part outside
    ``Q``'s span, which ``G`` maps to zero). Returns ``(W, T(Y), sigma2, tr(W^T G W))``.
    Loops run along the M points (``qt`` = Q^T, K x M)."""
    n_rank, n_points = qt.shape
    n_dims = moving.shape[1]
    rhs = np.empty((n_dims, n_points))  # R^T
    for m in range(n_points):
        for d in range(n_dims):
            rhs[d, m] = px[m, d] - p1[m] * moving[m, d]
    b = np.empty((n_rank, n_dims))
    for k in range(n_rank):
        for d in range(n_dims):
            b[k, d] = _dot(qt[k], rhs[d], 0.0)
        inner[k, k] += ls2 / values[k]
    z = np.linalg.solve(inner, b)
    field = np.zeros((n_dims, n_points))  # (Q z)^T
    w = np.zeros((n_dims, n_points))  # (Q diag(1 / values) z)^T
    g_term = 0.0
    for d in range(n_dims):
        fd = field[d]
        wd = w[d]
        for k in range(n_rank):
            q = qt[k]
            c = z[k, d]
            c_w = c / values[k]
            g_term += c * c_w
            for m in range(n_points):
                fd[m] += c * q[m]
                wd[m] += c_w * q[m]
    moved = np.empty((n_points, n_dims))
    w_out = np.empty((n_points, n_dims))
    x_px = 0.0
    for n in range(fixed.shape[0]):
        sq = 0.0
        for d in range(n_dims):
            sq += fixed[n, d] * fixed[n, d]
        x_px += pt1[n] * sq
    y_py = 0.0
    tr_pxy = 0.0
    for m in range(n_points):
        sq = 0.0
        for d in range(n_dims):
            v = moving[m, d] + field[d, m]
            moved[m, d] = v
            w_out[m, d] = w[d, m]
            sq += v * v
            tr_pxy += v * px[m, d]
        y_py += p1[m] * sq
    return w_out, moved, (x_px - 2.0 * tr_pxy + y_py) / (n_p * n_dims), g_term


@njit(nogil=True, cache=True, fastmath={"contract", "reassoc", "nsz"})
def _field_t(qt, values, wt):
    """``(Q diag(values) Q^T W)^T`` (D x M) from ``wt`` = W^T, along the contiguous rows of
    ``qt`` = Q^T (K x M)."""
    n_rank, n_points = qt.shape
    n_dims = wt.shape[0]
    field = np.zeros((n_dims, n_points))
    for d in range(n_dims):
        wd = wt[d]
        fd = field[d]
        for k in range(n_rank):
            q = qt[k]
            c = values[k] * _dot(q, wd, 0.0)
            for m in range(n_points):
                fd[m] += c * q[m]
    return field


@njit(nogil=True, cache=True)
def _low_rank_times(qt, values, w):
    """``Q diag(values) Q^T w`` (M x D, C-ordered)."""
    return np.ascontiguousarray(_field_t(qt, values, np.ascontiguousarray(w.T)).T)

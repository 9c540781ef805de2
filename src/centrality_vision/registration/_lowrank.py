"""Low-rank Gaussian kernels by pivoted Cholesky (the Nystrom approximation on greedy pivots).

For points ``y_1..y_M`` and ``G[i, j] = exp(-|y_i - y_j|^2 / (2 beta^2))``, the pivoted
Cholesky factorisation [1]_ picks, one at a time, the point whose diagonal residual
``G[i, i] - (L L^T)[i, i]`` is largest, and adds the column of ``G`` at that point, made
orthogonal to the columns already taken. After ``K`` steps ``G ~ L L^T`` with ``L`` of shape
(M, K); ``G - L L^T`` is positive semi-definite, so every entry of it, and its spectral norm,
is at most its trace, the sum of the residual diagonal, which the factorisation tracks. It
reads ``K`` columns of ``G`` (O(M K D)) and costs O(M K^2) in all: no M x M matrix, no
iterative eigensolver. ``L L^T`` is exactly the Nystrom approximation of ``G`` on the
pivots, ``G[:, S] G[S, S]^-1 G[S, :]``, so the low-rank displacement field
``v(z) = sum_i g(z, y_i) w_i`` projected on it is again a Gaussian-kernel field, on the
``K`` pivots alone (:func:`nystrom_field`).

References
----------
.. [1] H. Harbrecht, M. Peters and R. Schneider, "On the low-rank approximation by the
   pivoted Cholesky decomposition", Applied Numerical Mathematics 62(4), 428-440, 2012.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._parallel import run_chunks
from .._validation import ANY_DIMS, as_points, check_float, check_int
from ..exceptions import InputError
from ._kernels import fast_exp

__all__ = ["PivotedCholesky", "pivoted_cholesky", "low_rank_eigh", "nystrom_field", "weighted_gram"]

# weighted_gram: moving points per block (the block's K rows of Q^T and of Q^T d(p) stay in
# L2: 512 was 1.1-1.4x faster than 1,024 and 1.0-1.1x faster than 256, from 500 to 20,000
# points), and blocks per chunk of the pool from this many multiply-adds.
_GRAM_BLOCK = 512
_SERIAL_WEIGHTED_GRAM = 1 << 25
# Columns of L stored at first (rows of L^T); doubled when full (room for ``max_rank`` at
# once can be far more memory than the few columns usually needed).
_FIRST_WIDTH = 64


@njit(nogil=True, cache=True, fastmath={"contract"})
def _column(points, pivot, inv2b2, lt, k, out):
    """``out[j] = G[j, pivot] - sum_{q < k} L[j, q] L[pivot, q]`` with ``lt`` = L^T (rows
    = columns of L): the sum as ``k`` passes along contiguous rows (measured 1.3-2.1x faster
    than a short dot product per point, from 1,000 to 100,000 points)."""
    n_dims = points.shape[1]
    for j in range(points.shape[0]):
        d2 = 0.0
        for d in range(n_dims):
            diff = points[j, d] - points[pivot, d]
            d2 += diff * diff
        out[j] = fast_exp(max(-d2 * inv2b2, -700.0))
    for q in range(k):
        c = lt[q, pivot]
        row = lt[q]
        for j in range(out.shape[0]):
            out[j] -= c * row[j]


@njit(nogil=True, cache=True, fastmath={"contract"})
def _take(col, pivot, k, lt, diag):
    """Scale ``col`` into row ``k`` of ``lt`` (column ``k`` of L) and take its squares off ``diag``."""
    scale = 1.0 / np.sqrt(diag[pivot])
    row = lt[k]
    for j in range(col.shape[0]):
        c = col[j] * scale
        row[j] = c
        diag[j] = max(diag[j] - c * c, 0.0)
    diag[pivot] = 0.0


@njit(nogil=True, cache=True, fastmath={"contract"})
def _factor(points, inv2b2, target, lt, diag, pivots, start):
    """Columns ``start, start + 1, ...`` of the factorisation, until ``lt`` is full or the
    stopping rule holds; returns the number of columns taken so far. One thread: a column
    is a memory-bound pass, and per-column dispatch to a pool measured slower from 1,000 to
    300,000 points (1.5-3x at 3,000-30,000)."""
    n = points.shape[0]
    col = np.empty(n)
    for k in range(start, lt.shape[0]):
        if diag.sum() <= target:
            return k
        pivot = np.argmax(diag)
        if diag[pivot] <= 0.0:
            return k
        _column(points, pivot, inv2b2, lt, k, col)
        _take(col, pivot, k, lt, diag)
        pivots[k] = pivot
    return lt.shape[0]


class PivotedCholesky:
    """``G ~ L L^T`` for the Gaussian kernel of ``points``, by pivoted Cholesky.

    Parameters
    ----------
    points : array_like of shape (M, D)
    beta : float
        Kernel width: ``G[i, j] = exp(-|y_i - y_j|^2 / (2 beta^2))``.
    max_rank : int
        At most this many columns.
    tol : float, default=1e-12
        Stop once the trace of the residual ``G - L L^T`` (a bound on its spectral norm and on
        every entry) is at most ``tol`` times ``M`` (the trace of ``G``).

    Attributes
    ----------
    factor : ndarray of shape (K, M)
        ``L^T``: row ``k`` is the ``k``-th column of ``L``.
    pivots : ndarray of shape (K,)
        The points chosen, in order.
    residual_trace : float
        ``trace(G - L L^T)`` at the end, the error bound.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((300, 2))
    >>> pc = PivotedCholesky(y, 0.5, max_rank=100, tol=1e-12)
    >>> g = np.exp(-((y[:, None] - y[None]) ** 2).sum(-1) / (2 * 0.5**2))
    >>> bool(np.abs(g - pc.factor.T @ pc.factor).max() <= pc.residual_trace <= 1e-12 * 300)
    True
    """

    def __init__(self, points, beta, *, max_rank, tol=1e-12):
        points = np.ascontiguousarray(as_points(points, name="points", n_dims=ANY_DIMS), dtype=float)
        beta = check_float(beta, name="beta", low=0.0, low_open=True)
        max_rank = check_int(max_rank, name="max_rank", low=1)
        tol = check_float(tol, name="tol", low=0.0)
        n = points.shape[0]
        max_rank = min(max_rank, n)
        inv2b2 = 1.0 / (2.0 * beta * beta)
        if not math.isfinite(inv2b2):
            raise InputError(f"`beta` = {beta!r} is too small: 1 / (2 beta^2) overflows.")
        diag = np.ones(n)
        pivots = np.empty(max_rank, dtype=np.int64)
        target = tol * n
        lt = np.empty((min(max_rank, _FIRST_WIDTH), n))  # L^T: a column of L per row
        count = 0
        while True:
            count = _factor(points, inv2b2, target, lt, diag, pivots, count)
            if count < lt.shape[0] or count == max_rank:
                break
            wider = np.empty((min(2 * lt.shape[0], max_rank), n))
            wider[:count] = lt[:count]
            lt = wider
        self.factor = lt[:count] if count == lt.shape[0] else lt[:count].copy()
        self.pivots = pivots[:count].copy()
        self.residual_trace = float(diag.sum())


def pivoted_cholesky(points, beta, *, max_rank, tol=1e-12):
    """``(L, pivots, residual_trace)`` of :class:`PivotedCholesky`, with ``L`` of shape (M, K)."""
    pc = PivotedCholesky(points, beta, max_rank=max_rank, tol=tol)
    return pc.factor.T, pc.pivots, pc.residual_trace


def low_rank_eigh(points, beta, rank, *, tol=1e-12):
    """Approximate leading eigenpairs ``(values, vectors)`` of the Gaussian kernel matrix.

    ``G ~ L L^T`` by pivoted Cholesky (at most ``rank`` columns, fewer once the residual
    trace falls to ``tol * M``); with ``L^T L = V diag(values) V^T`` (K x K), the vectors
    ``L V diag(values)^-1/2`` are orthonormal and ``G ~ vectors diag(values) vectors^T``
    equals ``L L^T`` less the directions of values below 1e-10 of the largest, which are
    dropped (forming ``L^T L`` squares the condition number: a kept direction of relative
    value ``r`` is orthogonal to the others to about ``1e-16 / r``, so at worst 1e-6). O(M K^2):
    the two products by BLAS, like the M-step's (one thread: 112 and 122 us at 1,000 points
    and rank 47, against 153 and 546 for compiled loops; 3.1 and 7.7 ms at 10,000 and rank
    100, against 8.7 and 16.5). The spectral-norm error is at most the residual trace plus
    1e-10 of the largest value; values come in decreasing order.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(1).random((200, 2))
    >>> values, vectors = low_rank_eigh(y, 1.0, 30)
    >>> exact = np.linalg.eigvalsh(np.exp(-((y[:, None] - y[None]) ** 2).sum(-1) / 2))[::-1]
    >>> orthonormal = np.allclose(vectors.T @ vectors, np.eye(len(values)), atol=1e-6)
    >>> bool(np.allclose(values[:10], exact[:10], rtol=1e-8)), bool(orthonormal)
    (True, True)
    """
    values, vectors, _, _ = _low_rank_eigh_parts(points, beta, rank, tol)
    return values, vectors


def _low_rank_eigh_parts(points, beta, rank, tol=1e-12):
    """:func:`low_rank_eigh`'s ``(values, vectors)``, its :class:`PivotedCholesky` and the
    eigenvectors ``V`` (K x k) of ``L^T L`` kept: ``vectors = L V diag(values)^-1/2``."""
    pc = PivotedCholesky(points, beta, max_rank=rank, tol=tol)
    factor = pc.factor
    gram = factor @ factor.T
    values, v = np.linalg.eigh(gram)
    order = np.argsort(values)[::-1]
    values, v = values[order], v[:, order]
    keep = values > values[0] * 1e-10
    values, v = values[keep], v[:, keep]
    vectors = factor.T @ (v / np.sqrt(values))
    return values, vectors, pc, v


@njit(nogil=True, cache=True, fastmath={"contract", "reassoc", "nnan", "ninf", "nsz"})
def _weighted_gram_part(qt, p, lo, hi, out):
    """``out = sum_{lo <= m < hi} p[m] q_m q_m^T`` (lower triangle; ``qt`` is Q^T, K x M), by
    blocks of :data:`_GRAM_BLOCK` moving points and tiles of 2 x 2 entries (four dot products
    share each load)."""
    n_rank = qt.shape[0]
    out[:, :] = 0.0
    wq = np.empty((n_rank, _GRAM_BLOCK))
    for start in range(lo, hi, _GRAM_BLOCK):
        end = min(start + _GRAM_BLOCK, hi)
        n = end - start
        weight = p[start:end]
        for i in range(n_rank):
            qi = qt[i, start:end]
            wi = wq[i, :n]
            for m in range(n):
                wi[m] = qi[m] * weight[m]
        for i in range(0, n_rank - 1, 2):
            a0, a1 = wq[i, :n], wq[i + 1, :n]
            for j in range(0, i + 1, 2):
                b0, b1 = qt[j, start:end], qt[j + 1, start:end]
                s00 = s01 = s10 = s11 = 0.0
                for m in range(n):
                    x0, x1, y0, y1 = a0[m], a1[m], b0[m], b1[m]
                    s00 += x0 * y0
                    s01 += x0 * y1
                    s10 += x1 * y0
                    s11 += x1 * y1
                out[i, j] += s00
                out[i, j + 1] += s01
                out[i + 1, j] += s10
                out[i + 1, j + 1] += s11
        if n_rank % 2:
            a = wq[n_rank - 1, :n]
            for j in range(n_rank):
                b = qt[j, start:end]
                total = 0.0
                for m in range(n):
                    total += a[m] * b[m]
                out[n_rank - 1, j] += total


def weighted_gram(qt: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``Q^T d(p) Q`` (K x K, symmetric) from ``qt`` = Q^T (K x M, C-contiguous).

    The non-rigid M-step's Woodbury system, once per iteration. One thread: 2.1-2.7x faster
    than BLAS's ``Q.T @ (p[:, None] * Q)`` from 500 to 20,000 points at ranks 47-139 (69
    against 176 us at 1,000 points). From 2^25 multiply-adds the moving points are split
    into chunks that depend on M alone, summed in chunk order: the same result for any
    number of threads.

    Examples
    --------
    >>> import numpy as np
    >>> q = np.random.default_rng(0).random((300, 7))
    >>> p = np.random.default_rng(1).random(300)
    >>> bool(np.allclose(weighted_gram(np.ascontiguousarray(q.T), p), q.T @ (p[:, None] * q)))
    True
    """
    n_rank, n = qt.shape
    if n * n_rank * n_rank < _SERIAL_WEIGHTED_GRAM:
        out = np.empty((n_rank, n_rank))
        _weighted_gram_part(qt, p, 0, n, out)
    else:
        blocks = -(-n // _GRAM_BLOCK)
        n_chunks = min(blocks, 16)
        edges = [min(n, (i * blocks // n_chunks) * _GRAM_BLOCK) for i in range(n_chunks + 1)]
        parts = np.empty((n_chunks, n_rank, n_rank))

        def task(lo, hi):
            for c in range(lo, hi):
                _weighted_gram_part(qt, p, edges[c], edges[c + 1], parts[c])

        run_chunks(task, n_chunks)
        out = parts[0]
        for c in range(1, n_chunks):
            out += parts[c]
    _mirror_lower(out)
    return out


@njit(nogil=True, cache=True)
def _mirror_lower(a):
    for i in range(a.shape[0]):
        for j in range(i):
            a[j, i] = a[i, j]


def nystrom_field(points, pivots, factor, coefficients):
    """The displacement field ``L L^T W`` as Gaussian-kernel weights on the pivots alone.

    With ``G ~ L L^T`` the Nystrom approximation on the pivots ``S``, ``L = G[:, S] C^-T``
    where ``C`` is the lower-triangular ``L[S]``, so ``L L^T W = G[:, S] C^-T (L^T W)``: the
    field ``v(z) = sum_{s in S} g(z, y_s) a_s`` with ``a = C^-T L^T W`` (K x D) equals the
    low-rank displacement at every point and is defined everywhere. Returns ``(centres, a)``.

    ``factor`` is ``L^T`` (K x M) as in :class:`PivotedCholesky`.
    """
    return np.asarray(points)[pivots], pivot_weights(factor, pivots, factor @ coefficients)


def pivot_weights(factor, pivots, lt_w):
    """``a = C^-T lt_w`` with ``C = L[S]`` (lower triangular): the pivots' kernel weights of
    the field ``L lt_w`` (``lt_w`` stands for ``L^T W``, K x D)."""
    from scipy.linalg import solve_triangular

    c = factor[:, pivots].T  # L[S]: row i is the i-th pivot's row of L, lower triangular
    return solve_triangular(c, lt_w, lower=True, trans="T")

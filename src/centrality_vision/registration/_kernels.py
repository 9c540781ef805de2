"""Compiled pieces of the CPD/GPD E-step (numba, serial, GIL-free).

The dense path (:func:`dense_rows`) takes each row of fixed points ``n`` in a few
vectorised loops over row buffers that stay in L1:

1. scores ``s_mn = -|x_n - T(y_m)|^2 / (2 sigma2) + prior_mn``, their maximum (and its first
   position, when asked: a fit asks only for its last state, :func:`dense_best`), and
   ``ref_n = max(max_m s_mn, log c)``;
2. ``e_mn = exp(s_mn - ref_n)`` by :func:`fast_exp` (a vectorisable exponential, relative
   error below 4e-16; numba's scalar ``exp`` is a libm call that does not vectorise), or in
   float32 by :func:`fast_exp_single`, and the row sum, so every term is <= 1 and the
   largest is exactly 1;
3. the rows, four at a time, normalised by ``sum_m e_mn + c exp(-ref_n)`` and added into
   the sufficient statistics ``P1`` and ``P X``; ``P^T 1`` and ``log den`` per row.

With the moving points sorted along one axis, step 2 runs only over each row's band of
points that can hold a term above ``exp(-tau)`` (see :func:`dense_rows`), and step 3 over
the union of the four rows' bands; where the band is narrow enough, step 1 too runs only
over the run that the row's nearest moving point bounds the same way.

The truncated path visits, for each fixed point, only the moving points within
``sqrt(d_min^2 + 2 sigma2 tau')`` of it (a uniform grid of cells, searched by sorted cell
keys), which drops only terms below ``exp(-tau)`` of the row's largest one.

Every loop runs in a fixed order, and the callers reduce per-chunk partial sums in chunk
order over chunks that do not depend on the thread count, so results are bit-identical
whatever the number of threads.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

__all__ = [
    "fast_exp",
    "fast_exp_single",
    "exp_array",
    "dense_best",
    "dense_rows",
    "transpose_extent",
    "refine_order",
    "gather_columns",
    "scatter_statistics",
    "grid_keys",
    "bucket_points",
    "grid_nearest",
    "truncated_scores",
    "sparse_accumulate",
    "count_candidates",
]

# Terms more than this far below a row's largest one are below exp(-50) ~ 2e-22 of it and
# are skipped when accumulating (they change no sum at double precision).
_SKIP = np.exp(-50.0)
# Exponents are clamped here before ``exp`` (see _exp_row).
_FLOOR = -700.0


@njit(nogil=True, cache=True, inline="always")
def _advance(cur, lo_c, hi_c, last):
    """Step the cell odometer ``cur`` over dimensions ``0..last`` (``last`` fastest); False when done."""
    d = last
    while d >= 0:
        cur[d] += 1
        if cur[d] <= hi_c[d]:
            return True
        cur[d] = lo_c[d]
        d -= 1
    return False


@njit(nogil=True, cache=True, inline="always")
def _reach_box(point, reach, origin, cell, dims, lo_c, hi_c, cur):
    """Cells overlapping the box of half-side ``reach`` about ``point`` into ``lo_c``..``hi_c``
    (clipped to the grid), ``cur`` set to the first; returns the number of cells (0: none)."""
    span = 1
    for d in range(point.shape[0]):
        lo_c[d] = max(int(np.floor((point[d] - reach - origin[d]) / cell)), 0)
        hi_c[d] = min(int(np.floor((point[d] + reach - origin[d]) / cell)), dims[d] - 1)
        span *= max(hi_c[d] - lo_c[d] + 1, 0)
        cur[d] = lo_c[d]
    return span


@njit(nogil=True, cache=True, inline="always")
def _row_range(keys_sorted, cur, lo_c, hi_c, dims):
    """Positions ``a:b`` in ``keys_sorted`` of the points in the cells at ``cur`` in every
    dimension but the last, over its whole range (the last dimension is contiguous in key order)."""
    n_dims = cur.shape[0]
    key_lo = 0
    key_hi = 0
    for d in range(n_dims):
        key_lo = key_lo * dims[d] + (cur[d] if d < n_dims - 1 else lo_c[d])
        key_hi = key_hi * dims[d] + (cur[d] if d < n_dims - 1 else hi_c[d])
    return np.searchsorted(keys_sorted, key_lo, side="left"), np.searchsorted(keys_sorted, key_hi, side="right")


@njit(nogil=True, cache=True, inline="always")
def _scan_everything(lo_c, hi_c, n_points):
    """True when the box's cell rows (every dimension but the last) outnumber the points: a
    scan of all points in key order then visits the same candidates, in the same order, far
    cheaper (a far fixed point at a tiny sigma2 spans millions of empty cells)."""
    rows = 1
    for d in range(lo_c.shape[0] - 1):
        rows *= hi_c[d] - lo_c[d] + 1
        if rows > n_points:
            return True
    return False


# ---------------------------------------------------------------------------------------------
# A vectorisable exponential: exp(x) = 2^k exp(r), k = round(x / ln 2), |r| <= ln(2) / 2,
# exp(r) by its Taylor polynomial of degree 12 (truncation error 0.347^13 / 13! < 2e-16),
# 2^k built from its bits. Valid for -708 <= x <= 709; callers clamp at _FLOOR.

_LOG2E = 1.4426950408889634
_LN2_HI = 0.6931471803691238  # ln 2 split so that k * _LN2_HI is exact for |k| < 2^21
_LN2_LO = 1.9082149292705877e-10
_ROUND = 6755399441055744.0  # 1.5 * 2^52: adding and subtracting it rounds to an integer
_C = [1.0]
for _k in range(1, 13):
    _C.append(_C[-1] / _k)
_C2, _C3, _C4, _C5, _C6, _C7, _C8, _C9, _C10, _C11, _C12 = _C[2:]
_CONTRACT = {"contract"}  # fused multiply-adds only: no reassociation may touch the range reduction
_REDUCE = {"contract", "reassoc", "nnan", "ninf", "nsz"}  # sums and maxima of finite values, vectorised


@intrinsic
def _int_bits_as_float(typingctx, bits):
    """Reinterpret the 64 bits of an int64 as a float64 (no conversion)."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(types.float64))

    return sig, codegen


@njit(nogil=True, cache=True, inline="always")
def fast_exp(x):
    """``exp(x)`` for ``-708 <= x <= 709`` to a relative error below 4e-16, in a form LLVM vectorises.

    Inlined into its callers, which must be compiled with ``fastmath=_CONTRACT`` at most:
    reassociation would undo the rounding trick and the two-part range reduction.
    """
    k = (x * _LOG2E + _ROUND) - _ROUND
    r = (x - k * _LN2_HI) - k * _LN2_LO
    p = _C12
    p = p * r + _C11
    p = p * r + _C10
    p = p * r + _C9
    p = p * r + _C8
    p = p * r + _C7
    p = p * r + _C6
    p = p * r + _C5
    p = p * r + _C4
    p = p * r + _C3
    p = p * r + _C2
    p = p * r + 1.0
    p = p * r + 1.0
    return p * _int_bits_as_float((np.int64(k) + 1023) << 52)


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def exp_array(values, out):
    """``out = exp(max(values, -700))`` by :func:`fast_exp`."""
    for i in range(values.shape[0]):
        out[i] = fast_exp(max(values[i], _FLOOR))


@njit(nogil=True, cache=True, fastmath=_REDUCE)
def _max(row, n):
    """``max(row[:n])`` (``n >= 1``), over eight interleaved lanes so that it vectorises."""
    a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = row[0]
    end = n - n % 8
    for k in range(0, end, 8):
        v = row[k]
        a0 = v if v > a0 else a0
        v = row[k + 1]
        a1 = v if v > a1 else a1
        v = row[k + 2]
        a2 = v if v > a2 else a2
        v = row[k + 3]
        a3 = v if v > a3 else a3
        v = row[k + 4]
        a4 = v if v > a4 else a4
        v = row[k + 5]
        a5 = v if v > a5 else a5
        v = row[k + 6]
        a6 = v if v > a6 else a6
        v = row[k + 7]
        a7 = v if v > a7 else a7
    out = max(max(max(a0, a1), max(a2, a3)), max(max(a4, a5), max(a6, a7)))
    for m in range(end, n):
        out = max(out, row[m])
    return out


@njit(nogil=True, cache=True, fastmath=_REDUCE)
def _sum(row, a, b):
    """``sum(row[a:b])``. (Every loop here that should vectorise over part of an array runs
    over a slice from 0: a loop from an arbitrary start keeps numba's negative-index
    wraparound, which stops LLVM from vectorising it; measured 4-6x slower over 1,000 to
    90,000 terms.)"""
    part = row[a:b]
    total = 0.0
    for m in range(part.shape[0]):
        total += part[m]
    return total


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _exp_shifted(row, a, b, shift):
    """``row[a:b] = exp(max(row[a:b] - shift, -700))`` in place: the clamp keeps every value
    normal (exp(-700) ~ 1e-304 adds nothing to a sum whose largest term is 1)."""
    part = row[a:b]  # (a slice from 0: see _sum)
    for m in range(part.shape[0]):
        part[m] = fast_exp(max(part[m] - shift, _FLOOR))


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _scores_rows(x, n, y0, y1, y2, n_dims, inv2s2, row):
    """``row[m] = -|x_n - y_m|^2 inv2s2`` for D = 2 (``y2`` unused) and 3 from the moving
    set's coordinate rows (one loop: the full row and a band's run score alike)."""
    if n_dims == 2:
        x0, x1 = x[n, 0], x[n, 1]
        for m in range(row.shape[0]):
            d0 = x0 - y0[m]
            d1 = x1 - y1[m]
            row[m] = -(d0 * d0 + d1 * d1) * inv2s2
    else:
        x0, x1, x2 = x[n, 0], x[n, 1], x[n, 2]
        for m in range(row.shape[0]):
            d0 = x0 - y0[m]
            d1 = x1 - y1[m]
            d2 = x2 - y2[m]
            row[m] = -(d0 * d0 + d1 * d1 + d2 * d2) * inv2s2


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _scores_run(x, n, yt, c, e, inv2s2, part):
    """``part[m - c] = -|x_n - y_m|^2 inv2s2`` for the moving points ``c <= m < e``: one loop
    for D = 2 and 3, one per axis otherwise."""
    n_dims = yt.shape[0]
    if n_dims == 2:
        _scores_rows(x, n, yt[0, c:e], yt[1, c:e], yt[1, c:e], 2, inv2s2, part)
    elif n_dims == 3:
        _scores_rows(x, n, yt[0, c:e], yt[1, c:e], yt[2, c:e], 3, inv2s2, part)
    else:
        for m in range(e - c):
            part[m] = 0.0
        for d in range(n_dims):
            xd = x[n, d]
            yd = yt[d, c:e]
            for m in range(e - c):
                diff = xd - yd[m]
                part[m] += diff * diff
        for m in range(e - c):
            part[m] *= -inv2s2


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _scores(x, n, yt, inv2s2, row):
    """``row[m] = -|x_n - y_m|^2 inv2s2`` for every moving point."""
    n_moving = yt.shape[1]
    _scores_run(x, n, yt, 0, n_moving, inv2s2, row[:n_moving])


# ---------------------------------------------------------------------------------------------
# The dense E-step. Per row of fixed points: the scores (and the prior) into a buffer, their
# maximum (and its first position, when asked: a fit needs it only at its end), the
# exponentials into a second buffer and their sum, each one vectorised loop over the row
# (held in L1); the rows are then added into the sufficient statistics four at a time, so
# that P1 and P X are read and written once per four rows. The exponential dominates
# (measured on one core at 1,000 points, in compiled loops: 0.62 ns a term, against 0.15
# for a score, 0.14 for the maximum, 0.12 for its position, 0.06 for the sum and 0.14 a row
# for the accumulation). Scores and exponentials are not fused into one loop: that needs
# each row's shift beforehand (its nearest moving point, from a k-d tree), and the tree's
# query alone costs more than the passes it would save below about 10,000 points (0.65 ns
# a pair at 1,000 points, 0.14 at 3,000), while a score-and-exponential loop costs as much
# as the two loops (0.81 against 0.77 ns a term). Nor the scores and their maximum: numba's
# loop that stores a score and keeps a running maximum did not vectorise (0.47-0.69 ns a
# term against 0.27-0.33 for the two loops).

_GROUP = 4  # rows accumulated together


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _first_equal(row, value, order):
    """The least ``order[m]`` with ``row[m] == value`` (``order[M - 1]`` if none), as a
    vectorised minimum: the first such moving point in the caller's numbering."""
    n = row.shape[0]
    none = np.int64(1) << 62
    first = none
    for m in range(n):
        first = min(first, order[m] if row[m] == value else none)
    return first if first < none else order[n - 1]


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _exp_row(scores, shift, out):
    """``out[m] = exp(max(scores[m] - shift, -700))`` by :func:`fast_exp`."""
    for m in range(scores.shape[0]):
        out[m] = fast_exp(max(scores[m] - shift, _FLOOR))


# ---------------------------------------------------------------------------------------------
# A float32 exponential for -87 <= x <= 0, the same scheme as fast_exp: k = round(x / ln 2),
# |r| <= ln(2) / 2, exp(r) by its Taylor polynomial of degree 7 (truncation error
# 0.347^8 / 8! < 6e-9), 2^k from its bits (k >= -126: a normal float32).

_FLOOR_SINGLE = -87.0  # exp(-87) ~ 1.6e-38, near float32's least normal number: the clamp

_F = np.float32
_LOG2E_S = _F(1.4426950408889634)
_LN2_HI_S = _F(0.693359375)  # ln 2 split so that k * _LN2_HI_S is exact for |k| < 2^11
_LN2_LO_S = _F(-2.12194440e-4)
_ROUND_S = _F(12582912.0)  # 1.5 * 2^23
_S = [_F(c) for c in _C[:8]]
_S0, _S1, _S2, _S3, _S4, _S5, _S6, _S7 = _S


@intrinsic
def _int_bits_as_float32(typingctx, bits):
    """Reinterpret the 32 bits of an int32 as a float32 (no conversion)."""
    sig = types.float32(types.int32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(types.float32))

    return sig, codegen


@njit(nogil=True, cache=True, inline="always")
def fast_exp_single(x):
    """``exp(x)`` of a float32 ``-87 <= x <= 0`` to a relative error below 2e-7 (measured
    7.6e-8), in float32 throughout; callers compile with ``fastmath=_CONTRACT`` at most."""
    k = (x * _LOG2E_S + _ROUND_S) - _ROUND_S
    r = (x - k * _LN2_HI_S) - k * _LN2_LO_S
    p = _S7
    p = p * r + _S6
    p = p * r + _S5
    p = p * r + _S4
    p = p * r + _S3
    p = p * r + _S2
    p = p * r + _S1
    p = p * r + _S0
    return p * _int_bits_as_float32((np.int32(k) + np.int32(127)) << np.int32(23))


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _exp_row_single(scores, shift, out):
    """``out[m] = exp(max(t, -87))`` in float32 by :func:`fast_exp_single`, ``t = scores[m] -
    shift`` taken in float64 and rounded to float32 (an absolute error of at most
    ``87 * 2^-24 = 5.2e-6`` in ``t``)."""
    for m in range(scores.shape[0]):
        out[m] = fast_exp_single(_F(max(scores[m] - shift, _FLOOR_SINGLE)))


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def dense_rows(
    x,
    yt,
    lo,
    hi,
    inv2s2,
    log_c,
    log_weight,
    v_moving,
    v_fixed,
    prior_scale,
    inv2phi2,
    single,
    key,
    axis,
    tau,
    score_band,
    order,
    scores,
    rows,
    coef,
    p1,
    pxt,
    pt1,
    log_den,
    best,
):
    """The whole E-step for fixed points ``lo <= n < hi`` against every moving point.

    ``yt`` is the moving set transposed (D x M); scratch: ``scores`` (M float64), ``rows``
    (4 x M zeros: float64, or float32 with ``single``) and ``coef`` (D + 1 x 4). ``p1`` and
    ``pxt`` (D x M) are added to, ``pt1``, ``log_den`` and ``best`` written at ``n``;
    ``order[m]`` is moving point ``m``'s index in the caller's numbering (``best`` holds it).
    An empty ``best`` skips it (a fit needs it only from its last E-step: :func:`dense_best`).

    Per row: scores ``s_m = -|x_n - y_m|^2 inv2s2`` (plus the prior), their maximum ``smax``
    (``best[n]`` its first position, or -1 when ``smax < log c``), the shift
    ``r = max(smax, log c)``, the terms ``e_m = exp(max(s_m - r, -700))`` (every term <= 1)
    and the denominator ``den = sum_m e_m + exp(log c - r)``: ``P[m, n] = e_m / den``. With
    ``single`` the terms are :func:`_exp_row_single`'s float32 ones (clamped at ``exp(-87)``),
    every sum still in float64.

    Band (``key`` not empty; no prior): the moving points are sorted along ``axis`` and
    ``key`` holds that coordinate. ``s_m <= -(x_n - key_m)^2 inv2s2``, so every term above
    ``exp(-tau)`` of ``exp(r)`` lies where ``(x_n - key_m)^2 <= (tau - r) / inv2s2``: the
    exponentials are taken only over that run of the sorted points (two binary searches)
    and the rest of the row is zero, as in the truncated path. The scores and their maximum
    are taken over the run that the row's nearest moving point bounds the same way (found
    by scanning the sorted keys outwards from the row's own, at most ``M / 8`` of them, else
    every pair is scored): that run holds every score within ``tau`` of the largest, so the
    results are the same as from every pair.
    """
    n_dims, n_moving = yt.shape
    band = key.shape[0] > 0
    want_best = best.shape[0] > 0
    span = np.empty((2, _GROUP), dtype=np.int64)
    scan_limit = max(32, n_moving // _SCAN_FRACTION)
    for g in range(lo, hi, _GROUP):
        size = min(_GROUP, hi - g)
        coef[:, :] = 0.0
        lo_g = n_moving
        hi_g = 0
        for j in range(size):
            n = g + j
            # the run [c, e) of the row whose scores are needed: all of it, or with the band
            # the run that can hold a term above exp(-tau) of the row's largest, from its
            # nearest moving point (found along the sorted keys), widened against rounding
            c = 0
            e = n_moving
            if band and score_band:
                d2 = _nearest_sorted(x, n, yt, key, axis, scan_limit)
                if d2 < np.inf:
                    r_low = max(-d2 * inv2s2, log_c)
                    r_low -= 1e-9 * max(1.0, abs(r_low))
                    half = np.sqrt(max(tau - r_low, 0.0) / inv2s2)
                    c = np.searchsorted(key, x[n, axis] - half)
                    e = np.searchsorted(key, x[n, axis] + half, side="right")
            if c == 0 and e == n_moving:
                smax = _row_scores(x, n, yt, inv2s2, log_weight, v_moving, v_fixed, prior_scale, inv2phi2, scores)
            elif e > c:
                smax = _part_scores(x, n, yt, c, e, inv2s2, scores)
            else:  # the outlier term outweighs every pair by more than tau: r = log c, best -1
                smax = -np.inf
            r = max(smax, log_c)
            if want_best:
                best[n] = _first_equal(scores[c:e], smax, order[c:e]) if smax >= log_c else -1
            a = 0
            b = n_moving
            if band:
                half = np.sqrt(max(tau - r, 0.0) / inv2s2)
                a = np.searchsorted(key, x[n, axis] - half)
                b = np.searchsorted(key, x[n, axis] + half, side="right")
            span[0, j] = a
            span[1, j] = b
            lo_g = min(lo_g, a)
            hi_g = max(hi_g, b)
            # (every loop over part of a row runs over a slice from 0: see _sum)
            if single:
                _exp_row_single(scores[a:b], r, rows[j, a:b])
            else:
                _exp_row(scores[a:b], r, rows[j, a:b])
            total = _sum(rows[j], a, b)
            den = total + np.exp(log_c - r)
            inv = 1.0 / den
            log_den[n] = r + np.log(den)
            pt1[n] = total * inv
            coef[0, j] = inv
            for d in range(n_dims):
                coef[d + 1, j] = x[n, d] * inv
        if lo_g >= hi_g:
            continue  # no moving point within any of these rows' bands
        if band:
            for j in range(size):  # this group's span of each row outside its own band: zero
                rows[j, lo_g : span[0, j]] = 0.0
                rows[j, span[1, j] : hi_g] = 0.0
        _accumulate_group(rows, coef, p1, pxt, lo_g, hi_g)


# The band's nearest-point scan gives up after this fraction of the moving points (a row far
# from the set across the band's axis) and the row is scored in full.
_SCAN_FRACTION = 8


@njit(nogil=True, cache=True, inline="always")
def _squared_distance(x, n, yt, m):
    total = 0.0
    for d in range(yt.shape[0]):
        diff = x[n, d] - yt[d, m]
        total += diff * diff
    return total


@njit(nogil=True, cache=True, inline="always")
def _nearest_sorted(x, n, yt, key, axis, limit):
    """Squared distance from fixed point ``n`` to its nearest moving point, the moving points
    sorted along ``axis`` (``key``): scanning outwards from ``x[n, axis]``'s place while the
    key gap alone is below the best so far; ``inf`` after ``limit`` candidates."""
    n_moving = yt.shape[1]
    xa = x[n, axis]
    start = np.searchsorted(key, xa)
    best = np.inf
    seen = 0
    m = start
    while m < n_moving and (key[m] - xa) ** 2 < best:
        best = min(best, _squared_distance(x, n, yt, m))
        m += 1
        seen += 1
        if seen > limit:
            return np.inf
    m = start - 1
    while m >= 0 and (xa - key[m]) ** 2 < best:
        best = min(best, _squared_distance(x, n, yt, m))
        m -= 1
        seen += 1
        if seen > limit:
            return np.inf
    return best


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _part_scores(x, n, yt, c, e, inv2s2, scores):
    """Row ``n``'s scores for the moving points ``c <= m < e`` (no prior) into
    ``scores[c:e]``, by the loops :func:`_scores` runs; returns their maximum."""
    part = scores[c:e]
    _scores_run(x, n, yt, c, e, inv2s2, part)
    return _max(part, e - c)


@njit(nogil=True, cache=True, inline="always")
def _row_scores(x, n, yt, inv2s2, log_weight, v_moving, v_fixed, prior_scale, inv2phi2, scores):
    """Row ``n``'s scores (plus the prior when ``log_weight`` is not empty) into ``scores``;
    returns their maximum. :func:`dense_rows` and :func:`dense_best` share it, so that both
    see the same values."""
    n_moving = yt.shape[1]
    _scores(x, n, yt, inv2s2, scores)
    if log_weight.shape[0] > 0:
        vn = v_fixed[n]
        for m in range(n_moving):
            dv = vn - v_moving[m]
            scores[m] += prior_scale * (log_weight[m] - dv * dv * inv2phi2)
    return _max(scores, n_moving)


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def dense_best(x, yt, lo, hi, inv2s2, log_c, log_weight, v_moving, v_fixed, prior_scale, inv2phi2, order, best):
    """``best[n]`` for fixed points ``lo <= n < hi`` as :func:`dense_rows` computes it: the
    first moving point (least ``order[m]``) of largest score, or -1 when that score is below
    ``log c``. About a third of an E-step's work."""
    scores = np.empty(yt.shape[1])
    for n in range(lo, hi):
        smax = _row_scores(x, n, yt, inv2s2, log_weight, v_moving, v_fixed, prior_scale, inv2phi2, scores)
        best[n] = _first_equal(scores, smax, order) if smax >= log_c else -1


@njit(nogil=True, cache=True)
def transpose_extent(points):
    """``(points.T as a C array, the extent max - min along each axis)`` in one pass."""
    n_points, n_dims = points.shape
    yt = np.empty((n_dims, n_points))
    low = np.full(n_dims, np.inf)
    high = np.full(n_dims, -np.inf)
    for i in range(n_points):
        for d in range(n_dims):
            v = points[i, d]
            yt[d, i] = v
            low[d] = min(low[d], v)
            high[d] = max(high[d], v)
    return yt, high - low


@njit(nogil=True, cache=True)
def refine_order(values, order, max_moves):
    """Sort ``order`` in place by ``(values[i], i)`` (the order of a stable argsort) by
    insertion from its current, nearly sorted state; gives up (returns False, ``order``
    then some permutation) after ``max_moves`` moves. The order is total, so every start
    that finishes ends at the same permutation."""
    moves = 0
    for k in range(1, order.shape[0]):
        item = order[k]
        v = values[item]
        j = k - 1
        while j >= 0:
            other = order[j]
            w = values[other]
            if w < v or (w == v and other < item):
                break
            order[j + 1] = other
            j -= 1
            moves += 1
        order[j + 1] = item
        if moves > max_moves:
            return False
    return True


@njit(nogil=True, cache=True)
def gather_columns(yt, order):
    """``yt[:, order]`` as a C array."""
    n_dims = yt.shape[0]
    out = np.empty((n_dims, order.shape[0]))
    for d in range(n_dims):
        for j in range(order.shape[0]):
            out[d, j] = yt[d, order[j]]
    return out


@njit(nogil=True, cache=True)
def scatter_statistics(p1, pxt, order, pt1, log_den, row_order):
    """The dense path's statistics back in the callers' numbering: ``P1`` and ``P X`` (M x D)
    from the sorted moving points' ``p1`` and ``pxt`` (D x M), ``P^T 1`` and the log
    denominators from the sorted fixed points' (an empty ``order`` / ``row_order``: not
    sorted)."""
    n_dims, n_moving = pxt.shape
    p1_out = np.empty(n_moving)
    px = np.empty((n_moving, n_dims))
    sorted_moving = order.shape[0] > 0
    for j in range(n_moving):
        m = order[j] if sorted_moving else j
        p1_out[m] = p1[j]
        for d in range(n_dims):
            px[m, d] = pxt[d, j]
    if row_order.shape[0] == 0:
        return p1_out, px, pt1, log_den
    pt1_out = np.empty_like(pt1)
    log_den_out = np.empty_like(log_den)
    for j in range(pt1.shape[0]):
        n = row_order[j]
        pt1_out[n] = pt1[j]
        log_den_out[n] = log_den[j]
    return p1_out, px, pt1_out, log_den_out


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def _accumulate_group(rows, coef, p1, pxt, a, b):
    """``p1 += sum_j coef[0, j] rows[j]`` and ``pxt[d] += sum_j coef[d + 1, j] rows[j]`` over
    the four rows' columns ``a:b``, in one pass for D = 2 and 3 (a row with zero coefficients
    adds nothing)."""
    n_dims = pxt.shape[0]
    n_moving = b - a
    r0, r1, r2, r3 = rows[0, a:b], rows[1, a:b], rows[2, a:b], rows[3, a:b]
    p1 = p1[a:b]
    # (each row of P X sliced on its own: a row of the 2D slice pxt[:, a:b] is typed with
    # an unknown stride, and its loop does not vectorise; measured 3.4x slower)
    c0, c1, c2, c3 = coef[0, 0], coef[0, 1], coef[0, 2], coef[0, 3]
    if n_dims == 2:
        a0, a1, a2, a3 = coef[1, 0], coef[1, 1], coef[1, 2], coef[1, 3]
        b0, b1, b2, b3 = coef[2, 0], coef[2, 1], coef[2, 2], coef[2, 3]
        q0, q1 = pxt[0, a:b], pxt[1, a:b]
        for m in range(n_moving):
            e0, e1, e2, e3 = np.float64(r0[m]), np.float64(r1[m]), np.float64(r2[m]), np.float64(r3[m])
            p1[m] += (e0 * c0 + e1 * c1) + (e2 * c2 + e3 * c3)
            q0[m] += (e0 * a0 + e1 * a1) + (e2 * a2 + e3 * a3)
            q1[m] += (e0 * b0 + e1 * b1) + (e2 * b2 + e3 * b3)
    elif n_dims == 3:
        a0, a1, a2, a3 = coef[1, 0], coef[1, 1], coef[1, 2], coef[1, 3]
        b0, b1, b2, b3 = coef[2, 0], coef[2, 1], coef[2, 2], coef[2, 3]
        z0, z1, z2, z3 = coef[3, 0], coef[3, 1], coef[3, 2], coef[3, 3]
        q0, q1, q2 = pxt[0, a:b], pxt[1, a:b], pxt[2, a:b]
        for m in range(n_moving):
            e0, e1, e2, e3 = np.float64(r0[m]), np.float64(r1[m]), np.float64(r2[m]), np.float64(r3[m])
            p1[m] += (e0 * c0 + e1 * c1) + (e2 * c2 + e3 * c3)
            q0[m] += (e0 * a0 + e1 * a1) + (e2 * a2 + e3 * a3)
            q1[m] += (e0 * b0 + e1 * b1) + (e2 * b2 + e3 * b3)
            q2[m] += (e0 * z0 + e1 * z1) + (e2 * z2 + e3 * z3)
    else:
        for t in range(n_dims + 1):
            acc = p1 if t == 0 else pxt[t - 1, a:b]
            c0, c1, c2, c3 = coef[t, 0], coef[t, 1], coef[t, 2], coef[t, 3]
            for m in range(n_moving):
                e0, e1, e2, e3 = np.float64(r0[m]), np.float64(r1[m]), np.float64(r2[m]), np.float64(r3[m])
                acc[m] += (e0 * c0 + e1 * c1) + (e2 * c2 + e3 * c3)


@njit(nogil=True, cache=True)
def grid_keys(points, origin, cell, dims):
    """Linear cell index of each point in a grid of cubes of side ``cell`` starting at ``origin``."""
    n_points, n_dims = points.shape
    keys = np.empty(n_points, dtype=np.int64)
    for i in range(n_points):
        key = 0
        for d in range(n_dims):
            c = int((points[i, d] - origin[d]) / cell)
            c = min(max(c, 0), dims[d] - 1)
            key = key * dims[d] + c
        keys[i] = key
    return keys


@njit(nogil=True, cache=True)
def bucket_points(points, origin, cell, dims):
    """Points sorted by cell key by a stable counting sort: ``(order, sorted points,
    starts)``, ``starts[k]:starts[k + 1]`` the positions of cell ``k``'s points."""
    n_points, n_dims = points.shape
    keys = grid_keys(points, origin, cell, dims)
    n_cells = 1
    for d in range(n_dims):
        n_cells *= dims[d]
    starts = np.zeros(n_cells + 1, dtype=np.int64)
    for key in keys:
        starts[key + 1] += 1
    for k in range(n_cells):
        starts[k + 1] += starts[k]
    fill = starts[:-1].copy()
    order = np.empty(n_points, dtype=np.int64)
    for i in range(n_points):
        order[fill[keys[i]]] = i
        fill[keys[i]] += 1
    sorted_points = np.empty((n_points, n_dims))
    for j in range(n_points):
        for d in range(n_dims):
            sorted_points[j, d] = points[order[j], d]
    return order, sorted_points, starts


@njit(nogil=True, cache=True, inline="always")
def _scan_cells(q, points, order, a, b, best):
    """Closest of ``points[a:b]`` to ``q`` into ``best`` = (squared distance, original
    index, sorted position), ties to the smaller original index."""
    for j in range(a, b):
        d2 = 0.0
        for d in range(q.shape[0]):
            diff = q[d] - points[j, d]
            d2 += diff * diff
        if d2 < best[0] or (d2 == best[0] and order[j] < best[1]):
            best[0] = d2
            best[1] = order[j]


@njit(nogil=True, cache=True)
def grid_nearest(queries, points, order, starts, origin, cell, dims, lo, hi, d2_out, index_out):
    """Squared distance from each query ``lo <= n < hi`` to its nearest point, and that
    point's original index (the smaller one on ties), by rings of cells around the query's
    cell (clipped to the grid) until no unvisited cell can hold a closer point.

    ``points``, ``order`` and ``starts`` are :func:`bucket_points`' (sorted by cell key, the
    last dimension fastest). A ring is left when the squared
    distance found is at most the least squared distance from the query to any cell outside
    the box searched so far: for each axis and side with cells beyond the box, the gap to
    the box's face along that axis plus, on every other axis, the query's distance outside
    the grid's span (so a query far outside the grid stops after a ring or two).
    """
    n_dims = queries.shape[1]
    last = n_dims - 1
    stride = np.ones(n_dims, dtype=np.int64)
    for d in range(n_dims - 2, -1, -1):
        stride[d] = stride[d + 1] * dims[d + 1]
    c = np.empty(n_dims, dtype=np.int64)
    lo_c = np.empty(n_dims, dtype=np.int64)
    hi_c = np.empty(n_dims, dtype=np.int64)
    cur = np.empty(n_dims, dtype=np.int64)
    out = np.empty(n_dims)
    best = np.empty(2)
    for n in range(lo, hi):
        q = queries[n]
        outside2 = 0.0
        for d in range(n_dims):
            c[d] = min(max(int(np.floor((q[d] - origin[d]) / cell)), 0), dims[d] - 1)
            below = origin[d] - q[d]
            above = q[d] - (origin[d] + dims[d] * cell)
            out[d] = max(below, above, 0.0)
            outside2 += out[d] * out[d]
        best[0] = np.inf
        best[1] = np.inf
        k = 0
        while True:
            for d in range(n_dims):
                lo_c[d] = max(c[d] - k, 0)
                hi_c[d] = min(c[d] + k, dims[d] - 1)
                cur[d] = lo_c[d]
            while True:
                # one row of cells along the last axis: whole when it lies on the ring,
                # else only its two ends (the cells at distance k along the last axis)
                base = 0
                on_ring = k == 0
                for d in range(last):
                    base += cur[d] * stride[d]
                    if abs(cur[d] - c[d]) == k:
                        on_ring = True
                if on_ring:
                    _scan_cells(q, points, order, starts[base + lo_c[last]], starts[base + hi_c[last] + 1], best)
                else:
                    if c[last] - k >= 0:
                        key = base + c[last] - k
                        _scan_cells(q, points, order, starts[key], starts[key + 1], best)
                    if c[last] + k < dims[last]:
                        key = base + c[last] + k
                        _scan_cells(q, points, order, starts[key], starts[key + 1], best)
                if not _advance(cur, lo_c, hi_c, last - 1):
                    break
            bound = np.inf
            beyond = False
            for d in range(n_dims):
                rest = outside2 - out[d] * out[d]
                if lo_c[d] > 0:
                    beyond = True
                    gap = max(q[d] - (origin[d] + lo_c[d] * cell), 0.0)
                    bound = min(bound, gap * gap + rest)
                if hi_c[d] < dims[d] - 1:
                    beyond = True
                    gap = max(origin[d] + (hi_c[d] + 1) * cell - q[d], 0.0)
                    bound = min(bound, gap * gap + rest)
            # (the margin covers the rounding of a point's cell against the face, and keeps
            # exact ties for the ring that decides them; once the box holds the whole grid
            # every point has been seen, also when the squared distances overflow to inf)
            if not beyond or best[0] < bound * (1.0 - 1e-12):
                break
            k += 1
        d2_out[n] = best[0]
        index_out[n] = np.int64(best[1])


@njit(nogil=True, cache=True)
def truncated_scores(
    x,
    y_sorted,
    keys_sorted,
    origin,
    cell,
    dims,
    lo,
    hi,
    d2_min,
    extra,
    inv2s2,
    log_c,
    log_weight,
    v_moving,
    v_fixed,
    prior_scale,
    inv2phi2,
    index,
    value,
    row_ptr,
    ref,
    best,
):
    """Scores of the moving points within ``d_min^2 + extra`` of each fixed point.

    Processes rows from ``lo`` while the buffers have room for a whole row; returns the
    first row not processed. ``index``/``value`` hold the sorted-order index of each kept
    moving point and ``s - ref``; ``row_ptr[i]`` is where row ``lo + i`` starts.
    """
    n_dims = x.shape[1]
    capacity = index.shape[0]
    has_prior = log_weight.shape[0] > 0
    lo_c = np.empty(n_dims, dtype=np.int64)
    hi_c = np.empty(n_dims, dtype=np.int64)
    cur = np.empty(n_dims, dtype=np.int64)
    used = 0
    row_ptr[0] = 0
    n = lo
    while n < hi:
        r2 = d2_min[n] + extra
        span = _reach_box(x[n], np.sqrt(r2), origin, cell, dims, lo_c, hi_c, cur)
        start = used
        smax = -np.inf
        arg = -1
        if span > 0:
            # iterate over the cells of the box, the last dimension innermost and contiguous
            everything = _scan_everything(lo_c, hi_c, y_sorted.shape[0])
            while True:
                if everything:
                    a, b = 0, y_sorted.shape[0]
                else:
                    a, b = _row_range(keys_sorted, cur, lo_c, hi_c, dims)
                if used + (b - a) > capacity:
                    if start == 0:
                        # a single row larger than the buffer cannot happen: capacity >= M
                        return -1
                    row_ptr[n - lo] = start
                    return n
                vn = v_fixed[n] if has_prior else 0.0
                for j in range(a, b):
                    d2 = 0.0
                    for d in range(n_dims):
                        diff = x[n, d] - y_sorted[j, d]
                        d2 += diff * diff
                    if d2 <= r2:
                        s = -d2 * inv2s2
                        if has_prior:
                            dv = vn - v_moving[j]
                            s += prior_scale * (log_weight[j] - dv * dv * inv2phi2)
                        index[used] = j
                        value[used] = s
                        used += 1
                        if s > smax:
                            smax = s
                            arg = j
                if everything or not _advance(cur, lo_c, hi_c, n_dims - 2):
                    break
        r = max(smax, log_c)
        if r == -np.inf:
            r = 0.0
        kept = value[start:used]  # (a slice from 0: see _sum)
        for k in range(kept.shape[0]):
            kept[k] = max(kept[k] - r, _FLOOR)
        ref[n - lo] = r
        best[n] = arg if (arg >= 0 and smax >= log_c) else -1
        row_ptr[n - lo + 1] = used
        n += 1
    return n


@njit(nogil=True, cache=True)
def sparse_accumulate(index, e, row_ptr, x, lo, hi, ref, log_c, p1, pxt, pt1, log_den):
    """Steps 2 and 3 of :func:`dense_rows` for the rows kept by :func:`truncated_scores`;
    ``e`` holds ``s - ref`` and is overwritten by its exponential."""
    n_dims = pxt.shape[0]
    for i in range(hi - lo):
        n = lo + i
        a = row_ptr[i]
        b = row_ptr[i + 1]
        _exp_shifted(e, a, b, 0.0)
        total = _sum(e, a, b)
        c_term = np.exp(log_c - ref[i])
        den = total + c_term
        if den <= 0.0:  # no moving point in reach and no outlier term (cannot happen: d_min is in reach)
            log_den[n] = -np.inf
            pt1[n] = 0.0
            continue
        inv = 1.0 / den
        log_den[n] = ref[i] + np.log(den)
        pt1[n] = total * inv
        for k in range(a, b):
            p = e[k] * inv
            if p < _SKIP * inv:
                continue
            j = index[k]
            p1[j] += p
            for d in range(n_dims):
                pxt[d, j] += p * x[n, d]


@njit(nogil=True, cache=True)
def count_candidates(x, rows, keys_sorted, origin, cell, dims, d2_min, extra):
    """Number of moving points the truncated path would visit for each of ``rows``."""
    n_dims = x.shape[1]
    out = np.zeros(rows.shape[0], dtype=np.int64)
    lo_c = np.empty(n_dims, dtype=np.int64)
    hi_c = np.empty(n_dims, dtype=np.int64)
    cur = np.empty(n_dims, dtype=np.int64)
    for i in range(rows.shape[0]):
        n = rows[i]
        if _reach_box(x[n], np.sqrt(d2_min[n] + extra), origin, cell, dims, lo_c, hi_c, cur) == 0:
            continue
        if _scan_everything(lo_c, hi_c, keys_sorted.shape[0]):
            out[i] = keys_sorted.shape[0]
            continue
        total = 0
        while True:
            a, b = _row_range(keys_sorted, cur, lo_c, hi_c, dims)
            total += b - a
            if not _advance(cur, lo_c, hi_c, n_dims - 2):
                break
        out[i] = total
    return out


# ---------------------------------------------------------------------------------------------
# Fast Gauss transform (Hermite expansions about source boxes, evaluated directly at targets)
#
#   G(t)_r = sum_j q_jr exp(-|t - s_j|^2 / h^2)
#          = sum_boxes sum_alpha A_alpha,r h_alpha((t - c_B) / h),
#   A_alpha,r = sum_{j in B} q_jr ((s_j - c_B) / h)^alpha / alpha!,
#   h_a(v) = H_a(v) exp(-v^2) (physicists' Hermite H), per dimension; the identity is the
#   generating function exp(2uv - u^2) = sum_a H_a(v) u^a / a!.
# Boxes are cubes of side h (|u_d| <= 1/2); a target sums the boxes within ``reach`` box
# widths in every dimension. The multi-index alpha runs over [0, p)^D, flattened with the
# last dimension fastest.


@njit(nogil=True, cache=True, inline="always")
def _tensor(per_dim, prod):
    """``prod`` = the flattened outer product of the rows of ``per_dim`` (D x p), last fastest."""
    n_dims, p = per_dim.shape
    size = 1
    prod[0] = 1.0
    for d in range(n_dims):
        # expand in place from the back so that earlier entries are read before overwritten
        for k in range(size - 1, -1, -1):
            base = prod[k]
            for a in range(p - 1, -1, -1):
                prod[k * p + a] = base * per_dim[d, a]
        size *= p


@njit(nogil=True, cache=True, inline="always")
def _box_at(box_keys, cur, dims):
    """Index in the sorted ``box_keys`` of the box at cell ``cur``, or -1 if that box is empty."""
    key = 0
    for d in range(cur.shape[0]):
        key = key * dims[d] + cur[d]
    b = np.searchsorted(box_keys, key)
    return b if b < box_keys.shape[0] and box_keys[b] == key else -1


_FAST = {"reassoc", "contract"}  # reassociated dot products vectorise; no other IEEE liberty


@njit(nogil=True, cache=True, fastmath=_FAST)
def fgt_coefficients(src, weights, box_of, centers, inv_h, p, coeffs):
    """Add each source's monomials into its box: ``coeffs[box, r, alpha]``."""
    n_src, n_dims = src.shape
    n_rhs = weights.shape[1]
    mono = np.empty((n_dims, p))
    n_terms = p**n_dims
    prod = np.empty(n_terms)
    for j in range(n_src):
        b = box_of[j]
        for d in range(n_dims):
            u = (src[j, d] - centers[b, d]) * inv_h
            mono[d, 0] = 1.0
            for a in range(1, p):
                mono[d, a] = mono[d, a - 1] * u / a
        _tensor(mono, prod)
        for r in range(n_rhs):
            wr = weights[j, r]
            cbr = coeffs[b, r]
            for k in range(n_terms):
                cbr[k] += wr * prod[k]


@njit(nogil=True, cache=True, fastmath=_FAST)
def fgt_evaluate(targets, lo, hi, box_keys, centers, coeffs, origin, side, dims, inv_h, p, reach, out):
    """``out[t, r] = sum_boxes sum_alpha coeffs[box, r, alpha] h_alpha((t - c_box) / h)`` for rows lo..hi."""
    n_dims = targets.shape[1]
    n_rhs = coeffs.shape[1]
    n_terms = p**n_dims
    herm = np.empty((n_dims, p))
    prod = np.empty(n_terms)
    lo_c = np.empty(n_dims, dtype=np.int64)
    hi_c = np.empty(n_dims, dtype=np.int64)
    cur = np.empty(n_dims, dtype=np.int64)
    acc = np.empty(n_rhs)
    for t in range(lo, hi):
        for r in range(n_rhs):
            acc[r] = 0.0
        span = 1
        for d in range(n_dims):
            c = int(np.floor((targets[t, d] - origin[d]) / side))
            lo_c[d] = max(c - reach, 0)
            hi_c[d] = min(c + reach, dims[d] - 1)
            span *= max(hi_c[d] - lo_c[d] + 1, 0)
        if span > 0:
            for d in range(n_dims):
                cur[d] = lo_c[d]
            while True:
                b = _box_at(box_keys, cur, dims)
                if b >= 0:
                    for d in range(n_dims):
                        v = (targets[t, d] - centers[b, d]) * inv_h
                        g = np.exp(-v * v)
                        herm[d, 0] = g
                        if p > 1:
                            herm[d, 1] = 2.0 * v * g
                        for a in range(1, p - 1):
                            herm[d, a + 1] = 2.0 * v * herm[d, a] - 2.0 * a * herm[d, a - 1]
                    _tensor(herm, prod)
                    for r in range(n_rhs):
                        cbr = coeffs[b, r]
                        total = 0.0
                        for k in range(n_terms):
                            total += cbr[k] * prod[k]
                        acc[r] += total
                if not _advance(cur, lo_c, hi_c, n_dims - 1):
                    break
        for r in range(n_rhs):
            out[t, r] = acc[r]


@njit(nogil=True, cache=True)
def hermite_translation_matrices(reach, p):
    """``T[o, b, a] = (-1)^b / b! h_(a+b)(o - reach)``: Hermite -> Taylor for a box offset o - reach.

    With boxes of side h on one grid, a source box and a target box are a whole number of
    box widths apart in each dimension, so these (2 reach + 1) matrices serve every pair.
    """
    out = np.empty((2 * reach + 1, p, p))
    herm = np.empty(2 * p)
    for o in range(2 * reach + 1):
        w = float(o - reach)
        g = np.exp(-w * w)
        herm[0] = g
        herm[1] = 2.0 * w * g
        for a in range(1, 2 * p - 1):
            herm[a + 1] = 2.0 * w * herm[a] - 2.0 * a * herm[a - 1]
        fact = 1.0
        for b in range(p):
            if b > 0:
                fact *= b
            sign = -1.0 if b % 2 else 1.0
            for a in range(p):
                out[o, b, a] = sign / fact * herm[a + b]
    return out


@njit(nogil=True, cache=True, fastmath=_FAST)
def _mode_product(tensor, matrix, axis, n_dims, p, out):
    """``out`` = ``tensor`` (flattened p^D) multiplied along ``axis`` by ``matrix`` (p x p)."""
    inner = p ** (n_dims - 1 - axis)
    outer = p**axis
    for o in range(outer):
        for i in range(inner):
            base = o * p * inner + i
            for b in range(p):
                total = 0.0
                for a in range(p):
                    total += matrix[b, a] * tensor[base + a * inner]
                out[base + b * inner] = total


@njit(nogil=True, cache=True, fastmath=_FAST)
def fgt_translate_evaluate(
    targets,
    t_start,
    t_order,
    t_coords,
    s_box_keys,
    s_coords,
    coeffs,
    origin,
    side,
    dims,
    inv_h,
    p,
    reach,
    trans,
    lo,
    hi,
    out,
):
    """For target boxes lo..hi: sum the source boxes' Hermite series as one Taylor series about
    the box centre (separable translation, D p^(D+1) per pair), then evaluate it at each target."""
    n_dims = targets.shape[1]
    n_rhs = coeffs.shape[1]
    n_terms = p**n_dims
    local = np.empty((n_rhs, n_terms))
    buf_a = np.empty(n_terms)
    buf_b = np.empty(n_terms)
    mono = np.empty((n_dims, p))
    prod = np.empty(n_terms)
    cur = np.empty(n_dims, dtype=np.int64)
    lo_c = np.empty(n_dims, dtype=np.int64)
    hi_c = np.empty(n_dims, dtype=np.int64)
    for c in range(lo, hi):
        local[:, :] = 0.0
        for d in range(n_dims):
            lo_c[d] = max(t_coords[c, d] - reach, 0)
            hi_c[d] = min(t_coords[c, d] + reach, dims[d] - 1)
            cur[d] = lo_c[d]
        while True:
            b = _box_at(s_box_keys, cur, dims)
            if b >= 0:
                for r in range(n_rhs):
                    src = coeffs[b, r]
                    for k in range(n_terms):
                        buf_a[k] = src[k]
                    for d in range(n_dims):
                        # offset of the target centre from the source centre, in box widths
                        o = t_coords[c, d] - s_coords[b, d] + reach
                        _mode_product(buf_a, trans[o], d, n_dims, p, buf_b)
                        for k in range(n_terms):
                            buf_a[k] = buf_b[k]
                    for k in range(n_terms):
                        local[r, k] += buf_a[k]
            if not _advance(cur, lo_c, hi_c, n_dims - 1):
                break
        for j in range(t_start[c], t_start[c + 1]):
            t = t_order[j]
            for d in range(n_dims):
                v = (targets[t, d] - (origin[d] + (t_coords[c, d] + 0.5) * side)) * inv_h
                mono[d, 0] = 1.0
                for a in range(1, p):
                    mono[d, a] = mono[d, a - 1] * v
            _tensor(mono, prod)
            for r in range(n_rhs):
                total = 0.0
                for k in range(n_terms):
                    total += local[r, k] * prod[k]
                out[t, r] = total


@njit(nogil=True, cache=True, fastmath=_CONTRACT)
def batch_posteriors(moving_t, fixed, sigma2, log_c, lo, hi, p1, pt1, pxt, nll):
    """CPD's E-step statistics for poses ``lo:hi`` of K poses of one moving set (the global pose search).

    ``moving_t`` (K, D, M) holds the K transformed moving sets, transposed; ``sigma2`` and
    ``log_c`` (K,) each pose's variance and log outlier constant. Fills, for those poses,
    ``p1`` (K, M), ``pt1`` (K, N), ``pxt`` (K, D, M) (``(P X)^T``) and ``nll`` (K,):
    ``-sum_n log(sum_m exp(s_mn) + c) + N D / 2 log sigma2`` with
    ``s_mn = -|x_n - y_m|^2 / (2 sigma2)``. Each row is shifted by ``max(max_m s_mn, log c)``
    before the exponentials (log space, as :func:`dense_rows`), and the squared distances
    are summed from coordinate differences (no ``|x|^2 + |y|^2 - 2 x.y`` cancellation). Each
    pose is computed alone, serially in a fixed order.
    """
    n_dims, n_moving = moving_t.shape[1], moving_t.shape[2]
    n_fixed = fixed.shape[0]
    row = np.empty(n_moving)
    for k in range(lo, hi):
        yt = moving_t[k]
        inv2s2 = 0.5 / sigma2[k]
        lc = log_c[k]
        p1[k, :] = 0.0
        pxt[k, :, :] = 0.0
        total = 0.0
        for n in range(n_fixed):
            for m in range(n_moving):
                row[m] = 0.0
            for d in range(n_dims):
                xd = fixed[n, d]
                for m in range(n_moving):
                    t = yt[d, m] - xd
                    row[m] += t * t
            for m in range(n_moving):
                row[m] *= -inv2s2
            top = max(lc, _max(row, n_moving))  # (the search's subsets have >= 3 points)
            for m in range(n_moving):
                row[m] = fast_exp(max(row[m] - top, _FLOOR))
            den = _sum(row, 0, n_moving) + fast_exp(max(lc - top, _FLOOR))
            inv_den = 1.0 / den
            for m in range(n_moving):
                row[m] *= inv_den
            pt1[k, n] = _sum(row, 0, n_moving)
            for m in range(n_moving):
                p1[k, m] += row[m]
            for d in range(n_dims):
                xd = fixed[n, d]
                for m in range(n_moving):
                    pxt[k, d, m] += row[m] * xd
            total += np.log(den) + top
        nll[k] = -total + 0.5 * n_fixed * n_dims * np.log(sigma2[k])

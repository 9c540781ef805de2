"""Compiled pieces of the CPD/GPD E-step (numba, serial, GIL-free).

Every path splits the work in the same three steps, so that the exponential is taken by
numpy's vectorised ``exp`` (about 25x faster here than a scalar ``exp`` in a compiled
loop) on a block that stays in cache:

1. a ``*_scores`` kernel writes ``s_mn - ref_n`` for a block of fixed points ``n``, where
   ``s_mn = -|x_n - T(y_m)|^2 / (2 sigma2) + prior_mn`` and ``ref_n = max(max_m s_mn, log c)``,
   so every value is <= 0 and the largest term of each row is exp(0) = 1;
2. ``numpy.exp`` in place;
3. an ``*_accumulate`` kernel normalises each row by ``sum_m exp(.) + c exp(-ref_n)`` and adds
   the row into the sufficient statistics ``P1``, ``P X``, ``P^T 1`` and ``log den``.

The dense path visits every pair; the truncated path visits, for each fixed point, only
the moving points within ``sqrt(d_min^2 + 2 sigma2 tau')`` of it (a uniform grid of cells,
searched by sorted cell keys), which drops only terms below ``exp(-tau)`` of the row's
largest one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "dense_scores",
    "dense_accumulate",
    "grid_keys",
    "truncated_scores",
    "sparse_accumulate",
    "count_candidates",
]

# Terms more than this far below a row's largest one are below exp(-50) ~ 2e-22 of it and
# are skipped when accumulating (they change no sum at double precision).
_SKIP = np.exp(-50.0)


@njit(nogil=True, cache=True)
def dense_scores(x, yt, lo, hi, inv2s2, log_c, log_weight, v_moving, v_fixed, prior_scale, inv2phi2, out, ref, best):
    """Fill ``out[i, m] = s_(m, lo+i) - ref[i]`` for rows ``lo <= n < hi``; ``best`` = argmax_m."""
    n_dims, n_moving = yt.shape
    has_prior = log_weight.shape[0] > 0
    for i in range(hi - lo):
        n = lo + i
        row = out[i]
        for m in range(n_moving):
            row[m] = 0.0
        for d in range(n_dims):
            xd = x[n, d]
            yd = yt[d]
            for m in range(n_moving):
                diff = xd - yd[m]
                row[m] -= diff * diff
        if has_prior:
            vn = v_fixed[n]
            for m in range(n_moving):
                dv = vn - v_moving[m]
                row[m] = row[m] * inv2s2 + prior_scale * (log_weight[m] - dv * dv * inv2phi2)
        else:
            for m in range(n_moving):
                row[m] *= inv2s2
        smax = -np.inf
        arg = 0
        for m in range(n_moving):
            if row[m] > smax:
                smax = row[m]
                arg = m
        r = max(smax, log_c)
        for m in range(n_moving):
            row[m] -= r
        ref[i] = r
        best[n] = arg if smax >= log_c else -1


@njit(nogil=True, cache=True)
def dense_accumulate(e, x, lo, hi, ref, log_c, p1, pxt, pt1, log_den):
    """Normalise rows of ``e = exp(s - ref)`` and add them into the statistics (``pxt`` is D x M)."""
    n_dims, n_moving = pxt.shape
    for i in range(hi - lo):
        n = lo + i
        row = e[i]
        total = 0.0
        for m in range(n_moving):
            total += row[m]
        c_term = np.exp(log_c - ref[i])
        den = total + c_term
        inv = 1.0 / den
        log_den[n] = ref[i] + np.log(den)
        pt1[n] = total * inv
        for m in range(n_moving):
            p1[m] += row[m] * inv
        for d in range(n_dims):
            xd = x[n, d] * inv
            acc = pxt[d]
            for m in range(n_moving):
                acc[m] += row[m] * xd


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
def _cell_of(point, origin, cell, dims, coords):
    for d in range(point.shape[0]):
        c = int(np.floor((point[d] - origin[d]) / cell))
        coords[d] = c


@njit(nogil=True, cache=True)
def truncated_scores(
    x, y_sorted, keys_sorted, origin, cell, dims, lo, hi, d2_min, extra, inv2s2, log_c,
    log_weight, v_moving, v_fixed, prior_scale, inv2phi2, index, value, row_ptr, ref, best,
):
    """Scores of the moving points within ``d_min^2 + extra`` of each fixed point.

    Processes rows from ``lo`` while the buffers have room for a whole row; returns the
    first row not processed. ``index``/``value`` hold the sorted-order index of each kept
    moving point and ``s - ref``; ``row_ptr[i]`` is where row ``lo + i`` starts.
    """
    n_dims = x.shape[1]
    capacity = index.shape[0]
    has_prior = log_weight.shape[0] > 0
    coords = np.empty(n_dims, dtype=np.int64)
    lo_c = np.empty(n_dims, dtype=np.int64)
    hi_c = np.empty(n_dims, dtype=np.int64)
    cur = np.empty(n_dims, dtype=np.int64)
    used = 0
    row_ptr[0] = 0
    n = lo
    while n < hi:
        r2 = d2_min[n] + extra
        reach = np.sqrt(r2)
        span = 1
        for d in range(n_dims):
            a = int(np.floor((x[n, d] - reach - origin[d]) / cell))
            b = int(np.floor((x[n, d] + reach - origin[d]) / cell))
            lo_c[d] = max(a, 0)
            hi_c[d] = min(b, dims[d] - 1)
            span *= max(hi_c[d] - lo_c[d] + 1, 0)
        start = used
        smax = -np.inf
        arg = -1
        if span > 0:
            for d in range(n_dims):
                cur[d] = lo_c[d]
            # iterate over the cells of the box, the last dimension innermost and contiguous
            while True:
                key_lo = 0
                key_hi = 0
                for d in range(n_dims):
                    key_lo = key_lo * dims[d] + (cur[d] if d < n_dims - 1 else lo_c[d])
                    key_hi = key_hi * dims[d] + (cur[d] if d < n_dims - 1 else hi_c[d])
                a = np.searchsorted(keys_sorted, key_lo, side="left")
                b = np.searchsorted(keys_sorted, key_hi, side="right")
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
                # next cell box (odometer over all but the last dimension)
                d = n_dims - 2
                while d >= 0:
                    cur[d] += 1
                    if cur[d] <= hi_c[d]:
                        break
                    cur[d] = lo_c[d]
                    d -= 1
                if d < 0:
                    break
        r = max(smax, log_c)
        if r == -np.inf:
            r = 0.0
        for k in range(start, used):
            value[k] -= r
        ref[n - lo] = r
        best[n] = arg if (arg >= 0 and smax >= log_c) else -1
        row_ptr[n - lo + 1] = used
        n += 1
    return n


@njit(nogil=True, cache=True)
def sparse_accumulate(index, e, row_ptr, x, lo, hi, ref, log_c, p1, pxt, pt1, log_den):
    """:func:`dense_accumulate` for the rows kept by :func:`truncated_scores`."""
    n_dims = pxt.shape[0]
    for i in range(hi - lo):
        n = lo + i
        a = row_ptr[i]
        b = row_ptr[i + 1]
        total = 0.0
        for k in range(a, b):
            total += e[k]
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
def count_candidates(x, rows, keys_sorted, origin, cell, dims, d2_min, extra, y_sorted):
    """Number of moving points the truncated path would visit for each of ``rows``."""
    n_dims = x.shape[1]
    out = np.zeros(rows.shape[0], dtype=np.int64)
    lo_c = np.empty(n_dims, dtype=np.int64)
    hi_c = np.empty(n_dims, dtype=np.int64)
    cur = np.empty(n_dims, dtype=np.int64)
    for i in range(rows.shape[0]):
        n = rows[i]
        reach = np.sqrt(d2_min[n] + extra)
        span = 1
        for d in range(n_dims):
            lo_c[d] = max(int(np.floor((x[n, d] - reach - origin[d]) / cell)), 0)
            hi_c[d] = min(int(np.floor((x[n, d] + reach - origin[d]) / cell)), dims[d] - 1)
            span *= max(hi_c[d] - lo_c[d] + 1, 0)
        if span == 0:
            continue
        for d in range(n_dims):
            cur[d] = lo_c[d]
        total = 0
        while True:
            key_lo = 0
            key_hi = 0
            for d in range(n_dims):
                key_lo = key_lo * dims[d] + (cur[d] if d < n_dims - 1 else lo_c[d])
                key_hi = key_hi * dims[d] + (cur[d] if d < n_dims - 1 else hi_c[d])
            total += np.searchsorted(keys_sorted, key_hi, side="right") - np.searchsorted(keys_sorted, key_lo, side="left")
            d = n_dims - 2
            while d >= 0:
                cur[d] += 1
                if cur[d] <= hi_c[d]:
                    break
                cur[d] = lo_c[d]
                d -= 1
            if d < 0:
                break
        out[i] = total
    return out

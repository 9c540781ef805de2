"""Compiled kernels (numba) for the sampling approximations and eccentricity bounds.

Random choices come from a counter-based generator (SplitMix64 of the seed, the sample's
index and a step number), so that a sample's outcome does not depend on which thread
draws it or in which chunk: results are identical for any thread count.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import _neighbour, _span

__all__ = ["sample_paths", "uniform"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_RESCALE = 1e200
_BLOCKED = 1 << 30  # grid mode: the distance of background pixels, never a search level


@njit(cache=True, nogil=True, inline="always")
def _mix(z):
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(cache=True, nogil=True, inline="always")
def uniform(seed, sample, step):
    """A uniform float in [0, 1) determined by ``(seed, sample, step)`` alone."""
    z = _mix(np.uint64(seed) + _GOLDEN * np.uint64(sample + 1))
    z = _mix(z + _GOLDEN * np.uint64(step + 1))
    return (z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@njit(cache=True, nogil=True)
def _expand(indptr, indices, offs, grid, frontier, n_front, dist, sigma, other, nxt, visited, n_visited):
    """One breadth-first level of one side; returns (n_next, n_visited, met)."""
    level = dist[frontier[0]] + 1
    n_next = 0
    met = False
    for a in range(n_front):
        v = frontier[a]
        sv = sigma[v]
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            dw = dist[w]
            if dw < 0:
                dist[w] = level
                sigma[w] = sv
                nxt[n_next] = w
                n_next += 1
                visited[n_visited] = w
                n_visited += 1
                if other[w] >= 0:
                    met = True
            elif dw == level:
                sigma[w] += sv
    # Counts of one level share one scale: rescaling them all keeps every ratio.
    top = 0.0
    for a in range(n_next):
        top = max(top, sigma[nxt[a]])
    if top > _RESCALE:
        for a in range(n_next):
            sigma[nxt[a]] /= top
    return n_next, n_visited, met


@njit(cache=True, nogil=True)
def _walk(indptr, indices, offs, grid, start, dist, sigma, seed, sample, step, hits, path_len):
    """Walk from ``start`` down to distance 0, each step to a predecessor drawn with
    probability proportional to its path count; counts the inner nodes in ``hits``."""
    v = start
    while dist[v] > 1:
        total = 0.0
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            if dist[w] == dist[v] - 1:
                total += sigma[w]
        r = uniform(seed, sample, step) * total
        step += 1
        pick = -1
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            if dist[w] == dist[v] - 1:
                pick = w
                r -= sigma[w]
                if r < 0.0:
                    break
        v = pick
        hits[v] += 1
        path_len += 1
    return step, path_len


@njit(cache=True, nogil=True, inline="always")
def _lower_bound(here, step, there, reach):
    """Hops from the pixel at coordinates ``here + step`` to the one at ``there`` on the
    unobstructed grid whose steps move at most one in each axis and at most ``reach`` axes
    at once: max(L-inf, ceil(L1 / reach)). One step changes it by at most one, so it is a
    consistent lower bound on the masked grid."""
    far = 0
    total = 0
    for a in range(here.shape[0]):
        d = abs(here[a] + step[a] - there[a])
        far = max(far, d)
        total += d
    return max(far, (total + reach - 1) // reach)


@njit(cache=True, nogil=True, inline="always")
def _unravel(v, dims, out):
    for a in range(dims.shape[0] - 1, -1, -1):
        out[a] = v % dims[a]
        v //= dims[a]


@njit(cache=True, nogil=True)
def _pruned_bfs(offs, steps, dims, reach, marks, use_marks, s, t, budget, dist, sigma, visited):
    """Breadth-first search from ``s`` over the pixels ``w`` with
    ``hops(s, w) + lower_bound(w, t) <= budget``; returns (reached t, n_visited, the
    smallest ``hops + lower_bound`` of a pixel left out).

    When ``budget`` is at least the distance of ``t``, every shortest ``s``-``t`` path lies
    in that set with its true hop and path counts (each node of such a path has
    ``hops + lower_bound <= distance``; a pixel whose hop count in the set exceeds its true
    one cannot precede a node of such a path), and the search stops on discovering ``t``:
    the path counts of every level before it are then complete. On an open region the set
    is the parallelogram of shortest paths, not the ball of radius ``budget``.
    """
    here = np.empty(dims.shape[0], dtype=np.int64)
    there = np.empty(dims.shape[0], dtype=np.int64)
    _unravel(t, dims, there)
    flat = dims.shape[0] == 2
    width = dims[-1]
    vr = vc = 0
    toward = np.empty(marks.shape[1], dtype=np.int64)
    for k in range(marks.shape[1]):
        toward[k] = marks[t, k]
    dist[s] = 0
    sigma[s] = 1.0
    visited[0] = s
    n_visited = 1
    start = 0  # the frontier is visited[start:stop], the level before the one found
    level = 0
    left_out = np.int64(1) << 62
    while start < n_visited:
        level += 1
        stop = n_visited
        for a in range(start, stop):
            v = visited[a]
            sv = sigma[v]
            if flat:
                vr = v // width
                vc = v - vr * width
            else:
                _unravel(v, dims, here)
            for j in range(offs.shape[0]):
                w = v + offs[j]
                dw = dist[w]
                if dw < 0:
                    if flat:  # 2D, unrolled: L-inf for 8 neighbours, L1 for 4
                        dr = abs(vr + steps[j, 0] - there[0])
                        dc = abs(vc + steps[j, 1] - there[1])
                        f = level + (max(dr, dc) if reach == 2 else dr + dc)
                    else:
                        f = level + _lower_bound(here, steps[j], there, reach)
                    if use_marks and f <= budget:
                        for k in range(toward.shape[0]):
                            f = max(f, level + abs(np.int64(marks[w, k]) - toward[k]))
                    if f <= budget:
                        dist[w] = level
                        sigma[w] = sv
                        visited[n_visited] = w
                        n_visited += 1
                        if w == t:
                            # Every predecessor of t is on the level before: complete.
                            return True, n_visited, left_out
                    else:
                        left_out = min(left_out, f)
                elif dw == level:
                    sigma[w] += sv
        top = 0.0
        for a in range(stop, n_visited):
            top = max(top, sigma[visited[a]])
        if top > _RESCALE:
            for a in range(stop, n_visited):
                sigma[visited[a]] /= top
        start = stop
    return False, n_visited, left_out


@njit(cache=True, nogil=True)
def landmark_hops(foreground, offs, count, start):
    """Hop counts from ``count`` landmarks chosen farthest-first on the padded raster, as
    ``(pixel, landmark)`` int32; 0 where a landmark does not reach. The first landmark is
    the pixel farthest from ``start``; each next one is farthest from those before (in the
    component of ``start``)."""
    size = foreground.shape[0]
    marks = np.zeros((size, count), dtype=np.int32)
    hops = np.full(size, -1, dtype=np.int64)
    order = np.empty(size, dtype=np.int64)
    nearest = np.full(size, np.int64(1) << 62)
    source = start
    for k in range(-1, count):
        for i in range(size):
            hops[i] = -1 if foreground[i] else -2
        hops[source] = 0
        order[0] = source
        head = 0
        tail = 1
        while head < tail:
            v = order[head]
            head += 1
            for j in range(offs.shape[0]):
                w = v + offs[j]
                if hops[w] == -1:
                    hops[w] = hops[v] + 1
                    order[tail] = w
                    tail += 1
        far = source
        for q in range(tail):
            v = order[q]
            if k >= 0:
                marks[v, k] = hops[v]
                nearest[v] = min(nearest[v], hops[v])
                if nearest[v] > nearest[far]:
                    far = v
            elif hops[v] > hops[far]:
                far = v
        source = far
    return marks


def new_scratch(n, foreground, grid):
    """Work arrays of one thread for :func:`sample_paths`, at rest: ``(dist_s, dist_t,
    sig_s, sig_t, front_s, front_t, nxt, visited, hits)``.

    They are allocated by NumPy, which asks the kernel for huge pages on large arrays (the
    searches jump between raster rows; 15-20 % faster on a megapixel mask than arrays
    allocated inside the compiled code). Distances are -1 (unseen) or, for background
    pixels, a level no search reaches; :func:`sample_paths` returns them to that state.
    """
    dist = np.full(n, -1, dtype=np.int32)
    if grid:
        dist[~foreground] = _BLOCKED
    index = np.empty(n, dtype=np.int64)
    return (
        dist,
        dist.copy(),
        np.zeros(n),
        np.zeros(n),
        index,
        index.copy(),
        index.copy(),
        np.empty(2 * n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
    )


@njit(cache=True, nogil=True)
def _open_pair(s, t, width, height, foreground, transposed, seed, sample, cells, starts, temp, hits):
    """Draw a shortest ``s``-``t`` path of the 8-neighbour 2D grid by counting, when one
    as short as on the unobstructed grid exists; returns the number of cells counted,
    negated when there is none (nothing drawn: the caller searches).

    With ``|dc| >= |dr|`` (else rows and columns trade places) every path of the
    unobstructed length ``X = |dc|`` advances one column per step, and after ``i`` steps
    lies ``max(-i, dr - (X - i)) .. min(i, dr + (X - i))`` rows from the source: a band of
    column segments. The paths of that length in the mask are those that stay on its
    pixels in the band, so their counts follow column by column, each the sum of the (at
    most) three counts beside it in the column before, or 0 on background: no hop counts,
    queue or neighbour tests, and the column reads ``transposed`` (the raster stored
    column by column) contiguously. If t's count is 0, no path has that length.
    """
    sr = s // width
    sc = s - sr * width
    tr = t // width
    dr = tr - sr
    dc = t - tr * width - sc
    by_column = abs(dc) >= abs(dr)
    if by_column:
        steps, minor, sign, start, major, extent, stride, line = abs(dc), dr, 1, sr, sc, height, height, transposed
        if dc < 0:
            sign = -1
    else:
        steps, minor, sign, start, major, extent, stride, line = abs(dr), dc, 1, sc, sr, width, width, foreground
        if dr < 0:
            sign = -1
    # starts[2 i]: where column i's counts begin in ``cells``; starts[2 i + 1]: its first row
    # Column i's counts are stored as ``0, 0, counts of its rows live_lo .. live_hi, 0, 0``
    # from ``starts[2 i]`` (``starts[2 i + 1] = live_lo``): the zeros let every sum of three
    # read without bounds, so the loop over a column has no branch.
    if cells.shape[0] < 5:
        return -1
    cells[0:5] = 0.0
    cells[2] = 1.0
    starts[0] = 0
    starts[1] = 0
    prev_lo = 0
    prev_hi = 0
    used = 5
    for i in range(1, steps + 1):
        # the band's segment, within the raster and one row of the last column's paths
        lo = max(-i, minor - (steps - i), -start, prev_lo - 1)
        hi = min(i, minor + (steps - i), extent - 1 - start, prev_hi + 1)
        if lo > hi or used + hi - lo + 5 > cells.shape[0]:
            return -used
        # the column's sums into ``temp`` (no branch per row), then its rows with paths kept
        first = starts[2 * i - 2] + 2 - prev_lo + lo  # cells[first + k]: last column's row lo + k
        pixel = (major + sign * i) * stride + start + lo
        n_rows = hi - lo + 1
        for k in range(n_rows):
            temp[k] = (cells[first + k - 1] + cells[first + k] + cells[first + k + 1]) * line[pixel + k]
        head = 0
        while head < n_rows and temp[head] == 0.0:
            head += 1
        if head == n_rows:
            return -(used + n_rows)
        tail = n_rows - 1
        while temp[tail] == 0.0:
            tail -= 1
        top = 0.0
        for k in range(head, tail + 1):
            top = max(top, temp[k])
        scale = 1.0 / top if top > _RESCALE else 1.0
        out = used + 2 - head
        for k in range(head, tail + 1):  # rows live_lo .. live_hi
            cells[out + k] = temp[k] * scale
        live_lo = lo + head
        live_hi = lo + tail
        end = used + 2 + live_hi - live_lo + 1
        cells[used] = 0.0
        cells[used + 1] = 0.0
        cells[end] = 0.0
        cells[end + 1] = 0.0
        starts[2 * i] = used
        starts[2 * i + 1] = live_lo
        used = end + 2
        prev_lo = live_lo
        prev_hi = live_hi
    # Back from t, each step to one of the (at most) three counts before it, in proportion.
    y = minor
    step = 0
    for i in range(steps - 1, 0, -1):
        column = starts[2 * i] + 2 - starts[2 * i + 1]  # cells[column + row]; zeros around
        total = cells[column + y - 1] + cells[column + y] + cells[column + y + 1]
        r = uniform(seed, sample, step) * total
        step += 1
        pick = y + 1
        for z in range(y - 1, y + 2):
            if cells[column + z] > 0.0:
                pick = z
                r -= cells[column + z]
                if r < 0.0:
                    break
        y = pick
        if by_column:
            hits[(sr + y) * width + sc + sign * i] += 1
        else:
            hits[(sr + sign * i) * width + sc + y] += 1
    return used


@njit(cache=True, nogil=True)
def _open_pair_4(s, t, width, foreground, seed, sample, cells, scales, hits):
    """:func:`_open_pair` for the 4-neighbour 2D grid: the paths of the unobstructed
    length ``|dr| + |dc|`` are the monotone staircases inside the box of ``s`` and ``t``, so
    their counts follow row by row (each the count above plus the count before it, or 0 on
    background). A row's counts share one scale, kept as a logarithm in ``scales``, so two
    counts of different rows compare exactly in ratio. Returns the cells counted, negated
    when t's count is 0 (nothing drawn)."""
    sr = s // width
    sc = s - sr * width
    tr = t // width
    dr = tr - sr
    dc = t - tr * width - sc
    rows = abs(dr) + 1
    cols = abs(dc) + 1
    vr = 1 if dr > 0 else -1
    vc = 1 if dc > 0 else -1
    for i in range(rows):
        pixel = (sr + vr * i) * width + sc
        scales[i] = scales[i - 1] if i > 0 else 0.0
        top = 0.0
        for j in range(cols):
            total = 0.0
            if foreground[pixel + vc * j]:
                if i == 0 and j == 0:
                    total = 1.0
                else:
                    if i > 0:
                        total = cells[(i - 1) * cols + j]
                    if j > 0:
                        total += cells[i * cols + j - 1]
            cells[i * cols + j] = total
            top = max(top, total)
        if top == 0.0:
            return -(i + 1) * cols
        if top > _RESCALE:
            for j in range(cols):
                cells[i * cols + j] /= top
            scales[i] += np.log(top)
    if cells[rows * cols - 1] == 0.0:
        return -rows * cols
    # Back from t: up or left, in proportion to the counts (the row above rescaled to this one's).
    i = rows - 1
    j = cols - 1
    step = 0
    while i + j > 1:
        up = cells[(i - 1) * cols + j] * np.exp(scales[i - 1] - scales[i]) if i > 0 else 0.0
        left = cells[i * cols + j - 1] if j > 0 else 0.0
        if uniform(seed, sample, step) * (up + left) < up:
            i -= 1
        else:
            j -= 1
        step += 1
        hits[(sr + vr * i) * width + sc + vc * j] += 1
    return rows * cols


@njit(cache=True, nogil=True)
def _open_pair_26(s, t, dims, foreground, seed, sample, cells, starts, hits):
    """:func:`_open_pair` for the 26-neighbour 3D grid: paths of the unobstructed length
    advance one slice per step along the axis of the largest offset, inside a box of
    rectangles (each other axis as in 2D), and a count is the sum of the (at most) nine
    counts beside it in the slice before, or 0 on background. ``starts`` holds five numbers
    per slice: where its counts begin and its rectangle's first rows and extents."""
    here = np.empty(3, dtype=np.int64)
    gap = np.empty(3, dtype=np.int64)
    _unravel(s, dims, here)
    _unravel(t, dims, gap)
    gap -= here
    strides = np.array([dims[1] * dims[2], dims[2], 1], dtype=np.int64)
    major = 0
    for k in range(1, 3):
        if abs(gap[k]) > abs(gap[major]):
            major = k
    b = 1 if major == 0 else 0
    c = 2 if major != 2 else 1
    steps = abs(gap[major])
    sign = 1 if gap[major] > 0 else -1
    if 5 * (steps + 1) > starts.shape[0]:
        return -1
    cells[0] = 1.0
    starts[0] = 0
    starts[1] = 0
    starts[2] = 0
    starts[3] = 1
    starts[4] = 1
    live = (0, 0, 0, 0)  # the previous slice's rows with paths, along b and along c
    used = 1
    for i in range(1, steps + 1):
        lo_b = max(-i, gap[b] - (steps - i), -here[b], live[0] - 1)
        hi_b = min(i, gap[b] + (steps - i), dims[b] - 1 - here[b], live[1] + 1)
        lo_c = max(-i, gap[c] - (steps - i), -here[c], live[2] - 1)
        hi_c = min(i, gap[c] + (steps - i), dims[c] - 1 - here[c], live[3] + 1)
        if lo_b > hi_b or lo_c > hi_c:
            return -used
        n_b = hi_b - lo_b + 1
        n_c = hi_c - lo_c + 1
        prev = 5 * (i - 1)
        p_at, p_lo_b, p_lo_c, p_n_b, p_n_c = (
            starts[prev],
            starts[prev + 1],
            starts[prev + 2],
            starts[prev + 3],
            starts[prev + 4],
        )
        at = 5 * i
        starts[at] = used
        starts[at + 1] = lo_b
        starts[at + 2] = lo_c
        starts[at + 3] = n_b
        starts[at + 4] = n_c
        base = (here[major] + sign * i) * strides[major] + here[b] * strides[b] + here[c] * strides[c]
        top = 0.0
        new_live = (hi_b + 1, lo_b - 1, hi_c + 1, lo_c - 1)
        for y in range(lo_b, hi_b + 1):
            for z in range(lo_c, hi_c + 1):
                total = 0.0
                if foreground[base + y * strides[b] + z * strides[c]]:
                    for yy in range(max(y - 1, p_lo_b), min(y + 1, p_lo_b + p_n_b - 1) + 1):
                        for zz in range(max(z - 1, p_lo_c), min(z + 1, p_lo_c + p_n_c - 1) + 1):
                            total += cells[p_at + (yy - p_lo_b) * p_n_c + zz - p_lo_c]
                cells[used + (y - lo_b) * n_c + z - lo_c] = total
                if total > 0.0:
                    top = max(top, total)
                    new_live = (min(new_live[0], y), max(new_live[1], y), min(new_live[2], z), max(new_live[3], z))
        if top == 0.0:
            return -(used + n_b * n_c)
        if top > _RESCALE:
            for q in range(n_b * n_c):
                cells[used + q] /= top
        used += n_b * n_c
        live = new_live
    # Back from t, each step to one of the (at most) nine counts before it, in proportion.
    y = gap[b]
    z = gap[c]
    step = 0
    for i in range(steps - 1, 0, -1):
        at = 5 * i
        p_at, lo_b, lo_c, n_b, n_c = starts[at], starts[at + 1], starts[at + 2], starts[at + 3], starts[at + 4]
        total = 0.0
        for yy in range(max(y - 1, lo_b), min(y + 1, lo_b + n_b - 1) + 1):
            for zz in range(max(z - 1, lo_c), min(z + 1, lo_c + n_c - 1) + 1):
                total += cells[p_at + (yy - lo_b) * n_c + zz - lo_c]
        r = uniform(seed, sample, step) * total
        step += 1
        pick_y = -1
        pick_z = -1
        for yy in range(max(y - 1, lo_b), min(y + 1, lo_b + n_b - 1) + 1):
            for zz in range(max(z - 1, lo_c), min(z + 1, lo_c + n_c - 1) + 1):
                value = cells[p_at + (yy - lo_b) * n_c + zz - lo_c]
                if value > 0.0 and r >= 0.0:
                    pick_y = yy
                    pick_z = zz
                    r -= value
        y = pick_y
        z = pick_z
        hits[(here[major] + sign * i) * strides[major] + (here[b] + y) * strides[b] + (here[c] + z) * strides[c]] += 1
    return used


@njit(cache=True, nogil=True)
def sample_paths(
    indptr,
    indices,
    t_indptr,
    t_indices,
    pairs,
    seed,
    first,
    stop,
    offs,
    steps,
    shape,
    reach,
    marks,
    labels,
    rasters,
    scratch,
):
    """Riondato-Kornaropoulos samples ``first .. stop - 1``: for each pair ``(s, t)`` a
    shortest path drawn uniformly at random; adds to ``hits`` (in ``scratch``, see
    :func:`new_scratch`) how often each node was an inner node of a drawn path, and returns
    the number of nodes the searches visited and the number of pruned searches run again.

    ``t_indptr, t_indices`` is the transposed adjacency (the same arrays when undirected).
    A pair is searched by a balanced bidirectional breadth-first search, except in grid
    mode (``offs`` not empty: nodes are the pixels of a padded raster of ``shape`` whose
    background is never reached, undirected), where :func:`_pruned_bfs` visits only pixels
    that can lie on a shortest path, bounded by the open grid (``steps``, ``reach``) and by
    the landmark hop counts ``marks`` (no landmarks: zero columns); ``reach = 0`` turns
    the pruning off. Pairs whose ``labels`` (connected components; may be empty) differ are
    not searched. ``rasters``: the padded raster's foreground row by row and (2D) column by
    column, or two empty arrays; with them (2D grids and 26-neighbour 3D grids) a pair whose
    distance is the unobstructed one has its paths counted directly (:func:`_open_pair`,
    :func:`_open_pair_4`, :func:`_open_pair_26`), without a search.
    """
    grid = offs.shape[0] > 0
    dist_s, dist_t, sig_s, sig_t, front_s, front_t, nxt, visited, hits = scratch
    work = 0
    retries = 0
    dims = shape
    here = np.empty(dims.shape[0], dtype=np.int64)
    there = np.empty(dims.shape[0], dtype=np.int64)
    no_step = np.zeros(dims.shape[0], dtype=np.int64)
    foreground, transposed = rasters
    counting = grid and transposed.shape[0] > 0 and (dims.shape[0] == 2 or offs.shape[0] == 26)
    four = offs.shape[0] == 4
    cube = offs.shape[0] == 26
    direct = 0
    for i in range(first, stop):
        s = pairs[i, 0]
        t = pairs[i, 1]
        if labels.shape[0] > 0 and labels[s] != labels[t]:
            continue  # no path: no inner node
        if counting and s != t:
            # counts in sig_t, positions in front_t, a column in sig_s: work arrays of the
            # bidirectional search, which grid pairs do not use (raster-sized: the counted
            # cells are distinct pixels; the 8- and 26-neighbour counters check the rest)
            if cube:
                cells = _open_pair_26(s, t, dims, foreground, seed, i, sig_t, front_t, hits)
            elif four:
                cells = _open_pair_4(s, t, dims[1], foreground, seed, i, sig_t, sig_s, hits)
            else:
                cells = _open_pair(s, t, dims[1], dims[0], foreground, transposed, seed, i, sig_t, front_t, sig_s, hits)
            work += abs(cells)
            if cells > 0:
                direct += 1
                continue
        if grid and reach > 0 and s != t:
            # The region of shortest paths alone: first with t as near as the open grid
            # allows, then with the slack at least doubled (and at least the smallest
            # bound left out), until t is reached.
            _unravel(s, dims, here)
            _unravel(t, dims, there)
            nearest = _lower_bound(here, no_step, there, reach)
            open_grid = nearest
            for k in range(marks.shape[1]):
                nearest = max(nearest, abs(np.int64(marks[s, k]) - np.int64(marks[t, k])))
            budget = nearest
            use_marks = nearest > open_grid
            while True:
                found, n_visited, left_out = _pruned_bfs(
                    offs, steps, dims, reach, marks, use_marks, s, t, budget, dist_s, sig_s, visited
                )
                work += n_visited
                if found:
                    _walk(t_indptr, t_indices, offs, grid, t, dist_s, sig_s, seed, i, 0, hits, 0)
                for q in range(n_visited):
                    dist_s[visited[q]] = -1
                if found or left_out >= np.int64(1) << 62:
                    break
                retries += 1
                use_marks = marks.shape[1] > 0
                budget = max(left_out, nearest + 2 * (budget - nearest) + 1)
            continue
        dist_s[s] = 0
        sig_s[s] = 1.0
        dist_t[t] = 0
        sig_t[t] = 1.0
        visited[0] = s
        visited[1] = t
        n_visited = 2
        front_s[0] = s
        front_t[0] = t
        ns = 1
        nt = 1
        met = s == t
        meet_side = 0
        while not met and ns > 0 and nt > 0:
            # Expand the side whose frontier has fewer arcs to scan.
            cost_s = ns  # the grid: every pixel has the same offsets to scan
            cost_t = nt
            if not grid:
                cost_s = 0
                for a in range(ns):
                    cost_s += indptr[front_s[a] + 1] - indptr[front_s[a]]
                cost_t = 0
                for a in range(nt):
                    cost_t += t_indptr[front_t[a] + 1] - t_indptr[front_t[a]]
            if cost_s <= cost_t:
                ns, n_visited, met = _expand(
                    indptr, indices, offs, grid, front_s, ns, dist_s, sig_s, dist_t, nxt, visited, n_visited
                )
                front_s[:ns] = nxt[:ns]
                meet_side = 0
            else:
                nt, n_visited, met = _expand(
                    t_indptr, t_indices, offs, grid, front_t, nt, dist_t, sig_t, dist_s, nxt, visited, n_visited
                )
                front_t[:nt] = nxt[:nt]
                meet_side = 1
        work += n_visited
        if met and s != t:
            # The meeting nodes lie on the frontier just expanded; pick one with
            # probability proportional to sigma_s * sigma_t (paths through it).
            front = front_s if meet_side == 0 else front_t
            nf = ns if meet_side == 0 else nt
            total = 0.0
            for a in range(nf):
                w = front[a]
                if dist_s[w] >= 0 and dist_t[w] >= 0:
                    total += sig_s[w] * sig_t[w]
            r = uniform(seed, i, 0) * total
            pick = -1
            for a in range(nf):
                w = front[a]
                if dist_s[w] >= 0 and dist_t[w] >= 0:
                    pick = w
                    r -= sig_s[w] * sig_t[w]
                    if r < 0.0:
                        break
            if pick != s and pick != t:
                hits[pick] += 1
            # Towards s over in-arcs of the forward search, towards t over out-arcs.
            step, _ = _walk(t_indptr, t_indices, offs, grid, pick, dist_s, sig_s, seed, i, 1, hits, 0)
            _walk(indptr, indices, offs, grid, pick, dist_t, sig_t, seed, i, step, hits, 0)
        for q in range(n_visited):
            v = visited[q]
            dist_s[v] = -1
            dist_t[v] = -1
    return work, retries, direct

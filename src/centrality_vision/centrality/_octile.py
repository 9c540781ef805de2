"""Exact distances by edge length on 8-neighbour pixel graphs, most of them in closed form.

On the open grid, with steps of length ``L_x`` along a row, ``L_y`` along a column and
``L_d`` diagonally, ``max(L_x, L_y) <= L_d <= L_x + L_y`` (the Euclidean lengths of any
pixel spacing; 1, 1 and sqrt 2 for square pixels), the distance from ``s`` to a pixel
``q`` that lies ``dx >= dy >= 0`` columns and rows away is ``(dx - dy) L_x + dy L_d``
(the other octants alike): a diagonal step is no longer than the two axis steps it
replaces, so a shortest path takes all ``dy`` it can, and a path of that length is one
made of exactly ``dx - dy`` row steps and ``dy`` diagonal steps of the octant ``q`` lies
in, in any order. Call ``q`` *visible* from ``s`` when such a path stays in the mask: its
distance in the pixel graph is then this octile distance, and no search is needed to
find it.

**Visible pixels, 64 rows at a time.** The mask is stored as one bit per pixel, each
column a run of machine words. In the octant of the axis step east and the diagonal
step north-east, the pixels of column ``x + 1`` reached by those steps are those of
column ``x`` and the same shifted one row north, kept where the mask is set: three word
operations per 64 rows. In the octant of the steps north and north-east, a column's
reached pixels are the previous column's shifted north, then filled northward along
runs of the mask: with ``M`` the column's mask, ``S`` the seeds and ``R`` the first
pixel of each run of ``M``, the sum ``(M & ~S) + R`` carries from each run's start up
to its first seed and leaves the rest of the run standing, so ``((M & ~S) + R | S) & M``
is the fill (the carry crossing word boundaries like a long addition). The four
southern octants are the northern ones of the mask flipped upside down. Each of the
eight rays between octants is counted by exactly one of them, so every visible pixel
is counted once. Per column, the sum of the distances of the visible pixels follows
from the count and the sum of the row numbers (bit populations of six masks), the
largest from the highest set bit; the sum of inverse distances, when wanted, is one
difference of two prefix sums per run of set bits (a table per octant kind, summed once
per mask in extended precision).

**The rest by Dijkstra, seeded from the visible region.** A shortest path to a pixel
that is not visible leaves the visible region for the last time at a visible pixel,
whose distance is its octile distance, and then stays among the invisible pixels. So
Dijkstra's search runs on the invisible pixels only, its queue seeded with each
invisible pixel next to the visible region at its best distance through a visible
neighbour. Distances are kept as counts of the three steps and read as
``(a_x L_x + a_y L_y) + b L_d`` (one axis count for square pixels), so equal lengths tie
exactly. The seeds are sorted once; every later candidate comes from a settled pixel,
whose distance never decreases, so one first-in-first-out queue per step kind stays
sorted, and the next pixel is the least of the queue heads. A convex mask has no
invisible pixel at all: its searches cost a few word operations per 64 pixels.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from ._grid import open_distances

__all__ = ["OctileGrid", "octile_stats", "takes"]

_U0 = np.uint64(0)
_U1 = np.uint64(1)
_U63 = np.uint64(63)
# _POS[k]: the bits whose position has bit k set; sum over k of 2^k popcount(x & _POS[k])
# is the sum of the positions of the set bits of x
_POS = np.array(
    [
        0xAAAAAAAAAAAAAAAA,
        0xCCCCCCCCCCCCCCCC,
        0xF0F0F0F0F0F0F0F0,
        0xFF00FF00FF00FF00,
        0xFFFF0000FFFF0000,
        0xFFFFFFFF00000000,
    ],
    dtype=np.uint64,
)
_SETTLED = -2.0  # a settled pixel's distance d is stored as _SETTLED - d
_BLOCKED = -3.0  # a visible pixel next to the invisible region: never relaxed


@intrinsic
def _popcount(typingctx, x):
    """Set bits of a uint64 (one instruction)."""
    sig = types.int64(types.uint64)

    def codegen(context, builder, signature, args):
        return builder.ctpop(args[0])

    return sig, codegen


@intrinsic
def _lowest_bit(typingctx, x):
    """Position of the lowest set bit of a nonzero uint64."""
    sig = types.int64(types.uint64)

    def codegen(context, builder, signature, args):
        return builder.cttz(args[0], ir.Constant(ir.IntType(1), 1))

    return sig, codegen


@intrinsic
def _highest_bit(typingctx, x):
    """Position of the highest set bit of a nonzero uint64."""
    sig = types.int64(types.uint64)

    def codegen(context, builder, signature, args):
        lead = builder.ctlz(args[0], ir.Constant(ir.IntType(1), 1))
        return builder.sub(ir.Constant(ir.IntType(64), 63), lead)

    return sig, codegen


@intrinsic
def _reverse(typingctx, x):
    """The 64 bits of a uint64 in reverse order."""
    sig = types.uint64(types.uint64)

    def codegen(context, builder, signature, args):
        return builder.bitreverse(args[0])

    return sig, codegen


@njit(cache=True, nogil=True, inline="always")
def _position_sum(x):
    """Sum of the positions of the set bits of a uint64 (see ``_POS``)."""
    total = 0
    for k in range(6):
        total += _popcount(x & _POS[k]) << k
    return total


@njit(cache=True, nogil=True, inline="always")
def _fill_north(column, R, lo, hi):
    """Fill the seeds ``R[lo:hi]`` northward along the runs of ``column`` (in place);
    returns the new ``hi`` (words from it are zero)."""
    n_words = column.shape[0]
    carry = _U0
    below = _U0  # top bit of the mask's previous word: a run may continue across words
    new_hi = lo
    for w in range(lo, n_words):
        seeds = R[w]
        m = column[w]
        starts = m & ~((m << _U1) | below)
        below = m >> _U63
        rest = m & ~seeds
        t = rest + starts
        c1 = t < rest
        t2 = t + carry
        c2 = t2 < t
        carry = _U1 if (c1 or c2) else _U0
        filled = (t2 | seeds) & m
        R[w] = filled
        if filled != _U0:
            new_hi = w + 1
        elif w >= hi:  # past every seed, and no run carried on: the rest stays empty
            break
    return new_hi


@njit(cache=True, nogil=True)
def _octant(M, V, R, y0, x0, step, vertical, own_axis, own_diag, len_axis, len_d, need_inverse, inverse_of):
    """Pixels visible from ``(y0, x0)`` in one northern octant of the bit mask ``M``
    (columns of words): east (``step = 1``) or west, of the axis and diagonal steps
    (``vertical = False``) or of the north and diagonal steps. They are or-ed into ``V``.

    Returns ``(sum of axis counts a, sum of diagonal counts b, pixels, largest distance,
    sum of inverse distances)`` over the octant without the source, the axis ray counted
    when ``own_axis``, the diagonal ray when ``own_diag``.
    """
    n_words = M.shape[1]
    for w in range(n_words):
        R[w] = _U0
    lo = y0 >> 6
    hi = lo + 1
    R[lo] = _U1 << np.uint64(y0 & 63)
    sum_a = 0
    sum_b = 0
    count = 0
    largest = 0.0
    inverse = 0.0
    x = x0
    k = 0
    if vertical:
        hi = _fill_north(M[x0], R, lo, hi)
    while True:
        if k > 0:
            # the diagonal step (and, east or west, the axis step) into column x
            x += step
            hi = min(hi + 1, n_words)
            carry = _U0
            for w in range(lo, hi):
                r = R[w]
                if vertical:
                    R[w] = ((r << _U1) | carry) & M[x, w]
                else:
                    R[w] = (r | (r << _U1) | carry) & M[x, w]
                carry = r >> _U63
            if vertical:
                hi = _fill_north(M[x], R, lo, hi)
            while lo < hi and R[lo] == _U0:
                lo += 1
            if lo == hi:
                break
            while R[hi - 1] == _U0:
                hi -= 1
        for w in range(lo, hi):
            V[x, w] |= R[w]
        # the bits not counted here: the source, and a ray another octant owns
        skip1 = -1
        skip2 = -1
        if k == 0:
            skip1 = y0
            if not (vertical and own_axis):
                k += 1
                continue
        elif vertical:
            if not own_diag:
                skip1 = y0 + k
        else:
            if not own_axis:
                skip1 = y0
            if not own_diag:
                skip2 = y0 + k
        n = 0
        rows = 0
        for w in range(lo, hi):
            r = R[w]
            if skip1 >> 6 == w:
                r &= ~(_U1 << np.uint64(skip1 & 63))
            if skip2 >> 6 == w:
                r &= ~(_U1 << np.uint64(skip2 & 63))
            c = _popcount(r)
            n += c
            rows += c * (w << 6) + _position_sum(r)
            if need_inverse and inverse_of.shape[0] > 0:
                row = inverse_of[k]
                while r != _U0:  # run by run of set bits, from the table's prefix sums
                    start = _lowest_bit(r)
                    rest = ~(r >> np.uint64(start))
                    length = 64 - start if rest == _U0 else _lowest_bit(rest)
                    dy = (w << 6) + start - y0
                    inverse += row[dy + length] - row[dy]
                    if start + length == 64:
                        break
                    r &= ~(((_U1 << np.uint64(length)) - _U1) << np.uint64(start))
            elif need_inverse:
                while r != _U0:
                    dy = (w << 6) + _lowest_bit(r) - y0
                    if vertical:
                        inverse += 1.0 / ((dy - k) * len_axis + k * len_d)
                    else:
                        inverse += 1.0 / ((k - dy) * len_axis + dy * len_d)
                    r &= r - _U1
        if n > 0:
            dys = rows - n * y0
            if vertical:
                sum_a += dys - n * k
                sum_b += n * k
            else:
                sum_a += n * k - dys
                sum_b += dys
            top = ((hi - 1) << 6) + _highest_bit(R[hi - 1]) - y0
            far = (top - k) * len_axis + k * len_d if vertical else (k - top) * len_axis + top * len_d
            if far > largest:
                largest = far
            count += n
        k += 1
    return sum_a, sum_b, count, largest, inverse


@njit(cache=True, nogil=True, inline="always")
def _or_3x3(A, x, w, n_words):
    """Word ``w`` of column ``x`` of the 3 x 3 dilation of the bit mask ``A``."""
    d = A[x - 1, w] | A[x, w] | A[x + 1, w]
    out = d | (d << _U1) | (d >> _U1)
    if w > 0:
        out |= (A[x - 1, w - 1] | A[x, w - 1] | A[x + 1, w - 1]) >> _U63
    if w + 1 < n_words:
        out |= (A[x - 1, w + 1] | A[x, w + 1] | A[x + 1, w + 1]) << _U63
    return out


@njit(cache=True, nogil=True)
def octile_stats(
    north, south, labels, sizes, foreground, offs, steps, lengths, sources, need_inverse, inverse_across, inverse_up
):
    """See :func:`_octile_stats`; compiled apart for square pixels (one axis count), where
    the branches for three lengths fold away."""
    if lengths[0] == lengths[1]:
        return _octile_stats(
            north, south, labels, sizes, foreground, offs, steps, lengths, sources, need_inverse,
            inverse_across, inverse_up, True,
        )  # fmt: skip
    return _octile_stats(
        north, south, labels, sizes, foreground, offs, steps, lengths, sources, need_inverse,
        inverse_across, inverse_up, False,
    )  # fmt: skip


@njit(cache=True, nogil=True, inline="always")
def _octile_stats(
    north, south, labels, sizes, foreground, offs, steps, lengths, sources, need_inverse,
    inverse_across, inverse_up, square,
):  # fmt: skip
    """Sum of distances, of inverse distances (when ``need_inverse``, else 0), largest
    distance and pixels reached from each of ``sources`` (raster indices of the padded
    mask, ``width`` = ``north.shape[0]`` columns), by edge length.

    ``north``: the padded mask as bits, ``north[x, y >> 6]`` bit ``y & 63``; ``south`` the
    same upside down (row ``y`` at ``64 * words - 1 - y``). ``labels``/``sizes``: connected
    component of each raster pixel and pixels per component. ``offs``/``steps``: raster
    offsets and ``(dy, dx)`` of the 8 neighbours; ``lengths``: the steps along a row
    (``dx``), along a column (``dy``) and diagonal, ``L_diag >= max(L_x, L_y)`` and
    ``L_diag <= L_x + L_y``. ``inverse_across[k, d]`` / ``inverse_up[k, d]``: the sum of the
    inverse distances of the pixels less than ``d`` rows up in column ``k`` of an octant of
    row and diagonal steps / of column and diagonal steps
    (:meth:`OctileGrid.inverse_tables`); empty to divide pixel by pixel.

    A distance is kept as its step counts ``(a_x, a_y, b)``, 21 bits each in one int64
    (:class:`OctileGrid` sends larger masks elsewhere), and read as
    ``(a_x L_x + a_y L_y) + b L_diag``; with ``square`` (``L_x == L_y``) the two axis counts
    are one (``a_y = 0``), so equal lengths tie exactly.
    """
    width, n_words = north.shape
    size = foreground.shape[0]
    len_x = lengths[0]
    len_y = lengths[1]
    len_d = lengths[2]
    visible_n = np.zeros((width, n_words), dtype=np.uint64)
    visible_s = np.zeros((width, n_words), dtype=np.uint64)
    visible = np.zeros((width, n_words), dtype=np.uint64)
    hidden = np.zeros((width, n_words), dtype=np.uint64)
    has_hidden = np.zeros(width, dtype=np.bool_)
    R = np.zeros(n_words, dtype=np.uint64)
    dist, n_pixels = open_distances(foreground)
    counts = np.zeros(size, dtype=np.int64)  # (a_x << 42) | (a_y << 21) | b
    queue0 = np.empty(n_pixels, dtype=np.int64)  # reached by a step along a row (and a column if square)
    queue2 = np.empty(n_pixels, dtype=np.int64)  # by a step along a column (not square)
    queue1 = np.empty(n_pixels, dtype=np.int64)  # by a diagonal step
    seeds = np.empty(n_pixels, dtype=np.int64)
    seed_value = np.empty(n_pixels)
    order = np.empty(n_pixels, dtype=np.int64)
    blocked = np.empty(n_pixels, dtype=np.int64)
    n_offs = offs.shape[0]
    row_offs = np.empty(2, dtype=np.int64)
    column_offs = np.empty(2, dtype=np.int64)
    diagonal_offs = np.empty(4, dtype=np.int64)
    n_row = n_column = n_diagonal = 0
    for j in range(n_offs):
        if steps[j, 0] == 0:
            row_offs[n_row] = offs[j]
            n_row += 1
        elif steps[j, 1] == 0:
            column_offs[n_column] = offs[j]
            n_column += 1
        else:
            diagonal_offs[n_diagonal] = offs[j]
            n_diagonal += 1
    one_x = np.int64(1) << 42
    one_y = one_x if square else np.int64(1) << 21
    field = (np.int64(1) << 21) - 1
    flip = 64 * n_words - 1
    k = sources.shape[0]
    total = np.zeros(k)
    inverse = np.zeros(k)
    largest = np.zeros(k)
    reached = np.zeros(k, dtype=np.int64)
    for i in range(k):
        s = sources[i]
        y0 = s // width
        x0 = s - y0 * width
        visible_n[:] = _U0
        visible_s[:] = _U0
        sum_x = 0
        sum_y = 0
        sum_b = 0
        seen = 1
        far = 0.0
        h = 0.0
        for o in range(8):
            east = o % 4 == 0 or o % 4 == 1
            vertical = o % 4 == 1 or o % 4 == 2
            if o < 4:  # north: E-NE owns E, NE-N owns NE, N-NW owns N, NW-W owns NW
                part = _octant(
                    north, visible_n, R, y0, x0, 1 if east else -1, vertical,
                    o % 2 == 0, o % 2 == 1, len_y if vertical else len_x, len_d, need_inverse,
                    inverse_up if vertical else inverse_across,
                )  # fmt: skip
            else:  # south, upside down: W-SW owns W, SW-S owns SW, S-SE owns S, SE-E owns SE
                part = _octant(
                    south, visible_s, R, flip - y0, x0, -1 if east else 1, vertical,
                    o % 2 == 0, o % 2 == 1, len_y if vertical else len_x, len_d, need_inverse,
                    inverse_up if vertical else inverse_across,
                )  # fmt: skip
            if vertical and not square:
                sum_y += part[0]
            else:
                sum_x += part[0]
            sum_b += part[1]
            seen += part[2]
            if part[3] > far:
                far = part[3]
            h += part[4]
        t = (sum_x * len_x + sum_y * len_y) + sum_b * len_d
        count = 0
        n_blocked = 0
        if seen < sizes[labels[s]]:
            # the invisible pixels, the seeds among them and the visible pixels beside them
            for x in range(width):
                any_hidden = _U0
                for w in range(n_words):
                    v = visible_n[x, w] | _reverse(visible_s[x, n_words - 1 - w])
                    visible[x, w] = v
                    hidden[x, w] = north[x, w] & ~v
                    any_hidden |= hidden[x, w]
                has_hidden[x] = any_hidden != _U0
            n_seeds = 0
            for x in range(1, width - 1):
                if not (has_hidden[x - 1] or has_hidden[x] or has_hidden[x + 1]):
                    continue
                for w in range(n_words):
                    edge = visible[x, w] & _or_3x3(hidden, x, w, n_words)
                    while edge != _U0:
                        y = (w << 6) + _lowest_bit(edge)
                        q = y * width + x
                        dist[q] = _BLOCKED
                        blocked[n_blocked] = q
                        n_blocked += 1
                        edge &= edge - _U1
                    front = hidden[x, w] & _or_3x3(visible, x, w, n_words)
                    while front != _U0:
                        y = (w << 6) + _lowest_bit(front)
                        front &= front - _U1
                        best = np.inf
                        best_counts = 0
                        for j in range(n_offs):
                            yn = y + steps[j, 0]
                            xn = x + steps[j, 1]
                            if (visible[xn, yn >> 6] >> np.uint64(yn & 63)) & _U1:
                                # the octile counts of the visible neighbour, plus the step
                                ady = abs(yn - y0)
                                adx = abs(xn - x0)
                                b = min(ady, adx)
                                ax = adx - b
                                ay = ady - b
                                if square:
                                    ax += ay
                                    ay = 0
                                if steps[j, 0] != 0 and steps[j, 1] != 0:
                                    b += 1
                                elif steps[j, 0] == 0 or square:
                                    ax += 1
                                else:
                                    ay += 1
                                value = (ax * len_x + ay * len_y) + b * len_d
                                if value < best:
                                    best = value
                                    best_counts = (np.int64(ax) << 42) | (np.int64(ay) << 21) | b
                        q = y * width + x
                        dist[q] = best
                        counts[q] = best_counts
                        seeds[n_seeds] = q
                        seed_value[n_seeds] = best
                        n_seeds += 1
            by_value = np.argsort(seed_value[:n_seeds])
            for j in range(n_seeds):
                queue0[j] = seeds[by_value[j]]
            for j in range(n_seeds):
                seeds[j] = queue0[j]
            # heads cached: a head's value is at least its pixel's distance, and equal to
            # it unless the pixel was improved since, which pushed it again elsewhere
            head_s = head0 = tail0 = head1 = tail1 = head2 = tail2 = 0
            ds = dist[seeds[0]] if n_seeds > 0 else np.inf
            d0 = d1 = d2 = np.inf
            while True:
                if ds <= d0 and ds <= d1 and ds <= d2:
                    if ds == np.inf:
                        break
                    v = seeds[head_s]
                    head_s += 1
                    ds = dist[seeds[head_s]] if head_s < n_seeds else np.inf
                elif d0 <= d1 and d0 <= d2:
                    v = queue0[head0]
                    head0 += 1
                    d0 = dist[queue0[head0]] if head0 < tail0 else np.inf
                elif d1 <= d2:
                    v = queue1[head1]
                    head1 += 1
                    d1 = dist[queue1[head1]] if head1 < tail1 else np.inf
                else:
                    v = queue2[head2]
                    head2 += 1
                    d2 = dist[queue2[head2]] if head2 < tail2 else np.inf
                dv = dist[v]
                if dv < 0.0:  # settled from another queue
                    continue
                dist[v] = _SETTLED - dv
                order[count] = v
                count += 1
                t += dv
                if need_inverse:
                    h += 1.0 / dv
                if dv > far:
                    far = dv
                cv = counts[v]
                ax = cv >> 42
                ay = (cv >> 21) & field
                b = cv & field
                via = ((ax + 1) * len_x + ay * len_y) + b * len_d
                for j in range(2):
                    w = v + row_offs[j]
                    if via < dist[w]:
                        dist[w] = via
                        counts[w] = cv + one_x
                        if head0 == tail0:
                            d0 = via
                        queue0[tail0] = w
                        tail0 += 1
                if square:
                    for j in range(2):
                        w = v + column_offs[j]
                        if via < dist[w]:
                            dist[w] = via
                            counts[w] = cv + one_x
                            if head0 == tail0:
                                d0 = via
                            queue0[tail0] = w
                            tail0 += 1
                else:
                    via = (ax * len_x + (ay + 1) * len_y) + b * len_d
                    for j in range(2):
                        w = v + column_offs[j]
                        if via < dist[w]:
                            dist[w] = via
                            counts[w] = cv + one_y
                            if head2 == tail2:
                                d2 = via
                            queue2[tail2] = w
                            tail2 += 1
                via = (ax * len_x + ay * len_y) + (b + 1) * len_d
                for j in range(4):
                    w = v + diagonal_offs[j]
                    if via < dist[w]:
                        dist[w] = via
                        counts[w] = cv + 1
                        if head1 == tail1:
                            d1 = via
                        queue1[tail1] = w
                        tail1 += 1
            for q in range(count):
                dist[order[q]] = np.inf
            for q in range(n_blocked):
                dist[blocked[q]] = np.inf
        total[i] = t
        inverse[i] = h
        largest[i] = far
        reached[i] = seen + count
    return total, inverse, largest, reached


def takes(n_dims: int, n_neighbours: int, n_pixels: int) -> bool:
    """Whether a pixel grid of this kind takes the octile kernel: 8 neighbours in 2D, under
    2^21 pixels (the width of each step count's field). Any pixel spacing's Euclidean
    lengths meet the kernel's condition on them (see :meth:`OctileGrid.of`)."""
    return n_dims == 2 and n_neighbours == 8 and n_pixels < 1 << 21


#: The bound on the relative rounding error of the inverse-distance prefix tables beyond which
#: inverse distances are divided pixel by pixel (see :meth:`OctileGrid.inverse_tables`). The
#: bound is pessimistic: measured errors are about 0.04 eps x (spacing ratio), 1e-13 or less
#: here, so the tables (and their speed: about 3x on a 300 x 300 disk) are kept up to spacing
#: ratios of about 5,000 at that size.
_TABLE_LOSS = 1e-11


class OctileGrid:
    """The bit masks and components :func:`octile_stats` takes, from a grid whose steps
    are the 8 neighbours of a 2D mask (see :meth:`of`)."""

    def __init__(self, padded: np.ndarray, steps, lengths):
        from scipy import ndimage

        height, width = padded.shape
        n_words = (height + 63) // 64
        bits = np.zeros((width, n_words * 64), dtype=bool)
        bits[:, :height] = padded.T
        # little-endian bit order: row y is bit y & 63 of word y >> 6
        self.north = np.packbits(bits, axis=1, bitorder="little").view(np.uint64).reshape(width, n_words)
        self.north = np.ascontiguousarray(self.north)
        self.south = np.ascontiguousarray(
            np.packbits(bits[:, ::-1], axis=1, bitorder="little").view(np.uint64).reshape(width, n_words)
        )
        labels, n_labels = ndimage.label(padded, structure=np.ones((3, 3), dtype=bool))
        self.labels = labels.ravel().astype(np.int64)
        self.sizes = np.bincount(self.labels, minlength=n_labels + 1).astype(np.int64)
        self.steps = np.asarray(steps, dtype=np.int64)
        self.lengths = np.asarray(lengths, dtype=np.float64)
        self.tables = None  # (inverse_across, inverse_up), made by of(need_inverse=True)

    @staticmethod
    def of(grid, need_inverse: bool = False):
        """An :class:`OctileGrid` for ``grid`` (a ``_grid._Grid``), with the tables of
        inverse distances when ``need_inverse`` (:meth:`inverse_tables`), or None when its steps
        are not the 8 neighbours of a 2D mask, its lengths (along a row, along a column,
        diagonal) do not satisfy ``max(L_x, L_y) <= L_diag <= L_x + L_y`` (Euclidean
        lengths of any pixel spacing do), or it has ``2^21`` pixels or more (the step
        counts' field width)."""
        steps = np.asarray(grid.steps)
        if not takes(grid.padded.ndim, steps.shape[0], grid.raster.size):
            return None
        step_lengths = grid.lengths[grid.kind]
        along_row = steps[:, 0] == 0
        along_column = steps[:, 1] == 0
        diagonal = ~(along_row | along_column)
        groups = [step_lengths[along_row], step_lengths[along_column], step_lengths[diagonal]]
        if any(np.ptp(g) != 0 for g in groups):
            return None
        len_x, len_y, len_d = (float(g[0]) for g in groups)
        if not max(len_x, len_y) <= len_d <= len_x + len_y:
            return None
        octile = OctileGrid(grid.padded, steps, (len_x, len_y, len_d))
        if need_inverse:
            octile.tables = octile.inverse_tables()
        return octile

    # the inverse distances are read from two tables of (width + 1) x (rows + 1) entries
    # up to this many entries each (32 MiB), else divided pixel by pixel
    _MAX_TABLE = 1 << 22

    def inverse_tables(self):
        """``(inverse_across, inverse_up)`` for :func:`octile_stats`: per octant column
        ``k``, the prefix sums over ``d`` of the inverse distances of the pixels ``d`` rows
        up (summed in extended precision, then rounded), so a run of seen pixels costs one
        difference instead of a division per pixel. Empty when they would be too large."""
        width, n_words = self.north.shape
        rows = 64 * n_words
        len_x, len_y, len_d = self.lengths
        # the tables hold float64 prefix sums (of about log(terms) / smallest length), and a
        # difference of two loses about eps * (largest / smallest length) * log2(terms) of
        # a term: with very unequal spacings (rows 1e6 times farther apart than columns) the
        # small terms cancel away, so each pixel is divided instead
        ratio = max(self.lengths) / min(self.lengths)
        lost = np.finfo(np.float64).eps * ratio * np.log2(max(width, rows) + 2)
        if (width + 1) * (max(width, rows) + 1) > self._MAX_TABLE or lost > _TABLE_LOSS:
            empty = np.empty((0, 0))
            return empty, empty
        k = np.arange(width + 1)[:, None]
        d = np.arange(min(width, rows) + 1)[None, :]
        with np.errstate(divide="ignore"):
            across = np.where(d <= k, 1.0 / ((k - d) * len_x + d * len_d), 0.0)
            d = np.arange(rows + 1)[None, :]
            up = np.where(d >= k, 1.0 / ((d - k) * len_y + k * len_d), 0.0)
        across[0, 0] = up[0, 0] = 0.0  # the source itself, never counted

        def prefix(table):
            out = np.zeros((table.shape[0], table.shape[1] + 1))
            out[:, 1:] = np.cumsum(table.astype(np.longdouble), axis=1)
            return out

        return prefix(across), prefix(up)

    def stats(self, grid, sources, need_inverse: bool):
        """:func:`octile_stats` from ``sources`` (inverse sums divided pixel by pixel unless
        the tables were made: :meth:`of` with ``need_inverse``)."""
        empty = np.empty((0, 0))
        across, up = self.tables if need_inverse and self.tables is not None else (empty, empty)
        return octile_stats(
            self.north,
            self.south,
            self.labels,
            self.sizes,
            grid.foreground,
            grid.offs,
            self.steps,
            self.lengths,
            sources,
            need_inverse,
            across,
            up,
        )

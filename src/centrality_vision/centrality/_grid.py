"""Exact betweenness on pixel graphs by walking the pixel grid itself.

A :class:`~centrality_vision.graphs.PixelGraph` remembers its mask, so the breadth-first
searches of Brandes' algorithm can step between pixels by fixed raster offsets instead of
reading adjacency lists: the mask is cropped to its bounding box and padded by one
background pixel on every side, every neighbour of a pixel is ``pixel + offset`` for the
same few offsets, and background pixels carry a hop count no search can match, so no
bounds are checked. This halves the time per source against the adjacency-list kernel.

Symmetries of the mask save whole searches. An axis flip or (for equal extents) an axis
permutation that maps the mask onto itself maps the pixel graph onto itself, so it maps
shortest paths to shortest paths: the dependencies of source ``g(r)`` are those of ``r``
moved by ``g``. With ``G`` the group of such maps and ``O`` the orbit of a pixel ``r``,

    sum over s in O of delta_s(v)  =  |O| / |G| * sum over g in G of delta_r(g^-1 v),

so one search per orbit gives the exact sums: accumulate ``|O| / |G| * delta_r`` over one
representative ``r`` per orbit, then add the ``|G|`` moved copies of that image. A disk
has 8 such maps (its dihedral group), so 1/8 of the searches. ``|O| / |G|`` is 1, 1/2,
1/4 or 1/8 in 2D, exact in floating point.

The searches are those of :mod:`._kernels` in their grid mode: path counts are float64,
and a source whose counts overflow is run again with counts kept as logarithms.
"""

from __future__ import annotations

import itertools

import numpy as np
from numba import njit

from .._parallel import run_chunks
from . import _kernels

__all__ = ["grid_betweenness", "mask_symmetries"]

_BACKGROUND = 1 << 30  # a hop count no search reaches: background pixels never match


@njit(cache=True, nogil=True)
def grid_brandes(foreground, offs, sources, weights):
    """Weighted sum over ``sources`` (padded-raster indices) of their dependencies, and
    the number of sources whose path counts overflowed float64 (run in log space)."""
    size = foreground.shape[0]
    bc = np.zeros(size)
    hops = np.full(size, _BACKGROUND, dtype=np.int64)
    for i in range(size):
        if foreground[i]:
            hops[i] = -1
    order = np.empty(size, dtype=np.int64)
    sigma = np.empty(size)
    coef = np.zeros(size)
    lists = np.empty(0, dtype=np.int64)  # no adjacency lists: the grid mode
    heads = np.empty(0, dtype=np.int32)
    n_pixels = np.count_nonzero(foreground)
    # the hop-count search's node indices, unsigned; negative offsets wrap (see
    # _kernels._brandes_source_bfs)
    order_u = np.empty(size, dtype=np.uint64)
    offs_u = offs.astype(np.uint64)
    succ = np.empty(n_pixels * offs.shape[0], dtype=np.uint64)
    first = np.empty(n_pixels + 1, dtype=np.uint64)
    n_log = 0
    for i in range(sources.shape[0]):
        s, w = sources[i], weights[i]
        found = _kernels._brandes_source_bfs(
            lists, heads, offs_u, True, np.uint64(s), hops, order_u, sigma, coef, bc, w, succ, first
        )
        if not found:
            n_log += 1
            _kernels._brandes_source_bfs_log(lists, heads, offs, True, s, hops, order, sigma, coef, bc, w)
    return bc, n_log


def mask_symmetries(mask: np.ndarray) -> list[tuple[tuple[int, ...], tuple[int, ...]]]:
    """The axis permutations and flips that map ``mask`` (cropped to its bounding box)
    onto itself, as ``(axes, flipped)`` pairs; the identity comes first.

    Examples
    --------
    >>> import numpy as np
    >>> len(mask_symmetries(np.ones((3, 3), dtype=bool)))  # the square's 8 maps
    8
    >>> len(mask_symmetries(np.ones((2, 3), dtype=bool)))  # a rectangle's 4 flips
    4
    >>> mask_symmetries(np.array([[1, 1], [1, 0]], dtype=bool))  # identity and transpose
    [((0, 1), ()), ((1, 0), ())]
    """
    found = []
    for axes in itertools.permutations(range(mask.ndim)):
        if any(mask.shape[a] != mask.shape[i] for i, a in enumerate(axes)):
            continue
        moved = np.transpose(mask, axes)
        for n_flip in range(mask.ndim + 1):
            for flipped in itertools.combinations(range(mask.ndim), n_flip):
                if np.array_equal(np.flip(moved, flipped) if flipped else moved, mask):
                    found.append((tuple(axes), tuple(flipped)))
    return found


def _apply(image: np.ndarray, transform) -> np.ndarray:
    axes, flipped = transform
    moved = np.transpose(image, axes)
    return np.flip(moved, flipped) if flipped else moved


def _steps(ndim: int, connectivity: int) -> list[tuple[int, ...]]:
    """Neighbour steps within ``connectivity`` orthogonal moves, in a fixed order."""
    return [d for d in itertools.product((-1, 0, 1), repeat=ndim) if 0 < np.abs(d).sum() <= connectivity]


# pixel_graph's connectivity -> the most orthogonal steps of one neighbour
_MAX_STEPS = {4: 1, 8: 2, 6: 1, 18: 2, 26: 3}


class _Grid:
    """A PixelGraph's mask cropped to its bounding box and padded by one background pixel,
    with the raster index of each node (node order = row-major = the graph's order)."""

    def __init__(self, graph):
        mask = np.asarray(graph.mask, dtype=bool)
        box = tuple(slice(int(i.min()), int(i.max()) + 1) for i in np.nonzero(mask))
        self.crop = mask[box]
        self.padded = np.pad(self.crop, 1)
        self.foreground = self.padded.ravel()
        self.raster = np.ravel_multi_index(np.nonzero(self.padded), self.padded.shape).astype(np.int64)
        self.steps = _steps(mask.ndim, _MAX_STEPS[int(graph.connectivity)])
        strides = np.cumprod((1,) + self.padded.shape[:0:-1])[::-1]
        self.offs = np.array([int(np.dot(d, strides)) for d in self.steps], dtype=np.int64)
        spacing = np.ones(mask.ndim) if graph.spacing is None else np.asarray(graph.spacing, dtype=np.float64)
        self.spacing = spacing
        # Edge lengths as pixel_graph computes them, in classes as the adjacency kernels take them.
        from ..graphs._pixel import step_lengths

        lengths = step_lengths(np.array(self.steps, dtype=np.float64), spacing)
        self.kind, self.lengths = _kernels.length_classes(lengths, max_classes=len(self.steps))

    def image(self, raster_values: np.ndarray) -> np.ndarray:
        """Values on the padded raster -> an image of the crop."""
        inner = tuple(slice(1, -1) for _ in self.padded.shape)
        return raster_values.reshape(self.padded.shape)[inner]


def grid_betweenness(graph, weights: bool = False, progress: bool = False) -> tuple[np.ndarray, dict]:
    """Ordered-pair betweenness sums (node order of ``graph``) of a PixelGraph that
    :meth:`~centrality_vision.graphs.PixelGraph.matches_mask`, by hops or by edge length.

    Returns the sums and an info dict with ``searches`` and ``symmetries`` (``|G|``).
    """
    grid = _Grid(graph)
    crop = grid.crop
    group = mask_symmetries(crop)
    if weights:  # with lengths, an axis permutation must also keep the spacing
        group = [t for t in group if np.array_equal(grid.spacing[list(t[0])], grid.spacing)]
    # Orbit representative of each pixel: its smallest raster index over the group's maps.
    big = np.iinfo(np.int64).max
    index = np.where(crop, np.arange(crop.size, dtype=np.int64).reshape(crop.shape), big)
    rep = index
    for transform in group[1:]:
        rep = np.minimum(rep, _apply(index, transform))
    flat_rep = rep[crop]
    flat_index = index[crop]
    is_rep = flat_rep == flat_index
    orbit_size = np.bincount(np.searchsorted(flat_index, flat_rep), minlength=flat_index.size)
    source_weights = orbit_size[is_rep] / len(group)
    sources = grid.raster[is_rep]
    empty_lists = np.empty(0, dtype=np.int64)
    empty_heads = np.empty(0, dtype=np.int32)

    def task(lo, hi):
        if weights:
            part, n_log, _ = _kernels.class_brandes(
                empty_lists,
                empty_heads,
                grid.kind,
                grid.lengths,
                sources[lo:hi],
                _kernels.TIE_RTOL,
                False,
                False,
                grid.offs,
                grid.foreground,
                source_weights[lo:hi],
            )
            return part, n_log
        return grid_brandes(grid.foreground, grid.offs, sources[lo:hi], source_weights[lo:hi])

    total = np.zeros(grid.padded.size)
    n_log = 0
    for _, _, (part, count) in run_chunks(task, sources.size, progress=progress, desc="betweenness"):
        total += part
        n_log += count
    sums = grid.image(total)
    sums = sum(_apply(sums, transform) for transform in group)
    return sums[crop], {"searches": int(sources.size), "symmetries": len(group), "log_searches": n_log}


@njit(cache=True, nogil=True, inline="always")
def _live_head(queue, head, tail, dist):
    """The first entry of ``queue[head:tail]`` not yet settled (negative distance) and its
    distance, or ``tail`` and inf."""
    while head < tail:
        d = dist[queue[head]]
        if d >= 0.0:
            return head, d
        head += 1
    return tail, np.inf


@njit(cache=True, nogil=True)
def open_distances(foreground):
    """The distances a search over the padded raster starts from (inf on the pixels, -1 on
    the background, below every candidate) and the number of pixels."""
    size = foreground.shape[0]
    n_pixels = 0
    dist = np.empty(size)
    for i in range(size):
        if foreground[i]:
            dist[i] = np.inf
            n_pixels += 1
        else:
            dist[i] = -1.0
    return dist, n_pixels


@njit(cache=True, nogil=True)
def two_length_stats(foreground, offs, kind, lengths, sources):
    """Sum of distances, of inverse distances, largest distance and nodes reached from each
    of ``sources`` (padded-raster indices) when every step is one of two lengths (one class
    also works: class 1 is then never used).

    Dijkstra with one FIFO queue per class, specialised: a distance is kept as its integer
    counts ``(a, b)`` of each length (packed in one int64) and its value ``a L0 + b L1``
    rounded once, so equal lengths tie exactly. A node is pushed at most once per queue (a
    later push into the same queue comes from a node settled later, so it is no shorter),
    which bounds each queue by the pixel count. A settled node's distance is stored as
    ``-2 - d``, and a background pixel's as -1: both are below every candidate, so relaxing
    an arc is one comparison, and a queue entry is stale when its distance is negative.
    """
    size = foreground.shape[0]
    dist, n_pixels = open_distances(foreground)
    counts = np.zeros(size, dtype=np.int64)  # (a << 32) | b
    queue0 = np.empty(n_pixels, dtype=np.int64)
    queue1 = np.empty(n_pixels, dtype=np.int64)
    order = np.empty(n_pixels, dtype=np.int64)
    n_offs = offs.shape[0]
    len0 = lengths[0]
    len1 = lengths[1] if lengths.shape[0] > 1 else lengths[0]
    one_a = np.int64(1) << 32
    low = (np.int64(1) << 32) - 1
    k = sources.shape[0]
    total = np.zeros(k)
    inverse = np.zeros(k)
    largest = np.zeros(k)
    reached = np.zeros(k, dtype=np.int64)
    for i in range(k):
        s = sources[i]
        counts[s] = 0
        head0 = tail0 = head1 = tail1 = 0
        count = 0
        t = 0.0
        h = 0.0
        v = s
        dv = 0.0
        while True:
            dist[v] = -2.0 - dv
            order[count] = v
            count += 1
            if count > 1:
                t += dv
                h += 1.0 / dv
            cv = counts[v]
            a = cv >> 32
            b = cv & low
            via0 = (a + 1) * len0 + b * len1
            via1 = a * len0 + (b + 1) * len1
            for j in range(n_offs):
                w = v + offs[j]
                if kind[j] == 0:
                    if via0 < dist[w]:
                        dist[w] = via0
                        counts[w] = cv + one_a
                        queue0[tail0] = w
                        tail0 += 1
                elif via1 < dist[w]:
                    dist[w] = via1
                    counts[w] = cv + 1
                    queue1[tail1] = w
                    tail1 += 1
            # the next node: the queue head of least current distance (see _class_search)
            head0, d0 = _live_head(queue0, head0, tail0, dist)
            head1, d1 = _live_head(queue1, head1, tail1, dist)
            if d0 <= d1 and d0 < np.inf:
                v = queue0[head0]
                head0 += 1
                dv = d0
            elif d1 < np.inf:
                v = queue1[head1]
                head1 += 1
                dv = d1
            else:
                break
        total[i] = t
        inverse[i] = h
        largest[i] = dv
        reached[i] = count
        for q in range(count):
            dist[order[q]] = np.inf
    return total, inverse, largest, reached


def fifo_stats(grid: _Grid, sources: np.ndarray):
    """:func:`grid_length_stats`' four sums from ``sources`` (padded-raster indices) by one
    FIFO-queue search each: :func:`two_length_stats` for at most two step lengths, else the
    general search of :mod:`._kernels` in its grid mode."""
    if grid.lengths.shape[0] <= 2:
        return two_length_stats(grid.foreground, grid.offs, grid.kind, grid.lengths, sources)
    no_lists = np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int32)
    return _kernels.class_stats(*no_lists, grid.kind, grid.lengths, sources, grid.offs, grid.foreground)


def grid_length_stats(graph, progress: bool, desc: str, need_inverse: bool = True) -> list[np.ndarray]:
    """Per node (node order of ``graph``), by edge length: sum of distances, of inverse
    distances (zeros unless ``need_inverse``), largest distance, nodes reached.

    8-neighbour 2D masks (any pixel spacing, under 2^21 pixels) take
    :func:`._octile.octile_stats`: the pixels a source sees along octile paths in closed
    form, a search only for the rest. Other grids take one FIFO-queue search per node
    (:func:`two_length_stats` when the steps have at most two lengths, as with 4
    neighbours).
    """
    from ._octile import OctileGrid

    grid = _Grid(graph)
    octile = OctileGrid.of(grid, need_inverse)  # made once, before the threads share it

    def task(lo, hi):
        if octile is not None:
            return octile.stats(grid, grid.raster[lo:hi], need_inverse)
        return fifo_stats(grid, grid.raster[lo:hi])

    parts = [r for _, _, r in run_chunks(task, grid.raster.size, progress=progress, desc=desc)]
    return [np.concatenate(p) for p in zip(*parts)]

"""Pixel graphs of binary images and salt noise (thesis ch. 2 and 4)."""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit
from scipy import sparse

from .._seeding import as_generator
from .._validation import (
    FOREGROUNDS,
    as_binary_image,
    as_real_array,
    check_choice,
    check_float,
    check_threshold,
)
from ..exceptions import InputError
from ._pointsets import _robust_norms

__all__ = ["PixelGraph", "pixel_graph", "pixel_coordinates", "salt_noise"]

_CONNECTIVITY = {2: {4: 1, 8: 2}, 3: {6: 1, 18: 2, 26: 3}}  # ours -> scikit-image's (max orthogonal hops)


class PixelGraph(sparse.csr_array):
    """The adjacency :func:`pixel_graph` returns: a ``scipy.sparse.csr_array`` that also
    remembers the mask, neighbourhood and spacing it was built from.

    It is an ordinary ``csr_array`` everywhere (every scipy operation accepts it). The
    centralities use the remembered mask to walk the pixel grid directly, which is about
    twice as fast as walking the adjacency lists, and to exploit the mask's mirror and
    rotation symmetries (:func:`centrality_vision.centrality.betweenness`). They first
    check that the adjacency still is the pixel graph of ``mask`` (it may have been edited
    in place) and otherwise treat it as any other graph. Arrays derived from it (copies,
    products, slices) are plain pixel-less graphs: their ``mask`` is None.

    Attributes
    ----------
    mask : ndarray of bool or None
        The foreground mask (read-only), or None when this array was derived from one.
    connectivity : int or None
        8 or 4 (2D); 26, 18 or 6 (3D).
    spacing : ndarray or None
        Distance between pixel centres along each axis.

    Examples
    --------
    >>> import numpy as np
    >>> graph, nodes = pixel_graph(np.ones((2, 3), dtype=bool))
    >>> isinstance(graph, PixelGraph), graph.connectivity, graph.mask.shape
    (True, 8, (2, 3))
    >>> (2 * graph).mask is None  # a derived array is an ordinary graph
    True
    """

    mask = None
    connectivity = None
    spacing = None

    def matches_mask(self) -> bool:
        """Whether this adjacency (structure and edge lengths) is still exactly the pixel
        graph of :attr:`mask`; False when it was edited in place or derived from one.

        Examples
        --------
        >>> import numpy as np
        >>> graph, _ = pixel_graph(np.ones((2, 3), dtype=bool))
        >>> graph.matches_mask(), (2 * graph).matches_mask()
        (True, False)
        >>> graph.data[0] = 5.0  # an edge length edited in place
        >>> graph.matches_mask()
        False
        """
        if self.mask is None:
            return False
        mask = np.asarray(self.mask, dtype=bool)
        try:
            offsets, lengths = _steps_of(mask.ndim, self.connectivity, _spacing_key(self.spacing))
        except (ValueError, TypeError):  # pragma: no cover - settings pixel_graph itself took
            return False
        padded = np.pad(mask, 1)
        node_of = np.full(padded.shape, -1, dtype=np.int64)
        n = int(np.count_nonzero(padded))
        node_of[padded] = np.arange(n)
        strides = np.cumprod((1,) + padded.shape[:0:-1])[::-1]
        raster = np.flatnonzero(padded.ravel())
        offs = np.array([int(np.dot(d, strides)) for d in offsets], dtype=np.int64)
        return bool(
            self.shape == (n, n)
            and _csr_is_grid(self.indptr, self.indices, self.data, raster, node_of.ravel(), offs, lengths)
        )


def _spacing_key(spacing):
    return None if spacing is None else tuple(float(x) for x in np.asarray(spacing).ravel())


@functools.lru_cache(maxsize=64)
def _steps_of(ndim: int, connectivity: int, spacing):
    """The neighbour steps of :func:`pixel_graph` in the order of its sorted rows, and the
    edge length it stores for each: read off the middle pixel of a full 3 x 3 (x 3) patch,
    so they are the engine's own values to the last bit."""
    patch, _ = pixel_graph(np.ones((3,) * ndim, dtype=bool), connectivity=connectivity, spacing=spacing)
    middle = (3**ndim) // 2
    row = slice(patch.indptr[middle], patch.indptr[middle + 1])
    centre = np.array(np.unravel_index(middle, (3,) * ndim))
    offsets = [tuple(int(x) for x in np.array(np.unravel_index(k, (3,) * ndim)) - centre) for k in patch.indices[row]]
    return offsets, np.array(patch.data[row], dtype=np.float64)


@njit(cache=True)
def _csr_is_grid(indptr, indices, data, raster, node_of, offs, lengths):
    """Whether the CSR arrays are exactly the pixel graph whose node ``i`` sits at
    ``raster[i]`` of a padded raster (``node_of``: its inverse, -1 on background): row by
    row, the foreground neighbours at ``raster[i] + offs`` (sorted), each with its length."""
    n = raster.shape[0]
    if indptr.shape[0] != n + 1 or indptr[0] != 0:
        return False
    k = 0
    for i in range(n):
        if indptr[i] != k:
            return False
        r = raster[i]
        for j in range(offs.shape[0]):
            w = node_of[r + offs[j]]
            if w >= 0:
                if k >= indices.shape[0] or k >= data.shape[0] or indices[k] != w or data[k] != lengths[j]:
                    return False
                k += 1
    return indptr[n] == k and indices.shape[0] == k and data.shape[0] == k


def _volume_mask(arr: np.ndarray, threshold, foreground: str = "auto") -> np.ndarray:
    """Boolean mask of a 3D image ``arr`` (a real array, as :func:`pixel_graph` checked it): a
    boolean or 0/1 array, or ``arr > threshold``; the other side with ``foreground="dark"``."""
    if arr.size == 0:
        raise InputError(f"`image` must not be empty; got shape {arr.shape}.")
    if arr.dtype != bool and not np.all(np.isfinite(arr)):
        raise InputError("`image` must be finite; got NaN or inf values.")
    check_threshold(threshold)
    if arr.dtype == bool:  # a mask, as in 2D
        mask = arr.copy()
    elif threshold is not None:
        mask = arr > threshold
    elif np.all((arr == 0) | (arr == 1)):
        mask = arr == 1
    else:
        colour = (
            f" (an image of {arr.shape[2]} colour channels? average them, image.mean(axis=-1), or read it with "
            "centrality_vision.io.read_shape)"
            if arr.shape[2] in (3, 4)
            else ""
        )
        raise InputError(
            "`image` must be binary (bool or 0/1) in 3D, or come with `threshold`; got other values" + colour + "."
        )
    if foreground == "dark":
        mask = ~mask
    if not mask.any():
        raise InputError("`image` must have at least one foreground pixel; got none.")
    return mask


def pixel_graph(
    image,
    /,
    *,
    connectivity: int | None = None,
    spacing=None,
    threshold: float | None = None,
    foreground: str = "auto",
):
    """Graph of the foreground pixels (voxels) of a binary 2D or 3D image.

    One node per foreground pixel, in row-major (C) order; an edge joins two foreground
    pixels that are neighbours. The stored value of an edge is the Euclidean distance
    between the pixel centres: 1 for horizontal and vertical neighbours and sqrt(2)
    for diagonal ones (3D: also sqrt(3)), each axis scaled by ``spacing``. Centralities
    ignore these lengths unless called with ``weights=True`` (the thesis counts hops);
    with them, the few distinct lengths let shortest paths run on an exact FIFO-queue
    search.

    Parameters
    ----------
    image : array_like of shape (n_rows, n_cols) or (n_planes, n_rows, n_cols)
        Boolean mask, or an array holding only 0 and 1 (1 = foreground), or any other
        numeric image, split at ``threshold``.
    connectivity : {8, 4} in 2D, {26, 18, 6} in 3D, optional
        Neighbourhood; the default is the full one (8 in 2D, the thesis' choice; 26 in 3D).
    spacing : sequence of float, optional
        Distance between pixel centres along each axis (default 1 everywhere), e.g. the
        voxel size of an anisotropic scan. Each entry must keep path lengths and their sums
        within float64: at least the smallest normal float (about 2.2e-308) and ``n`` over the
        largest, at most the largest over ``n**2 * sqrt(ndim)``, for ``n`` foreground pixels.
    threshold : float, optional
        Grey level that splits a numeric image. 2D: as
        :func:`centrality_vision.io.read_shape` with ``foreground="auto"`` splits it (default
        half the image's range; the shape is the side that touches fewer border pixels, so
        dark shapes on white and white shapes on black both come out as the shape). 3D: the
        foreground is ``image > threshold``. A boolean image is a mask in 2D and 3D, and
        ``threshold`` does not apply to it. (:func:`centrality_vision.datasets.load_kimia99`
        already returns masks.) A colour picture is not an image here (in 3D it would be
        read as planes): average its channels, or read it with
        :func:`centrality_vision.io.read_shape`.
    foreground : {"auto", "dark", "light"}, default="auto"
        Which side is the shape: ``"light"`` the pixels above ``threshold`` (of a mask, the
        True or 1 pixels), ``"dark"`` the others. ``"auto"``: in 2D, the side that touches
        fewer border pixels of a grey image (a mask's True pixels); in 3D, ``"light"``.

    Returns
    -------
    graph : PixelGraph of shape (n_nodes, n_nodes)
        Symmetric adjacency with Euclidean edge lengths: a ``scipy.sparse.csr_array``
        that also remembers ``mask``, ``connectivity`` and ``spacing``, which lets the
        centralities walk the pixel grid directly (:class:`PixelGraph`).
    nodes : ndarray of shape (n_nodes,), dtype int64
        Flat (row-major) index into ``image`` of each node's pixel; see
        :func:`pixel_coordinates` for coordinates.

    See Also
    --------
    skimage.graph.pixel_graph : the engine used here.

    Examples
    --------
    >>> import numpy as np
    >>> graph, nodes = pixel_graph(np.ones((3, 3), dtype=bool))
    >>> (graph > 0).sum(axis=1).reshape(3, 3)  # corner 3, edge 5, centre 8 neighbours
    array([[3, 5, 3],
           [5, 8, 5],
           [3, 5, 3]])
    >>> graph, nodes = pixel_graph([[1, 0], [1, 1]], connectivity=4)
    >>> nodes
    array([0, 2, 3])
    >>> graph, _ = pixel_graph(np.ones((2, 2, 2), dtype=bool), spacing=(2.0, 1.0, 1.0))
    >>> sorted(set(np.round(graph.data, 3)))  # 1, sqrt 2, 2, sqrt 5, sqrt 6
    [np.float64(1.0), np.float64(1.414), np.float64(2.0), np.float64(2.236), np.float64(2.449)]
    """
    from skimage.graph import pixel_graph as _skimage_pixel_graph

    if sparse.issparse(image):
        raise TypeError("`image` must be a dense 2D or 3D array; got a sparse matrix.")
    image = as_real_array(image, name="image", shape="a 2D or 3D array")  # not copied
    ndim = image.ndim
    if ndim not in (2, 3):  # (the 2D reader's error said "must be a 2D array" of a 4D one)
        raise InputError(f"`image` must be a 2D or 3D array; got shape {image.shape}.")
    foreground = check_choice(foreground, FOREGROUNDS, name="foreground")
    if ndim == 3:
        mask = _volume_mask(image, threshold, foreground)
    else:
        mask = as_binary_image(image, name="image", threshold=threshold, foreground=foreground)  # 2D, or its error
    allowed = _CONNECTIVITY[mask.ndim]
    if connectivity is None:
        connectivity = max(allowed)
    if isinstance(connectivity, bool) or not isinstance(connectivity, (int, np.integer)) or connectivity not in allowed:
        choices = " or ".join(str(c) for c in sorted(allowed, reverse=True))
        raise InputError(f"`connectivity` must be {choices} for a {mask.ndim}D image; got {connectivity!r}.")
    if spacing is not None:
        given = spacing
        try:
            raw = np.asarray(spacing)
            spacing = raw.astype(np.float64)
        except OverflowError:
            raise InputError(
                f"`spacing` must be {mask.ndim} positive finite numbers; got an int beyond float64."
            ) from None
        except (TypeError, ValueError):
            raise TypeError(f"`spacing` must be {mask.ndim} positive finite numbers; got {given!r}.") from None
        items = given if isinstance(given, (list, tuple)) else ()
        if raw.dtype == bool or any(isinstance(x, (bool, np.bool_)) for x in items):  # ((True, 1): ints to numpy)
            raise TypeError(f"`spacing` must be {mask.ndim} positive finite numbers; got booleans {given!r}.")
        if spacing.shape != (mask.ndim,) or not np.all(np.isfinite(spacing)) or np.any(spacing <= 0):
            raise InputError(f"`spacing` must be {mask.ndim} positive finite numbers; got {spacing.tolist()!r}.")
        # every path length (at most n steps) and closeness' sum of n of them, and harmonic's
        # sum of n inverse lengths, must stay finite and keep full precision (no subnormals)
        n = max(int(np.count_nonzero(mask)), 1)
        biggest = float(np.finfo(np.float64).max)
        low = max(float(np.finfo(np.float64).tiny), n / biggest)
        high = biggest / (float(n) * n * np.sqrt(mask.ndim))
        if spacing.min() < low or spacing.max() > high:
            raise InputError(
                f"`spacing` must lie between {low:.3g} and {high:.3g} for an image of {n} foreground "
                f"pixels (so that path lengths and their sums stay within float64); got {spacing.tolist()!r}."
            )
    # skimage squares the spacing: it gets the spacing over its largest entry (squares no
    # smaller than 1e-300 while the entries are within 1e150 of each other) and the lengths
    # are scaled back; beyond that ratio they are computed step by step (slower, exact)
    top = None if spacing is None else float(spacing.max())
    unit = None if spacing is None or spacing.min() / top < 1e-150 else spacing / top
    graph, nodes = _skimage_pixel_graph(mask, mask=mask, connectivity=allowed[connectivity], spacing=unit)
    graph = PixelGraph(graph)
    graph.sort_indices()
    if spacing is not None:
        graph.data = (  # finite and normal, by the check on `spacing` above
            _spaced_lengths(graph, np.asarray(nodes, dtype=np.int64), mask.shape, spacing)
            if unit is None
            else graph.data * top
        )
    graph.indices = graph.indices.astype(np.int32, copy=False)
    graph.indptr = graph.indptr.astype(np.int32, copy=False)
    remembered = mask.copy()
    remembered.flags.writeable = False
    graph.mask = remembered
    graph.connectivity = int(connectivity)
    graph.spacing = None if spacing is None else spacing.copy()
    return graph, np.asarray(nodes, dtype=np.int64)


def _spaced_lengths(graph, nodes: np.ndarray, shape: tuple, spacing: np.ndarray) -> np.ndarray:
    """The edge lengths of ``graph`` (CSR order) with pixel ``spacing``, without overflow or underflow.

    Each edge joins pixels that differ by 0 or 1 along each axis; its length is the norm of
    those steps times ``spacing``, taken with the steps divided by the largest one before
    squaring (skimage squares the spacing itself: its lengths overflow above about 1e154
    and underflow to 0 below about 1e-162). Lengths beyond float64 come out 0 or inf (the
    caller refuses them).
    """
    rows = np.repeat(np.arange(graph.shape[0]), np.diff(graph.indptr))
    steps = np.abs(
        np.stack(np.unravel_index(nodes[rows], shape), axis=1)
        - np.stack(np.unravel_index(nodes[graph.indices], shape), axis=1)
    )
    return step_lengths(steps, spacing)


def step_lengths(steps: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """Lengths of pixel steps (rows of per-axis offsets) with ``spacing``: each step over the
    largest spacing before squaring, so that spacings of 1e-200 or 1e200 neither underflow
    nor overflow (a length beyond float64 comes out 0 or inf)."""
    top = float(spacing.max())
    return _robust_norms(np.abs(steps) * (spacing / top)) * top


def pixel_coordinates(nodes, shape) -> np.ndarray:
    """Pixel coordinates ((row, col), or (plane, row, col)) of pixel-graph nodes, as an
    int64 array of shape (n, len(shape)).

    Parameters
    ----------
    nodes : array_like of int, shape (n,)
        Flat (row-major) pixel indices, each in [0, prod(shape)), e.g. the ``nodes`` of
        :func:`pixel_graph`.
    shape : sequence of int
        The image's shape, ``(n_rows, n_cols)`` or ``(n_planes, n_rows, n_cols)``, every side >= 1.

    Returns
    -------
    ndarray of int64, shape (n, len(shape))
        Row ``i`` holds the coordinates of pixel ``nodes[i]``.

    Examples
    --------
    >>> pixel_coordinates([0, 2, 3], (2, 2))
    array([[0, 0],
           [1, 0],
           [1, 1]])
    """
    nodes = np.asarray(nodes)
    if nodes.ndim == 1 and nodes.size == 0:  # an empty list is float64 to numpy
        nodes = nodes.astype(np.int64)
    if nodes.ndim != 1 or not np.issubdtype(nodes.dtype, np.integer):
        raise InputError(f"`nodes` must be a 1D integer array; got shape {nodes.shape} and dtype {nodes.dtype}.")
    if isinstance(shape, (str, bytes)) or not hasattr(shape, "__iter__") or getattr(shape, "ndim", 1) != 1:
        raise TypeError(f"`shape` must be (n_rows, n_cols) or (n_planes, n_rows, n_cols); got {shape!r}.")
    if any(isinstance(s, (bool, np.bool_)) or not isinstance(s, (int, np.integer)) for s in shape):
        raise TypeError(f"`shape` must hold ints; got {tuple(shape)!r}.")
    shape = tuple(int(s) for s in shape)
    if len(shape) not in (2, 3) or min(shape) < 1:
        raise InputError(f"`shape` must be (n_rows, n_cols) or (n_planes, n_rows, n_cols); got {shape!r}.")
    if math.prod(shape) >= 2**63:  # (np.prod wrapped around, and blamed the nodes)
        raise InputError(f"`shape` must have fewer than 2^63 pixels; got {shape!r}.")
    if nodes.size and (nodes.min() < 0 or nodes.max() >= math.prod(shape)):
        raise InputError(
            f"`nodes` must index into an image of shape {shape}; got values in [{nodes.min()}, {nodes.max()}]."
        )
    return np.stack(np.unravel_index(nodes, shape), axis=1).astype(np.int64)


def salt_noise(
    image, /, rate: float, *, seed=None, threshold: float | None = None, foreground: str = "auto"
) -> np.ndarray:
    """Remove a share of the foreground pixels at random (thesis 4.4.1).

    Exactly ``round(rate * n_foreground)`` foreground pixels, drawn without replacement,
    are set to background. This is a topological change of the pixel graph, not an image
    filter: holes appear and thin parts may break off.

    Parameters
    ----------
    image : array_like of shape (n_rows, n_cols)
        Binary image (see :func:`pixel_graph`). It is not modified.
    rate : float in [0, 1]
        Share of the foreground pixels to remove.
    seed : int, numpy.random.Generator or None
        Seed of the random choice; ``None`` draws fresh entropy.
    threshold : float, optional
        As in :func:`pixel_graph`.
    foreground : {"auto", "dark", "light"}, default="auto"
        As in :func:`pixel_graph` (2D).

    Returns
    -------
    noisy : ndarray of bool, same shape as ``image``

    Examples
    --------
    >>> import numpy as np
    >>> noisy = salt_noise(np.ones((10, 10), dtype=bool), 0.05, seed=0)
    >>> int(noisy.sum())
    95
    """
    mask = as_binary_image(image, name="image", threshold=threshold, foreground=foreground)
    rate = check_float(rate, name="rate", low=0.0, high=1.0)
    rng = as_generator(seed)
    shape_pixels = np.flatnonzero(mask)
    n_remove = int(round(rate * shape_pixels.size))
    noisy = mask.copy()
    if n_remove:
        noisy.flat[rng.choice(shape_pixels, size=n_remove, replace=False)] = False
    return noisy

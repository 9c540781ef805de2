"""Pixel graphs of binary images and salt noise (thesis ch. 2 and 4)."""

from __future__ import annotations

import numpy as np
from scipy import sparse

from .._validation import as_binary_image, check_float
from .._seeding import as_generator

__all__ = ["pixel_graph", "pixel_coordinates", "salt_noise"]

_CONNECTIVITY = {4: 1, 8: 2}  # ours -> scikit-image's (max number of orthogonal hops)


def pixel_graph(image, /, *, connectivity: int = 8, threshold: float | None = None):
    """Graph of the foreground pixels of a binary image.

    One node per foreground pixel, in row-major order; an edge joins two foreground
    pixels that are 4- or 8-neighbours. The stored value of an edge is the Euclidean
    distance between the pixel centres: 1 for horizontal and vertical neighbours,
    sqrt(2) for diagonal ones. Centralities ignore these lengths unless called with
    ``weights=True`` (the thesis counts hops).

    Parameters
    ----------
    image : array_like of shape (n_rows, n_cols)
        Boolean mask, or an array holding only 0 and 1 (1 = foreground), or any numeric
        image together with ``threshold``.
    connectivity : {8, 4}, default=8
        8-neighbourhood (the thesis' default) or 4-neighbourhood.
    threshold : float, optional
        Foreground is ``image > threshold``. Invert dark-on-light images first
        (:func:`centrality_vision.datasets.load_kimia99` already returns masks).

    Returns
    -------
    graph : scipy.sparse.csr_array of shape (n_nodes, n_nodes)
        Symmetric adjacency with edge lengths 1 and sqrt(2).
    nodes : ndarray of shape (n_nodes,), dtype int64
        Flat (row-major) index into ``image`` of each node's pixel; see
        :func:`pixel_coordinates` for (row, col) coordinates.

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
    """
    from skimage.graph import pixel_graph as _skimage_pixel_graph

    if connectivity not in _CONNECTIVITY or isinstance(connectivity, bool):
        raise ValueError(f"`connectivity` must be 4 or 8; got {connectivity!r}.")
    mask = as_binary_image(image, name="image", threshold=threshold)
    graph, nodes = _skimage_pixel_graph(mask, mask=mask, connectivity=_CONNECTIVITY[connectivity])
    graph = sparse.csr_array(graph)
    graph.sort_indices()
    graph.indices = graph.indices.astype(np.int32, copy=False)
    graph.indptr = graph.indptr.astype(np.int32, copy=False)
    return graph, np.asarray(nodes, dtype=np.int64)


def pixel_coordinates(nodes, shape) -> np.ndarray:
    """(row, col) coordinates of pixel-graph nodes, as an int64 array of shape (n, 2).

    Examples
    --------
    >>> pixel_coordinates([0, 2, 3], (2, 2))
    array([[0, 0],
           [1, 0],
           [1, 1]])
    """
    nodes = np.asarray(nodes)
    if nodes.ndim != 1 or not np.issubdtype(nodes.dtype, np.integer):
        raise ValueError(f"`nodes` must be a 1D integer array; got shape {nodes.shape} and dtype {nodes.dtype}.")
    shape = tuple(int(s) for s in shape)
    if len(shape) != 2:
        raise ValueError(f"`shape` must be (n_rows, n_cols); got {shape!r}.")
    if nodes.size and (nodes.min() < 0 or nodes.max() >= shape[0] * shape[1]):
        raise ValueError(f"`nodes` must index into an image of shape {shape}; got values in [{nodes.min()}, {nodes.max()}].")
    return np.stack(np.unravel_index(nodes, shape), axis=1).astype(np.int64)


def salt_noise(image, /, rate: float, *, seed=None, threshold: float | None = None) -> np.ndarray:
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
    mask = as_binary_image(image, name="image", threshold=threshold)
    rate = check_float(rate, name="rate", low=0.0, high=1.0)
    rng = as_generator(seed)
    foreground = np.flatnonzero(mask)
    n_remove = int(round(rate * foreground.size))
    noisy = mask.copy()
    if n_remove:
        noisy.flat[rng.choice(foreground, size=n_remove, replace=False)] = False
    return noisy

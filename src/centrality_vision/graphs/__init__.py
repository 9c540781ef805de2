"""Graphs from images and point sets.

Every builder returns a symmetric :class:`scipy.sparse.csr_array` of shape (n, n) whose
stored values are Euclidean edge lengths; row ``i`` is node ``i`` (point ``i``, or the
``i``-th foreground pixel for pixel graphs).
"""

from ._convert import to_networkx
from ._entropy import MSTMEResult, MWMEResult, mstme_graph, mwme_degrees, mwme_graph, nhdd_graph, nhdd_joining
from ._pixel import PixelGraph, pixel_coordinates, pixel_graph, salt_noise
from ._pointsets import complete_graph, delaunay_graph, emst_graph, gabriel_graph, knn_graph

__all__ = [
    "PixelGraph",
    "pixel_graph",
    "pixel_coordinates",
    "salt_noise",
    "delaunay_graph",
    "gabriel_graph",
    "emst_graph",
    "knn_graph",
    "complete_graph",
    "to_networkx",
    "nhdd_graph",
    "nhdd_joining",
    "mwme_graph",
    "mwme_degrees",
    "MWMEResult",
    "mstme_graph",
    "MSTMEResult",
]

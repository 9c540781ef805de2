"""Conversion of our graphs to networkx, for users (never on a hot path)."""

from __future__ import annotations

from .._validation import ANY_DIMS, as_graph, as_points
from ..exceptions import InputError

__all__ = ["to_networkx"]


def to_networkx(graph, /, points=None, *, weight: str = "weight"):
    """Convert an adjacency to a :class:`networkx.Graph`.

    Parameters
    ----------
    graph : scipy.sparse array or matrix of shape (n, n)
        Symmetric adjacency whose values are edge lengths.
    points : array_like of shape (n, n_dims), optional
        Coordinates, stored as the node attribute ``"pos"`` (a tuple).
    weight : str, default="weight"
        Name of the edge attribute that receives the edge length.

    Returns
    -------
    networkx.Graph
        Nodes ``0 .. n-1``; isolated nodes are kept.

    Examples
    --------
    >>> from centrality_vision.graphs import complete_graph
    >>> g = to_networkx(complete_graph([[0, 0], [3, 0], [0, 4]]))
    >>> g.number_of_edges(), g[1][2]["weight"]
    (3, 5.0)
    """
    import networkx as nx

    adjacency = as_graph(graph, name="graph")
    if not isinstance(weight, str):  # (a networkx attribute name: any hashable, but ours say str)
        raise TypeError(f"`weight` must be a str, the edge attribute's name; got {weight!r}.")
    n = adjacency.shape[0]
    out = nx.Graph()
    out.add_nodes_from(range(n))
    coo = adjacency.tocoo()
    upper = coo.row < coo.col
    out.add_weighted_edges_from(
        zip(coo.row[upper].tolist(), coo.col[upper].tolist(), coo.data[upper].tolist()), weight=weight
    )
    if points is not None:
        pts = as_points(points, name="points", n_dims=ANY_DIMS)
        if pts.shape[0] != n:
            raise InputError(f"`points` must have one row per node ({n}); got {pts.shape[0]} rows.")
        nx.set_node_attributes(out, {i: tuple(p) for i, p in enumerate(pts.tolist())}, "pos")
    return out

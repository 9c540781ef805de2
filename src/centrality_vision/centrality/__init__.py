"""Node centralities of graphs and the entropy of the degree distribution.

Each centrality is a function ``f(graph, *, ...) -> ndarray`` returning one value per
node in node order (or ``{node: value}`` with ``as_dict=True``). ``graph`` is a scipy
sparse adjacency of edge lengths, a dense array, or a networkx or igraph graph.
``weights=True`` always means "shortest paths by the stored edge lengths" (path
centralities); degree, eigenvector, PageRank and Katz read the stored values as
connection strengths with ``strengths=True``. See each function's docstring for the
exact conventions.
"""

from ._api import (
    CENTRALITIES,
    PATH_CENTRALITIES,
    betweenness,
    closeness,
    compute,
    degree,
    degree_entropy,
    eccentricity,
    edge_betweenness,
    harmonic,
)
from ._spectral import eigenvector, katz, pagerank

__all__ = [
    "CENTRALITIES",
    "PATH_CENTRALITIES",
    "degree",
    "betweenness",
    "edge_betweenness",
    "closeness",
    "harmonic",
    "eigenvector",
    "eccentricity",
    "pagerank",
    "katz",
    "compute",
    "degree_entropy",
]

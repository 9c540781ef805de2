"""Node centralities of graphs and the entropy of the degree distribution.

Each centrality is a function ``f(graph, *, weights=False, normalized=...) -> ndarray``
returning one value per node, aligned with the rows of ``graph``. See SPEC section 2 and
each function's docstring for the exact conventions.
"""

from ._api import (
    CENTRALITIES,
    betweenness,
    closeness,
    compute,
    degree,
    degree_entropy,
    eccentricity,
    eigenvector,
    harmonic,
)

__all__ = [
    "CENTRALITIES",
    "degree",
    "betweenness",
    "closeness",
    "harmonic",
    "eigenvector",
    "eccentricity",
    "compute",
    "degree_entropy",
]

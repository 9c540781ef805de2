"""Exact centralities give the same bits with any number of threads."""

import numpy as np
import pytest

import centrality_vision as cv
from centrality_vision import centrality as cen
from centrality_vision.graphs import delaunay_graph, pixel_graph


def _graphs():
    yy, xx = np.ogrid[:19, :14]
    disk, _ = pixel_graph((yy - 9.5) ** 2 + (xx - 7) ** 2 <= 7.6**2)  # the grid path
    points = np.random.default_rng(0).random((300, 2))
    return {"pixel": disk, "delaunay": delaunay_graph(points)}


@pytest.mark.parametrize("name", ["betweenness", "harmonic", "closeness", "edge_betweenness"])
@pytest.mark.parametrize("graph_name", ["pixel", "delaunay"])
def test_same_bits_for_any_thread_count(name, graph_name):
    graph = _graphs()[graph_name]
    results = []
    try:
        for threads in (1, 2, 3, 5):
            cv.set_num_threads(threads)
            value = getattr(cen, name)(graph)
            results.append(value.toarray() if hasattr(value, "toarray") else np.asarray(value))
    finally:
        cv.set_num_threads(None)
    for other in results[1:]:
        np.testing.assert_array_equal(other, results[0])

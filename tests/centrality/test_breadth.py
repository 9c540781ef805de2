"""Graph inputs, directed graphs, PageRank/Katz/edge betweenness, eccentricity bounds,
the FIFO-queue kernel of pixel graphs and the long-thin eigenvector solver."""

import warnings

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import sparse

from centrality_vision import centrality as cen
from centrality_vision.centrality import _kernels
from centrality_vision.graphs import pixel_graph


def _labelled_digraph(seed, n=30, p=0.1):
    rng = np.random.default_rng(seed)
    g = nx.gnp_random_graph(n, p, seed=seed, directed=True)
    for u, v in g.edges:
        g[u][v]["weight"] = float(rng.uniform(0.5, 2.0))
    return nx.relabel_nodes(g, {i: f"v{(7 * i) % n}" for i in g})  # labels not in node order


def _close(ours: dict, ref: dict, atol=1e-9):
    assert set(ours) == set(ref)
    assert max(abs(ours[k] - ref[k]) for k in ref) <= atol


def _nx_eccentricity(g, weight):
    out = {}
    for v in g:
        if weight:
            d = nx.single_source_dijkstra_path_length(g, v, weight=weight)
        else:
            d = nx.single_source_shortest_path_length(g, v)
        out[v] = max(d.values())
    return out


@pytest.mark.parametrize("weights", [False, True])
@pytest.mark.parametrize("seed", [0, 1])
def test_directed_labelled_graphs_agree_with_networkx(seed, weights):
    g = _labelled_digraph(seed)
    w = "weight" if weights else None
    _close(cen.betweenness(g, weights=weights, as_dict=True), nx.betweenness_centrality(g, normalized=False, weight=w))
    _close(cen.betweenness(g, weights=weights, normalized=True, as_dict=True), nx.betweenness_centrality(g, weight=w))
    _close(cen.closeness(g, weights=weights, as_dict=True), nx.closeness_centrality(g, distance=w))
    _close(cen.harmonic(g, weights=weights, as_dict=True), nx.harmonic_centrality(g, distance=w))
    _close(cen.eccentricity(g, weights=weights, as_dict=True), _nx_eccentricity(g, w))
    _close(
        cen.edge_betweenness(g, weights=weights, as_dict=True),
        nx.edge_betweenness_centrality(g, normalized=False, weight=w),
    )
    _close(cen.pagerank(g, strengths=weights, as_dict=True), nx.pagerank(g, weight=w, tol=1e-14), atol=1e-10)
    _close(cen.katz(g, strengths=weights, as_dict=True), nx.katz_centrality_numpy(g, weight=w))
    _close(cen.degree(g, strengths=weights, as_dict=True), dict(g.out_degree(weight=w)))


@pytest.mark.parametrize("weights", [False, True])
def test_undirected_edge_betweenness_pagerank_katz_agree_with_networkx(weights):
    g = _labelled_digraph(2, n=40, p=0.12).to_undirected()
    w = "weight" if weights else None
    ours = cen.edge_betweenness(g, weights=weights, normalized=True, as_dict=True)
    ref = nx.edge_betweenness_centrality(g, weight=w)
    assert len(ours) == g.number_of_edges()
    assert max(abs(ours[e] - ref[e] if e in ref else ours[e] - ref[e[::-1]]) for e in ours) < 1e-9
    _close(cen.pagerank(g, strengths=weights, as_dict=True), nx.pagerank(g, weight=w, tol=1e-14), atol=1e-10)
    _close(cen.katz(g, strengths=weights, alpha=0.05, as_dict=True), nx.katz_centrality_numpy(g, alpha=0.05, weight=w))
    # The sparse result: symmetric, the graph's pattern, sums to the pairs' path lengths.
    graph = nx.to_scipy_sparse_array(g, weight=w)
    eb = cen.edge_betweenness(graph, weights=weights)
    assert (abs(eb - eb.T) > 1e-12).nnz == 0 and eb.nnz == graph.nnz


def test_networkx_and_igraph_inputs_keep_order_and_labels():
    ig = pytest.importorskip("igraph")
    g = nx.karate_club_graph()  # edges carry a "weight" attribute: used as lengths
    g = nx.relabel_nodes(g, {i: ("node", i) for i in g})
    matrix = nx.to_scipy_sparse_array(g, nodelist=list(g.nodes), weight="weight")
    expected = cen.closeness(matrix, weights=True)
    np.testing.assert_allclose(cen.closeness(g, weights=True), expected)
    labelled = cen.closeness(g, weights=True, as_dict=True)
    assert list(labelled) == list(g.nodes)
    np.testing.assert_allclose(list(labelled.values()), expected)
    h = ig.Graph.from_networkx(nx.convert_node_labels_to_integers(g))
    h.vs["name"] = [f"x{i}" for i in range(h.vcount())]
    values = cen.betweenness(h, weights=True, as_dict=True)
    assert list(values) == [f"x{i}" for i in range(34)]
    np.testing.assert_allclose(list(values.values()), cen.betweenness(matrix, weights=True))
    with pytest.raises(ValueError, match="undirected"):
        cen.eigenvector(nx.DiGraph([(0, 1)]))


def test_zero_length_edges_are_edges():
    # 0 -- 1 of length 0 (a stored zero), 1 -- 2 of length 1.
    graph = sparse.csr_array(
        (np.array([0.0, 0.0, 1.0, 1.0]), (np.array([0, 1, 1, 2]), np.array([1, 0, 2, 1]))), shape=(3, 3)
    )
    np.testing.assert_allclose(cen.closeness(graph), [2 / 3, 1, 2 / 3])  # hops: a path of 3
    np.testing.assert_allclose(cen.betweenness(graph), [0, 1, 0])
    np.testing.assert_allclose(cen.degree(graph), [1, 2, 1])
    # By length, 0 and 1 are at distance 0: as networkx, that term adds nothing to harmonic.
    g = nx.Graph()
    g.add_edge(0, 1, weight=0.0)
    g.add_edge(1, 2, weight=1.0)
    _close(cen.harmonic(g, weights=True, as_dict=True), nx.harmonic_centrality(g, distance="weight"))
    _close(cen.closeness(g, weights=True, as_dict=True), nx.closeness_centrality(g, distance="weight"))
    # Only the pair (0, 2) has an inner node (networkx 3.6 reports 1.5 for node 1 here).
    np.testing.assert_allclose(cen.betweenness(g, weights=True), [0, 1, 0])


def test_zero_length_triangle_is_symmetric():
    # Every pair is joined directly at length 0; a detour over the third node ties in
    # length but has one more zero-length edge, so it is not shortest. The three nodes
    # are interchangeable and must get equal values (the settling order gave [0, .5, .25]).
    g = nx.Graph([(0, 1), (1, 2), (0, 2)])
    nx.set_edge_attributes(g, 0.0, "weight")
    np.testing.assert_array_equal(cen.betweenness(g, weights=True), [0, 0, 0])
    assert set(cen.edge_betweenness(g, weights=True, as_dict=True).values()) == {1.0}
    # A zero-length detour beside a zero-length edge of a longer path: 0 -0- 1 -0- 2 with a
    # direct 0 -- 2 of length 0, and 2 -- 3 of length 1. Pair (0, 3) goes 0, 2, 3 only.
    g.add_edge(2, 3, weight=1.0)
    np.testing.assert_allclose(cen.betweenness(g, weights=True), [0, 0, 2, 0])


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(3, 11),
    edges=st.lists(st.tuples(st.integers(0, 10), st.integers(0, 10), st.integers(0, 2)), min_size=2, max_size=30),
)
def test_zero_length_edges_are_infinitesimal(n, edges):
    # Integer lengths with zeros against networkx with each zero replaced by 2**-10 (exact
    # in binary, and below any difference of integer sums on these graphs): the same paths
    # are shortest, and networkx's counts are unambiguous there.
    g = nx.Graph()
    g.add_nodes_from(range(n))
    for a, b, length in edges:
        if a < n and b < n and a != b:
            g.add_edge(a, b, weight=float(length))
    h = g.copy()
    for _, _, data in h.edges(data=True):
        data["weight"] = data["weight"] or 2.0**-10
    expected = nx.betweenness_centrality(h, weight="weight", normalized=False)
    np.testing.assert_allclose(cen.betweenness(g, weights=True), [expected[v] for v in range(n)], atol=1e-9)
    ours = cen.edge_betweenness(g, weights=True, as_dict=True)
    for (a, b), value in nx.edge_betweenness_centrality(h, weight="weight", normalized=False).items():
        assert ours[min(a, b), max(a, b)] == pytest.approx(value, abs=1e-9)


def test_complex_adjacency_is_a_type_error():
    for graph in (np.array([[0, 1j], [1j, 0]]), sparse.csr_array(np.array([[0, 1 + 1j], [1 + 1j, 0]]))):
        with pytest.raises(TypeError, match="`graph` must hold real edge lengths; got complex"):
            cen.closeness(graph)


def test_weights_alias_of_degree_and_eigenvector_is_deprecated():
    graph = sparse.csr_array(np.array([[0, 2.0, 0], [2.0, 0, 1.0], [0, 1.0, 0]]))
    with pytest.warns(FutureWarning, match=r"use degree\(strengths=True\)"):  # (as every rename)
        old = cen.degree(graph, weights=True)
    np.testing.assert_allclose(old, cen.degree(graph, strengths=True))
    np.testing.assert_allclose(old, [2, 3, 1])
    with pytest.warns(FutureWarning, match="strengths"):
        old = cen.eigenvector(graph, weights=True)
    np.testing.assert_allclose(old, cen.eigenvector(graph, strengths=True))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cen.degree(graph, weights=False)  # the unweighted default means the same either way


def test_katz_refuses_alpha_beyond_the_spectral_radius():
    path = sparse.csr_array(np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]]))  # lambda_max = sqrt 2
    with pytest.raises(ValueError, match="`alpha` must be below 1 / .* = 0.707107"):
        cen.katz(path, alpha=0.8)


def _holey_image():
    yy, xx = np.mgrid[:24, :30]
    image = (yy - 12) ** 2 / 130 + (xx - 15) ** 2 / 200 <= 1.0
    image[8:16, 10:13] = False
    image[5, 3:25] = False
    return image


def test_fifo_queue_kernel_matches_heap_dijkstra_on_pixel_graphs():
    graph, _ = pixel_graph(_holey_image())
    prep = cen._api._prepare(graph, reorder=False)
    kind, lengths = _kernels.length_classes(prep.data)
    np.testing.assert_array_equal(lengths, [1.0, np.sqrt(2.0)])
    sources = np.arange(prep.n, dtype=np.int64)
    fifo = _kernels.class_stats(prep.indptr, prep.indices, kind, lengths, sources, *_kernels.NO_GRID)
    heap = _kernels.dijkstra_stats(prep.indptr, prep.indices, prep.data, sources)
    for a, b in zip(fifo, heap):
        np.testing.assert_allclose(a, b, rtol=1e-12)
    plain, n_log, _ = _kernels.class_brandes(
        prep.indptr, prep.indices, kind, lengths, sources, 1e-10, False, False, *_kernels.NO_GRID, np.ones(sources.size)
    )
    logs, n_logs, _ = _kernels.class_brandes(
        prep.indptr, prep.indices, kind, lengths, sources, 1e-10, True, False, *_kernels.NO_GRID, np.ones(sources.size)
    )
    ref, _ = _kernels.brandes(prep.indptr, prep.indices, prep.data, sources, True, 1e-10, False)
    assert n_log == 0 and n_logs == prep.n
    np.testing.assert_allclose(plain, ref, rtol=1e-10)
    np.testing.assert_allclose(logs, ref, rtol=1e-9)


def test_weighted_strip_betweenness_is_symmetric_and_adds_up():
    graph, _ = pixel_graph(np.ones((4, 300), dtype=bool))
    values = cen.betweenness(graph, weights=True).reshape(4, 300)
    np.testing.assert_allclose(values, values[::-1, ::-1], rtol=1e-9)
    np.testing.assert_allclose(values, values[:, ::-1], rtol=1e-9)


@pytest.mark.parametrize("weights", [False, True])
def test_eccentricity_bounds_are_exact_with_few_searches(weights):
    image = _holey_image()
    graph, _ = pixel_graph(image)
    exact = cen.eccentricity(graph, weights=weights, method="all")
    values, info = cen.eccentricity(graph, weights=weights, method="bounds", return_info=True)
    np.testing.assert_allclose(values, exact, rtol=1e-12)
    assert info["searches"] < graph.shape[0] / 4
    # A disconnected graph with an isolated node.
    two = sparse.block_diag([graph, sparse.csr_array((1, 1)), graph]).tocsr()
    np.testing.assert_allclose(
        cen.eccentricity(two, weights=weights, method="bounds"), np.r_[exact, 0, exact], rtol=1e-12
    )


def test_eigenvector_of_long_thin_graphs_is_exact():
    # (its speed, 27.7 s -> 0.2 s, is measured in benchmarks/centrality.py --scale, not here)
    n = 10_000
    path = sparse.diags_array([np.ones(n - 1), np.ones(n - 1)], offsets=[-1, 1], format="csr")
    values = cen.eigenvector(path, normalized=False)
    k = np.arange(1, n + 1)
    exact = np.sin(np.pi * k / (n + 1))
    np.testing.assert_allclose(values, exact / np.linalg.norm(exact), atol=1e-9)


def test_eccentricity_auto_falls_back_when_the_bounds_do_not_meet():
    from centrality_vision.graphs import delaunay_graph

    graph = delaunay_graph(np.random.default_rng(0).random((4200, 2)))  # hop eccentricities: few values
    values, info = cen.eccentricity(graph, return_info=True)
    np.testing.assert_array_equal(values, cen.eccentricity(graph, method="all"))
    assert info["searches"] == 4200 // 32 + int(np.ceil(4200 / 64))  # the budget, then 64-source groups


def test_fifo_kernel_property_random_masks():
    """On random small masks the exact FIFO betweenness equals the exact-arithmetic reference."""
    from hypothesis.extra.numpy import arrays

    from tests.centrality.test_centrality import _exact_weighted_betweenness

    @settings(max_examples=10, deadline=None)
    @given(arrays(np.bool_, (7, 8), elements=st.booleans()))
    def check(image):
        if image.sum() < 2:
            return
        graph, _ = pixel_graph(image)
        np.testing.assert_allclose(
            cen.betweenness(graph, weights=True), _exact_weighted_betweenness(image), rtol=1e-9, atol=1e-9
        )
        prep = cen._api._prepare(graph, reorder=False)
        classes = _kernels.length_classes(prep.data)
        if classes is not None:
            sources = np.arange(prep.n, dtype=np.int64)
            fifo = _kernels.class_stats(prep.indptr, prep.indices, *classes, sources, *_kernels.NO_GRID)
            heap = _kernels.dijkstra_stats(prep.indptr, prep.indices, prep.data, sources)
            for a, b in zip(fifo, heap):
                np.testing.assert_allclose(a, b, rtol=1e-12)

    check()


def test_katz_default_alpha_works_on_dense_graphs():
    # lambda_max = 29 on K30: networkx's alpha = 0.1 diverges, the default falls back to 0.9 / 29
    complete = sparse.csr_array(np.ones((30, 30)) - np.eye(30))
    values = cen.katz(complete, normalized=False)
    np.testing.assert_allclose(values, np.full(30, 1.0 / (1.0 - 0.9)), rtol=1e-10)
    sparse_path = sparse.csr_array(np.diag(np.ones(4), 1) + np.diag(np.ones(4), -1))
    np.testing.assert_allclose(cen.katz(sparse_path), cen.katz(sparse_path, alpha=0.1))

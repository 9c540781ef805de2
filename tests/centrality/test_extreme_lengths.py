"""Centralities of graphs whose edge lengths sit near float64's limits: exact, or a named error.

Sums of lengths of 1e308 overflowed (every distance inf, so every path tied: betweenness 0
on a path) and subnormal lengths overflowed their inverses; the searches now run on the
lengths divided by a power of two and scale back, and a value beyond float64 is refused.
"""

import math

import networkx as nx
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy import sparse

from centrality_vision import centrality as cen
from centrality_vision.exceptions import InputError
from centrality_vision.graphs import delaunay_graph


def _path(n, length=1.0):
    return sparse.csr_array(nx.to_scipy_sparse_array(nx.path_graph(n)).astype(float) * length)


def test_a_path_of_1e308_edges():
    unit, huge = _path(4), _path(4, 1e308)
    np.testing.assert_array_equal(cen.betweenness(huge, weights=True), cen.betweenness(unit, weights=True))
    np.testing.assert_array_equal(cen.edge_betweenness(huge, weights=True).data, cen.edge_betweenness(unit).data)
    np.testing.assert_allclose(cen.closeness(huge, weights=True), cen.closeness(unit, weights=True) / 1e308)
    with pytest.raises(InputError, match=r"`graph` has distances beyond float64"):
        cen.eccentricity(huge, weights=True)  # 3e308
    with pytest.raises(InputError, match=r"`graph` has node strengths beyond float64"):
        cen.degree(huge, strengths=True)  # 2e308
    big = _path(4, 4e307)  # 1.2e308: still a float64
    np.testing.assert_allclose(cen.eccentricity(big, weights=True), [1.2e308, 8e307, 8e307, 1.2e308])
    np.testing.assert_allclose(cen.eccentricity(big, weights=True, method="all"), [1.2e308, 8e307, 8e307, 1.2e308])
    np.testing.assert_allclose(cen.degree(big, strengths=True), [4e307, 8e307, 8e307, 4e307])


def test_subnormal_lengths():
    points = np.random.default_rng(0).random((30, 2))
    plain = delaunay_graph(points)
    tiny = delaunay_graph(points * 1e-306)
    np.testing.assert_allclose(cen.harmonic(tiny, weights=True), cen.harmonic(plain, weights=True) / 1e-306)
    np.testing.assert_allclose(cen.closeness(tiny, weights=True), cen.closeness(plain, weights=True) / 1e-306)
    tinier = delaunay_graph(points * 1e-310)  # inverse distances of about 1e311
    for measure in (cen.harmonic, cen.closeness):
        with pytest.raises(InputError, match=r"`graph` has inverse distances beyond float64"):
            measure(tinier, weights=True)
    np.testing.assert_array_equal(cen.degree(_path(4, 1e-320), strengths=True), [1e-320, 2e-320, 2e-320, 1e-320])
    # PageRank's transitions do not depend on the values' scale
    expected = cen.pagerank(_path(4), strengths=True)
    for length in (1e-320, 1e-300, 1e300, 1e308):
        np.testing.assert_allclose(cen.pagerank(_path(4, length), strengths=True), expected, rtol=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(2, 25),
    p=st.floats(0.1, 0.9),
    seed=st.integers(0, 2**16),
    exponent=st.integers(-1060, 1015),
)
def test_a_power_of_two_scales_every_length_result_exactly(n, p, seed, exponent):
    graph = nx.gnp_random_graph(n, p, seed=seed)
    rng = np.random.default_rng(seed)
    for u, v in graph.edges:
        graph[u][v]["weight"] = float(rng.integers(1, 4))  # integer lengths: plenty of ties
    base = sparse.csr_array(nx.to_scipy_sparse_array(graph))
    scale = math.ldexp(1.0, exponent)
    scaled = base * scale
    np.testing.assert_array_equal(cen.betweenness(scaled, weights=True), cen.betweenness(base, weights=True))
    np.testing.assert_array_equal(
        cen.edge_betweenness(scaled, weights=True).data, cen.edge_betweenness(base, weights=True).data
    )
    reach = cen.eccentricity(base, weights=True) * scale
    if np.all(np.isfinite(reach)):
        np.testing.assert_array_equal(cen.eccentricity(scaled, weights=True), reach)
    inverse = cen.closeness(base, weights=True) / scale
    if np.all(np.isfinite(inverse)) and np.all(inverse[inverse > 0] > 1e-300):  # no subnormal rounding
        np.testing.assert_allclose(cen.closeness(scaled, weights=True), inverse, rtol=1e-14)


def test_katz_with_a_large_beta():
    path = _path(3)
    np.testing.assert_allclose(cen.katz(path, beta=1e308), cen.katz(path))  # normalised: beta cancels
    np.testing.assert_allclose(cen.katz(path, beta=1e300, normalized=False), 1e300 * cen.katz(path, normalized=False))
    complete = sparse.csr_array(nx.to_scipy_sparse_array(nx.complete_graph(5)).astype(float))
    with pytest.raises(InputError, match=r"`beta` = 1e\+308 puts Katz centralities beyond float64"):
        cen.katz(complete, alpha=0.2, beta=1e308, normalized=False)  # 5e308
    with pytest.raises(InputError, match=r"`alpha` must be below"):
        cen.katz(path, alpha=1e308)  # (a RuntimeWarning first)


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 20), seed=st.integers(0, 2**16), exponent=st.integers(-1000, 1023))
@example(n=15, seed=1, exponent=1023)
@example(n=15, seed=1, exponent=1019)
def test_katz_strengths_scale_with_alpha(n, seed, exponent):
    # Strengths times 2**e with alpha times 2**-e is the same system, up to float64's
    # limits (strengths near 1e308 overflowed the row sums; 1e307 failed in LAPACK).
    graph = nx.gnp_random_graph(n, 0.5, seed=seed)
    rng = np.random.default_rng(seed)
    for u, v in graph.edges:
        graph[u][v]["weight"] = float(rng.uniform(0.5, 1.9))
    base = sparse.csr_array(nx.to_scipy_sparse_array(graph))
    scaled = base * math.ldexp(1.0, exponent)
    expected = cen.katz(base, strengths=True, alpha=0.01)
    np.testing.assert_allclose(
        cen.katz(scaled, strengths=True, alpha=math.ldexp(0.01, -exponent)), expected, rtol=1e-12
    )
    top = cen.katz(scaled, strengths=True)  # the default never fails or warns
    assert np.all(np.isfinite(top)) and np.all(top > 0)
    if graph.number_of_edges():
        with pytest.raises(InputError, match=r"`alpha` must be below 1 / \(largest eigenvalue"):
            cen.katz(scaled, strengths=True, alpha=math.ldexp(2.0 * n, -exponent))


@pytest.mark.parametrize("scale", [1.0, 1e-13, 1e-200])
def test_a_directed_graph_of_small_lengths_stays_directed(scale):
    # asymmetries below 1e-12 of the largest length (or of 1) were taken for rounding: the
    # arcs then counted as edges, closeness came out swapped and betweenness halved
    arcs = sparse.csr_array(np.array([[0.0, 1.0], [3.0, 0.0]]) * scale)  # 0 -> 1: 1, 1 -> 0: 3
    np.testing.assert_allclose(cen.closeness(arcs, weights=True) * scale, [1 / 3, 1.0], rtol=1e-12)
    np.testing.assert_allclose(cen.harmonic(arcs, weights=True) * scale, [1 / 3, 1.0], rtol=1e-12)
    triangle = sparse.csr_array(np.array([[0, 1, 3], [1, 0, 1], [1.5, 1, 0.0]]) * scale)
    np.testing.assert_array_equal(cen.betweenness(triangle, weights=True), [0.0, 1.0, 0.0])
    with pytest.raises(InputError, match="symmetric"):
        cen.eigenvector(arcs, strengths=True)


def test_short_arcs_beside_a_long_edge_stay_directed():
    lengths = np.array([[0, 1e6, 0], [1e6, 0, 1e-7], [0, 5e-7, 0]])  # 1 -> 2: 1e-7, 2 -> 1: 5e-7
    expected = nx.harmonic_centrality(nx.from_numpy_array(lengths, create_using=nx.DiGraph), distance="weight")
    ours = cen.harmonic(sparse.csr_array(lengths), weights=True)
    np.testing.assert_allclose(ours, [expected[i] for i in range(3)], rtol=1e-12)
    np.testing.assert_allclose(ours, [2e-6, 2e6, 1e7], rtol=1e-6)  # paths into each node


def _tied_square(extra_component):
    # 0-1-2 is 2 long and 0-3-2 is 2 + 1e-9: not a tie (ties are within 1e-10)
    rows, cols, lengths, n = [0, 1, 0, 3], [1, 2, 3, 2], [1.0, 1.0, 1.0 + 5e-10, 1.0 + 5e-10], 4
    if extra_component:  # a separate path with nine other lengths
        rows += list(range(4, 13))
        cols += list(range(5, 14))
        lengths += [2.0 + 0.37 * i for i in range(9)]
        n = 14
    half = sparse.coo_array((lengths, (rows, cols)), shape=(n, n))
    return sparse.csr_array(half + half.T)


def test_a_components_centralities_do_not_depend_on_the_lengths_of_another():
    # with at most 8 distinct lengths, lengths within 1e-9 were merged into one: the square's
    # two paths tied, and its distances were rounded down, until another component added lengths
    alone, beside = _tied_square(False), _tied_square(True)
    graph = nx.from_scipy_sparse_array(alone)
    expected = nx.betweenness_centrality(graph, weight="weight", normalized=False)
    np.testing.assert_array_equal(cen.betweenness(alone, weights=True), [expected[i] for i in range(4)])
    np.testing.assert_array_equal(cen.betweenness(beside, weights=True)[:4], cen.betweenness(alone, weights=True))
    closeness = nx.closeness_centrality(graph, distance="weight")
    np.testing.assert_allclose(cen.closeness(alone, weights=True), [closeness[i] for i in range(4)], rtol=1e-15, atol=0)


def test_hop_counts_do_not_read_lengths_beyond_float64s_range_of_one_another():
    # found by fuzz round 16: a path with lengths 1e300 and 1e-300 was refused by every hop
    # count centrality, whose values never depend on the lengths
    wide = sparse.csr_array(np.array([[0, 1e300, 0], [1e300, 0, 1e-300], [0, 1e-300, 0]]))
    unit = _path(3)
    for name in ("betweenness", "closeness", "harmonic", "eccentricity"):
        np.testing.assert_array_equal(getattr(cen, name)(wide), getattr(cen, name)(unit), err_msg=name)
    np.testing.assert_array_equal(cen.edge_betweenness(wide).toarray(), cen.edge_betweenness(unit).toarray())
    np.testing.assert_array_equal(cen.closeness(wide, epsilon=0.5, seed=0), cen.closeness(unit, epsilon=0.5, seed=0))
    with pytest.raises(InputError, match="within float64's range of one another"):
        cen.closeness(wide, weights=True)  # the lengths are read: still refused


def test_an_int_beyond_float64_as_a_length_or_spacing_is_refused_by_name():
    """Ints of more than 308 digits raised a bare OverflowError from the conversion to float,
    which `except (ValueError, TypeError)` does not catch."""
    from centrality_vision.graphs import pixel_graph

    huge = 10**400
    path = nx.path_graph(3)
    path[0][1]["weight"] = huge
    with pytest.raises(InputError, match=r"`graph` must have finite edge lengths \('weight'\); got an int beyond"):
        cen.closeness(path, weights=True)
    with pytest.raises(InputError, match=r"`graph` must hold finite edge lengths; got an int beyond float64"):
        cen.closeness([[0, huge], [huge, 0]])
    with pytest.raises(InputError, match=r"`spacing` must be 2 positive finite numbers; got an int beyond"):
        pixel_graph(np.ones((2, 2), dtype=bool), spacing=(huge, 1))

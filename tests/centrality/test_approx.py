"""Sampling approximations: the stated error bound holds against exact values."""

import numpy as np
import pytest
from scipy import sparse

import centrality_vision as cv
from centrality_vision import centrality as cen
from centrality_vision.centrality import _approx
from centrality_vision.graphs import delaunay_graph, pixel_graph


@pytest.fixture(scope="module")
def graphs():
    yy, xx = np.mgrid[:32, :32]
    disk = (yy - 15.5) ** 2 + (xx - 15.5) ** 2 < 15**2
    disk[12:16, 6:22] = False  # a slot, so that paths bend
    pixel, _ = pixel_graph(disk)
    tri = delaunay_graph(np.random.default_rng(1).random((600, 2)))
    return {"pixel": pixel, "delaunay": tri}


@pytest.mark.parametrize("name", ["pixel", "delaunay"])
def test_sampled_betweenness_error_is_below_epsilon(graphs, name):
    graph = graphs[name]
    exact = cen.betweenness(graph, normalized=True)
    epsilon = 0.02
    approx, info = cen.betweenness(graph, normalized=True, epsilon=epsilon, seed=0, return_info=True)
    assert np.abs(approx - exact).max() < epsilon
    assert 0 < info["samples"] and info["bound"] <= epsilon
    # Unnormalised values carry the same bound times the number of pairs.
    n = graph.shape[0]
    raw = cen.betweenness(graph, epsilon=epsilon, seed=0)
    np.testing.assert_allclose(raw, approx * (n - 1) * (n - 2) / 2)


def test_sampled_betweenness_is_seeded_and_thread_independent(graphs):
    graph = graphs["delaunay"]
    try:
        cv.set_num_threads(1)
        one = cen.betweenness(graph, epsilon=0.05, seed=3)
        cv.set_num_threads(3)
        three = cen.betweenness(graph, epsilon=0.05, seed=3)
    finally:
        cv.set_num_threads(None)
    np.testing.assert_array_equal(one, three)
    assert not np.array_equal(one, cen.betweenness(graph, epsilon=0.05, seed=4))


def test_sampled_paths_are_uniform_on_a_diamond():
    # 0 -> {1, 2} -> 3: the two shortest 0-3 paths must be drawn equally often.
    graph = sparse.csr_array(np.array([[0, 1, 1, 0], [1, 0, 0, 1], [1, 0, 0, 1], [0, 1, 1, 0]], float))
    exact = cen.betweenness(graph, normalized=True)  # 0.5 each for 1 and 2
    approx = cen.betweenness(graph, normalized=True, epsilon=0.02, seed=0)
    np.testing.assert_allclose(approx, exact, atol=0.02)


def test_rk_sample_size_formula():
    # c / eps^2 (floor(log2(VD - 2)) + 1 + ln(1 / delta)) with c = 0.5
    assert _approx.rk_sample_size(34, 0.1, 0.1) == int(np.ceil(0.5 / 0.01 * (5 + 1 + np.log(10))))


@pytest.mark.parametrize("name", ["pixel", "delaunay"])
def test_sampled_harmonic_and_closeness_meet_their_bounds(graphs, name):
    graph = graphs[name]
    n = graph.shape[0]
    epsilon = 0.1
    exact_h = cen.harmonic(graph, normalized=True)
    approx_h, info = cen.harmonic(graph, normalized=True, epsilon=epsilon, seed=0, return_info=True)
    assert info["samples"] < n  # really sampled
    assert np.abs(approx_h - exact_h).max() < epsilon
    # Closeness: the estimated sum of distances / n is within epsilon * the diameter.
    diameter = cen.eccentricity(graph).max()
    exact_sum = (n - 1) / cen.closeness(graph)
    approx_sum = (n - 1) / cen.closeness(graph, epsilon=epsilon, seed=0)
    assert np.abs(approx_sum - exact_sum).max() / n < epsilon * diameter


def test_small_epsilon_falls_back_to_exact(graphs):
    graph = graphs["pixel"]
    values, info = cen.harmonic(graph, epsilon=0.001, seed=0, return_info=True)
    assert info["samples"] == graph.shape[0]
    np.testing.assert_allclose(values, cen.harmonic(graph))


@pytest.mark.parametrize("epsilon", [1e-4, 1e-20, 1e-160, 1e-300])
@pytest.mark.parametrize("measure", ["closeness", "harmonic", "betweenness"])
def test_a_tiny_epsilon_gives_exact_values(graphs, measure, epsilon):
    """Sample sizes of 1 / epsilon^2 underflowed (ZeroDivisionError), overflowed int()
    (OverflowError) or passed numpy's largest array (betweenness drew them all up front)."""
    graph = graphs["delaunay"]
    function = getattr(cen, measure)
    values, info = function(graph, epsilon=epsilon, seed=0, return_info=True)
    np.testing.assert_allclose(values, function(graph), rtol=1e-12)
    assert info["samples"] == (0 if measure == "betweenness" else graph.shape[0])


def test_sampled_pairs_beyond_the_cap_are_refused_by_name():
    """More pairs than the cap, but fewer than the graph has (4e8): 6e7 pairs would take
    1.4 GiB before the first search."""
    graph = delaunay_graph(np.random.default_rng(0).random((20_000, 2)))
    with pytest.raises(ValueError, match=r"`epsilon`=0.0003 asks for up to .* sampled pairs"):
        cen.betweenness(graph, epsilon=3e-4)


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"epsilon": 0.0}, ValueError, "`epsilon` must be in"),
        ({"epsilon": 1.5}, ValueError, "`epsilon`"),
        ({"epsilon": 0.1, "delta": 1.0}, ValueError, "`delta` must be in"),
        ({"epsilon": 0.1, "weights": True}, ValueError, "hop counts only"),
        ({"epsilon": 0.1, "seed": "x"}, TypeError, "`seed`"),
    ],
)
def test_bad_approximation_options(graphs, options, error, match):
    with pytest.raises(error, match=match):
        cen.betweenness(graphs["pixel"], **options)

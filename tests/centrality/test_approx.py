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

"""Betweenness on pixel graphs walked on the grid, with the mask's symmetries."""

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy import sparse

import centrality_vision as cv
from centrality_vision import centrality as cen
from centrality_vision.centrality._grid import mask_symmetries
from centrality_vision.graphs import PixelGraph, pixel_graph


def _disk(radius):
    y, x = np.mgrid[-radius : radius + 1, -radius : radius + 1]
    return x * x + y * y <= radius * radius


def _plain(graph):
    """The same adjacency as an ordinary csr_array: the adjacency-list kernels."""
    return sparse.csr_array(graph)


def _close(a, b):
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * max(1.0, float(np.max(b))))


@settings(max_examples=40, deadline=None)
@given(
    mask=arrays(bool, st.tuples(st.integers(1, 9), st.integers(1, 9))),
    connectivity=st.sampled_from([4, 8]),
    mirror=st.sampled_from([None, 0, 1, "both", "transpose"]),
    spacing=st.sampled_from([None, (1.0, 1.5)]),
)
def test_grid_equals_adjacency_lists_on_any_mask(mask, connectivity, mirror, spacing):
    # Symmetric masks (made so half the time) take the orbit path; others the plain grid path.
    if mirror in (0, 1):
        mask = mask | np.flip(mask, mirror)
    elif mirror == "both":
        mask = mask | mask[::-1] | mask[:, ::-1] | mask[::-1, ::-1]
    elif mirror == "transpose":
        k = min(mask.shape)
        mask = mask[:k, :k] | mask[:k, :k].T
    if not mask.any():
        return
    # lengths: 1 (4-neighbour), 1 and sqrt 2 (8-neighbour), 1 and 1.5 (4-neighbour with
    # spacing), three lengths (8-neighbour with spacing): the two-length kernel and the
    # general one, against the adjacency lists
    graph, _ = pixel_graph(mask, connectivity=connectivity, spacing=spacing)
    _close(cen.betweenness(graph, normalized=True), cen.betweenness(_plain(graph), normalized=True))
    _close(cen.betweenness(graph, weights=True), cen.betweenness(_plain(graph), weights=True))
    for name in ("closeness", "harmonic", "eccentricity"):
        _close(cen.compute(graph, name, weights=True), cen.compute(_plain(graph), name, weights=True))


@pytest.mark.parametrize("connectivity", [26, 18, 6])
def test_grid_equals_adjacency_lists_in_3d(connectivity):
    rng = np.random.default_rng(4)
    volume = rng.random((5, 6, 7)) > 0.35
    symmetric = np.ones((4, 4, 4), dtype=bool)
    symmetric[1:3, 1:3, 1:3] = False
    for mask in (volume, symmetric):
        for spacing in (None, (1.0, 2.0, 0.5)):
            graph, _ = pixel_graph(mask, connectivity=connectivity, spacing=spacing)
            _close(cen.betweenness(graph), cen.betweenness(_plain(graph)))
            for name in ("betweenness", "closeness", "harmonic"):
                _close(cen.compute(graph, name, weights=True), cen.compute(_plain(graph), name, weights=True))


def test_anisotropic_spacing_keeps_only_the_isometries():
    graph, _ = pixel_graph(_disk(6), spacing=(1.0, 1.5))
    values, info = cen.betweenness(graph, weights=True, return_info=True)
    assert info["symmetries"] == 4  # the flips; the transposes would swap the spacings
    _close(values, cen.betweenness(_plain(graph), weights=True))
    _, info = cen.betweenness(graph, return_info=True)
    assert info["symmetries"] == 8  # hop counts do not see the spacing


def test_grid_agrees_with_networkx():
    mask = np.zeros((7, 9), dtype=bool)
    mask[1:6, 1:8] = True
    mask[3, 2:7] = False  # a hole: two routes around it
    graph, _ = pixel_graph(mask)
    ref = nx.betweenness_centrality(nx.from_scipy_sparse_array(_plain(graph)), normalized=False)
    _close(cen.betweenness(graph), np.array([ref[i] for i in range(graph.shape[0])]))


@pytest.mark.parametrize(
    ("mask", "count"),
    [
        (np.ones((3, 3), dtype=bool), 8),  # the square's dihedral group
        (np.ones((2, 5), dtype=bool), 4),  # a rectangle: its flips
        (np.array([[1, 1, 1], [1, 0, 0]], dtype=bool), 1),  # an L: none
        (np.array([[1, 1], [1, 0]], dtype=bool), 2),  # identity and transpose
        (np.array([[0, 1, 0], [1, 1, 1]], dtype=bool), 2),  # a T: one mirror
        (np.ones((2, 2, 2), dtype=bool), 48),  # the cube's group
    ],
)
def test_mask_symmetries_counts_the_maps(mask, count):
    found = mask_symmetries(mask)
    assert len(found) == count
    assert found[0] == (tuple(range(mask.ndim)), ())
    for axes, flipped in found:  # every map found maps the mask onto itself
        moved = np.transpose(mask, axes)
        assert np.array_equal(np.flip(moved, flipped) if flipped else moved, mask)


def test_disk_needs_one_search_per_orbit():
    mask = _disk(12)
    graph, _ = pixel_graph(mask)
    values, info = cen.betweenness(graph, return_info=True)
    n = graph.shape[0]
    assert info["symmetries"] == 8
    # Orbits of the dihedral group: n / 8 plus the fixed axes' extra ones.
    assert n / 8 <= info["searches"] <= n / 8 + 2 * 12 + 2
    _close(values, cen.betweenness(_plain(graph)))
    # Symmetric values: the centre is the largest and mirror pixels agree.
    image = np.zeros(mask.shape)
    image[mask] = values
    np.testing.assert_allclose(image, image[::-1], rtol=1e-12)
    np.testing.assert_allclose(image, image.T, rtol=1e-12)
    assert image[12, 12] == image.max()


def test_overflowing_counts_fall_back_to_logarithms():
    mask = np.ones((5, 1100), dtype=bool)  # more than 1e300 shortest paths end to end
    mask[2, 500] = False
    graph, _ = pixel_graph(mask)
    for weights in (False, True):
        values, info = cen.betweenness(graph, normalized=True, weights=weights, return_info=True)
        # By length the straight paths win and counts stay small; by hops they overflow.
        assert (info["log_searches"] > 0) != weights and info["symmetries"] == 2
        assert np.all(np.isfinite(values))
        _close(values, cen.betweenness(_plain(graph), normalized=True, weights=weights))


def test_edited_pixel_graph_is_treated_as_a_plain_graph():
    graph, _ = pixel_graph(np.ones((6, 6), dtype=bool))
    assert graph.matches_mask()
    expected = cen.betweenness(_plain(graph))
    graph.data[:] = 2.0  # edited in place: lengths no longer the mask's
    assert not graph.matches_mask()
    _close(cen.betweenness(graph), expected)  # hop counts: same graph, plain path
    cut = graph.copy()
    cut.data[0] = 0.0
    cut.eliminate_zeros()  # structure edited: one edge fewer
    assert cut.mask is None and not cut.matches_mask()
    _, info = cen.betweenness(cut, return_info=True)
    assert "symmetries" not in info


def test_pixel_graph_is_a_csr_array_that_remembers_its_mask():
    mask = _disk(3)
    graph, _ = pixel_graph(mask, spacing=(2.0, 1.0))
    assert isinstance(graph, sparse.csr_array) and isinstance(graph, PixelGraph)
    assert np.array_equal(graph.mask, mask) and graph.connectivity == 8
    np.testing.assert_array_equal(graph.spacing, [2.0, 1.0])
    with pytest.raises(ValueError):
        graph.mask[0, 0] = True  # read-only
    mask[0, 0] = not mask[0, 0]  # the caller's array is a different one
    assert graph.matches_mask()
    assert (graph @ graph).mask is None


def test_grid_results_do_not_depend_on_thread_count():
    graph, _ = pixel_graph(_disk(9) & (np.arange(19)[:, None] > 3))  # one mirror axis
    try:
        cv.set_num_threads(1)
        single = cen.betweenness(graph)
        cv.set_num_threads(3)
        multi = cen.betweenness(graph)
    finally:
        cv.set_num_threads(None)
    np.testing.assert_array_equal(multi, single)


def test_sampled_betweenness_on_the_grid_keeps_its_bound():
    mask = _disk(14)
    mask[:3, 10:] = True  # no symmetry
    graph, _ = pixel_graph(mask)
    exact = cen.betweenness(graph, normalized=True)
    try:
        cv.set_num_threads(1)
        single, info = cen.betweenness(graph, normalized=True, epsilon=0.03, seed=5, return_info=True)
        cv.set_num_threads(3)
        multi = cen.betweenness(graph, normalized=True, epsilon=0.03, seed=5)
    finally:
        cv.set_num_threads(None)
    np.testing.assert_array_equal(single, multi)  # the thread count changes nothing
    assert np.abs(single - exact).max() <= info["bound"] <= 0.03
    # Same estimator as on the adjacency lists: the same guarantee, other draws.
    plain = cen.betweenness(_plain(graph), normalized=True, epsilon=0.03, seed=5)
    assert np.abs(plain - exact).max() <= 0.03


def _rebuilt_equal(graph):
    """The slow definition of PixelGraph.matches_mask: rebuild and compare."""
    fresh, _ = pixel_graph(graph.mask, connectivity=graph.connectivity, spacing=graph.spacing)
    return bool(
        graph.shape == fresh.shape
        and np.array_equal(graph.indptr, fresh.indptr)
        and np.array_equal(graph.indices, fresh.indices)
        and np.array_equal(graph.data, fresh.data)
    )


@settings(max_examples=60, deadline=None)
@given(
    mask=arrays(bool, st.one_of(st.tuples(st.integers(1, 7), st.integers(1, 7)), st.tuples(*[st.integers(1, 4)] * 3))),
    full=st.booleans(),
    spacing=st.booleans(),
    edit=st.sampled_from([None, "length", "neighbour", "drop", "spacing"]),
    data=st.data(),
)
def test_matches_mask_agrees_with_rebuilding_the_graph(mask, full, spacing, edit, data):
    if not mask.any():
        mask.flat[0] = True
    connectivity = {2: (8, 4), 3: (26, 6)}[mask.ndim][0 if full else 1]
    spacings = (1.0, 2.5, 0.7)[: mask.ndim] if spacing else None
    graph, _ = pixel_graph(mask, connectivity=connectivity, spacing=spacings)
    assert graph.matches_mask()
    if edit is not None and graph.nnz:
        k = data.draw(st.integers(0, graph.nnz - 1))
        if edit == "length":
            graph.data[k] = graph.data[k] * (1 + 1e-15) + 1e-300
        elif edit == "neighbour":
            graph.indices[k] = (graph.indices[k] + 1) % graph.shape[0]
        elif edit == "drop":
            graph.data[k] = 0.0
            graph.eliminate_zeros()  # in place on this PixelGraph: one edge fewer
        else:
            graph.spacing = None if spacing else np.full(mask.ndim, 1.5)
    assert graph.matches_mask() == _rebuilt_equal(graph)


@pytest.mark.parametrize(
    ("spacing", "mask"),
    [
        ((1e-200, 0.5), np.ones((2, 3), dtype=bool)),
        ((0.5, 1e-200), np.ones((3, 3), dtype=bool)),
        ((3.0, 1e-160), np.array([[0, 0], [1, 1], [0, 0]], dtype=bool)),
        ((1e200, 1e-3), np.eye(3, dtype=bool)),
        ((1e-3, 1e200), np.eye(4, dtype=bool)),
    ],
)
def test_extreme_spacings_give_the_adjacency_lists_values(spacing, mask):
    # the grid squared the spacing itself: at 1e-200 every step length was 0 (betweenness
    # raised a TypeError), at 1e-160 closeness was 5.6e-6 off, at 1e200 lengths overflowed
    graph, _ = pixel_graph(mask, spacing=spacing)
    plain = _plain(graph)
    for measure in (cen.closeness, cen.harmonic, cen.eccentricity):
        _close(measure(graph, weights=True), measure(plain, weights=True))
    _close(cen.closeness(graph, weights=True, normalized=False), cen.closeness(plain, weights=True, normalized=False))
    _close(cen.betweenness(graph), cen.betweenness(plain))
    if min(spacing) / max(spacing) > 1e-180:  # (edges of 1e-200 against 0.5 tie like zero-length ones)
        with pytest.warns(UserWarning, match="spacing's ratio"):  # (these small masks have no near-ties)
            on_grid = cen.betweenness(graph, weights=True)
        _close(on_grid, cen.betweenness(plain, weights=True))


def test_weighted_betweenness_warns_beyond_the_spacing_ratio_it_is_exact_at():
    """At a spacing ratio of 1e10 the grid path and the same graph's plain copy differed by
    238 (of about 2,000) and neither was exact, silently (audit 25)."""
    import warnings

    y, x = np.mgrid[-12:13, -9:10]
    mask = (x * x / 81 + y * y / 144) <= 1
    graph, _ = pixel_graph(mask, spacing=(1e-10, 1.0))
    with pytest.warns(UserWarning, match=r"spacing's ratio is 1e\+10; beyond about 10000, .* not exact"):
        cen.betweenness(graph, weights=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cen.betweenness(graph)  # hop counts do not depend on the spacing
        cen.betweenness(pixel_graph(mask, spacing=(1e-3, 1.0))[0], weights=True)

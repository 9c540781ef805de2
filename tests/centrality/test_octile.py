"""Distances by length on 8-neighbour pixel graphs: octile-visible pixels in closed form,
the rest by a search seeded from them, against the plain FIFO-queue search."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy import ndimage, sparse

from centrality_vision import centrality as cen
from centrality_vision.centrality._grid import _Grid, fifo_stats, grid_length_stats, two_length_stats
from centrality_vision.centrality._octile import OctileGrid
from centrality_vision.graphs import pixel_graph

SQRT2 = np.sqrt(2.0)
NAMES = ("total", "inverse", "largest", "reached")


def _both(mask, spacing=None, sources=None):
    """(octile kernel, plain search) statistics from ``sources`` (all pixels by default)."""
    graph, _ = pixel_graph(mask, connectivity=8, spacing=spacing)
    grid = _Grid(graph)
    octile = OctileGrid.of(grid, need_inverse=True)
    assert octile is not None
    raster = grid.raster if sources is None else grid.raster[sources]
    # the plain search: two lengths, or three (anisotropic spacing) by the general one
    return octile.stats(grid, raster, True), fifo_stats(grid, raster)


def _agree(fast, plain):
    for name, got, want in zip(NAMES, fast, plain):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12, err_msg=name)


def test_hand_computed_u_turn():
    # (row, col) from the top-left corner; the middle row only has its right pixel.
    #   X X X
    #   . . X
    #   X X X
    # Seen along octile paths from (0, 0): (0, 1) at 1, (0, 2) at 2, (1, 2) at 1 + sqrt 2.
    # Hidden: (2, 2) at 2 + sqrt 2 (not 2 sqrt 2), (2, 1) at 1 + 2 sqrt 2 (not 1 + sqrt 2),
    # (2, 0) at 2 + 2 sqrt 2 (not 2).
    mask = np.array([[1, 1, 1], [0, 0, 1], [1, 1, 1]], dtype=bool)
    graph, _ = pixel_graph(mask, connectivity=8)
    total, inverse, largest, reached = grid_length_stats(graph, False, "", True)
    distances = [1, 2, 1 + SQRT2, 2 + SQRT2, 1 + 2 * SQRT2, 2 + 2 * SQRT2]
    assert total[0] == pytest.approx(sum(distances), rel=1e-15)
    assert inverse[0] == pytest.approx(sum(1 / d for d in distances), rel=1e-15)
    assert largest[0] == pytest.approx(2 + 2 * SQRT2, rel=1e-15)
    assert reached[0] == 7  # itself included
    # without the inverse sums: zeros there, the rest unchanged
    total2, inverse2, largest2, reached2 = grid_length_stats(graph, False, "", False)
    assert not inverse2.any()
    np.testing.assert_array_equal(total2, total)
    np.testing.assert_array_equal(largest2, largest)
    np.testing.assert_array_equal(reached2, reached)


def test_convex_mask_needs_no_search_and_matches_octile_distances():
    # On a filled rectangle every pixel is seen: the sums are those of octile distances.
    mask = np.ones((7, 11), dtype=bool)
    fast, plain = _both(mask)
    _agree(fast, plain)
    rows, cols = np.nonzero(mask)
    dy = np.abs(rows[:, None] - rows[None, :])
    dx = np.abs(cols[:, None] - cols[None, :])
    octile = np.abs(dx - dy) + np.minimum(dx, dy) * SQRT2
    np.testing.assert_allclose(fast[0], octile.sum(axis=1), rtol=1e-13)
    np.testing.assert_allclose(fast[2], octile.max(axis=1), rtol=1e-15)


@settings(max_examples=60, deadline=None)
@given(
    mask=arrays(bool, st.tuples(st.integers(1, 12), st.integers(1, 12))),
    spacing=st.sampled_from([None, (2.5, 2.5), (0.3, 0.3), (1.0, 1.5), (0.7, 0.2), (2.0, 1.0)]),
)
def test_equals_the_plain_search_on_any_small_mask(mask, spacing):
    if not mask.any():
        return
    _agree(*_both(mask, spacing))


@pytest.mark.parametrize("seed", range(6))
def test_equals_the_plain_search_on_tall_masks(seed):
    # Several words per column (64 rows each): runs, fills and shifts cross word edges.
    rng = np.random.default_rng(seed)
    height, width = rng.integers(65, 260), rng.integers(20, 90)
    noise = ndimage.gaussian_filter(rng.random((height, width)), rng.uniform(1.0, 3.0))
    mask = noise > np.quantile(noise, rng.uniform(0.3, 0.6))
    sources = rng.choice(np.count_nonzero(mask), 40, replace=False)
    spacing = None if seed < 3 else (1.0, rng.uniform(0.3, 3.0))
    _agree(*_both(mask, spacing, sources=sources))


def test_corridor_across_word_edges():
    # A one-pixel corridor up 150 rows with pockets off it: the fill north carries
    # through two word edges, and the pockets are hidden behind the corridor's corners.
    mask = np.zeros((150, 9), dtype=bool)
    mask[:, 4] = True
    for row in (10, 63, 64, 65, 127, 128, 140):
        mask[row, 1:8] = True
    _agree(*_both(mask))


def test_parts_count_only_their_own_pixels():
    mask = np.zeros((9, 9), dtype=bool)
    mask[:3, :3] = True  # a square of 9
    mask[5:, 5] = True  # a bar of 4
    mask[5, 8] = True  # an isolated pixel
    fast, plain = _both(mask)
    _agree(fast, plain)
    np.testing.assert_array_equal(np.sort(fast[3]), [1] + [4] * 4 + [9] * 9)


def test_hand_computed_anisotropic_spacing():
    # Rows 1 apart, columns 2 apart: a step along a row is 2 long, along a column 1, a
    # diagonal sqrt 5. From the top-left pixel of a 2 x 3 block with its middle-bottom
    # pixel missing, (1, 2) is seen at 2 + sqrt 5 (one row step, one diagonal), and only
    # through (0, 1) or (0, 2); (1, 0) at 1 (a column step).
    mask = np.array([[1, 1, 1], [1, 0, 1]], dtype=bool)
    graph, _ = pixel_graph(mask, connectivity=8, spacing=(1.0, 2.0))
    total, _, largest, reached = grid_length_stats(graph, False, "", False)
    distances = [2, 4, 1, 2 + np.sqrt(5)]  # (0, 1), (0, 2), (1, 0), (1, 2)
    assert total[0] == pytest.approx(sum(distances), rel=1e-15)
    assert largest[0] == pytest.approx(2 + np.sqrt(5), rel=1e-15)
    assert reached[0] == 5


@pytest.mark.parametrize("spacing", [(1e6, 1.0), (1e12, 1.0), (1e200, 1.0), (1.0, 1e12)])
def test_very_unequal_spacings_keep_inverse_distances_exact(spacing):
    """The inverse-distance tables are prefix sums; with rows 1e12 apart and columns 1, the
    tiny terms cancelled in their differences: harmonic was 6.9e-6 off (1.9e-12 at 1e6)."""
    import networkx as nx

    mask = np.ones((4, 5), dtype=bool)
    mask[1, 1:4] = False
    graph, _ = pixel_graph(mask, connectivity=8, spacing=spacing)
    plain = nx.from_scipy_sparse_array(sparse.csr_array(graph.copy()))
    exact = [
        float(sum(1 / d for d in nx.single_source_dijkstra_path_length(plain, s, weight=_fraction).values() if d))
        for s in range(graph.shape[0])
    ]
    np.testing.assert_allclose(cen.harmonic(graph, weights=True), exact, rtol=1e-14)


def _fraction(u, v, data):
    """An edge's stored length as an exact fraction: the reference sums path lengths exactly."""
    from fractions import Fraction

    return Fraction(data["weight"])


def test_only_8_neighbour_2d_grids_take_the_kernel():
    disk = np.ones((5, 5), dtype=bool)
    cases = [
        (dict(connectivity=8), True),
        (dict(connectivity=8, spacing=(0.7, 0.7)), True),
        (dict(connectivity=8, spacing=(1.0, 1.5)), True),  # three lengths
        (dict(connectivity=4), False),
    ]
    for options, expected in cases:
        graph, _ = pixel_graph(disk, **options)
        assert (OctileGrid.of(_Grid(graph)) is not None) == expected, options
    graph, _ = pixel_graph(np.ones((3, 3, 3), dtype=bool), connectivity=26)
    assert OctileGrid.of(_Grid(graph)) is None


def test_closeness_harmonic_eccentricity_by_length_unchanged_through_the_api():
    rng = np.random.default_rng(7)
    mask = ndimage.gaussian_filter(rng.random((40, 50)), 2.0) > 0.5
    graph, _ = pixel_graph(mask, connectivity=8)
    plain = sparse.csr_array(graph)  # adjacency lists: the Dijkstra kernels
    for name in ("closeness", "harmonic", "eccentricity"):
        np.testing.assert_allclose(
            cen.compute(graph, name, weights=True), cen.compute(plain, name, weights=True), rtol=1e-12, err_msg=name
        )


def test_inverse_sums_from_tables_and_by_division_agree(monkeypatch):
    # Masks too wide for the tables of inverse distances divide pixel by pixel instead; the
    # prefix sums of the tables and the division agree to rounding.
    rng = np.random.default_rng(3)
    mask = ndimage.gaussian_filter(rng.random((70, 40)), 2.0) > 0.45
    graph, _ = pixel_graph(mask, connectivity=8)
    grid = _Grid(graph)
    tables = OctileGrid.of(grid, need_inverse=True)
    assert tables.tables[0].size > 0
    with_tables = tables.stats(grid, grid.raster, True)
    monkeypatch.setattr(OctileGrid, "_MAX_TABLE", 0)
    divided = OctileGrid.of(grid, need_inverse=True)
    assert divided.tables[0].size == 0
    by_division = divided.stats(grid, grid.raster, True)
    _agree(with_tables, by_division)
    plain = two_length_stats(grid.foreground, grid.offs, grid.kind, grid.lengths, grid.raster)
    _agree(by_division, plain)


@pytest.mark.parametrize("spacing", [None, (1.0, 1.5)])
def test_results_do_not_depend_on_thread_count(spacing):
    # Every source is one independent computation: the chunks change, the values do not.
    import centrality_vision as cv

    rng = np.random.default_rng(5)
    mask = ndimage.gaussian_filter(rng.random((60, 45)), 2.0) > 0.5
    graph, _ = pixel_graph(mask, connectivity=8, spacing=spacing)
    try:
        cv.set_num_threads(1)
        single = [cen.compute(graph, name, weights=True) for name in ("closeness", "harmonic")]
        cv.set_num_threads(3)
        multi = [cen.compute(graph, name, weights=True) for name in ("closeness", "harmonic")]
    finally:
        cv.set_num_threads(None)
    for a, b in zip(single, multi):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("seed", [1, 2])
def test_eccentricity_auto_by_length_gives_up_bounds_for_the_octile_search(seed):
    # 'auto' runs Takes-Kosters bounds for up to n / 16 searches, then the octile search
    # from every pixel: the largest part of a smoothed noise mask needs 120 bound searches
    # (seed 1, 1,505 pixels: falls back) or 57 (seed 2, 1,624 pixels: the bounds finish).
    rng = np.random.default_rng(seed)
    mask = ndimage.gaussian_filter(rng.random((60, 60)), 2.5) > 0.5
    labels, _ = ndimage.label(mask, np.ones((3, 3)))
    mask = labels == np.argmax(np.bincount(labels.ravel())[1:]) + 1
    graph, _ = pixel_graph(mask)
    n = graph.shape[0]
    bounds, bound_info = cen.eccentricity(graph, weights=True, method="bounds", return_info=True)
    auto, info = cen.eccentricity(graph, weights=True, return_info=True)
    every = cen.eccentricity(graph, weights=True, method="all")
    np.testing.assert_allclose(auto, bounds, rtol=1e-12)
    np.testing.assert_allclose(every, bounds, rtol=1e-12)
    if bound_info["searches"] > n // 16:
        assert info["searches"] == n // 16 + n
    else:
        assert info["searches"] == bound_info["searches"]
    assert (seed == 1) == (bound_info["searches"] > n // 16)  # both branches are covered

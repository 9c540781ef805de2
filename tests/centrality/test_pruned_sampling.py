"""The pruned path sampler of pixel grids: every drawn path is a shortest path, drawn
uniformly, whatever the mask, connectivity or dimension."""

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.sparse.csgraph import shortest_path

from centrality_vision import centrality as cen
from centrality_vision.centrality import _approx, _sampling
from centrality_vision.centrality._grid import _Grid
from centrality_vision.graphs import pixel_graph

EMPTY = np.empty(0, dtype=np.int64)
EMPTY32 = np.empty(0, dtype=np.int32)


def _setup(mask, connectivity, landmarks=True):
    graph, _ = pixel_graph(mask, connectivity=connectivity)
    grid = _Grid(graph)
    steps = np.array(grid.steps, dtype=np.int64)
    shape = np.array(grid.padded.shape, dtype=np.int64)
    reach = int(np.abs(steps).sum(axis=1).max())
    labels, marks, rasters = _approx._grid_guides(grid, reach)
    if not landmarks:
        marks = np.zeros((grid.foreground.size, 0), dtype=np.int32)
    return graph, grid, steps, shape, reach, labels, marks, rasters


def _draw(setup, pairs, seed=11, reach=None, counting=True):
    """Hits of one sample per row of ``pairs`` (node indices) in node order, the work and
    the retries; ``counting=False``: no pair's paths are counted directly."""
    graph, grid, steps, shape, own_reach, labels, marks, rasters = setup
    if not counting:
        rasters = _approx._NO_RASTERS
    scratch = _sampling.new_scratch(grid.foreground.size, grid.foreground, True)
    raster_pairs = grid.raster[np.asarray(pairs, dtype=np.int64)]
    work, retries, counted = _sampling.sample_paths(
        EMPTY,
        EMPTY32,
        EMPTY,
        EMPTY32,
        raster_pairs,
        seed,
        0,
        len(raster_pairs),
        grid.offs,
        steps,
        shape,
        own_reach if reach is None else reach,
        marks,
        labels,
        rasters,
        scratch,
    )
    assert counting or counted == 0
    # Every work array is back at rest for the next call.
    rest = np.where(grid.foreground, -1, _sampling._BLOCKED)
    np.testing.assert_array_equal(scratch[0], rest)
    np.testing.assert_array_equal(scratch[1], rest)
    return scratch[8][grid.raster], work, retries, counted


@settings(max_examples=60, deadline=None)
@given(
    mask=arrays(bool, st.tuples(st.integers(2, 12), st.integers(2, 12)), elements=st.booleans()),
    connectivity=st.sampled_from([4, 8]),
    landmarks=st.booleans(),
    data=st.data(),
)
def test_each_drawn_path_is_a_shortest_path(mask, connectivity, landmarks, data):
    _check_drawn_path(mask, connectivity, landmarks, data)


@settings(max_examples=40, deadline=None)
@given(
    mask=arrays(bool, st.tuples(st.integers(2, 6), st.integers(2, 6), st.integers(2, 6)), elements=st.booleans()),
    connectivity=st.sampled_from([6, 18, 26]),
    data=st.data(),
)
def test_each_drawn_path_is_a_shortest_path_in_3d(mask, connectivity, data):
    _check_drawn_path(mask, connectivity, True, data)


def _check_drawn_path(mask, connectivity, landmarks, data):
    if mask.sum() < 2:
        mask[:2, 0] = True
    setup = _setup(mask, connectivity, landmarks)
    graph = setup[0]
    n = graph.shape[0]
    hops = shortest_path(graph, unweighted=True)
    s = data.draw(st.integers(0, n - 1))
    t = data.draw(st.integers(0, n - 1))
    hits, *_ = _draw(setup, [(s, t)])
    if s == t or not np.isfinite(hops[s, t]):
        assert hits.sum() == 0  # no inner node: the same node, or no path at all
        return
    d = int(hops[s, t])
    inner = np.flatnonzero(hits)
    assert hits.sum() == d - 1 and np.all(hits[inner] == 1)
    # One inner node at each hop count 1 .. d - 1, each on a shortest s-t path, in a chain.
    np.testing.assert_array_equal(np.sort(hops[s, inner]), np.arange(1, d))
    np.testing.assert_array_equal(hops[s, inner] + hops[inner, t], d)
    chain = [s, *inner[np.argsort(hops[s, inner])], t]
    assert all(hops[a, b] == 1 for a, b in zip(chain, chain[1:]))


@pytest.mark.parametrize(
    ("shape", "connectivity"),
    [((9, 13), 8), ((9, 13), 4), ((5, 6, 7), 26), ((5, 6, 7), 6), ((5, 6, 7), 18)],
)
@pytest.mark.parametrize("wall", [False, True])
@pytest.mark.parametrize(("reach", "counting"), [(None, True), (None, False), (0, False)])
def test_paths_are_drawn_uniformly(shape, connectivity, wall, reach, counting):
    # The exact share of shortest s-t paths through each node against the frequency with
    # which the drawn paths pass it, for pairs in several directions; with a wall, paths
    # bend and the landmark bounds matter.
    mask = np.ones(shape, dtype=bool)
    if wall:
        mask[(slice(2, -2), 4) + (slice(None),) * (len(shape) - 2)] = False
    setup = _setup(mask, connectivity)
    graph = setup[0]
    g = nx.from_scipy_sparse_array(graph)
    n = graph.shape[0]
    rng = np.random.default_rng(len(shape) + connectivity)
    k = 3000
    for s, t in [(0, n - 1), (n - 1, n // 3), *rng.integers(0, n, size=(3, 2))]:
        if s == t:
            continue
        paths = list(nx.all_shortest_paths(g, s, t))
        share = np.zeros(n)
        for path in paths:
            share[path[1:-1]] += 1 / len(paths)
        hits, _, retries, counted = _draw(
            setup, np.tile([s, t], (k, 1)), seed=s * n + t, reach=reach, counting=counting
        )
        share = np.clip(share, 0.0, 1.0)  # sums of 1 / len(paths) may pass 1 by a rounding
        tolerance = 5 * np.sqrt(share * (1 - share) / k) + 1e-9
        assert np.all(np.abs(hits / k - share) <= tolerance), (s, t)
        if not wall and reach is None:
            assert retries == 0  # on an open box the grid bound is the distance itself
        if not wall and counting and (len(shape) == 2 or connectivity == 26):
            assert counted == k  # a clear view: paths counted slice by slice, no search
        elif not counting or connectivity in (6, 18):
            assert counted == 0


def test_pairs_in_different_parts_are_skipped_and_retries_are_counted():
    mask = np.zeros((12, 30), dtype=bool)
    mask[1:11, 1:12] = True
    mask[1:11, 18:29] = True
    mask[5, 12:18] = True  # a bridge: the far side is reached by a detour through it
    mask[:, 25] = False  # ... and a separate strip
    setup = _setup(mask, 8)
    graph = setup[0]
    hops = shortest_path(graph, unweighted=True)
    n = graph.shape[0]
    rng = np.random.default_rng(0)
    pairs = rng.integers(0, n, size=(300, 2))
    hits, work, retries, _ = _draw(setup, pairs)
    lengths = hops[pairs[:, 0], pairs[:, 1]]
    connected = np.isfinite(lengths) & (pairs[:, 0] != pairs[:, 1])
    assert hits.sum() == np.sum(lengths[connected] - 1)
    assert work > 0 and retries > 0  # the bridge's detours miss the first allowance
    # Pairs in different parts cost nothing: no search, no count, no hit.
    across = pairs[~np.isfinite(lengths)]
    assert len(across) > 20
    hits, work, retries, counted = _draw(setup, across)
    assert hits.sum() == 0 and work == 0 and retries == 0 and counted == 0


def test_landmarks_are_hop_counts_from_far_apart_pixels():
    mask = np.zeros((20, 20), dtype=bool)
    mask[2:18, 2:5] = True
    mask[15:18, 2:18] = True  # an L
    graph, grid, *_ = _setup(mask, 8)
    marks = _sampling.landmark_hops(grid.foreground, grid.offs, 3, int(grid.raster[0]))
    hops = shortest_path(graph, unweighted=True)
    found = []
    for k in range(3):
        column = marks[grid.raster, k]
        source = np.flatnonzero(column == 0)
        assert source.size == 1  # a landmark is at hop count 0 from itself alone
        np.testing.assert_array_equal(column, hops[source[0]])
        found.append(source[0])
    # The first landmark is the pixel farthest from the start, the second farthest from it.
    assert hops[0, found[0]] == hops[0].max()
    assert hops[found[0], found[1]] == hops[found[0]].max()


def test_long_line_keeps_landmark_hops_exact_beyond_uint16():
    # 70,000 pixels in a row: hop counts pass 65,535, so the landmarks stay int32; the
    # sampled values keep their bound against the path graph's exact ones, i (n - 1 - i).
    n = 70_000
    graph, _ = pixel_graph(np.ones((1, n), dtype=bool))
    grid = _Grid(graph)
    labels, marks, _ = _approx._grid_guides(grid, 2)
    assert marks.dtype == np.int32 and marks.max() == n - 1
    approx, info = cen.betweenness(graph, normalized=True, epsilon=0.1, seed=2, return_info=True)
    i = np.arange(n)
    exact = i * (n - 1 - i) / ((n - 1) * (n - 2) / 2)
    assert np.abs(approx - exact).max() <= info["bound"] <= 0.1
    assert info["retries"] == 0  # on a line the grid bound is the distance


def test_sampled_betweenness_on_a_mask_in_parts_keeps_its_bound():
    mask = np.zeros((16, 40), dtype=bool)
    mask[1:15, 1:15] = True
    mask[5:9, 15:30] = True  # a corridor to a second room
    mask[1:15, 30:37] = True
    mask[4:12, 8:12] = False  # a pillar
    mask[2:6, 38:40] = True  # and a separate part
    graph, _ = pixel_graph(mask)
    exact = cen.betweenness(graph, normalized=True)
    approx, info = cen.betweenness(graph, normalized=True, epsilon=0.03, seed=1, return_info=True)
    assert np.abs(approx - exact).max() <= info["bound"] <= 0.03
    assert info["retries"] > 0  # the pillar and the corridor make detours


def _exact_shares(mask, s, t, steps):
    """Share of the shortest s-t paths through each pixel, by exact integer path counts."""
    g, _ = pixel_graph(mask, connectivity=len(steps))
    d = shortest_path(g, unweighted=True, indices=[s, t])
    coords = np.argwhere(mask)
    index = {tuple(c): k for k, c in enumerate(coords)}
    counts = [[0] * len(coords), [0] * len(coords)]
    for side, src in ((0, s), (1, t)):
        counts[side][src] = 1
        for v in sorted(range(len(coords)), key=lambda v: d[side][v]):
            for step in steps:
                u = index.get(tuple(int(a) - b for a, b in zip(coords[v], step)))
                if u is not None and d[side][u] == d[side][v] - 1:
                    counts[side][v] += counts[side][u]
    total = counts[0][t]
    return np.array(
        [counts[0][v] * counts[1][v] / total if d[0][v] + d[1][v] == d[0][t] else 0.0 for v in range(len(coords))]
    )


@pytest.mark.parametrize("connectivity", [4, 8, 26])
def test_counted_paths_stay_uniform_past_float64_range(connectivity):
    # Path counts past float64's range (rescaled per column or row) against shares from exact
    # integer counts.
    if connectivity == 4:
        mask = np.ones((530, 530), dtype=bool)  # C(1058, 529) ~ 1e317 monotone paths
        s, t = 0, mask.size - 1
        steps = None
    elif connectivity == 8:
        mask = np.ones((121, 720), dtype=bool)  # 719 columns of about 3-way choices ~ 1e340
        s, t = 60 * 720, 60 * 720 + 719
        steps = [(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1) if a or b]
    else:
        mask = np.ones((7, 7, 420), dtype=bool)  # 419 slices of about 7-way choices ~ 1e350
        s, t = 3 * 7 * 420 + 3 * 420, 3 * 7 * 420 + 3 * 420 + 419
        steps = [d for d in np.ndindex(3, 3, 3) if d != (1, 1, 1)]
        steps = [tuple(x - 1 for x in d) for d in steps]
    setup = _setup(mask, connectivity)
    k = 2000
    hits, _, _, counted = _draw(setup, np.tile([s, t], (k, 1)), seed=3)
    assert counted == k
    if connectivity == 4:  # monotone staircases in the full box: binomial counts
        from scipy.special import gammaln

        i, j = np.divmod(np.arange(mask.size), mask.shape[1])
        rows, cols = mask.shape[0] - 1, mask.shape[1] - 1

        def log_paths(a, b):  # C(a + b, a)
            return gammaln(a + b + 1) - gammaln(a + 1) - gammaln(b + 1)

        share = np.exp(log_paths(i, j) + log_paths(rows - i, cols - j) - log_paths(rows, cols))
    else:
        share = _exact_shares(mask, s, t, steps)
    share = np.clip(share, 0.0, 1.0)
    share[[s, t]] = 0.0  # the ends are no inner nodes
    probe = np.flatnonzero(share > 0.05)
    tolerance = 5 * np.sqrt(share[probe] * (1 - share[probe]) / k)
    assert probe.size > 20 and np.all(np.abs(hits[probe] / k - share[probe]) <= tolerance)

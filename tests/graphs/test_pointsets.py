import itertools

import networkx as nx
import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.spatial import ConvexHull
from scipy.spatial.distance import pdist, squareform

from centrality_vision.centrality import betweenness
from centrality_vision.exceptions import InputError
from centrality_vision.graphs import (
    complete_graph,
    delaunay_graph,
    emst_graph,
    gabriel_graph,
    knn_graph,
    to_networkx,
)
from centrality_vision.graphs._pointsets import edges_to_graph

BUILDERS = [delaunay_graph, gabriel_graph, emst_graph, complete_graph, lambda p: knn_graph(p, n_neighbors=3)]


def _edges(graph):
    coo = sparse.triu(graph, k=1).tocoo()
    return set(zip(coo.row.tolist(), coo.col.tolist()))


def _random_points(seed, n, dim):
    return np.random.default_rng(seed).random((n, dim))


@pytest.mark.parametrize("builder", BUILDERS)
@pytest.mark.parametrize("dim", [2, 3])
def test_graphs_are_symmetric_with_euclidean_lengths(builder, dim):
    points = _random_points(0, 40, dim)
    graph = builder(points)
    assert isinstance(graph, sparse.csr_array)
    assert graph.shape == (40, 40) and graph.dtype == np.float64
    np.testing.assert_array_equal(graph.toarray(), graph.toarray().T)
    coo = graph.tocoo()
    np.testing.assert_allclose(coo.data, np.linalg.norm(points[coo.row] - points[coo.col], axis=1), rtol=1e-14)
    assert np.all(graph.diagonal() == 0)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("dim", [2, 3])
def test_emst_subset_gabriel_subset_delaunay(seed, dim):
    points = _random_points(seed, 60, dim)
    d, g, e = _edges(delaunay_graph(points)), _edges(gabriel_graph(points)), _edges(emst_graph(points))
    assert e <= g <= d
    assert len(e) == 59 and len(g) < len(d)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("dim", [2, 3])
def test_gabriel_matches_brute_force(seed, dim):
    points = _random_points(seed, 25, dim)
    expected = set()
    for i, j in itertools.combinations(range(len(points)), 2):
        centre = (points[i] + points[j]) / 2
        r2 = np.sum((points[i] - centre) ** 2)
        others = np.delete(np.arange(len(points)), [i, j])
        if np.all(np.sum((points[others] - centre) ** 2, axis=1) > r2):
            expected.add((i, j))
    assert _edges(gabriel_graph(points)) == expected


def test_gabriel_three_points_and_cocircular_square():
    assert _edges(gabriel_graph([[0, 0], [2, 0], [1, 0.2]])) == {(0, 2), (1, 2)}
    # The diagonals of a square have the other two corners on their circle: not Gabriel.
    assert _edges(gabriel_graph([[0, 0], [1, 0], [1, 1], [0, 1]])) == {(0, 1), (1, 2), (2, 3), (0, 3)}


def test_a_point_just_outside_a_circle_beside_its_end_point_keeps_the_edge():
    # point 1 lies 1e-14 outside the circles of edges 0-2 and 0-3 (inside those of 1-2 and
    # 1-3): a tolerance of 1e-12 of the squared radius took it as on them, and the graph split
    expected = {(0, 1), (0, 2), (0, 3), (2, 3)}
    assert _edges(gabriel_graph([[0, 0], [-1e-14, 0], [1, 0], [0.5, 2]])) == expected


@pytest.mark.parametrize("separation", [1e-14, 1e-13, 1e-12, 1e-11])
def test_gabriel_graph_of_a_set_with_a_tight_pair_holds_its_emst(separation):
    # 87 of 135 such sets were disconnected at 1e-14 to 1e-13, 10 of 150 at 1e-13 to 1e-12
    rng = np.random.default_rng(0)
    tested = 0
    for _ in range(60):
        points = rng.random((12, 2))
        direction = rng.standard_normal(2)
        points = np.vstack([points, points[rng.integers(12)] + separation * direction / np.linalg.norm(direction)])
        try:
            gabriel = gabriel_graph(points)
        except ValueError:  # Qhull could not triangulate the pair reliably: refused, named
            continue
        tested += 1
        assert _edges(emst_graph(points)) <= _edges(gabriel) and connected_components(gabriel)[0] == 1
    assert tested >= 30


@pytest.mark.parametrize("dim", [2, 3])
def test_emst_weight_equals_mst_of_complete_graph(dim):
    points = _random_points(11, 50, dim)
    tree = emst_graph(points)
    assert connected_components(tree)[0] == 1
    reference = minimum_spanning_tree(complete_graph(points)).sum()
    assert tree.sum() / 2 == pytest.approx(reference, rel=1e-12)


def test_delaunay_edge_count_euler():
    points = _random_points(5, 100, 2)
    hull = ConvexHull(points)
    assert len(_edges(delaunay_graph(points))) == 3 * 100 - 3 - len(hull.vertices)


@pytest.mark.parametrize("k", [1, 2, 5])
def test_knn_degrees_and_neighbours(k):
    points = _random_points(2, 30, 2)
    graph = knn_graph(points, n_neighbors=k)
    assert np.all(np.diff(graph.indptr) >= k)
    dist = np.linalg.norm(points[:, None] - points[None], axis=2)
    np.fill_diagonal(dist, np.inf)
    dense = graph.toarray() > 0
    for i in range(30):
        assert dense[i, np.argsort(dist[i])[:k]].all()


@pytest.mark.parametrize("seed", range(12))
def test_knn_neighbours_in_a_cluster_below_squared_precision(seed):
    # A cluster 1e-150 to 1e-300 of the extent across: the tree's squared distances
    # underflow there, and it picked wrong neighbours in 181 of 200 such sets.
    rng = np.random.default_rng(seed)
    m = int(rng.integers(4, 12))
    k = int(rng.integers(1, m - 1))
    shape = rng.random((m, 2))
    points = np.vstack([shape * 10.0 ** -rng.integers(150, 300), rng.random((5, 2)) + 1.0])
    dense = knn_graph(points, n_neighbors=k).toarray()[:m, :m] > 0
    dist = squareform(pdist(shape))  # the cluster's shape, at unit size
    np.fill_diagonal(dist, np.inf)
    expected = np.zeros((m, m), dtype=bool)
    expected[np.repeat(np.arange(m), k), np.argsort(dist, axis=1)[:, :k].ravel()] = True
    np.testing.assert_array_equal(dense, expected | expected.T)


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("dim", [2, 3])
def test_emst_of_a_line_with_a_cluster_below_its_precision(seed, dim):
    # Points within 1e-12 of a line count as on it; a cluster 1e-15 to 1e-20 across at the
    # origin was joined in order along the line (wrong in 198 of 200 such 2D sets).
    rng = np.random.default_rng(seed)
    line = np.outer(rng.random(8), [1.0, 0.5, 0.25][:dim])
    points = np.vstack([line, rng.standard_normal((6, dim)) * 10.0 ** -rng.integers(15, 21)])
    tree = emst_graph(points)
    # (networkx: scipy's dense input takes lengths below 1e-8 for non-edges)
    expected = nx.minimum_spanning_tree(nx.from_numpy_array(squareform(pdist(points))))
    lengths = [length for _, _, length in expected.edges(data="weight")]
    # Edge lengths, cluster edges included, to within rounding (the edge to the cluster
    # may be another of lengths equal to a few units in the last place).
    np.testing.assert_allclose(np.sort(sparse.triu(tree).data), np.sort(lengths), rtol=1e-14)
    inner = sparse.csr_array(tree)[8:, 8:]
    assert connected_components(inner, directed=False)[0] == 1  # the cluster's own tree


def test_line_with_a_huge_cluster_below_its_precision_is_refused(monkeypatch):
    from centrality_vision.graphs import _pointsets

    monkeypatch.setattr(_pointsets, "_MAX_LINE_CANDIDATES", 100)
    rng = np.random.default_rng(0)
    points = np.vstack([np.outer(rng.random(5), [1.0, 0.5]), rng.standard_normal((30, 2)) * 1e-18])
    with pytest.raises(InputError, match=r"`points` lie on a line .* closer together along it than their offsets"):
        emst_graph(points)


def test_complete_graph_edge_count():
    assert complete_graph(_random_points(0, 12, 3)).nnz == 12 * 11


def test_to_networkx_round_trip():
    points = _random_points(4, 15, 2)
    graph = delaunay_graph(points)
    g = to_networkx(graph, points)
    assert g.number_of_nodes() == 15 and g.number_of_edges() == graph.nnz // 2
    back = nx.to_scipy_sparse_array(g, nodelist=range(15), weight="weight")
    np.testing.assert_allclose(back.toarray(), graph.toarray())
    np.testing.assert_allclose(g.nodes[3]["pos"], points[3])


def test_input_not_modified():
    points = _random_points(1, 20, 2)
    before = points.copy()
    for builder in BUILDERS:
        builder(points)
    np.testing.assert_array_equal(points, before)


@pytest.mark.parametrize("builder", [delaunay_graph, gabriel_graph, emst_graph])
@pytest.mark.parametrize(
    ("points", "match"),
    [
        ([[0, 0]], "at least [23] points"),
        ([[0, 0], [1, 1], [np.nan, 2]], "finite"),
        ([[0, 0], [1, 1], [1, 1], [0, 1]], "duplicate"),
        (np.zeros((5, 4)), r"shape \(n_points, 2 or 3\)"),
        (np.zeros(5), "shape"),
    ],
)
def test_bad_point_sets(builder, points, match):
    with pytest.raises(ValueError, match=match):
        builder(points)


@pytest.mark.parametrize(
    ("points", "match"),
    [([[0, 0], [1, 1]], "at least 3 points"), ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "at least 4 points in 3D")],
)
def test_a_triangulation_needs_one_point_more_than_the_dimension(points, match):
    with pytest.raises(ValueError, match=match):
        delaunay_graph(points)


@pytest.mark.parametrize("builder", [gabriel_graph, emst_graph])
def test_gabriel_graph_and_emst_of_two_points_and_of_a_3d_triangle(builder):
    # fuzz round 6 (L9): the EMST of two points, their one edge, was refused as "at least
    # 3 points"; so was a triangle in 3D (at least 4), although both graphs take flat sets
    for points in ([[0.0, 0.0], [3.0, 4.0]], [[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]]):
        np.testing.assert_array_equal(builder(points).toarray(), [[0, 5], [5, 0]])
    triangle = np.array([[0.0, 0.0, 1.0], [4.0, 0.0, 1.0], [0.0, 3.0, 1.0]])  # right angle at node 0
    edges = {(int(i), int(j)) for i, j in zip(*sparse.triu(builder(triangle)).nonzero())}
    assert edges == {(0, 1), (0, 2)}  # the hypotenuse's circle holds node 0; it is also the longest


@pytest.mark.parametrize(
    ("points", "match"),
    [
        ([[0, 0], [1, 1], [2, 2], [3, 3]], "collinear"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], "coplanar"),
        ([[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]], "collinear"),  # (a line in 3D was "coplanar")
    ],
)
def test_a_delaunay_triangulation_needs_the_full_dimension(points, match):
    with pytest.raises(ValueError, match=match):
        delaunay_graph(points)


@pytest.mark.parametrize("seed", range(4))
def test_gabriel_graph_and_emst_of_points_on_a_line_or_a_plane(seed):
    # both graphs are defined there (a path along the line; the plane's own graphs), but
    # needing a Delaunay triangulation of the full dimension they were refused
    rng = np.random.default_rng(seed)
    line = rng.permutation(np.outer(rng.random(12), rng.standard_normal(3)) + rng.standard_normal(3))
    order = np.argsort(line[:, 0])
    path = {tuple(sorted(pair)) for pair in zip(order[:-1].tolist(), order[1:].tolist())}
    for points in (line, line[:, :2]):
        for builder in (gabriel_graph, emst_graph):
            graph = builder(points)
            assert {(int(i), int(j)) for i, j in zip(*sparse.triu(graph).nonzero())} == path
    flat = rng.random((30, 2))
    rotation = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    plane = np.c_[flat, np.zeros(30)] @ rotation.T + 5.0
    best = minimum_spanning_tree(squareform(pdist(plane))).sum()
    assert emst_graph(plane).sum() / 2 == pytest.approx(best, rel=1e-12)
    assert set(zip(*sparse.triu(gabriel_graph(plane)).nonzero())) == set(
        zip(*sparse.triu(gabriel_graph(flat)).nonzero())
    )


def test_bad_points_type():
    with pytest.raises(TypeError, match="`points`"):
        delaunay_graph([["a", "b"], ["c", "d"], ["e", "f"]])


@pytest.mark.parametrize(("k", "error"), [(0, ValueError), (10, ValueError), (2.5, TypeError), (True, TypeError)])
def test_knn_bad_k(k, error):
    with pytest.raises(error, match="`n_neighbors`"):
        knn_graph(_random_points(0, 10, 2), n_neighbors=k)


def test_knn_former_name_k_warns_and_agrees():
    points = _random_points(0, 10, 2)
    with pytest.warns(FutureWarning, match="`k` of knn_graph\\(\\) is renamed `n_neighbors`"):
        old = knn_graph(points, k=3)
    assert (old != knn_graph(points, n_neighbors=3)).nnz == 0
    with pytest.raises(TypeError, match="give `n_neighbors` only"):
        knn_graph(points, k=3, n_neighbors=3)


def test_to_networkx_bad_points():
    with pytest.raises(ValueError, match="`points` must have one row per node"):
        to_networkx(complete_graph(_random_points(0, 4, 2)), _random_points(0, 5, 2))


@pytest.mark.parametrize("scale", [1e300, 1e-300, 1e155])
def test_builders_are_scale_invariant_at_extreme_coordinates(scale):
    """Squared distances overflow (or underflow) here; the graphs must not change."""
    from centrality_vision.graphs import complete_graph, delaunay_graph, emst_graph, gabriel_graph, knn_graph

    points = np.random.default_rng(3).random((40, 2))
    for build in (lambda p: knn_graph(p, n_neighbors=3), delaunay_graph, gabriel_graph, emst_graph, complete_graph):
        reference = build(points)
        scaled = build(points * scale)
        assert (scaled != 0).nnz == (reference != 0).nnz
        np.testing.assert_allclose(scaled.toarray() / scale, reference.toarray(), rtol=1e-12)


@pytest.mark.parametrize("build", [complete_graph, lambda p: knn_graph(p, n_neighbors=1)])
def test_a_pair_closer_than_squares_can_hold_keeps_its_true_length(build):
    """1e-170 apart: the squared difference underflows to 0; the edge must still be there."""
    points = np.array([[0.0, 0.0], [1e-170, 0.0], [1.0, 0.0], [0.0, 1.0]])
    graph = build(points)
    assert graph[0, 1] == graph[1, 0] == pytest.approx(1e-170, rel=1e-12)
    assert graph.data.min() > 0  # no explicit zero: every stored edge is an edge
    assert (abs(graph - graph.T)).nnz == 0


@pytest.mark.parametrize("build", BUILDERS)
def test_distances_beyond_float64_are_refused(build):
    points = np.array([[1.7e308, 0.0], [-1.7e308, 0.0], [0.0, 1.7e308], [0.0, -1.7e308]])
    with pytest.raises(ValueError, match="`points` must have every distance"):
        build(points)


@pytest.mark.parametrize("offset", [1e6, 1e8, 2.0**40 + 0.5])
@pytest.mark.parametrize("seed", range(6))
def test_a_set_far_from_the_origin_gives_the_same_graphs(offset, seed):
    """Found by a fuzz run: the points were divided by their largest coordinate (rounding each)
    and triangulated uncentred, so at offset 1e6 the EMST was not minimal (Qhull's triangulation
    was not Delaunay) and equal distances came out 1e-8 apart at 1e8."""
    rng = np.random.default_rng(seed)
    # integer points: `points + offset` is then an exact translation
    points = np.unique(rng.integers(0, 1000, size=(int(rng.integers(4, 30)), 2)), axis=0).astype(float)
    far = points + offset
    for build in BUILDERS:
        near_graph, far_graph = build(points), build(far)
        assert (near_graph != far_graph).nnz == 0  # the same edges, bit for bit the same lengths
    complete = sparse.csr_array(squareform(pdist(far)))
    assert emst_graph(far).sum() / 2 == pytest.approx(minimum_spanning_tree(complete).sum(), rel=1e-12)


def test_equal_distances_stay_equal_far_from_the_origin():
    # the weighted betweenness of this k-NN graph has a tie that rounding broke at offset 3e8
    points = np.array([[7.0, 6.0], [8.0, 7.0], [9.0, 7.0], [9.0, 8.0], [10.0, 6.0], [11.0, 3.0]])
    near = betweenness(knn_graph(points, n_neighbors=3), weights=True)
    np.testing.assert_array_equal(betweenness(knn_graph(points + 300000670.0, n_neighbors=3), weights=True), near)
    np.testing.assert_array_equal(near, [0.0, 1.0, 0.5, 0.0, 2.0, 0.0])


def test_edges_to_graph_keeps_each_length_on_its_own_edge():
    # found by a fuzz run: the edges were sorted but given lengths kept the caller's order
    rows, cols = [3, 1, 0, 2, 1], [0, 2, 1, 3, 2]  # (0, 3) reversed; (1, 2) twice: the first kept
    graph = edges_to_graph(4, rows, cols, lengths=[30.0, 12.0, 1.0, 23.0, 99.0])
    assert graph[0, 3] == graph[3, 0] == 30.0 and graph[1, 2] == 12.0 and graph[0, 1] == 1.0
    assert graph[2, 3] == 23.0 and graph.nnz == 8


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e8, 1e12])
def test_flat_sets_far_from_the_origin_get_their_path_or_plane_graph(offset):
    # the flatness test centred on the mean, which at an offset rounds away the set's digits:
    # a line looked 2D, and the triangulation that followed refused it
    two = np.array([[0.0, 0.0], [1.0, 0.3]]) + offset
    line = np.array([[-57.0, 19], [-54, 18], [-15, 5], [-3, 1], [0, 0]]) + [2 * offset, offset]
    plane = np.array([[0.0, 1, 3], [2, 5, 3], [2, 7, 9], [5, 11, 3], [7, 22, 24], [9, 26, 24]]) + [
        offset,
        offset,
        2 * offset,
    ]
    for points, n_edges in ((two, 1), (line, 4), (plane, 5)):
        for build in (emst_graph, gabriel_graph):
            graph = build(points)
            assert graph.nnz // 2 >= n_edges and sparse.csgraph.connected_components(graph)[0] == 1
        assert emst_graph(points).nnz // 2 == n_edges
    assert gabriel_graph(line).nnz // 2 == 4  # the path along the line


def test_a_gabriel_edge_of_points_on_a_tilted_plane_is_kept():
    # the points were projected onto their plane about their bounding box's middle, which lies
    # off the plane: distances came out distorted (here ~0.5%), and p-q, whose circle has r and s
    # 0.1% outside it, lost to r-s in the Delaunay candidates
    turn = 2.5364329801
    rotation = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    p, q, r, s, far = [-1.0, 0], [1.0, 0], [0, 1.001], [0, -1.001], [0.3, 3.0]
    plane = np.linalg.qr([[-0.60412767, -0.74119306], [0.45183195, -0.62113495], [-0.65641272, 0.254606]])[0]
    points = np.array([p, q, r, s, far]) @ rotation.T @ plane.T  # on a plane through the origin
    centred = points - points.mean(axis=0)
    in_plane = centred @ np.linalg.svd(centred)[2][:2].T  # an isometry onto 2D
    graph, flat = gabriel_graph(points), gabriel_graph(in_plane)
    assert graph[0, 1] > 0
    np.testing.assert_array_equal(graph.indices, flat.indices)
    np.testing.assert_allclose(graph.data, flat.data, rtol=1e-12)


@pytest.mark.parametrize("angle", np.linspace(0.05, 1.5, 30))
def test_a_turned_grid_keeps_its_gabriel_edges_only(angle):
    """On a square grid the diagonals have their two other corners exactly on the circle of
    which they are the diameter: only rounding tells them apart. With the tolerance, every
    turn gives the 60 grid edges of a 6 x 6 grid; without it, the diagonals came and went."""
    grid = np.stack(np.meshgrid(np.arange(6.0), np.arange(6.0)), axis=-1).reshape(-1, 2)
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    assert gabriel_graph(grid @ turn.T + [3.7, -1.3]).nnz // 2 == 60


@pytest.mark.parametrize("offset", [1e4, 1e6, 1e8])
def test_a_turned_plane_far_from_the_origin_is_a_plane(offset):
    """Rounding alone makes a turned plane at 1e4 6e-12 of its extent thick: read against a
    fixed 1e-12 it was 3D, and its Delaunay graph was Qhull's luck (slivers, or a refusal)."""
    flat = np.random.default_rng(3).random((60, 2))
    turn = np.linalg.qr(np.random.default_rng(4).normal(size=(3, 3)))[0]
    lifted = np.c_[flat, np.zeros(len(flat))] @ turn.T + np.array([1.0, -2.0, 0.5]) * offset

    def edges(graph):
        graph = sparse.coo_array(graph)
        return set(zip(graph.row.tolist(), graph.col.tolist()))

    assert edges(emst_graph(lifted)) == edges(emst_graph(flat))
    assert edges(gabriel_graph(lifted)) == edges(gabriel_graph(flat))
    with pytest.raises(InputError, match="got 60 coplanar points .* or the rounding of their coordinates"):
        delaunay_graph(lifted)

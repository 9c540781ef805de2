"""NHDD theorems as properties, MWME and MSTME against brute force."""

import itertools

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.csgraph import connected_components

from centrality_vision.centrality import degree_entropy
from centrality_vision.graphs import emst_graph, mstme_graph, mwme_graph, nhdd_graph


def _degrees(graph):
    return np.diff(sparse.csr_array(graph).indptr)


def _edge_set(graph):
    coo = sparse.triu(graph, k=1).tocoo()
    return set(zip(coo.row.tolist(), coo.col.tolist()))


@pytest.mark.parametrize("n", range(3, 201))
def test_nhdd_theorems(n):
    graph = nhdd_graph(n)
    deg = _degrees(graph)
    assert len(set(deg.tolist())) == n - 1  # NHDD: n - 1 distinct degrees
    values, counts = np.unique(deg, return_counts=True)
    assert values[counts == 2].tolist() == [n // 2]  # Lemma 4: the repeated degree
    assert graph.nnz // 2 == (n * (n - 1) // 2 + n // 2) // 2  # Theorem 4
    assert (n * (n - 1) // 2 + n // 2) % 2 == 0
    assert connected_components(graph)[0] == 1  # Theorem 3
    assert degree_entropy(graph) == pytest.approx(np.log2(n) - 2 / n, abs=1e-12)  # Theorem 6
    # Lemma 2: the complement is the other NHDD graph, with one isolated node.
    other = nhdd_graph(n, connected=False)
    complement = np.ones((n, n), dtype=bool) & ~np.eye(n, dtype=bool) & ~(graph.toarray() > 0)
    np.testing.assert_array_equal(other.toarray() > 0, complement)
    other_deg = _degrees(other)
    assert (other_deg == 0).sum() == 1 and len(set(other_deg.tolist())) == n - 1
    assert degree_entropy(other) == pytest.approx(np.log2(n) - 2 / n, abs=1e-12)


@pytest.mark.parametrize("n", [3, 4, 5, 6])
def test_theorems_2_and_5_by_enumerating_every_graph(n):
    """No graph has n distinct degrees (Thm 2); none beats the NHDD entropy (Thm 5)."""
    pairs = list(itertools.combinations(range(n), 2))
    masks = np.arange(2 ** len(pairs))
    bits = (masks[:, None] >> np.arange(len(pairs))) & 1
    incidence = np.zeros((len(pairs), n), dtype=np.int64)
    for e, (i, j) in enumerate(pairs):
        incidence[e, i] = incidence[e, j] = 1
    degrees = bits @ incidence
    best = 0.0
    for row in degrees:
        assert len(set(row.tolist())) < n
        _, counts = np.unique(row, return_counts=True)
        p = counts / n
        best = max(best, float(-(p * np.log2(p)).sum()))
    assert best == pytest.approx(np.log2(n) - 2 / n)


def _brute_force_mwme(points):
    n = len(points)
    dist = np.linalg.norm(points[:, None] - points[None], axis=2)
    adjacency = nhdd_graph(n).toarray() > 0
    best = np.inf
    for perm in itertools.permutations(range(n)):
        p = np.array(perm)
        best = min(best, dist[p[:, None], p[None, :]][adjacency].sum() / 2)
    return best


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("n", [4, 5, 6, 7])
def test_mwme_exact_matches_brute_force(n, seed):
    points = np.random.default_rng(seed).random((n, 2))
    exact = mwme_graph(points, method="exact")
    assert exact.cost == pytest.approx(_brute_force_mwme(points), rel=1e-12)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("n", [5, 8, 11, 14])
def test_mwme_every_method_returns_nhdd_and_exact_is_lowest(n, seed):
    points = np.random.default_rng(100 + seed).random((n, 2))
    results = {m: mwme_graph(points, method=m) for m in ("exact", "greedy", "local")}
    for method, res in results.items():
        deg = res.degrees
        assert len(set(deg.tolist())) == n - 1, method
        assert connected_components(res.graph)[0] == 1, method
        np.testing.assert_array_equal(np.sort(deg), np.sort(_degrees(nhdd_graph(n))))
        assert res.cost == pytest.approx(res.graph.sum() / 2, rel=1e-12)
        assert sorted(res.order.tolist()) == list(range(n))
    assert results["exact"].cost <= results["local"].cost + 1e-12
    assert results["local"].cost <= results["greedy"].cost + 1e-12


def test_mwme_large_greedy_and_3d():
    points = np.random.default_rng(5).random((150, 3))
    res = mwme_graph(points, method="greedy")
    assert len(set(res.degrees.tolist())) == 149
    assert res.graph.nnz // 2 == (150 * 149 // 2 + 75) // 2


def test_mwme_is_invariant_to_similarity_transforms():
    rng = np.random.default_rng(7)
    points = rng.random((30, 2))
    angle = 0.7
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    moved = 3.0 * points @ rot.T + [5.0, -2.0]
    a, b = mwme_graph(points), mwme_graph(moved)
    np.testing.assert_array_equal(a.degrees, b.degrees)
    assert b.cost == pytest.approx(3.0 * a.cost)


# --- MSTME ----------------------------------------------------------------------------


FIG_7_1 = np.array([[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]], dtype=float)


def _brute_force_mstme(points, lam):
    n = len(points)
    dist = np.linalg.norm(points[:, None] - points[None], axis=2)
    pairs = list(itertools.combinations(range(n), 2))
    best = np.inf
    for edges in itertools.combinations(pairs, n - 1):
        rows, cols = zip(*edges)
        tree = sparse.coo_array((np.ones(n - 1), (rows, cols)), shape=(n, n))
        if connected_components(tree, directed=False)[0] != 1:
            continue
        deg = np.bincount(np.array(edges).ravel(), minlength=n)
        _, counts = np.unique(deg, return_counts=True)
        p = counts / n
        best = min(best, dist[rows, cols].sum() + lam * float((p * np.log2(p)).sum()))
    return best


def test_fig_7_1_mst_and_mstme():
    mst = mstme_graph(FIG_7_1, lam=0.0, normalize=False)
    assert round(mst.weight, 2) == 4.0 and round(mst.entropy, 2) == 0.72
    tree = mstme_graph(FIG_7_1, lam=1.0, normalize=False)
    assert sorted(_degrees(tree.graph).tolist(), reverse=True) == [3, 2, 1, 1, 1]
    assert round(tree.weight, 2) == 4.41 and round(tree.entropy, 2) == 1.37 and round(tree.cost, 2) == 3.04
    assert tree.cost < mst.weight - mst.entropy
    assert tree.cost == pytest.approx(_brute_force_mstme(FIG_7_1, 1.0))  # also the exhaustive optimum


@pytest.mark.parametrize("seed", range(5))
def test_lam_zero_is_the_euclidean_mst(seed):
    points = np.random.default_rng(seed).random((80, 2))
    for method in ("greedy", "exchange"):
        tree = mstme_graph(points, lam=0.0, method=method)
        assert _edge_set(tree.graph) == _edge_set(emst_graph(points))
    # the greedy kernel itself, run with a tiny lam, also starts out as Kruskal would
    assert _edge_set(mstme_graph(points, lam=1e-12).graph) == _edge_set(emst_graph(points))


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("lam", [0.3, 1.0, 3.0])
def test_mstme_trees_and_exchange_improves(seed, lam):
    points = np.random.default_rng(seed).random((6, 2))
    greedy = mstme_graph(points, lam=lam, normalize=False)
    better = mstme_graph(points, lam=lam, normalize=False, method="exchange")
    optimum = _brute_force_mstme(points, lam)
    for tree in (greedy, better):
        assert tree.graph.nnz // 2 == 5 and connected_components(tree.graph)[0] == 1
        assert tree.cost >= optimum - 1e-12
    assert better.cost <= greedy.cost + 1e-12


def test_mstme_normalized_is_scale_invariant():
    points = np.random.default_rng(3).random((40, 2))
    a = mstme_graph(points, lam=0.5)
    b = mstme_graph(10.0 * points, lam=0.5)
    assert _edge_set(a.graph) == _edge_set(b.graph)
    assert b.scale == pytest.approx(10.0 * a.scale)


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda: mwme_graph([[0, 0], [1, 1]]), ValueError, "at least 3 points"),
        (lambda: mwme_graph([[0, 0], [1, 1], [1, 1]]), ValueError, "duplicate"),
        (lambda: mwme_graph([[0, 0], [1, np.nan], [2, 1]]), ValueError, "finite"),
        (lambda: mwme_graph(np.random.default_rng(0).random((21, 2)), method="exact"), ValueError, "up to 20 points"),
        (lambda: mwme_graph(np.eye(3), method="best"), ValueError, "`method`"),
        (lambda: mstme_graph(FIG_7_1, lam=-0.1), ValueError, "`lam`"),
        (lambda: mstme_graph(FIG_7_1, normalize="yes"), TypeError, "`normalize`"),
        (lambda: mstme_graph([[0, 0], [1, 1]]), ValueError, "at least 3 points"),
        (lambda: nhdd_graph(2), ValueError, "`n`"),
    ],
)
def test_errors(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_inputs_not_modified():
    points = np.random.default_rng(0).random((12, 2))
    before = points.copy()
    mwme_graph(points, method="exact")
    mstme_graph(points, method="exchange")
    np.testing.assert_array_equal(points, before)

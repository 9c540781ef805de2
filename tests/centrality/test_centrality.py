"""Centralities: the thesis' worked example, networkx agreement, exactness and errors."""

import heapq
import warnings
from fractions import Fraction

import networkx as nx
import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.csgraph import shortest_path

from centrality_vision import centrality as cen
from centrality_vision.centrality import _kernels
from centrality_vision.graphs import delaunay_graph, pixel_graph

NAMES = ("degree", "betweenness", "closeness", "harmonic", "eigenvector", "eccentricity")
# Degree-like measures read stored values as strengths; path centralities as lengths.
_WEIGHT_OPTION = {"degree": "strengths", "eigenvector": "strengths"}


def _graph(n, edges, lengths=None):
    rows, cols = zip(*edges)
    data = np.ones(len(edges)) if lengths is None else np.asarray(lengths, float)
    a = sparse.coo_array((data, (rows, cols)), shape=(n, n))
    return sparse.csr_array(a + a.T)


@pytest.fixture(scope="module")
def table_2_1_graph():
    idx = {c: i for i, c in enumerate("abcdef")}
    edges = [(idx[u], idx[v]) for u, v in ["ab", "bc", "bd", "be", "cd", "cf", "de", "ef"]]
    return _graph(6, edges)


def test_table_2_1(table_2_1_graph):
    """Thesis Table 2.1, to two decimals, with the default arguments."""
    expected = {
        "degree": [1, 4, 3, 3, 3, 2],
        "closeness": [0.50, 0.83, 0.71, 0.71, 0.71, 0.56],
        "betweenness": [0.00, 4.33, 1.50, 0.33, 1.50, 0.33],
        "eigenvector": [0.34, 1.00, 0.85, 0.91, 0.85, 0.57],
    }
    for name, values in expected.items():
        np.testing.assert_array_equal(np.round(cen.compute(table_2_1_graph, name), 2), values, err_msg=name)


def test_table_2_1_hand_computed_harmonic_and_eccentricity(table_2_1_graph):
    # a: d(b) = 1, d(c) = d(d) = d(e) = 2, d(f) = 3
    assert cen.harmonic(table_2_1_graph)[0] == pytest.approx(1 + 3 / 2 + 1 / 3)
    np.testing.assert_array_equal(cen.eccentricity(table_2_1_graph), [3, 2, 2, 2, 2, 3])


def test_small_hand_cases():
    path = _graph(3, [(0, 1), (1, 2)])
    np.testing.assert_allclose(cen.betweenness(path), [0, 1, 0])
    np.testing.assert_allclose(cen.betweenness(path, normalized=True), [0, 1, 0])
    k5 = _graph(5, [(i, j) for i in range(5) for j in range(i + 1, 5)])
    np.testing.assert_allclose(cen.betweenness(k5), 0)
    np.testing.assert_allclose(cen.closeness(k5), 1)
    np.testing.assert_allclose(cen.eigenvector(k5), 1)
    np.testing.assert_allclose(cen.eccentricity(k5), 1)
    star = _graph(5, [(0, i) for i in range(1, 5)])
    np.testing.assert_allclose(cen.betweenness(star), [6, 0, 0, 0, 0])  # C(4, 2) pairs through the hub
    np.testing.assert_allclose(cen.degree(star, normalized=True), [1, 0.25, 0.25, 0.25, 0.25])
    # Weighted: the two-hop route 0-1-2 (length 2) beats the direct edge 0-2 (length 3).
    tri = _graph(3, [(0, 1), (1, 2), (0, 2)], [1.0, 1.0, 3.0])
    np.testing.assert_allclose(cen.betweenness(tri, weights=True), [0, 1, 0])
    np.testing.assert_allclose(cen.betweenness(tri), [0, 0, 0])


# --- agreement with networkx on seeded random graphs -----------------------------------


def _random_case(seed):
    """A random graph with random lengths; odd seeds are disconnected (isolated nodes too)."""
    rng = np.random.default_rng(seed)
    n = int(rng.choice([12, 40, 150, 300]))
    if seed % 2:
        g = nx.gnp_random_graph(n, 2.5 / n, seed=seed)
    else:
        g = nx.connected_watts_strogatz_graph(n, 4, 0.3, seed=seed)
    for u, v in g.edges:
        g[u][v]["weight"] = float(rng.uniform(0.5, 2.0))
    graph = sparse.csr_array(nx.to_scipy_sparse_array(g, nodelist=range(n), weight="weight"))
    return g, graph


def _nx_values(g, name, weights):
    w = "weight" if weights else None
    n = g.number_of_nodes()
    if name == "degree":
        d = dict(g.degree(weight=w))
    elif name == "betweenness":
        d = nx.betweenness_centrality(g, normalized=False, weight=w)
    elif name == "closeness":
        d = nx.closeness_centrality(g, distance=w)
    elif name == "harmonic":
        d = nx.harmonic_centrality(g, distance=w)
    elif name == "eccentricity":
        d = {}
        for comp in nx.connected_components(g):
            d.update(nx.eccentricity(g.subgraph(comp), weight=w))
    elif name == "eigenvector":
        d = nx.eigenvector_centrality(g, max_iter=100_000, tol=1e-15, weight=w)
    return np.array([d[i] for i in range(n)], dtype=float)


@pytest.mark.parametrize("weights", [False, True])
@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("name", NAMES)
def test_agrees_with_networkx(name, seed, weights):
    g, graph = _random_case(seed)
    options = {"normalized": False} if name == "eigenvector" else {}  # networkx: unit 2-norm
    options[_WEIGHT_OPTION.get(name, "weights")] = weights
    ours = cen.compute(graph, name, **options)
    np.testing.assert_allclose(ours, _nx_values(g, name, weights), rtol=0, atol=1e-9)


@pytest.mark.parametrize("seed", [0, 1])
def test_normalized_betweenness_agrees_with_networkx(seed):
    g, graph = _random_case(seed)
    ref = nx.betweenness_centrality(g, normalized=True)
    np.testing.assert_allclose(cen.betweenness(graph, normalized=True), [ref[i] for i in range(len(ref))], atol=1e-12)


def test_agrees_with_networkx_on_pixel_and_delaunay_graphs():
    """Graphs of the kind the library is for; larger than one 64-source group."""
    yy, xx = np.mgrid[:30, :30]
    disk = (yy - 14.5) ** 2 + (xx - 14.5) ** 2 < 14**2
    disk[10:14, 8:20] = False  # a slot, so that paths bend
    pixel, _ = pixel_graph(disk)
    tri = delaunay_graph(np.random.default_rng(0).random((400, 2)))
    for graph in (pixel, tri):
        g = nx.from_scipy_sparse_array(graph)
        for name in ("betweenness", "closeness", "harmonic", "eccentricity"):
            np.testing.assert_allclose(cen.compute(graph, name), _nx_values(g, name, False), atol=1e-9, err_msg=name)


def test_eigenvector_tied_components_match_power_iteration():
    # Two disjoint triangles and a path: the triangles tie for the largest eigenvalue 2.
    graph = _graph(8, [(0, 1), (1, 2), (0, 2), (3, 4), (4, 5), (3, 5), (6, 7)])
    np.testing.assert_allclose(cen.eigenvector(graph), [1, 1, 1, 1, 1, 1, 0, 0], atol=1e-12)
    edgeless = sparse.csr_array((4, 4))
    np.testing.assert_allclose(cen.eigenvector(edgeless, normalized=False), 0.5)


@pytest.mark.parametrize("value", [1e-300, 1e-10, 1.0, 1e10, 1e308])
def test_eigenvector_strengths_are_scale_free(value):
    # an edge and a triangle (eigenvalues 1 and 2): at 1e-10 every component counted as tied
    # (an absolute tolerance), at 1e308 the eigenvalues overflowed to NaN
    graph = _graph(5, [(0, 1), (2, 3), (2, 4), (3, 4)]) * value
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_allclose(cen.eigenvector(graph, strengths=True), [0, 0, 1, 1, 1], atol=1e-12)
    lengths = np.array([1.0, 2.0, 3.0])
    expected = cen.eigenvector(_graph(3, [(0, 1), (0, 2), (1, 2)], lengths), strengths=True)
    scaled = _graph(3, [(0, 1), (0, 2), (1, 2)], lengths * (value / 4))
    np.testing.assert_allclose(cen.eigenvector(scaled, strengths=True), expected, rtol=1e-12)


def test_pagerank_follows_a_subnormal_arc_like_any_other():
    # node 0's only arc carries all its mass whatever its value (1 / 1e-310 overflowed: 1000
    # warnings, then "did not converge"); node 1's mass goes to 2 (1e-310 against 1). By hand,
    # alpha = 0.85, n = 3: x0 = 0.05, x1 = 0.05 + 0.85 (x0 + x2), x2 = 0.05 + 0.85 x1
    x1 = 0.135 / (1 - 0.85**2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tiny = cen.pagerank(np.array([[0, 1e-310, 0], [1e-310, 0, 1.0], [0, 1.0, 0]]), strengths=True)
    np.testing.assert_allclose(tiny, [0.05, x1, 0.05 + 0.85 * x1], rtol=1e-10)


def test_pagerank_refuses_a_tolerance_it_can_never_reach():
    # tol=0 was accepted and ran max_iter iterations to "did not converge"
    path = np.array([[0, 1.0, 0], [1.0, 0, 1.0], [0, 1.0, 0]])
    with pytest.raises(ValueError, match=r"`tol` must be .*got 0"):
        cen.pagerank(path, tol=0.0)


def test_eigenvector_large_component_uses_sparse_solver():
    yy, xx = np.mgrid[:40, :40]
    graph, _ = pixel_graph((yy - 20) ** 2 + (xx - 20) ** 2 < 18**2)
    assert graph.shape[0] > 256
    dense = np.linalg.eigh(graph.toarray() > 0)[1][:, -1]
    np.testing.assert_allclose(cen.eigenvector(graph), np.abs(dense) / np.abs(dense).max(), atol=1e-9)


# --- exactness where the libraries are not ---------------------------------------------


def _parts(graph):
    prep = cen._api._prepare(graph, reorder=False)
    return prep.n, prep.indptr, prep.indices, prep.data, None


def _strip(rows, cols):
    graph, _ = pixel_graph(np.ones((rows, cols), dtype=bool))
    return graph


def test_thin_strip_3x300_agrees_with_networkx():
    graph = _strip(3, 300)
    ref = nx.betweenness_centrality(nx.from_scipy_sparse_array(graph), normalized=False)
    np.testing.assert_allclose(cen.betweenness(graph), [ref[i] for i in range(900)], rtol=1e-9)


def test_thin_strip_5x1200_is_finite_symmetric_and_exact_in_total():
    """Shortest-path counts pass 1e308 here; other libraries return NaN."""
    graph = _strip(5, 1200)
    n = graph.shape[0]
    _, indptr, indices, data, _ = _parts(graph)
    sources = np.arange(0, n, 600, dtype=np.int64)
    _, n_log = _kernels.brandes(indptr, indices, data, sources, False, 1e-10, False)
    assert n_log > 0, "the case must overflow float64 path counts"
    values = cen.betweenness(graph)
    assert np.all(np.isfinite(values))
    grid = values.reshape(5, 1200)
    np.testing.assert_allclose(grid, grid[::-1, :], rtol=1e-9)
    np.testing.assert_allclose(grid, grid[:, ::-1], rtol=1e-9)
    # Every shortest s-t path has d(s, t) - 1 inner nodes, so the betweenness adds up to
    # the sum over pairs of (d - 1) whatever the path counts are.
    expected = 0.0
    for lo in range(0, n, 1000):
        d = shortest_path(graph, unweighted=True, indices=np.arange(lo, min(lo + 1000, n)))
        expected += (d - 1).clip(min=0).sum()
    assert values.sum() == pytest.approx(expected / 2, rel=1e-9)


@pytest.mark.parametrize("weights", [False, True])
@pytest.mark.parametrize("seed", range(4))
def test_log_space_path_counts_agree_with_float_counts(seed, weights):
    _, graph = _random_case(seed)
    n, indptr, indices, data, _ = _parts(graph)
    sources = np.arange(n, dtype=np.int64)
    plain, n_plain = _kernels.brandes(indptr, indices, data, sources, weights, 1e-10, False)
    logs, n_logs = _kernels.brandes(indptr, indices, data, sources, weights, 1e-10, True)
    assert n_plain == 0 and n_logs == n
    np.testing.assert_allclose(logs, plain, rtol=1e-10, atol=1e-10)


def _less(p, q):
    """Exact p < q for lengths p = a + b sqrt(2) kept as integer pairs (a, b)."""
    da, db = p[0] - q[0], p[1] - q[1]
    if da <= 0 and db <= 0:
        return (da, db) != (0, 0)
    if da >= 0 and db >= 0:
        return False
    return da * da > 2 * db * db if da < 0 else 2 * db * db > da * da


class _Key:
    def __init__(self, length):
        self.length = length

    def __lt__(self, other):
        return _less(self.length, other.length)


def _exact_weighted_betweenness(image):
    """Brandes with lengths as integer pairs, path counts as ints, dependencies as Fractions."""
    coords = np.argwhere(image)
    index = {tuple(c): i for i, c in enumerate(coords.tolist())}
    adj = [[] for _ in coords]
    for (r, c), i in index.items():
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                j = index.get((r + dr, c + dc))
                if j is not None and j != i:
                    adj[i].append((j, (0, 1) if dr and dc else (1, 0)))
    bc = [Fraction(0)] * len(coords)
    for s in range(len(coords)):
        dist, sigma, preds, order, done = {s: (0, 0)}, {s: 1}, {s: []}, [], set()
        heap = [(_Key((0, 0)), s)]
        while heap:
            _, u = heapq.heappop(heap)
            if u in done:
                continue
            done.add(u)
            order.append(u)
            for v, w in adj[u]:
                if v in done:
                    continue
                nd = (dist[u][0] + w[0], dist[u][1] + w[1])
                if v not in dist or _less(nd, dist[v]):
                    dist[v], sigma[v], preds[v] = nd, sigma[u], [u]
                    heapq.heappush(heap, (_Key(nd), v))
                elif nd == dist[v]:
                    sigma[v] += sigma[u]
                    preds[v].append(u)
        delta = dict.fromkeys(order, Fraction(0))
        for w in reversed(order):
            for v in preds[w]:
                delta[v] += Fraction(sigma[v], sigma[w]) * (1 + delta[w])
            if w != s:
                bc[w] += delta[w]
    return np.array([float(b / 2) for b in bc])


def test_weighted_pixel_betweenness_ties_exactly():
    yy, xx = np.mgrid[:9, :11]
    image = (yy - 4) ** 2 / 16 + (xx - 5) ** 2 / 25 <= 1.0
    image[4, 3:7] = False  # a hole: many equal-length routes around it
    graph, _ = pixel_graph(image)
    exact = _exact_weighted_betweenness(image)
    np.testing.assert_allclose(cen.betweenness(graph, weights=True), exact, rtol=1e-9, atol=1e-9)
    # The case does exercise floating-point ties: exact float comparison (networkx) is off.
    g = nx.from_scipy_sparse_array(graph)
    naive = nx.betweenness_centrality(g, normalized=False, weight="weight")
    assert np.abs(np.array([naive[i] for i in range(len(naive))]) - exact).max() > 1e-3


# --- degree entropy ---------------------------------------------------------------------


def test_degree_entropy_hand_cases():
    star = _graph(5, [(0, i) for i in range(1, 5)])
    assert cen.degree_entropy(star) == pytest.approx(-(0.2 * np.log2(0.2) + 0.8 * np.log2(0.8)))
    k4 = _graph(4, [(i, j) for i in range(4) for j in range(i + 1, 4)])
    assert cen.degree_entropy(k4) == 0.0
    # Isolated nodes count with degree 0: degrees (1, 1, 0, 0) give H = 1.
    assert cen.degree_entropy(_graph(4, [(0, 1)])) == pytest.approx(1.0)
    # MSTME of thesis fig. 7.1: degrees (3, 2, 1, 1, 1), H = 1.37.
    tree = _graph(5, [(0, 1), (0, 2), (0, 3), (3, 4)])
    assert round(cen.degree_entropy(tree), 2) == 1.37


# --- errors and input handling ----------------------------------------------------------


def test_unknown_centrality_name():
    with pytest.raises(ValueError, match="`centrality` must be one of .*'closeness'.* got 'closness'"):
        cen.compute(_graph(2, [(0, 1)]), "closness")


def test_compute_takes_centrality_and_its_former_name_with_a_warning():
    # API audit F6: GPD, the histograms and the CLI say centrality; compute said name
    graph = _graph(3, [(0, 1), (1, 2)])
    with pytest.warns(FutureWarning, match=r"`name` of compute\(\) is renamed `centrality`"):
        old = cen.compute(graph, name="closeness")
    np.testing.assert_array_equal(old, cen.compute(graph, centrality="closeness"))


def test_unknown_option():
    with pytest.raises(TypeError, match="accepts: strengths, normalized"):
        cen.compute(_graph(2, [(0, 1)]), "degree", weight=True)


@pytest.mark.parametrize(
    ("graph", "error", "match"),
    [
        (np.ones((2, 3)), ValueError, r"square adjacency of shape \(n, n\); got shape \(2, 3\)"),
        (np.array([[0, -1], [-1, 0]]), ValueError, "non-negative"),
        (np.array([[0, np.nan], [np.nan, 0]]), ValueError, "finite"),
        (np.array([[0, 1, 1], [1, 0, np.inf], [1, np.inf, 0]]), ValueError, "finite edge lengths"),
        (np.zeros((0, 0)), ValueError, "at least one node"),
        ("graph", TypeError, "`graph` must be a scipy.sparse matrix"),
    ],
)
@pytest.mark.parametrize("name", NAMES)
def test_bad_graphs(name, graph, error, match):
    with pytest.raises(error, match=match):
        cen.compute(graph, name)


@pytest.mark.parametrize("name", NAMES)
def test_bad_flags(name):
    with pytest.raises(TypeError, match="`weights` must be True or False"):
        cen.compute(_graph(2, [(0, 1)]), name, weights="yes")


@pytest.mark.parametrize("name", NAMES)
def test_input_not_modified(name, table_2_1_graph):
    graph = table_2_1_graph.copy()
    graph.data *= 2.0
    before = graph.copy()
    cen.compute(graph, name, **{_WEIGHT_OPTION.get(name, "weights"): True})
    assert (graph != before).nnz == 0 and graph.indices.dtype == before.indices.dtype


def test_accepts_dense_and_other_sparse_formats(table_2_1_graph):
    expected = cen.betweenness(table_2_1_graph)
    np.testing.assert_allclose(cen.betweenness(table_2_1_graph.toarray()), expected)
    np.testing.assert_allclose(cen.betweenness(sparse.coo_matrix(table_2_1_graph)), expected)


def test_progress_bar_writes_to_stderr(capsys, table_2_1_graph):
    cen.betweenness(table_2_1_graph, progress=True)
    assert "betweenness" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["betweenness", "closeness", "harmonic", "eccentricity"])
def test_results_do_not_depend_on_thread_count(name):
    import centrality_vision as cv

    _, graph = _random_case(3)  # 300 nodes, disconnected: many chunks and groups
    try:
        cv.set_num_threads(1)
        single = cen.compute(graph, name)
        cv.set_num_threads(3)
        multi = cen.compute(graph, name, weights=True), cen.compute(graph, name)
        cv.set_num_threads(1)
        np.testing.assert_allclose(multi[0], cen.compute(graph, name, weights=True), rtol=1e-12)
    finally:
        cv.set_num_threads(None)
    np.testing.assert_allclose(multi[1], single, rtol=1e-12)


def test_set_num_threads_validates():
    import centrality_vision as cv

    with pytest.raises(ValueError, match=r"`n` must be an int in \[1, 2\^62\]"):
        cv.set_num_threads(0)


def test_compute_names_the_unknown_option():
    with pytest.raises(TypeError, match=r"unknown option `bogus`; it accepts: .*normalized"):
        cen.compute(np.eye(3), "degree", bogus=1)


def test_eigenvector_runs_lapack_on_one_blas_thread(monkeypatch):
    # LAPACK's eigh in a 1-thread worker and in a many-thread parent differed in the last bits,
    # so features depended on n_jobs; every BLAS call of the eigenvector runs on one thread
    from threadpoolctl import threadpool_info

    from centrality_vision.centrality import _spectral

    seen = []
    eigh = np.linalg.eigh

    def spy(a):
        seen.append(max(info["num_threads"] for info in threadpool_info()))
        return eigh(a)

    monkeypatch.setattr(_spectral.np.linalg, "eigh", spy)
    graph = sparse.csr_array(np.ones((5, 5)) - np.eye(5))
    blocks = sparse.block_diag([graph, graph[:3, :3]], format="csr")
    values = cen.eigenvector(blocks)
    assert seen == [1, 1]  # one call per component, each on one thread
    np.testing.assert_allclose(values[:5], values[0])
    np.testing.assert_allclose(values[5:], values[5])


def test_normalised_degree_and_harmonic_on_a_path_by_hand():
    """A path of 4 nodes: its largest degree (2) is not n - 1 (3), so dividing by either tells
    the rules apart (the star and the doctest have both equal). Harmonic: sum of 1/d over
    the others, over n - 1: (1 + 1/2 + 1/3) / 3 and (1 + 1 + 1/2) / 3."""
    path = np.array([[0, 1, 0, 0], [1, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0]])
    np.testing.assert_allclose(cen.degree(path, normalized=True), [0.5, 1.0, 1.0, 0.5], rtol=1e-15)
    np.testing.assert_allclose(cen.harmonic(path, normalized=True), [11 / 18, 5 / 6, 5 / 6, 11 / 18], rtol=1e-15)


def test_a_self_loop_counts_for_no_measure():
    looped = np.array([[1, 1, 0], [1, 0, 1], [0, 1, 0]])
    plain = looped - np.diag(np.diag(looped))
    np.testing.assert_array_equal(cen.degree(looped), [1, 2, 1])
    for name in NAMES:
        np.testing.assert_allclose(cen.compute(looped, name), cen.compute(plain, name), rtol=1e-15)

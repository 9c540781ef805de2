"""Bad arguments found by fuzzing the graph, centrality and shape APIs: each is a ValueError or
TypeError naming the parameter (before: unhashable-type, numba typing, overflow and reshape
errors from deep inside, a wrong parameter named, truthy strings taken as True, NaN cached)."""

import math

import numpy as np
import pytest

from centrality_vision import graphs
from centrality_vision._validation import check_float
from centrality_vision.exceptions import InputError
from centrality_vision.graphs import mwme_degrees, mwme_graph, nhdd_graph, pixel_coordinates, pixel_graph, to_networkx
from centrality_vision.shapes import (
    CentralityCache,
    CentralityComparisonForest,
    CentralityComparisons,
    as_shape_images,
    bullseye_score,
    shape_centralities,
)
from centrality_vision.transforms import SimilarityTransform

POINTS = np.random.default_rng(0).random((6, 2))
SQUARE = np.pad(np.ones((3, 3), dtype=bool), 1)


def _masks():
    out = []
    for i in range(6):
        mask = np.zeros((12, 12), dtype=bool)
        mask[2 : 6 + i % 3, 2:9] = True
        out.append(mask)
    return out


CASES = [
    (lambda: pixel_graph(np.ones((3, 3), dtype=bool), connectivity=[8]), "`connectivity` must be 8 or 4"),
    (lambda: pixel_graph(np.arange(16.0).reshape(4, 4), threshold=10**400), "`threshold` must be a finite real"),
    (lambda: mwme_graph(POINTS, max_iter=10**20), "`max_iter` must be an int in [1, 2^62]"),
    (lambda: mwme_graph(POINTS, progress="no"), "`progress` must be True or False"),
    (lambda: nhdd_graph(10**20), "`n` must be an int in [3, 20000]"),
    (lambda: nhdd_graph(5, connected="no"), "`connected` must be True or False"),
    (lambda: mwme_degrees([[[0, 0], [0, 0], [1, 1]]]), "`point_sets[0]` must not contain duplicate points"),
    (lambda: mwme_degrees(np.zeros((1, 3, 0))), "`point_sets` must have shape (n_sets, n_points, n_dims)"),
    (lambda: shape_centralities([SQUARE], ["bogus"]), "`centrality` must be one of"),
    (lambda: as_shape_images(np.array(2)), "must be a sequence of 2D binary images"),
    (lambda: pixel_coordinates([0], np.array(2)), "`shape` must be (n_rows, n_cols)"),
    (lambda: to_networkx(graphs.delaunay_graph(POINTS), weight=[]), "`weight` must be a str"),
    (
        lambda: bullseye_score(np.abs(np.subtract.outer([0.0, 1, 2, 3], [0.0, 1, 2, 3])), list("aabb"), top=10**20),
        "`top` must be an int in [1, 2^62]",
    ),
    (
        lambda: CentralityComparisons(n_comparisons=10**20).fit(_masks()),
        "`n_comparisons` must be an int in [1, 10000000]",
    ),
    (lambda: CentralityComparisons(extent=1e20).fit(_masks()), "`extent` must be a finite number in (0, 1e+06]"),
    (
        lambda: CentralityComparisonForest(n_estimators=3, n_comparisons=20, max_depth=10**20).fit(
            _masks(), [0, 1] * 3
        ),
        "`max_depth` must be an int in [1, 2^62]",
    ),
    (
        lambda: CentralityComparisonForest(n_estimators=3, n_comparisons=20, max_features=10**20).fit(
            _masks(), [0, 1] * 3
        ),
        "`max_features` must be an int in [1, 2^62]",
    ),
    (lambda: CentralityCache().put(SQUARE, "closeness", np.full(9, np.nan)), "`values` must be finite"),
    (lambda: CentralityCache().put(SQUARE, "bogus", np.ones(9)), "`centrality` must be one of"),
    (lambda: CentralityCache().put(SQUARE, "closeness", np.ones(9), connectivity=5), "`connectivity` must be 4 or 8"),
]


@pytest.mark.parametrize(("call", "message"), CASES, ids=[message for _, message in CASES])
def test_a_bad_argument_is_a_named_error(call, message):
    with pytest.raises((ValueError, TypeError)) as info:
        call()
    assert message in str(info.value)


def test_a_nan_put_is_not_served_later():
    cache = CentralityCache()
    with pytest.raises(ValueError):
        cache.put(SQUARE, "closeness", np.full(9, np.nan))
    values = shape_centralities([SQUARE], ["closeness"], cache=cache)[0]["closeness"]
    assert np.all(np.isfinite(values))


def test_job_counts_and_resolutions_beyond_c_and_memory_are_named():
    from centrality_vision.shapes import normalize_shape, pairwise_shape_distances

    with pytest.raises(ValueError, match=r"`n_jobs` must be None, a positive int"):
        pairwise_shape_distances([SQUARE, SQUARE], n_points=8, resolution=8, n_jobs=10**20)  # OverflowError
    with pytest.raises(ValueError, match=r"`resolution` must be an int in \[1, 32768\]"):
        normalize_shape(SQUARE, resolution=10**12)  # numpy's "array is too big"


@pytest.mark.parametrize(
    "call",
    [
        lambda bad: graphs.delaunay_graph(bad),
        lambda bad: mwme_graph(bad),
        lambda bad: pixel_graph(np.tile(bad[:, :1], (1, 6))),
        lambda bad: __import__("centrality_vision.matching", fromlist=["match"]).match(bad, POINTS),
    ],
)
def test_durations_are_not_coordinates_or_pixel_values(call):
    # fuzz round 6 (L7): numpy counts timedelta64 as a number, so durations were read as
    # coordinates (datetime64 was refused)
    durations = (POINTS * 1000).astype("m8[ms]")
    with pytest.raises(TypeError, match=r"`(points|image|moving)` must .*timedelta64"):
        call(durations)


@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan, 0.0])
def test_an_unbounded_side_reads_open(value):
    # "(0, inf]" said inf was allowed, next to "got inf"
    with pytest.raises(InputError, match=r"`scale` must be a finite number in \(0, inf\); got"):
        SimilarityTransform(np.eye(2), [0.0, 0.0], scale=value)
    with pytest.raises(InputError, match=r"`x` must be a finite number in \(-inf, 1\]; got"):
        check_float(math.inf if value != 0 else 2.0, name="x", high=1.0)


def _masked(values, where):
    array = np.ma.masked_array(np.array(values, dtype=float))
    array[where] = np.ma.masked
    return array


_PICTURE = np.zeros((5, 6))
_PICTURE[1:4, 1:4] = 255.0
_DISTANCES = np.abs(np.subtract.outer(np.arange(4.0), np.arange(4.0))) + ~np.eye(4, dtype=bool)

# fuzz round 10: each was accepted with its mask ignored, or raised numpy's own error, or
# described a reshaped array instead of the argument given
ROUND_10 = [
    (lambda: pixel_graph(_masked(_PICTURE, (0, 0))), TypeError, "`image` must be a plain array; got a masked array"),
    (
        lambda: pixel_graph(_masked(np.ones((2, 3, 3)), (0, 0, 0))),
        TypeError,
        "`image` must be a plain array; got a masked array",
    ),
    (lambda: pixel_graph([[0, 1], [1]]), InputError, "`image` must be a 2D or 3D array; got [[0, 1], [1]]"),
    (
        lambda: pixel_graph(np.stack([_PICTURE] * 3, axis=-1)),
        InputError,
        "(an image of 3 colour channels? average them, image.mean(axis=-1)",
    ),
    (lambda: pixel_graph(np.ones((3, 3, 2)), threshold=True), TypeError, "`threshold` must be a finite real number"),
    (lambda: pixel_graph(SQUARE, spacing=(True, True)), TypeError, "`spacing` must be 2 positive finite numbers; got"),
    (lambda: pixel_graph(SQUARE, spacing=[[1, 2]]), InputError, "`spacing` must be 2 positive finite numbers"),
    (
        lambda: mwme_graph(_masked(_DISTANCES, (0, 3)), metric="precomputed"),
        TypeError,
        "(metric='precomputed') must be a plain array",
    ),
    (lambda: mwme_graph(_DISTANCES > 0, metric="precomputed"), TypeError, "must hold real numbers (not booleans)"),
    (lambda: mwme_degrees(np.zeros((0, 5, 2))), InputError, "with n_sets >= 1, 3 <= n_points <= 20"),
    (lambda: mwme_degrees(np.zeros((1, 4, 65))), InputError, "1 <= n_dims <= 64; got shape (1, 4, 65)"),
    (
        lambda: mwme_degrees(
            np.where(np.arange(3)[:, None, None] == 2, np.nan, np.random.default_rng(0).random((3, 5, 2)))
        ),
        InputError,
        "`point_sets[2]` must be finite",
    ),
    (lambda: mwme_degrees(None), TypeError, "`point_sets` must hold real numbers; got None"),
    (lambda: to_networkx(None), TypeError, "`graph` must be a scipy.sparse matrix, a square array"),
    (lambda: to_networkx(-_DISTANCES), InputError, "non-negative edge lengths; got min -4."),
]


@pytest.mark.parametrize(("call", "kind", "message"), ROUND_10, ids=[message for _, _, message in ROUND_10])
def test_masked_ragged_and_reshaped_inputs_are_named(call, kind, message):
    with pytest.raises(kind) as info:
        call()
    assert message in str(info.value)


def test_a_boolean_3d_image_is_a_mask_whatever_the_threshold_as_in_2d():
    """A 2D mask ignored ``threshold`` and a 3D mask applied it (and failed: no foreground)."""
    volume = np.zeros((2, 3, 3), dtype=bool)
    volume[0] = True
    assert pixel_graph(volume, threshold=5)[0].shape == pixel_graph(volume)[0].shape == (9, 9)
    assert pixel_graph(SQUARE, threshold=5)[0].shape == (9, 9)


def _weightless_edge(kind):
    if kind == "networkx":
        import networkx as nx

        graph = nx.Graph()
        graph.add_edge(0, 1, weight=2.0)
        graph.add_edge(1, 2, weight=None)
        return graph
    try:
        import igraph
    except ImportError:  # (not a dependency: the parts of igraph's Graph the reader uses)
        return _IgraphLike([(0, 1), (1, 2)], [2.0, None])
    graph = igraph.Graph([(0, 1), (1, 2)])
    graph.es[0]["weight"] = 2.0  # the other edge gets None
    return graph


class _Attributes(dict):
    def attributes(self):
        return list(self)


class _IgraphLike:
    """What the graph reader asks of an ``igraph.Graph``: edges, their weights, vertices."""

    __module__ = "igraph"

    def __init__(self, edges, weights):
        self._edges = edges
        self.es = _Attributes(weight=weights)
        self.vs = _Attributes()

    def get_edgelist(self):
        return list(self._edges)

    def vcount(self):
        return 1 + max(max(edge) for edge in self._edges)

    def is_directed(self):
        return False


@pytest.mark.parametrize("kind", ["networkx", "igraph"])
def test_an_edge_with_weight_none_is_named_not_called_nan(kind):
    from centrality_vision import centrality

    with pytest.raises(TypeError, match=r"edge \(1, 2\) has weight None"):
        centrality.closeness(_weightless_edge(kind), weights=True)


def test_pixel_coordinates_of_no_nodes_and_of_shapes_past_int64():
    """An empty list (float64 to numpy) was refused; a shape of 2^80 pixels wrapped around in
    np.prod and the message blamed node 1."""
    assert pixel_coordinates([], (5, 6)).shape == (0, 2)
    with pytest.raises(InputError, match=r"`shape` must have fewer than 2\^63 pixels"):
        pixel_coordinates([1], (2**40, 2**40))


def test_read_shape_of_extreme_grey_values_warns_nothing(tmp_path):
    """np.ptp overflowed on values of +-1e308 (a RuntimeWarning, an error under -W error)."""
    tifffile = pytest.importorskip("tifffile")
    from centrality_vision.io import read_shape

    picture = np.full((6, 6), -1e308)
    picture[2:4, 2:4] = 1e308
    tifffile.imwrite(tmp_path / "extreme.tif", picture)
    assert read_shape(tmp_path / "extreme.tif").sum() == 4


def test_a_tiff_page_of_too_many_samples_is_described_as_decoded(tmp_path):
    tifffile = pytest.importorskip("tifffile")
    from centrality_vision.io import read_image

    tifffile.imwrite(tmp_path / "five.tif", np.zeros((12, 10, 5), dtype=np.uint8), photometric="rgb")
    expected = r"five\.tif: must be a 2D grey or colour image; got an array of shape \(12, 10, 5\)\."
    with pytest.raises(InputError, match=expected):
        read_image(tmp_path / "five.tif")


def test_as_dict_refuses_repeated_or_unhashable_igraph_names():
    # found by fuzz round 16: names ['a', 'b', 'a', 'c'] gave 3 entries for 4 nodes (one value
    # overwritten), and list names a bare "unhashable type: 'list'"
    from centrality_vision import centrality as cen

    graph = _IgraphLike([(0, 1), (1, 2), (2, 3)], [1.0, 1.0, 1.0])
    graph.vs["name"] = ["a", "b", "a", "c"]
    np.testing.assert_array_equal(cen.betweenness(graph), [0.0, 2.0, 2.0, 0.0])  # the array is fine
    with pytest.raises(InputError, match=r"`as_dict` \(True\) needs distinct node labels; the graph names 'a'"):
        cen.betweenness(graph, as_dict=True)
    graph.vs["name"] = [[1], [2], [3], [4]]
    with pytest.raises(TypeError, match=r"`as_dict` \(True\) needs hashable node labels; got the label \[1\]"):
        cen.degree(graph, as_dict=True)
    graph.vs["name"] = ["a", "b", "c", "d"]
    assert cen.degree(graph, as_dict=True) == {"a": 1.0, "b": 2.0, "c": 2.0, "d": 1.0}


@pytest.mark.parametrize("dtype", ["<U3", "S3", "timedelta64[s]", "datetime64[s]"])
def test_a_dense_graph_of_text_or_times_is_refused(dtype):
    # found by fuzz round 16: '2.5' text converted to lengths (closeness [0.4, 0.4]); point
    # sets of these dtypes were already refused
    from centrality_vision import centrality as cen

    adjacency = np.array([[0, 2], [2, 0]]).astype(dtype)
    with pytest.raises(TypeError, match=r"`graph` must hold real edge lengths; got array of shape \(2, 2\)"):
        cen.closeness(adjacency, weights=True)


def test_sampling_options_are_checked_when_the_values_are_exact():
    # found by fuzz round 16: delta=nan and seed='a' passed unnoticed without epsilon
    from centrality_vision import centrality as cen

    triangle = np.ones((3, 3)) - np.eye(3)
    for function in (cen.betweenness, cen.closeness, cen.harmonic):
        with pytest.raises(InputError, match=r"`delta` must be a finite number in \[0, 1\]; got nan"):
            function(triangle, delta=float("nan"))
        with pytest.raises(TypeError, match="`seed` must be None, a non-negative int"):
            function(triangle, seed="a")
    generator = np.random.default_rng(0)
    cen.betweenness(triangle, seed=generator)
    assert generator.random() == np.random.default_rng(0).random()  # nothing drawn from it


def test_a_spacing_with_a_boolean_among_numbers_is_refused():
    with pytest.raises(TypeError, match=r"`spacing` must be 2 positive finite numbers; got booleans \(True, 1\)"):
        pixel_graph(np.ones((3, 3), dtype=bool), spacing=(True, 1))  # (it was read as (1, 1))


def test_a_precomputed_mwme_matrix_names_what_is_wrong_and_where():
    distances = np.array([[0.0, 1.0, 2.0], [1.0, 0.0, 3.0], [2.0, 4.0, 0.0]])
    with pytest.raises(InputError, match=r"entries \(1, 2\) and \(2, 1\) differ: 3 and 4"):
        mwme_graph(distances, metric="precomputed")
    distances[2, 1] = 3.0
    distances[0, 0] = 0.5
    with pytest.raises(InputError, match=r"diagonal entry \(0, 0\) is 0.5"):
        mwme_graph(distances, metric="precomputed")
    distances[0, 0], distances[0, 2], distances[2, 0] = 0.0, 0.0, 0.0
    with pytest.raises(InputError, match=r"off-diagonal entry \(0, 2\) is 0 \(distinct points"):
        mwme_graph(distances, metric="precomputed")


def test_numbers_held_as_objects_are_points_as_a_graphs_are_edge_lengths():
    # audit 25 L5: an object array of numbers (a mixed-type DataFrame's .values, ints past
    # int64) was refused as points but read as a graph; now both read it, and keep the input
    held = np.array([[0, 0], [1, 0], [0, 1.5]], dtype=object)
    before = held.copy()
    np.testing.assert_array_equal(
        graphs.delaunay_graph(held).toarray(), graphs.delaunay_graph(before.astype(float)).toarray()
    )
    assert held.dtype == object and np.array_equal(held, before)
    big = graphs.knn_graph([[0, 0], [1, 0], [0, 10**20]], n_neighbors=1)  # 10**20 makes numpy choose objects
    assert big.shape == (3, 3)
    for bad in ([[0, None], [1, 1]], [[0, "1"], [1, 1]], [[0, 10**400], [1, 1]]):
        with pytest.raises(TypeError, match="`points` must hold real numbers"):
            graphs.delaunay_graph(np.array(bad, dtype=object))

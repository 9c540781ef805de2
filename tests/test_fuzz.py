"""Fuzzing the public API: every call either returns a finite answer or raises a named error.

Each property draws inputs a user could pass (point sets at extreme scales and offsets, with
duplicates, collinear rows, NaN and inf; random graphs, including disconnected and weighted
ones; images with and without a shape) and checks the one contract of the library:

- the call returns, with every float in the result finite, or
- it raises :class:`~centrality_vision.exceptions.InputError` (a ValueError) or a TypeError whose
  message names a parameter in backquotes, and nothing else (no IndexError, ZeroDivisionError,
  LinAlgError, MemoryError, segfault or hang; hypothesis' deadline catches slow paths);
- the inputs are left unchanged.
"""

from __future__ import annotations

import os
import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import sparse

from centrality_vision import centrality as cen
from centrality_vision import graphs
from centrality_vision.exceptions import InputError
from centrality_vision.registration import GPD, ICP, AffineCPD, MultiscaleCPD, NonRigidCPD, RigidCPD
from centrality_vision.transforms import fit_similarity

FUZZ = settings(
    max_examples=25,
    deadline=5000,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

SCALES = [1e-300, 1e-150, 1e-8, 1.0, 1e8, 1e150, 1e300]
OFFSETS = [0.0, 1.0, 1e8, 1e15]
_NAMED = re.compile(r"`[A-Za-z_][\w\[\]. ']*`")  # a name, an attribute or an item (`errors['a']`)


@st.composite
def point_sets(draw, *, dims=(2, 3), min_points=1, max_points=24, allow_bad=True):
    """Point sets as users have them: any scale and offset, repeated rows, lines, NaN."""
    n_dims = draw(st.sampled_from(dims))
    n_points = draw(st.integers(min_points, max_points))
    kind = draw(st.sampled_from(["random", "grid", "line", "same"]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    if kind == "random":
        points = rng.random((n_points, n_dims))
    elif kind == "grid":  # many ties and duplicates
        points = rng.integers(0, 3, size=(n_points, n_dims)).astype(float)
    elif kind == "line":
        points = np.outer(rng.random(n_points), rng.random(n_dims))
    else:
        points = np.repeat(rng.random((1, n_dims)), n_points, axis=0)
    points = points * draw(st.sampled_from(SCALES)) + draw(st.sampled_from(OFFSETS))
    if allow_bad and draw(st.integers(0, 9)) == 0:
        points[rng.integers(n_points), rng.integers(n_dims)] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    return points


@st.composite
def adjacency(draw, *, max_nodes=30):
    """Random symmetric graphs: sparse or dense, weighted or not, connected or not."""
    n = draw(st.integers(1, max_nodes))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    density = draw(st.sampled_from([0.0, 0.05, 0.2, 0.6, 1.0]))
    upper = np.triu(rng.random((n, n)) < density, 1)
    lengths = draw(st.sampled_from(["ones", "random", "tiny", "huge"]))
    values = {"ones": np.ones((n, n)), "random": rng.random((n, n)) + 0.1}.get(lengths)
    if values is None:
        values = rng.random((n, n)) * (1e-200 if lengths == "tiny" else 1e200) + (1e-200 if lengths == "tiny" else 1.0)
    dense = np.where(upper, values, 0.0)
    dense = dense + dense.T
    return sparse.csr_array(dense)


@st.composite
def images(draw):
    """Binary and grey images, with and without a shape, touching the border or not."""
    rows, cols = draw(st.integers(1, 24)), draw(st.integers(1, 24))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    kind = draw(st.sampled_from(["blob", "noise", "empty", "full", "grey"]))
    image = np.zeros((rows, cols), dtype=bool)
    if kind == "blob":
        r, c = np.ogrid[:rows, :cols]
        image = (r - rows / 2) ** 2 + (c - cols / 2) ** 2 <= (min(rows, cols) / 3) ** 2
    elif kind == "noise":
        image = rng.random((rows, cols)) < 0.5
    elif kind == "full":
        image = np.ones((rows, cols), dtype=bool)
    elif kind == "grey":
        return (rng.random((rows, cols)) * 255).astype(np.uint8)
    return image


def _finite(value, where="result"):
    if isinstance(value, np.ndarray):
        if np.issubdtype(value.dtype, np.floating):
            assert np.all(np.isfinite(value)), f"non-finite values in {where}"
    elif sparse.issparse(value):
        _finite(value.data, where)
    elif isinstance(value, float):
        assert np.isfinite(value), f"non-finite {where}: {value}"
    elif isinstance(value, (tuple, list)):
        for i, item in enumerate(value):
            _finite(item, f"{where}[{i}]")


def honest(call, *args, **kwargs):
    """Run ``call``: a finite result or a named InputError/TypeError; inputs unchanged."""
    copies = [a.copy() if isinstance(a, np.ndarray) or sparse.issparse(a) else None for a in args]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # warnings are allowed; silence is not checked here
            result = call(*args, **kwargs)
    except (InputError, TypeError) as exc:
        assert _NAMED.search(str(exc)), f"{type(exc).__name__} names no parameter: {exc}"
        result = None
    for before, after in zip(copies, args):
        if before is None:
            continue
        if sparse.issparse(before):
            assert (before != after).nnz == 0, "an input graph was modified"
        else:
            np.testing.assert_array_equal(before, after, err_msg="an input array was modified")
    if result is not None:
        _finite(result)
    return result


# --------------------------------------------------------------------------- graphs
@pytest.mark.parametrize(
    "builder",
    [
        graphs.delaunay_graph,
        graphs.gabriel_graph,
        graphs.emst_graph,
        graphs.complete_graph,
        lambda points: graphs.knn_graph(points, n_neighbors=3),
    ],
    ids=["delaunay", "gabriel", "emst", "complete", "knn"],
)
@FUZZ
@given(points=point_sets())
def test_point_graphs(builder, points):
    graph = honest(builder, points)
    if graph is not None:
        assert graph.shape == (points.shape[0], points.shape[0])
        assert (graph != graph.T).nnz == 0
        assert np.all(graph.data > 0) and np.all(np.isfinite(graph.data))  # a stored edge is an edge
    if points.shape[0] >= 4 and np.all(np.isfinite(points)):
        # two points far closer than their coordinates' size: squares of their differences underflow
        near = points.copy()
        near[:2] = 0.0
        near[1, 0] = 1e-170 * float(np.abs(points).max())
        graph = honest(builder, near)
        if graph is not None:
            assert np.all(graph.data > 0) and (graph != graph.T).nnz == 0


@FUZZ
@given(points=point_sets(max_points=9))
def test_entropy_graphs(points):
    honest(lambda p: graphs.mwme_graph(p).graph, points)
    honest(lambda p: graphs.mstme_graph(p).graph, points)


@FUZZ
@given(image=images(), connectivity=st.sampled_from([4, 8, 6]))
def test_pixel_graph(image, connectivity):
    honest(graphs.pixel_graph, image, connectivity=connectivity)


# --------------------------------------------------------------------------- centralities
@pytest.mark.parametrize("name", ["degree", "betweenness", "closeness", "harmonic", "eigenvector", "eccentricity"])
@FUZZ
@given(graph=adjacency(), weights=st.booleans())
def test_centralities(name, graph, weights):
    values = honest(cen.compute, graph, name, weights=weights)
    if values is not None:
        assert values.shape == (graph.shape[0],)


@FUZZ
@given(graph=adjacency())
def test_degree_entropy(graph):
    value = honest(cen.degree_entropy, graph)
    if value is not None:
        assert 0.0 <= value <= np.log2(max(graph.shape[0], 1)) + 1e-12


# --------------------------------------------------------------------------- registration
@pytest.mark.parametrize(
    "make",
    [
        lambda: RigidCPD(max_iter=20),
        lambda: RigidCPD(scale=True, max_iter=20),
        lambda: AffineCPD(max_iter=20),
        lambda: NonRigidCPD(max_iter=10),
        lambda: ICP(max_iter=20),
    ],
    ids=["rigid", "similarity", "affine", "nonrigid", "icp"],
)
@FUZZ
@given(moving=point_sets(max_points=15), data=st.data())
def test_registration(make, moving, data):
    fixed = data.draw(point_sets(dims=(moving.shape[1],), max_points=15))
    estimator = honest(lambda m, f: make().fit(m, f), moving, fixed)
    if estimator is not None:
        _finite(estimator.moving_transformed_, "moving_transformed_")
        assert estimator.moving_transformed_.shape == moving.shape


@st.composite
def estimators(draw):
    """A CPD estimator with a random combination of its options, bare or under GPD or MultiscaleCPD."""
    kind = draw(st.sampled_from(["rigid", "similarity", "affine", "nonrigid"]))
    kw = {"max_iter": draw(st.integers(1, 12))}
    kw["w"] = draw(st.sampled_from([0.0, 0.1, 0.9, "auto"]))
    if draw(st.booleans()):
        kw["n_neighbors"] = draw(st.integers(1, 8))
    else:
        kw["method"] = draw(st.sampled_from(["auto", "dense", "truncated", "fgt"]))
    kw["accelerate"] = draw(st.booleans())
    kw["precision"] = draw(st.sampled_from(["float64", "float32"]))
    kw["normalize"] = draw(st.booleans())
    kw["tol"] = draw(st.sampled_from([0.0, 1e-12, 1e-3]))
    if kind == "nonrigid":
        kw["low_rank"] = draw(st.sampled_from([None, 3, "auto"]))
        estimator = NonRigidCPD(**kw)
    elif kind == "affine":
        estimator = AffineCPD(**kw)
    else:
        estimator = RigidCPD(scale=kind == "similarity", init=draw(st.sampled_from([None, "global"])), **kw)
    wrap = draw(st.sampled_from(["none", "none", "gpd", "multiscale"]))
    if wrap == "gpd" and kw.get("method") != "fgt":
        return GPD(estimator, centrality=draw(st.sampled_from(["closeness", "degree"])), prior_schedule="anneal")
    if wrap == "multiscale":
        return MultiscaleCPD(estimator, sizes=(draw(st.integers(2, 8)), 12), refine_max_iter=2)
    return estimator


@settings(FUZZ, max_examples=100, deadline=60_000)  # (numba compiles some paths on first use)
@given(estimator=estimators(), moving=point_sets(max_points=15), data=st.data())
def test_registration_option_combinations(estimator, moving, data):
    # the option combinations a fuzz run over 400,000 fits checked (a hang and six crashes
    # were found there and fixed): the same contract as the defaults above
    fixed = data.draw(point_sets(dims=(moving.shape[1],), max_points=15))
    fitted = honest(lambda m, f: estimator.fit(m, f), moving, fixed)
    if fitted is not None:
        _finite(fitted.moving_transformed_, "moving_transformed_")
        _finite(float(fitted.sigma2_), "sigma2_")


@FUZZ
@given(source=point_sets(max_points=12), data=st.data())
def test_fit_similarity(source, data):
    target = data.draw(point_sets(dims=(source.shape[1],), min_points=source.shape[0], max_points=source.shape[0]))
    honest(lambda s, t: fit_similarity(s, t).matrix, source, target)


# --------------------------------------------------------------------------- matching
@pytest.mark.parametrize("method", ["robust", "shape-context", "mwme"])
@settings(FUZZ, max_examples=12)
@given(moving=point_sets(dims=(2,), max_points=16), data=st.data(), scale=st.booleans())
def test_match(method, moving, data, scale):
    from centrality_vision.matching import match

    if method == "mwme":  # the global matching pairs sets of one size (3D allowed)
        moving = data.draw(point_sets(max_points=10))
        size = {"min_points": moving.shape[0], "max_points": moving.shape[0]}
    else:
        size = {"max_points": 16}
    fixed = data.draw(point_sets(dims=(moving.shape[1],), **size))
    result = honest(
        lambda m, f: (lambda r: (r.correspondence, r.transform.matrix))(match(m, f, method=method, scale=scale)),
        moving,
        fixed,
    )
    if result is not None:
        correspondence, matrix = result
        assert correspondence.shape == (moving.shape[0],) and np.issubdtype(correspondence.dtype, np.integer)
        assert correspondence.min() >= -1 and correspondence.max() < fixed.shape[0]
        assert matrix.shape == (moving.shape[1] + 1, moving.shape[1] + 1)


# --------------------------------------------------------------------------- io
_FLOATS = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(FUZZ, max_examples=20)
@given(
    suffix=st.sampled_from([".csv", ".txt", ".xyz", ".npy", ".mat", ".ply", ".pcd", ".obj"]),
    n_dims=st.sampled_from([2, 3]),
    rows=st.lists(st.lists(_FLOATS, min_size=3, max_size=3), min_size=1, max_size=12),
)
def test_io_round_trip(suffix, n_dims, rows):
    """Every finite array written is read back bit for bit, or refused with a named error."""
    import tempfile
    from pathlib import Path

    from centrality_vision.io import read_points, write_points

    points = np.array(rows, dtype=float)[:, :n_dims]
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"points{suffix}"
        written = honest(lambda p: write_points(path, p), points)
        if written is None and not path.exists():  # refused (e.g. 2D points for a 3D format)
            assert suffix in {".ply", ".pcd", ".obj"} and n_dims == 2
            return
        back = read_points(path)
    np.testing.assert_array_equal(back, points)


@settings(FUZZ, max_examples=20)
@given(data=st.binary(max_size=200), suffix=st.sampled_from([".csv", ".npy", ".mat", ".ply", ".pcd", ".obj"]))
def test_read_points_of_random_bytes(data, suffix):
    """Any bytes: points or an InputError naming `path` (never another exception)."""
    import tempfile
    from pathlib import Path

    from centrality_vision.io import read_points

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"random{suffix}"
        path.write_bytes(data)
        try:
            points = read_points(path)
        except InputError as exc:
            assert str(path) in str(exc) or _NAMED.search(str(exc)), str(exc)
        else:
            assert points.ndim == 2 and points.shape[1] in (2, 3)


# --------------------------------------------------------------------------- plotting
@settings(FUZZ, max_examples=15)
@given(points=point_sets(max_points=12), data=st.data())
def test_plotting(points, data):
    """The plotting functions on random inputs, each on an Agg canvas (no pyplot, no backend switch)."""
    from matplotlib.figure import Figure

    from centrality_vision import plotting

    n, n_dims = points.shape
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    upper = sparse.triu(sparse.random_array((n, n), density=0.3, rng=rng), 1)
    graph = sparse.csr_array(upper + upper.T)
    values = data.draw(st.sampled_from([None, rng.random(n), np.full(n, 1e300), np.zeros(n), rng.random(n + 1)]))
    norm = data.draw(st.sampled_from([None, "linear", "log", "power"]))

    def canvas():
        return Figure().add_subplot(projection="3d" if n_dims == 3 else None)

    honest(lambda p: plotting.plot_graph(p, graph, values, ax=canvas(), norm=norm) and None, points)
    honest(lambda p: plotting.plot_registration(p, p[::-1] * 2.0, ax=canvas()) and None, points)
    if n_dims == 2:
        correspondence = rng.integers(-1, n, size=n)
        honest(lambda p: plotting.plot_matching(p, p[::-1], correspondence, ax=canvas()) and None, points)
    image = data.draw(images())
    nodes = np.argwhere(image)
    honest(
        lambda v: plotting.plot_centrality_image(v, nodes, image.shape, ax=Figure().add_subplot(), norm=norm) and None,
        rng.random(len(nodes)),
    )
    errors = {"a": data.draw(st.lists(st.floats(0, 1e300), min_size=0, max_size=6)), "b": [1.0, 0.0, -0.0]}
    honest(lambda e: plotting.plot_alignment_errors(e, ax=Figure().add_subplot()) and None, errors)


def test_hypothesis_examples_are_the_same_on_every_run():
    """Settings made in a test module inherit the session's profile: derandomized unless a fuzz
    run asks for new examples (`HYPOTHESIS_PROFILE=fuzz`)."""
    expected = os.environ.get("HYPOTHESIS_PROFILE", "reproducible") != "fuzz"
    assert FUZZ.derandomize is expected
    assert settings(max_examples=3).derandomize is expected

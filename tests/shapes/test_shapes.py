import numpy as np
import pytest
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, cross_val_score
from sklearn.naive_bayes import GaussianNB
from sklearn.pipeline import Pipeline

from centrality_vision import centrality as cen
from centrality_vision.graphs import pixel_graph
from centrality_vision.shapes import (
    CentralityCache,
    CentralityComparisonForest,
    CentralityComparisons,
    CentralityHistogram,
    centrality_map,
    default_cache,
    shape_centralities,
)


def _disk(r, size=None):
    size = size or 2 * r + 5
    yy, xx = np.mgrid[:size, :size]
    c = (size - 1) / 2
    return (yy - c) ** 2 + (xx - c) ** 2 < r * r


def _bar(h, w, size=40):
    image = np.zeros((size, size), dtype=bool)
    image[(size - h) // 2 : (size + h) // 2, (size - w) // 2 : (size + w) // 2] = True
    return image


def _cross(t, size=40):
    c = size // 2
    image = np.zeros((size, size), dtype=bool)
    image[c - t : c + t, 4:-4] = True
    image[4:-4, c - t : c + t] = True
    return image


def _toy_dataset():
    images, labels = [], []
    for k in range(4):
        images += [_disk(8 + k), _bar(6 + k % 2, 26 + k), _cross(2 + k % 2, 36 + 2 * k)]
        labels += ["disk", "bar", "cross"]
    return images, np.array(labels)


def test_histogram_hand_case():
    """3x3 square: degrees 3 (4 corners), 5 (4 edges), 8 (centre); min-max to [0, 1] and 2 bins."""
    square = np.zeros((5, 5), dtype=bool)
    square[1:4, 1:4] = True
    features = CentralityHistogram(centrality="degree", bins=2, scaling="minmax").fit_transform([square])
    # scaled values: corners 0, edges 0.4, centre 1 -> bins [0, 0.5): 8 pixels, [0.5, 1]: 1 pixel
    np.testing.assert_allclose(features, [[8 / 9, 1 / 9]])
    features = CentralityHistogram(centrality="degree", bins=2).fit_transform([square])
    # scaled by max (the default): 3/8, 5/8, 1 -> 4 pixels in the first bin, 5 in the second
    np.testing.assert_allclose(features, [[4 / 9, 5 / 9]])


def test_histogram_all_concatenates_and_sums_to_one():
    images, _ = _toy_dataset()
    features = CentralityHistogram(centrality="all", bins=40).fit_transform(images)
    assert features.shape == (len(images), 160)
    np.testing.assert_allclose(features.reshape(len(images), 4, 40).sum(axis=2), 1.0)
    single = CentralityHistogram(centrality="closeness").fit_transform(images)
    np.testing.assert_allclose(features[:, 40:80], single)  # order: betweenness, closeness, eigenvector, degree


def test_histogram_is_size_invariant_in_expectation():
    small = CentralityHistogram(centrality="closeness", bins=10).fit_transform([_disk(10)])
    large = CentralityHistogram(centrality="closeness", bins=10).fit_transform([_disk(20)])
    assert np.abs(small - large).sum() < 0.2  # same shape at twice the size: similar histograms


def test_centralities_are_cached_and_not_recomputed():
    cache = CentralityCache()
    image = _disk(9)
    shape_centralities([image], ["closeness", "degree"], cache=cache)
    assert (cache.hits, cache.misses) == (0, 2)
    out = shape_centralities([image.copy()], ["degree", "closeness"], cache=cache)  # same pixels, new array
    assert (cache.hits, cache.misses) == (2, 2)
    graph, nodes = pixel_graph(image)
    np.testing.assert_array_equal(out[0]["closeness"], cen.closeness(graph))
    np.testing.assert_array_equal(out[0]["nodes"], nodes)
    assert not out[0]["closeness"].flags.writeable


def test_cache_is_bounded():
    cache = CentralityCache(max_images=2)
    for r in (5, 6, 7):
        shape_centralities([_disk(r)], ["degree"], cache=cache)
    assert len(cache) == 2
    cache.clear()
    assert len(cache) == 0 and cache.hits == 0


def test_histogram_in_pipeline_clone_and_grid_search():
    images, labels = _toy_dataset()
    pipe = Pipeline([("hist", CentralityHistogram()), ("nb", GaussianNB())])
    assert clone(pipe).get_params()["hist__bins"] == 40
    search = GridSearchCV(pipe, {"hist__centrality": ["closeness", "degree"], "hist__bins": [5, 40]}, cv=3)
    search.fit(images, labels)
    assert search.best_score_ >= 0.9
    # Cloned and re-parametrised pipelines reproduce the search's score exactly.
    pipe.set_params(**search.best_params_)
    assert cross_val_score(pipe, images, labels, cv=3).mean() == pytest.approx(search.best_score_)


def test_feature_names():
    names = CentralityHistogram(centrality=["degree", "closeness"], bins=3).fit([_disk(5)]).get_feature_names_out()
    expected = [f"{name}_bin{k}" for name in ("degree", "closeness") for k in range(3)]
    assert names.tolist() == expected
    # the fitted bins name the features: bins changed after fit (which transform refuses)
    # gave names that did not match n_features_out_
    histogram = CentralityHistogram(centrality=["degree", "closeness"], bins=3).fit([_disk(5)])
    histogram.bins = 5
    assert histogram.get_feature_names_out().tolist() == expected


def test_the_cache_hands_out_copies_of_its_entries():
    from centrality_vision.shapes import CentralityCache

    cache = CentralityCache()
    mask = _disk(4)
    entry = cache.put(mask, "degree", np.ones(int(mask.sum())))
    entry["degree"] = np.zeros(3)  # changes the caller's copy only
    values, _ = cache.get(mask, "degree")
    np.testing.assert_array_equal(values, np.ones(int(mask.sum())))


def test_centrality_map_fills_holes_from_nearest_pixel():
    image = _disk(6)
    image[8, 8] = False  # a hole
    graph, nodes = pixel_graph(image)
    dense, centre, size = centrality_map(image, cen.degree(graph), nodes)
    neighbours = {dense[8 + dr, 8 + dc] for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc}
    assert dense[8, 8] in neighbours
    np.testing.assert_allclose(centre, np.argwhere(image).mean(axis=0))
    assert dense[0, 0] > 0  # background reads the nearest shape pixel


def test_comparisons_are_invariant_to_translation():
    image = np.zeros((60, 60), dtype=bool)
    image[10:30, 5:45] = _cross(3, 40)[10:30, :40]
    shifted = np.roll(image, (12, 9), axis=(0, 1))
    comp = CentralityComparisons(n_comparisons=300, random_state=1).fit([image])
    np.testing.assert_array_equal(comp.transform([image]), comp.transform([shifted]))


def _lopsided(size=64):
    """An L with arms of different lengths and widths: no mirror or rotation symmetry."""
    image = np.zeros((size, size), dtype=bool)
    image[8:50, 10:22] = True
    image[40:50, 10:40] = True
    image[30:40, 30:40] = True
    return image


def test_principal_orientation_turns_with_the_shape():
    image = _lopsided()
    turned = np.rot90(image)  # an exact quarter turn: the pixel graph is the same
    principal = CentralityComparisons(n_comparisons=400, orientation="principal", random_state=2).fit([image])
    same = np.mean(principal.transform([image]) == principal.transform([turned]))
    assert same > 0.98  # the offsets turn with the shape's axes (rare rounding ties may differ)
    fixed = CentralityComparisons(n_comparisons=400, random_state=2).fit([image])
    assert np.mean(fixed.transform([image]) == fixed.transform([turned])) < 0.9  # image axes do not turn
    with pytest.raises(ValueError, match="`orientation` must be one of"):
        CentralityComparisons(orientation="pca").fit([image])


def test_principal_comparisons_do_not_depend_on_the_margin():
    from scipy import ndimage

    # an oblique shape cropped to a one-pixel margin: many positions fall beyond the border
    image = ndimage.rotate(np.pad(_lopsided(), 20).astype(float), 37, order=0) > 0.5
    rows, cols = np.nonzero(image)
    tight = np.pad(image[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1], 1)
    comp = CentralityComparisons(n_comparisons=500, orientation="principal", random_state=4).fit([image])
    np.testing.assert_array_equal(comp.transform([tight]), comp.transform([np.pad(tight, 40)]))


def test_comparisons_are_seeded():
    a = CentralityComparisons(n_comparisons=20, random_state=3).fit([_disk(5)])
    b = CentralityComparisons(n_comparisons=20, random_state=3).fit([_disk(5)])
    c = CentralityComparisons(n_comparisons=20, random_state=4).fit([_disk(5)])
    np.testing.assert_array_equal(a.offsets_, b.offsets_)
    assert not np.array_equal(a.offsets_, c.offsets_)


def test_forest_learns_toy_shapes_and_is_reproducible():
    images, labels = _toy_dataset()
    clf = CentralityComparisonForest(n_estimators=50, n_comparisons=200, random_state=0)
    assert cross_val_score(clf, images, labels, cv=4).mean() > 0.9
    p1 = clone(clf).fit(images, labels).predict_proba(images)
    p2 = clone(clf).fit(images, labels).predict_proba(images)
    np.testing.assert_array_equal(p1, p2)
    assert clf.fit(images, labels).classes_.tolist() == ["bar", "cross", "disk"]


def test_forest_graph_centre_reference():
    images, labels = _toy_dataset()
    clf = CentralityComparisonForest(n_estimators=30, n_comparisons=100, reference="graph-centre").fit(images, labels)
    assert np.mean(clf.predict(images) == labels) > 0.9


@pytest.mark.parametrize(
    ("images", "error", "match"),
    [
        ([np.zeros((5, 5), bool)], ValueError, r"`X\[0\]` must have at least one foreground pixel"),
        ([np.ones((5, 5), bool)], ValueError, r"`X\[0\]` must have background pixels.*inverted"),
        ([np.full((4, 4), 0.5)], ValueError, r"`X\[0\]` is uniform"),
        ([np.ones((2, 2, 2))], ValueError, r"`X\[0\]` must be a 2D array"),
        (np.ones((5, 5)), ValueError, "single 2D array"),
        ([], ValueError, "at least one image"),
        (5, TypeError, "sequence of 2D binary images"),
    ],
)
@pytest.mark.parametrize("estimator", [CentralityHistogram(), CentralityComparisons(n_comparisons=5)])
def test_bad_images(estimator, images, error, match):
    with pytest.raises(error, match=match):
        estimator.fit(images)


@pytest.mark.parametrize(
    ("params", "error", "match"),
    [
        ({"centrality": "closness"}, ValueError, "`centrality` must be one of"),
        ({"bins": 0}, ValueError, r"`bins` must be an int in \[2, 100000\]"),
        ({"bins": 1}, ValueError, r"`bins` must be an int in \[2, 100000\]"),  # the constant feature 1
        ({"scaling": "log"}, ValueError, "`scaling`"),
        ({"connectivity": 6}, ValueError, "'connectivity' parameter"),
        ({"centrality": []}, ValueError, "at least one centrality"),
    ],
)
def test_histogram_bad_parameters(params, error, match):
    with pytest.raises(error, match=match):
        CentralityHistogram(**params).fit([_disk(4)])


def test_forest_bad_labels():
    with pytest.raises(ValueError, match="one label per image"):
        CentralityComparisonForest(n_estimators=2, n_comparisons=5).fit([_disk(4), _disk(5)], [0])
    with pytest.raises(ValueError, match="Unknown label type"):
        CentralityComparisonForest(n_estimators=2, n_comparisons=5).fit([_disk(4), _disk(5)], [0.5, 1.5])


def test_inputs_not_modified():
    images, labels = _toy_dataset()
    before = [im.copy() for im in images]
    CentralityHistogram(centrality="all").fit_transform(images)
    CentralityComparisonForest(n_estimators=5, n_comparisons=20).fit(images, labels).predict(images)
    for a, b in zip(images, before):
        np.testing.assert_array_equal(a, b)


def test_progress_bar(capsys):
    default_cache.clear()
    CentralityHistogram(progress=True).fit_transform([_disk(6), _disk(7)])
    assert "centralities" in capsys.readouterr().err


def test_disk_cache_is_reused_by_a_new_cache(tmp_path):
    image = _disk(7)
    first = CentralityCache(directory=tmp_path)
    values = shape_centralities([image], ["closeness"], cache=first)[0]["closeness"]
    assert first.misses == 1 and len(list(tmp_path.glob("*.npz"))) == 1
    second = CentralityCache(directory=tmp_path)  # e.g. a later process
    again = shape_centralities([image], ["closeness"], cache=second)[0]
    assert (second.hits, second.misses) == (1, 0)
    np.testing.assert_array_equal(again["closeness"], values)
    np.testing.assert_array_equal(again["nodes"], np.flatnonzero(image))
    assert not list(tmp_path.glob("*.tmp"))


def test_disk_cache_of_other_code_is_not_read(tmp_path, monkeypatch):
    """Files were keyed by the pixels and options only: values computed by another version of
    the centralities were read back."""
    from centrality_vision.shapes import _cache

    image = _disk(7)
    shape_centralities([image], ["closeness"], cache=CentralityCache(directory=tmp_path))
    monkeypatch.setattr(_cache, "code_digest", lambda: "0" * 16)
    monkeypatch.setattr(_cache, "current_code_digest", lambda: "0" * 16)
    later = CentralityCache(directory=tmp_path)  # a process running edited code
    shape_centralities([image], ["closeness"], cache=later)
    assert (later.hits, later.misses) == (0, 1)
    assert len(list(tmp_path.glob("*-closeness.npz"))) == 2


def test_values_computed_after_the_code_changed_are_not_stored(tmp_path, monkeypatch):
    """The file's name carries the digest read when the process started: values computed
    after the package's files changed were stored under it and read back by that code."""
    from centrality_vision.shapes import _cache

    monkeypatch.setattr(_cache, "current_code_digest", lambda: "e" * 16)
    cache = CentralityCache(directory=tmp_path)
    first = shape_centralities([_disk(7)], ["closeness"], cache=cache)
    assert not list(tmp_path.glob("*.npz"))  # kept in memory only
    again = shape_centralities([_disk(7)], ["closeness"], cache=cache)
    assert cache.hits == 1
    np.testing.assert_array_equal(again[0]["closeness"], first[0]["closeness"])


def test_memory_hits_are_written_to_a_directory_set_later(tmp_path):
    cache = CentralityCache()
    image = _disk(6)
    shape_centralities([image], ["degree"], cache=cache)
    cache.directory = tmp_path
    shape_centralities([image], ["degree"], cache=cache)
    assert len(list(tmp_path.glob("*-degree.npz"))) == 1


def test_the_cache_and_shape_centralities_name_the_centrality_centrality():
    # API audit F6: `name`/`names` here, `centrality` in GPD and the shape estimators
    square = np.zeros((6, 6), dtype=bool)
    square[1:5, 1:5] = True
    cache = CentralityCache()
    values, _ = cache.get(square, centrality="degree")
    with pytest.warns(FutureWarning, match=r"`name` of get\(\) is renamed `centrality`"):
        old, _ = cache.get(square, name="degree")
    np.testing.assert_array_equal(old, values)
    with pytest.warns(FutureWarning, match=r"`name` of lookup\(\) is renamed `centrality`"):
        assert cache.lookup(square, name="degree") is not None
    with pytest.warns(FutureWarning, match=r"`name` of put\(\) is renamed `centrality`"):
        cache.put(square, name="closeness", values=np.ones(16))
    with pytest.warns(FutureWarning, match=r"`names` of shape_centralities\(\) is renamed `centrality`"):
        record = shape_centralities([square], names=["degree"])[0]
    np.testing.assert_array_equal(record["degree"], shape_centralities([square], centrality="degree")[0]["degree"])

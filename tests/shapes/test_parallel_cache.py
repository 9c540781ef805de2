"""Estimator options added for the field's protocols: cache parameter, n_jobs, weights, fill_holes, random_state."""

import copy
import pickle

import numpy as np
import pytest
from joblib import parallel_config
from sklearn.base import clone

from centrality_vision import centrality as cen
from centrality_vision.graphs import pixel_graph
from centrality_vision.shapes import (
    CentralityCache,
    CentralityComparisonForest,
    CentralityComparisons,
    CentralityHistogram,
    resolve_cache,
    shape_centralities,
)


def _disk(r, size=None):
    size = size or 2 * r + 5
    yy, xx = np.mgrid[:size, :size]
    return (yy - size // 2) ** 2 + (xx - size // 2) ** 2 <= r * r


def test_cache_is_shared_not_copied_and_pickles_its_directory(tmp_path):
    cache = CentralityCache(directory=tmp_path)
    assert copy.deepcopy(cache) is cache
    est = CentralityHistogram(cache=cache)
    assert clone(est).cache is cache
    again = pickle.loads(pickle.dumps(cache))
    assert again.directory == tmp_path and len(again) == 0
    assert resolve_cache(str(tmp_path)) is resolve_cache(tmp_path)
    with pytest.raises(TypeError, match="`cache` must be None, a CentralityCache or a directory"):
        resolve_cache(3)


def test_directory_cache_is_reused_across_processes_and_leaves_no_lock(tmp_path):
    images = [_disk(4), _disk(5), _disk(6)]
    with parallel_config(backend="threading"):  # loky workers take the same path (benchmarks/shapes.py --cv)
        first = CentralityHistogram(cache=tmp_path, n_jobs=2).fit_transform(images)
    assert len(list(tmp_path.glob("*-closeness.npz"))) == 3
    assert not list(tmp_path.glob("*.lock")) and not list(tmp_path.glob("*.tmp"))
    fresh = CentralityCache(directory=tmp_path)  # a new process would start like this
    np.testing.assert_array_equal(CentralityHistogram(cache=fresh).fit_transform(images), first)
    assert (fresh.hits, fresh.misses) == (3, 0)


def test_a_lock_held_elsewhere_is_waited_for_and_a_dead_ones_taken_over(tmp_path):
    image = _disk(5)
    cache = CentralityCache(directory=tmp_path)
    key = __import__("centrality_vision.shapes._cache", fromlist=["_key"])._key(image, 8, False)
    lock = cache._path(key, "degree").with_suffix(".lock")
    lock.write_text("999999999")  # no such process: stale
    values, _ = cache.get(image, "degree")
    assert not lock.exists()
    graph, _ = pixel_graph(image)
    np.testing.assert_array_equal(values, cen.degree(graph))
    lock2 = cache._path(key, "closeness").with_suffix(".lock")
    import os

    lock2.write_text(str(os.getpid()))  # a live holder: do not wait, report None
    assert cache.get(image, "closeness", wait=False) is None
    lock2.unlink()


def test_n_jobs_and_threading_backend_give_identical_features():
    images = [_disk(r) for r in (4, 5, 6, 7)]
    serial = CentralityHistogram(centrality="all", bins=6, cache=CentralityCache()).fit_transform(images)
    with parallel_config(backend="threading"):
        parallel = CentralityHistogram(centrality="all", bins=6, cache=CentralityCache(), n_jobs=2).fit_transform(
            images
        )
    np.testing.assert_array_equal(serial, parallel)


def test_weights_give_euclidean_closeness_and_a_separate_cache_entry():
    image = _disk(6)
    cache = CentralityCache()
    hops = shape_centralities([image], ["closeness", "degree"], cache=cache)[0]
    euclid = shape_centralities([image], ["closeness", "degree"], cache=cache, weights=True)[0]
    graph, _ = pixel_graph(image)
    np.testing.assert_allclose(euclid["closeness"], cen.closeness(graph, weights=True))
    np.testing.assert_allclose(hops["closeness"], cen.closeness(graph))
    assert not np.allclose(hops["closeness"], euclid["closeness"])
    np.testing.assert_array_equal(hops["degree"], euclid["degree"])  # degree ignores lengths
    assert cache.misses == 4


def test_fill_holes_makes_a_salted_disk_read_as_the_clean_one():
    clean = _disk(8)
    salted = clean.copy()
    salted[8:14:2, 8:14:2] = False  # interior holes
    plain = CentralityHistogram(centrality="eigenvector", bins=10, cache=CentralityCache())
    filled = clone(plain).set_params(fill_holes=True)
    assert not np.array_equal(plain.fit_transform([clean]), plain.fit_transform([salted]))
    np.testing.assert_array_equal(filled.fit_transform([salted]), plain.fit_transform([clean]))


def test_grey_images_with_threshold_and_foreground():
    mask = _disk(6)
    grey = np.where(mask, 30, 220).astype(np.uint8)
    expected = CentralityHistogram(bins=8).fit_transform([mask])
    np.testing.assert_array_equal(CentralityHistogram(bins=8).fit_transform([grey]), expected)
    np.testing.assert_array_equal(
        CentralityHistogram(bins=8, foreground="dark", threshold=100).fit_transform([grey]), expected
    )


def test_seed_is_deprecated_for_random_state():
    images = [_disk(4), _disk(5)]
    new = CentralityComparisons(n_comparisons=10, random_state=3).fit(images)
    with pytest.warns(FutureWarning, match="`seed` of CentralityComparisons is deprecated"):
        old = CentralityComparisons(n_comparisons=10, seed=3).fit(images)
    np.testing.assert_array_equal(new.offsets_, old.offsets_)
    forest = CentralityComparisonForest(n_estimators=3, n_comparisons=10, random_state=1)
    assert "random_state" in forest.get_params() and clone(forest).random_state == 1


def test_a_cache_folder_that_refuses_new_files_serves_what_it_holds(tmp_path, monkeypatch):
    """A shared cache filled beforehand and mounted read-only: every image not yet in it failed
    the whole call with a bare PermissionError on its .lock file."""
    import builtins
    import os
    import warnings

    from centrality_vision.shapes import _cache

    folder = tmp_path / "shared"
    CentralityCache(directory=folder).get(_disk(3), "closeness")
    stored = sorted(p.name for p in folder.iterdir())
    real_os_open, real_open = os.open, builtins.open

    def refused(path, *args, **kwargs):
        if str(path).startswith(str(folder)) and (args[0] if args else kwargs.get("mode", "r")) not in ("r", "rb"):
            raise PermissionError(13, "Permission denied", str(path))
        return real_open(path, *args, **kwargs)

    def refused_os(path, flags, *args):
        if str(path).startswith(str(folder)) and flags & os.O_CREAT:
            raise PermissionError(13, "Permission denied", str(path))
        return real_os_open(path, flags, *args)

    monkeypatch.setattr(os, "open", refused_os)
    monkeypatch.setattr(_cache, "open", refused, raising=False)
    cache = CentralityCache(directory=folder)
    assert cache.get(_disk(3), "closeness") is not None and (cache.hits, cache.misses) == (1, 0)
    with pytest.warns(UserWarning, match=r"could not take .* \(Permission denied\): centralities computed now"):
        values, _ = cache.get(_disk(4), "closeness")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # said once per cache
        cache.get(_disk(5), "degree")
    monkeypatch.undo()
    np.testing.assert_array_equal(values, CentralityCache().get(_disk(4), "closeness")[0])
    assert sorted(p.name for p in folder.iterdir()) == stored


def test_a_folder_where_a_cache_file_goes_is_said_not_raised(tmp_path):
    cache = CentralityCache(directory=tmp_path)
    path = cache._path(_cache_key(_disk(3)), "degree")
    path.mkdir(parents=True)
    with pytest.warns(UserWarning, match=r"could not take .*-degree.npz"):
        values, _ = cache.get(_disk(3), "degree")
    np.testing.assert_array_equal(values, CentralityCache().get(_disk(3), "degree")[0])


def _cache_key(mask):
    from centrality_vision.shapes._cache import _as_mask, _key

    return _key(_as_mask(mask), 8, False)


def test_the_forest_runs_on_the_cache_and_jobs_set_after_fit(tmp_path):
    """cache, n_jobs and progress may change after fit; the forest's inner comparisons kept
    the fit-time ones, so a disk cache set for prediction was never used."""
    forest = CentralityComparisonForest(n_estimators=5, n_comparisons=20, cache=CentralityCache())
    forest.fit([_disk(4), _disk(6), _disk(5)[:, 2:], _disk(3)], [0, 1, 0, 1])
    expected = forest.predict([_disk(5), _disk(4)[::-1]])
    later = CentralityCache(directory=tmp_path / "later")
    forest.set_params(cache=later, n_jobs=2)
    np.testing.assert_array_equal(forest.predict([_disk(5), _disk(4)[::-1]]), expected)
    assert len(later) == 2 and any((tmp_path / "later").iterdir())  # (workers compute, the cache keeps)
    assert forest.comparisons_.n_jobs == forest.forest_.n_jobs == 2
    with pytest.raises(TypeError, match="`max_features` must be an int"):
        CentralityComparisonForest(max_features=True).fit([_disk(4), _disk(6)], [0, 1])

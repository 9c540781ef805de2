"""Wrong answers a correctness fuzz run of the shape layer found, each checked against the
definition it broke."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from centrality_vision.datasets import contour_points
from centrality_vision.shapes import (
    CentralityCache,
    CentralityComparisonForest,
    CentralityComparisons,
    CentralityHistogram,
)


def test_contour_points_follow_the_outer_contour_not_a_longer_hole():
    # a square with a comb-shaped hole: the hole's outline (743 long) is longer than the
    # square's (159), and the longest contour was taken: every point lay on the hole
    mask = np.zeros((44, 44), dtype=bool)
    mask[2:42, 2:42] = True
    hole = np.zeros_like(mask)
    hole[36:39, 5:39] = True
    for col in range(5, 39, 3):
        hole[5:37, col] = True
    points = contour_points(mask & ~hole, 100)
    np.testing.assert_allclose(points.min(axis=0), [1.5, 1.5])
    np.testing.assert_allclose(points.max(axis=0), [41.5, 41.5])


def test_the_cache_keys_a_grey_image_by_the_shape_it_computes_on():
    # the key hashed a grey image's nonzero pixels while the values were computed on its
    # thresholded shape: 12 values came with 52 node indices, and the 52-pixel bool mask
    # `grey > 0` then got the 12 dark-shape values from the cache
    grey = np.full((8, 8), 255, dtype=np.uint8)
    grey[2:6, 2:5] = 0
    cache = CentralityCache()
    values, nodes = cache.get(grey, "degree")
    assert values.shape == nodes.shape == (12,)
    values, nodes = cache.get(grey > 0, "degree")
    fresh, fresh_nodes = CentralityCache().get(grey > 0, "degree")
    assert values.shape == nodes.shape == (52,)
    np.testing.assert_array_equal(values, fresh)
    np.testing.assert_array_equal(nodes, fresh_nodes)


def test_a_cache_that_keeps_nothing_works_with_parallel_jobs():
    # max_images=0 with n_jobs=2 and several centralities raised KeyError: each put evicted
    # the entry holding the previous centrality
    square = np.zeros((12, 12), dtype=bool)
    square[2:9, 2:9] = True
    other = np.zeros((12, 12), dtype=bool)
    other[3:10, 2:8] = True
    features = [
        CentralityHistogram(centrality="all", cache=CentralityCache(max_images=0), n_jobs=jobs).fit_transform(
            [square, other]
        )
        for jobs in (1, 2)
    ]
    np.testing.assert_array_equal(features[0], features[1])


def test_a_shape_and_its_transpose_or_mirror_image_get_the_same_histogram():
    # values on a bin edge (0.5 of the largest, 25/36, ...) came out a few ulp below the edge on
    # one graph and above it on its isomorphic copy: 25 rectangles up to 10 x 12 changed bins
    changed = []
    for h in range(1, 11):
        for w in range(1, 13):
            mask = np.zeros((h + 2, w + 2), dtype=bool)
            mask[1:-1, 1:-1] = True
            for centrality, weights in (("eigenvector", False), ("betweenness", True)):
                rows = CentralityHistogram(centrality=centrality, weights=weights).fit_transform(
                    [mask, mask.T, mask[::-1], mask[:, ::-1]]
                )
                if np.abs(rows[1:] - rows[0]).sum() > 0:
                    changed.append((h, w, centrality))
    assert changed == []
    bar = np.zeros((7, 3), dtype=bool)
    bar[1:6, 1] = True
    rows = CentralityHistogram(centrality="harmonic", bins=36, weights=True).fit_transform([bar, bar.T])
    np.testing.assert_array_equal(rows[0], rows[1])


def test_a_stored_file_of_another_length_type_or_not_finite_is_recomputed_not_used(tmp_path):
    square = np.zeros((6, 6), dtype=bool)
    square[1:5, 1:5] = True
    expected, _ = CentralityCache(directory=tmp_path).get(square, "closeness")
    (path,) = tmp_path.glob("*closeness.npz")
    # (inf and float32 files were served: inf values turned into a numpy error in the histogram)
    for foreign in (
        np.ones(5),
        np.full(16, np.nan),
        np.full(16, np.inf),
        np.ones(16, np.float32),
        np.arange(16),
        np.ones((4, 4)),
    ):
        with open(path, "wb") as handle:  # with the checksum of what it holds: the checks above it
            np.savez(handle, values=foreign, check=CentralityCache._checksum(path, np.asarray(foreign)))
        cache = CentralityCache(directory=tmp_path)
        values, nodes = cache.get(square, "closeness")
        np.testing.assert_array_equal(values, expected)
        assert values.shape == nodes.shape == (16,) and cache.misses == 1
        features = CentralityHistogram(cache=CentralityCache(directory=tmp_path), bins=5).fit_transform([square])
        assert features[0, -1] < 1  # the ones were binned as one full last bin


def test_a_damaged_or_edited_file_is_recomputed_not_used(tmp_path):
    # values of the right length and type, finite, written over a stored file: fig. 4.2's
    # closeness distances all became 0 on a re-run
    square = np.zeros((6, 6), dtype=bool)
    square[1:5, 1:5] = True
    expected, _ = CentralityCache(directory=tmp_path).get(square, "closeness")
    (path,) = tmp_path.glob("*closeness.npz")
    with np.load(path) as stored:
        check = stored["check"]
    for write in (
        lambda handle: np.savez(handle, values=np.full(16, 0.5), check=check),  # edited values
        lambda handle: np.savez(handle, values=expected),  # no checksum
        lambda handle: np.save(handle, expected),  # a bare .npy
        lambda handle: handle.write(path.read_bytes()[:-40]),  # cut short
    ):
        with open(path, "wb") as handle:
            write(handle)
        cache = CentralityCache(directory=tmp_path)
        values, _ = cache.get(square, "closeness")
        np.testing.assert_array_equal(values, expected)
        assert cache.misses == 1
        again = CentralityCache(directory=tmp_path)  # stored again, and read back
        np.testing.assert_array_equal(again.get(square, "closeness")[0], expected)
        assert again.misses == 0


def test_comparisons_check_parameters_changed_after_fit():
    import pytest

    from centrality_vision.exceptions import InputError
    from centrality_vision.shapes import CentralityComparisons

    disk = np.add.outer((np.arange(15) - 7) ** 2, (np.arange(15) - 7) ** 2) < 30
    model = CentralityComparisons(n_comparisons=5).fit([disk])
    before = model.transform([disk])
    with pytest.raises(InputError, match=r"changed since fit: `centrality` \('closeness' at fit, now 'degree'\)"):
        model.set_params(centrality="degree").transform([disk])  # features of closeness, silently
    with pytest.raises(InputError, match="`orientation` must be one of"):
        model.set_params(centrality="closeness", orientation="bogus").transform([disk])  # ran as "image"
    with pytest.raises(InputError, match=r"`extent` \(2.0 at fit, now 3.0\); call fit again"):
        model.set_params(orientation="image", extent=3.0).transform([disk])
    with pytest.raises(InputError, match=r"`reference` \('centroid' at fit, now 'graph-centre'\)"):
        model.set_params(extent=2.0, reference="graph-centre").transform([disk])  # was used live
    model.set_params(reference="centroid", n_jobs=2, progress=False)  # how it runs may change
    np.testing.assert_array_equal(model.set_params(extent=2.0).transform([disk]), before)


def test_cache_inputs_found_by_fuzzing_get_named_errors(tmp_path):
    import pytest

    from centrality_vision.exceptions import InputError

    square = np.zeros((6, 6), dtype=bool)
    square[1:4, 1:4] = True
    afile = tmp_path / "afile"
    afile.write_text("")
    with pytest.raises(InputError, match="`directory` must be a folder"):  # FileExistsError on first use
        CentralityCache(directory=afile)
    with pytest.raises(TypeError, match="`values` must hold real numbers"):  # OverflowError
        CentralityCache().put(square, "degree", [10**400] * 9)
    with pytest.raises(TypeError, match="`values` must hold real numbers; got complex"):  # imaginary part dropped
        CentralityCache().put(square, "degree", np.ones(9) + 1j)
    with pytest.raises(InputError, match="`mask` must be"):  # a 3D bool mask: an unpacking ValueError
        CentralityCache(directory=tmp_path).get(np.ones((2, 3, 3), bool), "degree")
    cache = CentralityCache(directory=tmp_path)
    expected, _ = cache.get(square, "degree")
    (values,) = tmp_path.glob("*degree.npz")
    values.unlink()
    values.with_suffix(".lock").write_text(str(2**80))  # a lock naming no possible process: stale
    found, _ = CentralityCache(directory=tmp_path).get(square, "degree", wait=False)  # was OverflowError
    np.testing.assert_array_equal(found, expected)


def test_parameters_changed_after_fit_are_checked_not_mixed_with_the_fitted_ones():
    import pytest

    from centrality_vision.exceptions import InputError

    disk = np.add.outer((np.arange(15) - 7) ** 2, (np.arange(15) - 7) ** 2) < 30
    model = CentralityHistogram(bins=10).fit([disk])
    with pytest.raises(InputError, match=r"changed since fit: `bins` \(10 at fit, now 20\); call fit again"):
        model.set_params(bins=20).transform([disk])  # was a numpy broadcast error
    with pytest.raises(InputError, match=r"`centrality` \('closeness' at fit, now 'degree'\); call fit again"):
        model.set_params(bins=10, centrality="degree").transform([disk])  # silently stayed closeness
    for name, value in (("fill_holes", True), ("connectivity", 4), ("weights", True)):  # fuzz round 7: used live
        with pytest.raises(InputError, match=rf"changed since fit: `{name}`"):
            model.set_params(centrality="closeness", **{name: value}).transform([disk])
        model.set_params(**{name: CentralityHistogram().get_params()[name]})
    with pytest.raises(InputError, match=r"`scaling` \('max' at fit, now 'minmax'\)"):
        model.set_params(scaling="minmax").transform([disk])
    model.set_params(scaling="max")
    with pytest.raises(InputError, match="`scaling` must be one of"):
        model.set_params(centrality="closeness", scaling="bogus").transform([disk])  # silently 'max'
    refit = model.set_params(scaling="minmax", bins=20).fit([disk]).transform([disk])
    assert refit.shape == (1, 20) and np.isclose(refit.sum(), 1)


def test_bad_options_of_the_shape_layer_name_the_parameter():
    import pytest

    from centrality_vision.exceptions import InputError
    from centrality_vision.shapes import CentralityCache, CentralityComparisons, outline_profiles, shape_centralities

    square = np.zeros((8, 8), dtype=bool)
    square[2:6, 2:6] = True
    # one name is a name, not its letters ("got 'd'")
    np.testing.assert_array_equal(
        shape_centralities([square], "degree")[0]["degree"], shape_centralities([square], ["degree"])[0]["degree"]
    )
    cases = [
        (lambda: shape_centralities([square], None), TypeError, "`centrality` must be a centrality name, 'all' or a"),
        (lambda: shape_centralities([square], ["degree", "degree"]), InputError, "must name each centrality once"),
        (lambda: shape_centralities([square], ["degree"], connectivity=8.0), InputError, "`connectivity` must be 4"),
        (lambda: shape_centralities([square], ["degree"], progress="x"), TypeError, "`progress` must be True"),
        (lambda: CentralityHistogram(connectivity=8.0).fit([square]), InputError, "connectivity"),
        # the cache's three entry points accept what shape_centralities accepts (put alone refused
        # 8.0 and lookup or get took a weights of "no" as True)
        (lambda: CentralityCache().put(square, "degree", np.ones(16), connectivity=8.0), InputError, "must be 4"),
        (lambda: CentralityCache().lookup(square, "degree", connectivity=8.0), InputError, "`connectivity` must be 4"),
        (lambda: CentralityCache().get(square, "degree", connectivity=6), InputError, "`connectivity` must be 4"),
        (lambda: CentralityCache().get(square, "degree", weights="no"), TypeError, "`weights` must be True"),
        (lambda: CentralityHistogram(fill_holes="x").fit([square]), TypeError, "`fill_holes` must be True"),
        (lambda: CentralityComparisons(random_state=-1).fit([square, square], [0, 1]), TypeError, "`random_state`"),
        (lambda: outline_profiles(np.zeros((20, 20))), InputError, r"^`image` must have at least one foreground"),
    ]
    for call, error, match in cases:
        with pytest.raises(error, match=match):
            call()


@pytest.mark.parametrize(
    ("pixels", "centrality", "connectivity"),
    [((slice(1, 2), slice(1, 3)), "katz", 8), ((slice(1, 3), slice(1, 3)), "eigenvector", 4)],
)
def test_minmax_histogram_of_values_equal_but_for_rounding(pixels, centrality, connectivity):
    # a two-pixel shape (katz) or a 2x2 block (eigenvector): the values are equal in exact
    # arithmetic and a few ulp apart in float64; min-max scaling spread them over the bins
    # ([0.5, 0, 0, 0.5]); values that are all equal fall in the first bin
    mask = np.zeros((4, 4), bool)
    mask[pixels] = True
    features = CentralityHistogram(centrality=centrality, bins=4, scaling="minmax", connectivity=connectivity)
    np.testing.assert_array_equal(features.fit_transform([mask]), [[1.0, 0.0, 0.0, 0.0]])


def test_second_fuzz_round_shape_inputs_are_named(tmp_path):
    from centrality_vision.exceptions import InputError
    from centrality_vision.shapes import outline_profiles, pairwise_shape_distances, shape_centralities, shape_distance

    mask = np.zeros((12, 12), bool)
    mask[3:9, 2:10] = True
    (tmp_path / "afile").write_text("x")
    # a cache folder below a file raised NotADirectoryError; "" wrote into the current folder
    with pytest.raises(InputError, match=r"`directory` must be a folder .* below a file \('.*afile' is a file\)"):
        shape_centralities([mask], ["degree"], cache=tmp_path / "afile" / "sub")
    with pytest.raises(InputError, match=r"`cache` must name a folder; got an empty path"):
        shape_centralities([mask], ["degree"], cache="")
    # n_points had no bound (10**7 asked numpy for 176 GiB)
    with pytest.raises(InputError, match=r"`n_points` must be .*4096"):
        outline_profiles(mask, n_points=10**7)
    # the profile method ignored the histogram options, whatever they were
    with pytest.raises(InputError, match=r"`bins`"):
        pairwise_shape_distances([mask, mask.T], bins=-5)
    with pytest.raises(InputError, match=r"`centrality` must be one of"):
        pairwise_shape_distances([mask, mask.T], centrality="nope")
    with pytest.raises(InputError, match=r"`centrality` must name each centrality once; got 'degree' more than once"):
        CentralityHistogram(centrality=["degree", "degree"]).fit_transform([mask])
    # the pair's own names, not the list's
    with pytest.raises(InputError, match=r"^`b` must have at least one foreground pixel"):
        shape_distance(mask, np.zeros((5, 5), bool))
    with pytest.raises(InputError, match=r"`centrality` must be one of"):
        CentralityCache().lookup(mask, "foo")


def test_the_forest_predicts_only_with_its_fitted_parameters():
    # found by fuzz round 7: predict read fill_holes/foreground/threshold as they were now and
    # the rest as at fit, and accepted invalid values set after fit
    import pytest

    from centrality_vision.exceptions import InputError
    from centrality_vision.shapes import CentralityComparisonForest

    rows = np.arange(15) - 7
    disk = np.add.outer(rows**2, rows**2) < 30
    ring = disk & ~(np.add.outer(rows**2, rows**2) < 8)
    square = np.zeros((15, 15), dtype=bool)
    square[3:12, 3:12] = True
    shapes, labels = [disk, ring, square] * 2, [0, 1, 2] * 2
    forest = CentralityComparisonForest(n_comparisons=20, n_estimators=5).fit(shapes, labels)
    before, fitted = forest.predict(shapes), forest.get_params()
    for name, value in (("fill_holes", True), ("orientation", "principal"), ("extent", 3.0), ("n_estimators", 9)):
        with pytest.raises(InputError, match=rf"changed since fit: `{name}`"):
            forest.set_params(**{name: value}).predict(shapes)
        forest.set_params(**{name: fitted[name]})
    with pytest.raises(InputError, match="`orientation` must be one of"):
        forest.set_params(orientation="bogus").fit(shapes, labels)
    forest.set_params(orientation="image", n_jobs=1)
    np.testing.assert_array_equal(forest.predict(shapes), before)  # how it runs may change
    with pytest.raises(TypeError, match="`seed` is the former name of `random_state`; give `random_state` only"):
        CentralityComparisonForest(random_state=7, seed=3).fit(shapes, labels)  # seed silently won


def test_an_off_shape_pixel_goes_to_the_first_of_its_tied_nearest_pixels():
    # the k-d tree returned one of the tied pixels, not the first in row-major order as
    # documented (126 of 551 tied queries on random masks)
    from centrality_vision.shapes._comparisons import _nearest_pixels

    rng = np.random.default_rng(0)
    for _ in range(40):
        mask = rng.random((12, 12)) < 0.15
        mask[rng.integers(12), rng.integers(12)] = True
        pixels = np.argwhere(~mask)
        rows, cols = _nearest_pixels(mask, pixels)
        foreground = np.argwhere(mask)
        squared = ((pixels[:, None, :] - foreground[None]) ** 2).sum(axis=2)
        first = foreground[np.argmax(squared == squared.min(axis=1, keepdims=True), axis=1)]
        np.testing.assert_array_equal(np.c_[rows, cols], first)


def test_fuzz_round_13_labels_names_and_levels():
    """Bytes and text labels of one spelling were one class; a bytes centrality name was read
    letter by letter ("got 100"); an empty list of centralities gave records without nodes;
    grey levels near float64's limit put the default threshold at inf (no foreground)."""
    from centrality_vision.shapes import CentralityHistogram, as_shape_images, retrieval_counts, shape_centralities

    square = np.zeros((6, 6), dtype=bool)
    square[1:5, 1:5] = True
    distances = np.random.default_rng(0).random((4, 4))
    with pytest.raises(TypeError, match=r"`labels` must be all strings or all numbers; got a mix \(e.g. b'x' beside"):
        retrieval_counts(distances + distances.T, [b"x", "x", b"y", "y"], top=2)
    for call in (lambda: shape_centralities([square], b"degree"), lambda: CentralityHistogram(b"degree").fit([square])):
        with pytest.raises(TypeError, match=r"`centrality` must be a centrality name \(str\).*got b'degree'"):
            call()
    with pytest.raises(ValueError, match="`centrality` must name at least one centrality"):
        shape_centralities([square], [])
    np.testing.assert_array_equal(as_shape_images([np.where(square, 1.5e308, 1e308)])[0], square)


def test_of_parts_tied_for_the_largest_area_the_same_is_kept_whatever_the_pose():
    """Between two parts of equal area the first in raster order was kept, so a rotated or
    mirrored image kept the other part (its profile distance to its own mirror was about 16).
    Keeping both instead disconnected the graph; the part of larger second moment is kept."""
    from centrality_vision.shapes import normalize_shape

    mask = np.zeros((20, 30), dtype=bool)
    mask[2:6, 2:8] = True  # 24 pixels
    mask[10:18, 15:18] = True  # 24 pixels, more elongated: kept
    mask[0, 29] = True  # a smaller part, dropped
    kept = normalize_shape(mask, resolution=10)
    for turned in (np.rot90(mask), mask[::-1], mask[:, ::-1]):
        np.testing.assert_array_equal(normalize_shape(turned, resolution=10).sum(), kept.sum())
        assert normalize_shape(turned, resolution=10).shape in (kept.shape, kept.shape[::-1])
    from centrality_vision.shapes._retrieval import _largest_component

    expected = np.zeros_like(mask)
    expected[10:18, 15:18] = True
    np.testing.assert_array_equal(_largest_component(mask), expected)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: CentralityHistogram(weights=1), "`weights` must be True or False"),
        (lambda: CentralityHistogram(n_jobs=0), "`n_jobs` must be None"),
        (lambda: CentralityHistogram(cache=5), "`cache` must be None"),
        (lambda: CentralityHistogram(progress="yes"), "`progress` must be True or False"),
        (lambda: CentralityComparisons(connectivity=5), "`connectivity`.*CentralityComparisons must be 4 or 8"),
        (lambda: CentralityComparisons(weights="no"), "`weights` must be True or False"),
        (lambda: CentralityComparisons(n_jobs=0), "`n_jobs` must be None"),
    ],
)
def test_shape_estimators_check_every_parameter_at_fit(make, message):
    """These passed fit and failed only in transform."""
    square = np.zeros((8, 8), dtype=bool)
    square[2:6, 2:6] = True
    with pytest.raises((ValueError, TypeError), match=message):
        make().fit([square])


@pytest.mark.parametrize(
    ("y", "error", "message"),
    [
        ([0, "bar"], TypeError, r"`y` must be all strings or all numbers"),
        ([np.nan, 1.0], ValueError, r"`y` must not hold NaN or None"),
        ([0.5, 1.5], ValueError, r"`y` must hold class labels: Unknown label type"),
        ([0, 1, 2], ValueError, r"`y` must hold one label per image \(2\)"),
        ([[0], [1]], ValueError, r"`y` must hold one label per image; got shape \(2, 1\)"),
    ],
)
def test_forest_labels_are_checked_as_the_retrieval_scores_check_them(y, error, message):
    """[0, 'bar'] became the strings '0' and 'bar' (predict gave '0', never the caller's 0);
    continuous labels got scikit-learn's words without a name. (One class is fine, as in
    scikit-learn: every image is predicted as it.)"""
    disk = np.add.outer((np.arange(30) - 15) ** 2, (np.arange(30) - 15) ** 2) < 64
    bar = np.zeros((30, 30), dtype=bool)
    bar[12:18, 3:27] = True
    with pytest.raises(error, match=message):
        CentralityComparisonForest(n_estimators=5, n_comparisons=20).fit([disk, bar], y)


def test_counts_beyond_any_use_are_refused_by_name():
    """10^11 comparisons raised a MemoryError (2.9 TiB); 10^15 diffusion steps or splits ran on."""
    from centrality_vision.shapes import diffusion_rerank, nearest_neighbor_accuracy

    square = np.zeros((8, 8), dtype=bool)
    square[2:6, 2:6] = True
    with pytest.raises(ValueError, match=r"`n_comparisons` must be an int in \[1, 10000000\]"):
        CentralityComparisons(n_comparisons=10**11).fit([square])
    d = abs(np.subtract.outer(np.arange(4.0), np.arange(4.0)))
    with pytest.raises(ValueError, match=r"`n_iter` must be an int in \[1, 1000000\]"):
        diffusion_rerank(d, n_iter=10**15)
    with pytest.raises(ValueError, match=r"`n_splits` must be an int in \[1, 1000000\]"):
        nearest_neighbor_accuracy(d, [0, 0, 1, 1], n_train=1, n_splits=10**15)


def test_comparison_features_have_names_for_pipelines_and_set_output():
    """CentralityComparisons had no get_feature_names_out: no set_output, and a Pipeline's
    get_feature_names_out failed."""
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    square = np.zeros((8, 8), dtype=bool)
    square[2:6, 2:6] = True
    comparisons = CentralityComparisons(["degree", "closeness"], n_comparisons=6, random_state=0)
    pipe = make_pipeline(comparisons, StandardScaler()).fit([square, square.T])
    names = pipe.get_feature_names_out()
    assert names.tolist() == [f"{('degree', 'closeness')[c]}_cmp{k}" for k, c in enumerate(comparisons.which_)]


@pytest.mark.parametrize(("value", "message"), [(0.0, r"in \(0, 1\]; got 0.0"), (1.5, "got 1.5"), ("bad", "got 'bad'")])
def test_forest_max_features_is_checked_by_name(value, message):
    """A float out of (0, 1] or an unknown string reached scikit-learn's error, which names
    RandomForestClassifier and no parameter of ours."""
    square = np.zeros((8, 8), dtype=bool)
    square[2:6, 2:6] = True
    with pytest.raises(ValueError, match="`max_features` must be .*" + message):
        CentralityComparisonForest(n_estimators=3, n_comparisons=10, max_features=value).fit([square, square.T], [0, 1])


def test_an_enlarged_diagonal_line_stays_whole_and_like_the_same_line_straight():
    """Enlarged with bilinear interpolation, a one-pixel line that steps diagonally is exactly
    one half between its pixels, the threshold at one half cut it into 6 parts and the
    largest, a fifth of the line, was kept: 366 pixels for a target of 2,304, and the line
    was further from itself turned by 45 degrees (301) than from a square (207)."""
    from centrality_vision.shapes import normalize_shape, shape_distance

    straight = np.zeros((24, 24), dtype=bool)
    straight[12, 2:22] = True
    diagonal = np.zeros((24, 24), dtype=bool)
    diagonal[np.arange(2, 22), np.arange(2, 22)] = True
    square = np.zeros((24, 24), dtype=bool)
    square[6:18, 6:18] = True
    small = normalize_shape(diagonal)
    assert 0.8 * 48**2 <= small.sum() <= 1.2 * 48**2
    rows, cols = np.nonzero(small)
    length = np.hypot(*np.ptp([rows, cols], axis=1))
    assert length >= 0.9 * np.hypot(*np.ptp(np.nonzero(normalize_shape(straight)), axis=1))
    assert shape_distance(straight, diagonal) < 0.6 * shape_distance(straight, square)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.sampled_from([(-1, -1), (-1, 1), (1, -1), (1, 1), (0, 1), (1, 0)]), min_size=5, max_size=40))
def test_an_enlarged_one_pixel_path_keeps_its_area(steps):
    """Any 8-connected path of one-pixel width, enlarged, keeps at least half the target
    area in one part (the threshold at one half split diagonal steps apart)."""
    from centrality_vision.shapes import normalize_shape

    position = np.cumsum([(0, 0), *steps], axis=0)
    position -= position.min(axis=0)
    mask = np.zeros(tuple(position.max(axis=0) + 1), dtype=bool)
    mask[position[:, 0], position[:, 1]] = True
    small = normalize_shape(mask, resolution=32)
    assert small.sum() >= 0.5 * 32**2


def test_shape_centralities_takes_all_as_the_other_shape_functions_do():
    # CentralityHistogram and pairwise_shape_distances took 'all'; shape_centralities refused it
    from centrality_vision.shapes import SHAPE_CENTRALITIES, shape_centralities

    square = np.zeros((6, 6), dtype=bool)
    square[1:5, 1:5] = True
    every = shape_centralities([square], "all")[0]
    assert set(every) == {*SHAPE_CENTRALITIES, "nodes"}
    np.testing.assert_array_equal(every["degree"], shape_centralities([square], "degree")[0]["degree"])

"""Shape retrieval: outline profiles, pairwise distances, re-ranking and the field's scores."""

import warnings

import numpy as np
import pytest
from scipy import ndimage, sparse
from scipy.stats import wasserstein_distance

from centrality_vision.shapes import (
    bullseye_score,
    diffusion_rerank,
    nearest_neighbor_accuracy,
    normalize_shape,
    outline_profiles,
    pairwise_shape_distances,
    retrieval_counts,
    shape_distance,
)


def _ell(size=70):
    image = np.zeros((size, size), dtype=bool)
    image[10:60, 15:30] = True
    image[45:60, 15:55] = True
    return image


def _cross(size=70):
    image = np.zeros((size, size), dtype=bool)
    image[15:55, 30:40] = True
    image[30:40, 12:58] = True
    return image


def _disk(size=70, r=22):
    yy, xx = np.mgrid[:size, :size]
    return (yy - size / 2) ** 2 + (xx - size / 2) ** 2 < r**2


def _rotate(image, degrees):
    padded = np.pad(image, 30).astype(float)
    return ndimage.rotate(padded, degrees, order=1, reshape=True) > 0.5


def test_profile_distance_invariant_to_similarity_and_mirror():
    ell = _ell()
    variants = [
        np.roll(ell, (7, -5), axis=(0, 1)),  # translation
        ndimage.zoom(ell.astype(float), 1.7, order=1) > 0.5,  # scale
        _rotate(ell, 37),  # rotation
        ell[:, ::-1],  # mirror
    ]
    d = pairwise_shape_distances([ell, *variants, _cross(), _disk()], n_candidates=3, n_points=60, resolution=32)
    same = d[0, 1:5]
    other = d[0, 5:]
    assert same.max() < 0.5 * other.min(), (same, other)
    assert d[0, 1] < 1e-12  # translation changes nothing at all


def test_distances_symmetric_zero_diagonal_and_refinement_never_worse():
    images = [_ell(), _cross(), _disk(), _rotate(_cross(), 20)]
    shift_only = pairwise_shape_distances(images, n_candidates=0)
    refined = pairwise_shape_distances(images, n_candidates=3)
    for d in (shift_only, refined):
        np.testing.assert_array_equal(d, d.T)
        assert np.all(np.diag(d) == 0) and np.all(d >= 0)
    assert np.all(refined <= shift_only + 1e-12)
    assert shape_distance(images[1], images[3], n_candidates=1) == pytest.approx(refined[1, 3])


@pytest.mark.parametrize("n_candidates", [2, 3])
def test_copies_are_exactly_alike_and_the_order_of_the_collection_does_not_matter(n_candidates):
    """Byte-identical copies were refined or not depending on where a cut fell inside a
    tie: a query was 57.0 from one copy and 58.5 from the other, and reordering the
    collection moved entries by up to 5.4."""
    from centrality_vision.datasets import load_kimia99

    kimia = load_kimia99()
    images = [kimia.image(name) for name in ("cow1", "dude0", "hand2", "hand2")]
    d = pairwise_shape_distances(images, n_candidates=n_candidates)
    assert d[2, 3] == 0.0
    np.testing.assert_array_equal(d[2], d[3][[0, 1, 3, 2]])  # a copy's row, its own entries swapped
    for seed in range(2):
        perm = np.random.default_rng(seed).permutation(len(images))
        e = pairwise_shape_distances([images[i] for i in perm], n_candidates=n_candidates)
        np.testing.assert_array_equal(e, d[np.ix_(perm, perm)])


def test_n_jobs_does_not_change_the_result():
    from joblib import parallel_config

    images = [_ell(), _cross(), _disk(), _ell()[::-1]]
    options = {"n_points": 40, "resolution": 24, "n_candidates": 2}
    with parallel_config(backend="threading"):  # no process start-up in the unit tests
        parallel = pairwise_shape_distances(images, n_jobs=2, **options)
    np.testing.assert_array_equal(pairwise_shape_distances(images, n_jobs=1, **options), parallel)


def test_grey_images_and_inputs_not_modified():
    ell = _ell()
    grey = np.where(ell, 0, 255).astype(np.uint8)  # dark shape on white
    before = grey.copy()
    d = pairwise_shape_distances([ell, grey])
    assert d[0, 1] == 0.0
    np.testing.assert_array_equal(grey, before)


def test_profile_features_reach_quantiles_and_visibility():
    from centrality_vision.shapes._retrieval import FEATURE_SCALES

    raw = outline_profiles(_ell(), n_points=40) * np.asarray(FEATURE_SCALES)
    assert raw.shape == (40, 8 + 20 + 10 + 10)
    reach, quantiles, visibility, sines = raw[:, :8], raw[:, 8:28], raw[:, 28:38], raw[:, 38:]
    # shares of the shape, growing with the radius; quantiles growing with the level
    assert np.all(np.diff(reach, axis=1) >= 0) and np.all((reach > 0) & (reach <= 1 + 1e-12))
    assert np.all(np.diff(quantiles, axis=1) >= -1e-12) and np.all(quantiles >= 0)
    assert np.all((visibility > 0) & (visibility <= 1 + 1e-12))
    assert np.all(np.diff(sines, axis=1) >= -1e-12) and np.all(np.abs(sines) <= 1 + 1e-12)
    # Round the L's inner corner some paths leave backwards, away from the shape's side.
    assert sines.min() < -0.3
    # The L's outline sees round its inner corner: some points see part of it at a
    # visibility well below 1. A convex rectangle is seen straight: an 8-neighbour path is
    # at most 1/cos(22.5 deg) = 1.0824 times the straight line.
    assert visibility[:, 0].min() < 0.8
    box = np.zeros((60, 60), dtype=bool)
    box[10:50, 20:40] = True
    seen = outline_profiles(box, n_points=40) * np.asarray(FEATURE_SCALES)
    assert seen[:, 28:38].min() >= 1 / 1.0824 - 1e-9
    # From a convex outline every path leaves into the shape or along the outline.
    assert seen[:, 38:].min() >= -1e-9


def test_normalize_shape_keeps_largest_part_and_area():
    image = np.zeros((300, 300), dtype=bool)
    image[20:220, 40:140] = True
    image[250:255, 250:255] = True  # a speck
    small = normalize_shape(image, resolution=30)
    assert abs(int(small.sum()) - 900) < 60
    assert ndimage.label(small)[1] == 1


def test_a_shape_of_two_equal_parts_is_described_by_one_of_them():
    """Both parts were kept: the graph was disconnected, its mean inner distance infinite,
    and every such profile alike (two disks and two bars 3.6 times closer than one disk and
    one bar)."""
    disk, bar = _disk(40, 15), np.zeros((40, 40), dtype=bool)
    bar[17:23, 4:36] = True
    pair = lambda image: np.hstack([image, image])  # noqa: E731
    d = pairwise_shape_distances([disk, bar, pair(disk), pair(bar)], n_points=40, resolution=24)
    assert d[0, 2] < 1e-12 and d[1, 3] < 1e-12  # the kept part is the shape itself
    assert d[2, 3] == pytest.approx(d[0, 1])
    # of two parts of equal area, the one of larger second moment (the bar), wherever it is
    square, bar = np.zeros((40, 40), dtype=bool), np.zeros((40, 40), dtype=bool)
    square[15:25, 15:25] = True
    bar[18:22, 8:33] = True  # 100 pixels each
    alone = normalize_shape(bar, resolution=20)
    np.testing.assert_array_equal(normalize_shape(np.hstack([square, bar]), resolution=20), alone)
    np.testing.assert_array_equal(normalize_shape(np.hstack([bar, square]), resolution=20), alone)


def test_a_comb_of_teeth_thinner_than_a_block_keeps_its_area():
    """Teeth 1 pixel wide and 4 apart averaged to 0.25 over the blocks and vanished at the
    threshold of one half: a connected comb of 90,450 pixels became one pixel, its profile
    NaN and its distances infinite."""
    comb = np.zeros((600, 600), dtype=bool)
    comb[:, ::4] = True
    comb[:10] = True  # the spine that connects the teeth
    comb = np.pad(comb, 5)
    small = normalize_shape(comb, resolution=48)
    assert small.sum() >= 0.5 * 48**2 and ndimage.label(small)[1] == 1
    profile = outline_profiles(comb, n_points=40)
    assert np.all(np.isfinite(profile))
    assert np.isfinite(shape_distance(comb, _disk(), n_points=40))


def test_emd_equals_scipy_wasserstein_on_bin_centres():
    from centrality_vision.shapes import CentralityHistogram

    images = [_ell(), _cross()]
    d = pairwise_shape_distances(images, method="emd", bins=10, resolution=12)
    small = [normalize_shape(im, resolution=12) for im in images]
    h = CentralityHistogram(bins=10, weights=True).fit_transform(small)
    centres = (np.arange(10) + 0.5) / 10
    assert d[0, 1] == pytest.approx(wasserstein_distance(centres, centres, h[0], h[1]))
    chi2 = pairwise_shape_distances(images, method="chi2", bins=10, resolution=12)
    total = h[0] + h[1]
    expected = 0.5 * np.sum(np.where(total > 0, (h[0] - h[1]) ** 2 / np.where(total > 0, total, 1), 0))
    assert chi2[0, 1] == pytest.approx(expected)


def _blocks():
    x = np.r_[np.arange(4.0), 50 + np.arange(4.0), 200 + np.arange(4.0)]
    return np.abs(np.subtract.outer(x, x)), np.repeat(["a", "b", "c"], 4)


def test_the_query_ranks_first_even_tied_with_an_earlier_shape():
    """Shape 1 is at distance 0 from shape 0 as from itself: ranked by index alone, query 1
    found itself at rank 1 (its own class) where its first other shape is of class a."""
    d = np.array([[0.0, 0.0, 5.0], [0.0, 0.0, 5.0], [5.0, 5.0, 0.0]])
    labels = ["a", "b", "b"]
    np.testing.assert_array_equal(retrieval_counts(d, labels, top=1), [0])
    assert bullseye_score(d, labels, top=1) == 1.0  # each query finds itself first


def test_scores_by_hand():
    d, labels = _blocks()
    assert bullseye_score(d, labels, top=4) == 1.0
    assert bullseye_score(d, labels, top=8) == 1.0  # capped at the class size
    assert bullseye_score(d, labels, top=2) == 1.0  # capped at top (24 of 24, not of 48)
    np.testing.assert_array_equal(retrieval_counts(d, labels, top=4), [12, 12, 12, 0])
    assert nearest_neighbor_accuracy(d, labels, n_train=2, n_splits=4) == 1.0
    swapped = labels.copy()
    swapped[[0, 4]] = swapped[[4, 0]]  # two shapes in the wrong block
    # rank 1 (ties to the lower index): queries 0, 1, 4 and 5 find the wrong class
    assert retrieval_counts(d, swapped, top=1)[0] == 8
    # top 4, query included: 1 + 3 + 3 + 3 in each of the first two blocks, 16 in the last
    assert bullseye_score(d, swapped, top=4) == pytest.approx(36 / 48)


def test_nearest_neighbour_ties_go_to_the_lower_index_whatever_the_class_names():
    # all shapes equally far apart: the training shapes were kept in class order, so
    # renaming the classes changed which one a tie went to (1/3 against 2/3)
    d = 1 - np.eye(5)
    as_letters = nearest_neighbor_accuracy(d, ["b", "b", "b", "a", "a"], n_train=1, n_splits=1)
    assert as_letters == nearest_neighbor_accuracy(d, [0, 0, 0, 1, 1], n_train=1, n_splits=1)
    # by hand: each test shape takes the class of the lower of the two training shapes,
    # always one of class 0 (indices 0-2): its two other shapes are right, of three tests
    assert as_letters == pytest.approx(2 / 3)


def test_rerank_pulls_a_chain_together():
    x = np.r_[np.arange(6.0) * 3, 40 + np.arange(6.0)]
    d = np.abs(np.subtract.outer(x, x))
    labels = np.repeat([0, 1], 6)
    r = diffusion_rerank(d, n_neighbors=3, bandwidth=2)
    np.testing.assert_allclose(r, r.T)
    assert np.all(np.diag(r) == 0)
    assert retrieval_counts(r, labels, top=5).sum() == 60


def test_rerank_does_not_depend_on_the_order_of_the_collection():
    """Neighbours tied at the cut kept the lower index: on points of a grid an entry moved by
    up to 0.75 under a permutation."""
    points = np.r_[np.arange(6.0), 20 + np.arange(6.0)]
    d = abs(np.subtract.outer(points, points))
    r = diffusion_rerank(d, n_neighbors=2, bandwidth=2)
    for seed in range(5):
        perm = np.random.default_rng(seed).permutation(points.size)
        np.testing.assert_allclose(
            diffusion_rerank(d[np.ix_(perm, perm)], n_neighbors=2, bandwidth=2), r[np.ix_(perm, perm)], atol=1e-12
        )


def test_rerank_defaults_fit_any_collection_size():
    # the defaults (8 neighbours, bandwidth 10) once refused fewer than 11 shapes
    rng = np.random.default_rng(3)
    for n, neighbors, bandwidth in ((2, 2, 1), (5, 5, 4), (11, 8, 10), (20, 8, 10)):
        x = rng.random(n)
        d = np.abs(np.subtract.outer(x, x))
        np.testing.assert_array_equal(
            diffusion_rerank(d), diffusion_rerank(d, n_neighbors=neighbors, bandwidth=bandwidth)
        )
    with pytest.raises(ValueError, match="`bandwidth` must be"):
        diffusion_rerank(np.zeros((5, 5)), bandwidth=10)  # a value given is not shrunk


def test_rerank_of_huge_finite_distances_stays_finite():
    # squared distances over 1e308 once gave inf / inf = NaN affinities
    x = np.r_[np.arange(4.0), 1e200 + np.arange(4.0) * 1e190]
    d = np.abs(np.subtract.outer(x, x))
    r = diffusion_rerank(d, n_neighbors=2, bandwidth=1)
    assert np.all(np.isfinite(r))
    assert retrieval_counts(r, np.repeat([0, 1], 4), top=3).sum() == 24
    # a factor d / s_i beyond float64 (1e300 / 1e-300) is an affinity of 0, without a warning
    d = np.array([[0, 1e-300, 1e300], [1e-300, 0, 1e300], [1e300, 1e300, 0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = diffusion_rerank(d, n_neighbors=2, bandwidth=1)
    assert np.all(np.isfinite(r)) and r[0, 1] < r[0, 2]


_D4 = np.abs(np.subtract.outer([0.0, 1, 10, 11], [0.0, 1, 10, 11]))


def test_rerank_of_shapes_with_exact_copies_keeps_the_classes_apart():
    # a shape with `bandwidth` exact copies had scale 0: every other affinity was 0 and the
    # ranking past the copies went by index (bullseye 1.0 before re-ranking, 0.58 after)
    rng = np.random.default_rng(0)
    x = np.repeat(np.concatenate([10 * c + 3 * rng.random(6) for c in range(4)]), 3)
    d = np.abs(np.subtract.outer(x, x))
    labels = np.repeat(np.arange(4), 18)
    assert bullseye_score(d, labels, top=36) == 1.0
    r = diffusion_rerank(d, n_neighbors=5, bandwidth=2)
    assert np.all(np.isfinite(r))
    assert bullseye_score(r, labels, top=36) > 0.85
    # the labels' own types are kept: ints and strings still score alike
    assert bullseye_score(d, labels.astype(str), top=36) == bullseye_score(d, list(labels), top=36) == 1.0


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda: pairwise_shape_distances([_ell()], method="hausdorff"), ValueError, "`method` must be one of"),
        (lambda: pairwise_shape_distances([_ell()], n_points=3), ValueError, "`n_points`"),
        (lambda: pairwise_shape_distances(_ell()), ValueError, "single 2D array"),
        (lambda: pairwise_shape_distances([_ell()], n_jobs=0), ValueError, "`n_jobs`"),
        (lambda: bullseye_score(np.zeros((3, 2)), [0, 1, 2]), ValueError, "square"),
        (lambda: bullseye_score(np.full((2, 2), np.nan), [0, 1]), ValueError, "finite"),
        (lambda: retrieval_counts(np.zeros((3, 3)), [0, 1]), ValueError, "one label per shape"),
        (lambda: nearest_neighbor_accuracy(np.zeros((4, 4)), [0, 0, 1, 1], n_train=2), ValueError, "`n_train`"),
        (lambda: diffusion_rerank(np.zeros((3, 3)), n_neighbors=5), ValueError, "`n_neighbors`"),
        # found by a fuzz run: labels numpy merged or NaN that matched no class
        (lambda: retrieval_counts(_D4, [1, "1", 2, "2"], top=1), TypeError, "all strings or all numbers; got a mix"),
        (lambda: bullseye_score(_D4, [np.nan, np.nan, 1.0, 1.0], top=2), ValueError, "must not hold NaN or None"),
        (lambda: bullseye_score(_D4, [None, None, "b", "b"], top=2), TypeError, "got NoneType, str"),
        (lambda: nearest_neighbor_accuracy(_D4, [np.nan] * 2 + [1.0] * 2, n_train=1), ValueError, "NaN or None"),
        (lambda: bullseye_score(sparse.csr_array(_D4), [0, 0, 1, 1]), TypeError, "`distances` must be a dense"),
        (lambda: diffusion_rerank(np.array([[0, [1]], [1, 0]], dtype=object)), TypeError, "`distances` must hold"),
        # found by a fuzz run: numpy's own messages, numeric strings read as numbers, masks ignored
        (lambda: bullseye_score([[0, 1], [1]], [0, 1]), ValueError, "`distances` must be a square"),
        (lambda: retrieval_counts([[0, 10**400], [1, 0]], [0, 1]), TypeError, "`distances` must hold real"),
        (lambda: retrieval_counts([["0", "1"], ["1", "0"]], [0, 1]), TypeError, "`distances` must hold real"),
        (
            lambda: bullseye_score(np.ma.masked_array(_D4, mask=np.eye(4)), [0, 0, 1, 1]),
            TypeError,
            "`distances` must be a plain array; got a masked array",
        ),
        (
            lambda: diffusion_rerank(_D4 - 1, n_neighbors=2, bandwidth=2),
            ValueError,
            "`distances` must not be negative; got a smallest value of -1",
        ),
    ],
)
def test_bad_inputs(call, error, match):
    with pytest.raises(error, match=match):
        call()


@pytest.mark.parametrize(
    ("mask", "kwargs", "error", "message"),
    [
        (np.ones((4, 6), bool), {"resolution": 0}, ValueError, "`resolution`"),
        (np.ones((4, 6), bool), {"resolution": -5}, ValueError, "`resolution`"),
        (np.ones((4, 6), bool), {"resolution": 2.5}, TypeError, "`resolution`"),
        (np.zeros((4, 4), bool), {}, ValueError, "`mask`"),
        (np.zeros((5, 5, 3), np.uint8), {}, ValueError, "`mask` must be a 2D array"),
    ],
)
def test_normalize_shape_names_bad_input(mask, kwargs, error, message):
    from centrality_vision.shapes import normalize_shape

    with pytest.raises(error, match=message):
        normalize_shape(mask, **kwargs)


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"directory": 3}, TypeError, "`directory` must be a path"),
        ({"max_images": None}, TypeError, "`max_images`"),
        ({"max_images": 2.5}, TypeError, "`max_images`"),
        ({"max_images": -1}, ValueError, "`max_images`"),
    ],
)
def test_centrality_cache_checks_its_arguments(kwargs, error, message):
    from centrality_vision.shapes import CentralityCache

    with pytest.raises(error, match=message):
        CentralityCache(**kwargs)


def test_retrieval_counts_former_k_still_works_with_a_warning():
    # API audit F9: bullseye_score said top, retrieval_counts k, for the ranks inspected
    d = abs(np.subtract.outer([0.0, 1, 10, 11, 12], [0.0, 1, 10, 11, 12]))
    labels = ["a", "a", "b", "b", "b"]
    with pytest.warns(FutureWarning, match=r"`k` of retrieval_counts\(\) is renamed `top`"):
        old = retrieval_counts(d, labels, k=3)
    np.testing.assert_array_equal(old, retrieval_counts(d, labels, top=3))
    np.testing.assert_array_equal(old, [5, 3, 0])  # rank 2: the three b only


def test_nearest_neighbour_accuracy_is_the_former_name_with_a_warning():
    from centrality_vision import shapes

    d = abs(np.subtract.outer([0.0, 1, 2, 10, 11, 12], [0.0, 1, 2, 10, 11, 12]))
    labels = ["a", "a", "a", "b", "b", "b"]
    with pytest.warns(
        FutureWarning, match=r"`nearest_neighbour_accuracy\(\)` is renamed `nearest_neighbor_accuracy\(\)`"
    ):
        old = shapes.nearest_neighbour_accuracy(d, labels, n_train=1, n_splits=2, seed=3)
    assert old == nearest_neighbor_accuracy(d, labels, n_train=1, n_splits=2, seed=3) == 1.0
    assert "nearest_neighbour_accuracy" not in shapes.__all__

import warnings

import numpy as np
import pytest

from centrality_vision.datasets import contour_points, load_kimia99
from centrality_vision.exceptions import InputError, MatchingWarning
from centrality_vision.matching import match, mwme_match
from centrality_vision.transforms import SimilarityTransform, fit_similarity


def _rotation(angle):
    return np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


@pytest.mark.parametrize("method", ["exact", "greedy", "local"])
@pytest.mark.parametrize("seed", range(5))
def test_recovers_random_similarity_transforms(seed, method):
    rng = np.random.default_rng(seed)
    fixed = rng.random((12, 2))
    perm = rng.permutation(12)
    scale, angle, shift = rng.uniform(0.5, 2), rng.uniform(0, 2 * np.pi), rng.uniform(-5, 5, 2)
    moving = scale * fixed[perm] @ _rotation(angle).T + shift
    correspondence, transform = mwme_match(moving, fixed, solver=method)
    np.testing.assert_array_equal(correspondence, perm)
    np.testing.assert_allclose(transform(moving), fixed[perm], atol=1e-9)
    assert transform.scale == pytest.approx(1 / scale)


def test_kimia_outlines_50_points():
    data = load_kimia99()
    rng = np.random.default_rng(0)
    correct = []
    for name in ("cow1", "dog1", "f16", "bunny04"):
        fixed = contour_points(data.image(name), 50)
        perm = rng.permutation(50)
        moving = 1.7 * fixed[perm] @ _rotation(rng.uniform(0, 6.28)).T + 40.0
        correspondence, _ = mwme_match(moving, fixed)
        correct.append(np.mean(correspondence == perm))
    assert np.mean(correct) >= 0.95


def test_3d_and_rigid():
    rng = np.random.default_rng(3)
    fixed = rng.random((10, 3))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    correspondence, transform = mwme_match(fixed @ q.T + 1.0, fixed, scale=False)
    np.testing.assert_array_equal(correspondence, np.arange(10))
    assert transform.scale == 1.0 and np.linalg.det(transform.rotation) == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("moving", "fixed", "match"),
    [
        (np.zeros((4, 2)) + np.arange(4)[:, None] * [1, 0.5], np.random.default_rng(0).random((5, 2)), "same shape"),
        ([[0, 0], [1, 1]], [[0, 0], [1, 1]], "at least 3 points"),
        ([[0, 0], [1, 1], [0, 0]], [[0, 0], [1, 1], [2, 0]], "duplicate"),
        ([[0, 0], [1, np.nan], [2, 0]], [[0, 0], [1, 1], [2, 0]], "finite"),
    ],
)
def test_errors(moving, fixed, match):
    with pytest.raises(ValueError, match=match):
        mwme_match(moving, fixed)


def test_similarity_transform_inverse_and_matrix():
    t = SimilarityTransform(_rotation(0.4), np.array([1.0, -2.0]), 1.5)
    pts = np.random.default_rng(0).random((5, 2))
    np.testing.assert_allclose(t.inverse()(t(pts)), pts)
    homogeneous = np.c_[pts, np.ones(5)] @ t.matrix.T
    np.testing.assert_allclose(homogeneous[:, :2], t(pts))
    fitted = fit_similarity(pts, t(pts))
    np.testing.assert_allclose(fitted.matrix, t.matrix, atol=1e-12)
    with pytest.raises(ValueError, match="`scale`"):
        SimilarityTransform(np.eye(2), np.zeros(2), -1.0)


def test_fit_similarity_never_reflects():
    pts = np.random.default_rng(1).random((6, 2))
    mirrored = pts * [-1, 1]
    assert np.linalg.det(fit_similarity(pts, mirrored).rotation) == pytest.approx(1.0)


def test_contour_points_spacing():
    yy, xx = np.mgrid[:60, :60]
    disk = (yy - 30) ** 2 + (xx - 30) ** 2 < 20**2
    pts = contour_points(disk, 40)
    radius = np.linalg.norm(pts - 30, axis=1)
    assert np.all(np.abs(radius - 20) < 1.0)
    steps = np.linalg.norm(np.diff(np.vstack([pts, pts[:1]]), axis=0), axis=1)
    assert steps.std() / steps.mean() < 0.1
    with pytest.raises(ValueError, match="`n_points`"):
        contour_points(disk, 2)


@pytest.mark.parametrize("method", ["local", "greedy"])
@pytest.mark.parametrize("far", [1e8, 1e9, 1e10])
def test_relabelling_a_set_with_one_far_point_does_not_change_the_matching(method, far):
    # ties to 1e-9 of the total: the far point dominated every total, every difference among
    # the others was a tie, the first index won, and a relabelled copy was matched wrongly
    for seed in range(8):
        rng = np.random.default_rng(seed)
        fixed = np.vstack([rng.random((10, 2)), [[far, 0.0]]])
        perm = rng.permutation(11)
        correspondence, _ = mwme_match(fixed[perm], fixed, solver=method)
        np.testing.assert_array_equal(correspondence, perm)


def test_rigid_mwme_matching_of_incomparable_extents_and_bad_options_are_errors():
    rng = np.random.default_rng(0)
    points = rng.random((7, 2))
    # both candidates' residuals overflowed to inf and the first one won, right or not
    with pytest.raises(InputError, match=r"`scale=False` needs `moving` and `fixed` of comparable extent"):
        mwme_match(points * 1e200, points, scale=False)
    for scale in (None, 0, "no", np.nan):  # a rigid or a similarity fit, silently
        with pytest.raises(TypeError, match="`scale` must be True or False"):
            mwme_match(points, points, scale=scale)
    with pytest.raises(InputError, match="`mwme_solver` must be one of"):  # it named `method`
        match(points, points, method="mwme", mwme_solver="fast")


def test_a_similarity_match_of_a_tiny_copy_raises_no_overflow_warning():
    import warnings

    points = np.random.default_rng(1).random((12, 2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the unused rigid unit ratio overflowed in ldexp
        result = match(points, points * 1e-308)
    assert result.transform.scale == pytest.approx(1e-308)


@pytest.mark.parametrize("pair", [(1e-310, 1.0), (1e-300, 1e300)])
def test_a_scale_beyond_float64_is_a_named_error_without_a_warning_first(pair):
    import warnings

    points = np.random.default_rng(0).random((12, 2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # ldexp's overflow warning came before the error
        with pytest.raises(InputError, match="differ in scale or position beyond float64"):
            match(points * pair[0], points * pair[1])


@pytest.mark.parametrize(
    ("method", "options", "error"),
    [
        ("mwme", {"n_neighbors": None}, TypeError),
        ("mwme", {"n_candidates": -5}, InputError),
        ("mwme", {"refine": "nonsense"}, InputError),
        ("mwme", {"w": np.nan}, InputError),
        ("robust", {"mwme_solver": "nonsense"}, InputError),
        ("shape-context", {"mwme_solver": 3}, InputError),
    ],
)
def test_every_option_is_checked_whatever_the_method(method, options, error):
    points = np.random.default_rng(2).random((8, 2))
    with pytest.raises(error, match=f"`{next(iter(options))}`"):
        match(points, points, method=method, **options)


def _grid_trials():
    """A 3 x 4 integer grid (tied MWME optima), permuted and rotated: seeded trials."""
    grid = np.array([(i, j) for i in range(3) for j in range(4)], dtype=float)
    rng = np.random.default_rng(0)
    for _ in range(5):
        perm, angle = rng.permutation(len(grid)), rng.uniform(0, 2 * np.pi)
        rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        yield grid[perm] @ rotation.T + 1.0, grid


@pytest.mark.parametrize("method", ["exact", "local", "greedy"])
def test_a_matching_its_own_transform_contradicts_is_a_warning_not_silent(method):
    # tied optima on a grid: the degrees paired unrelated points, with an RMS residual of
    # about the grid's spacing, and nothing said so
    outcomes = []
    for moving, fixed in _grid_trials():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            correspondence, transform = mwme_match(moving, fixed, solver=method)
        moved = transform(moving)
        nearest = np.argmin(((moved[:, None, :] - fixed[None, :, :]) ** 2).sum(axis=2), axis=1)
        wrong = int(np.count_nonzero(nearest != correspondence))
        said = [str(w.message) for w in caught if issubclass(w.category, MatchingWarning)]
        assert len(caught) == len(said)
        if wrong:
            assert said == [said[0]] and said[0].startswith(f"mwme_match: {wrong} of 12 matched pairs")
        else:  # the right matching, or one of the grid's symmetries: a right match too
            assert not said and np.sqrt(np.mean(np.sum((moved - fixed[correspondence]) ** 2, axis=1))) < 1e-9
        outcomes.append(bool(wrong))
    assert any(outcomes)  # the case happens on these trials


def test_noise_that_changes_the_graphs_is_said():
    fixed = contour_points(load_kimia99().image("cow1"), 50)
    rng = np.random.default_rng(5)
    perm = rng.permutation(50)
    spacing = float(np.min(np.linalg.norm(np.diff(fixed, axis=0), axis=1)))
    noisy = fixed[perm] + rng.normal(0.0, 2.0 * spacing, size=fixed.shape)
    with pytest.warns(MatchingWarning, match=r"mwme_match: \d+ of 50 matched pairs are not nearest neighbours"):
        mwme_match(noisy, fixed)
    with pytest.warns(MatchingWarning):  # through match() too
        match(noisy, fixed, method="mwme")

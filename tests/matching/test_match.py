"""match(): recovery of known similarity transforms, partial sets, outliers, errors, extreme scales."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from centrality_vision.exceptions import InputError, MatchingWarning
from centrality_vision.matching import METHODS, MatchResult, match, mwme_match


def _rotation(angle):
    return np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


def _outline(u):
    """A closed, asymmetric star-like curve (no rotational symmetry)."""
    r = 1 + 0.3 * np.cos(3 * u) + 0.15 * np.sin(2 * u)
    return np.c_[r * np.cos(u), r * np.sin(u)]


N = 60
STEP = 2 * np.pi / N
FIXED = _outline(STEP * np.arange(N))


def _similar(points, rng):
    scale, angle, shift = rng.uniform(0.5, 2), rng.uniform(0, 2 * np.pi), rng.uniform(-50, 50, 2)
    return scale * points @ _rotation(angle).T + shift


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("seed", range(3))
def test_exact_copies_are_matched_exactly(method, seed):
    rng = np.random.default_rng(seed)
    perm = rng.permutation(N)
    moving = _similar(FIXED[perm], rng)
    result = match(moving, FIXED, method=method)
    np.testing.assert_array_equal(result.correspondence, perm)
    np.testing.assert_allclose(result.transform(moving), FIXED[perm], atol=1e-6)
    assert result.n_matched == N and result.method == method


@pytest.mark.parametrize("seed", range(3))
def test_robust_resampled_partial_outline_with_outliers(seed):
    """Different samples along the outline, a quarter missing, 30 outliers: every kept
    point lands within one step of its true place, outliers away from the outline stay
    unmatched."""
    rng = np.random.default_rng(seed)
    offset = rng.uniform(0.25, 0.75)
    first = rng.integers(N)
    kept_u = STEP * ((first + np.arange(45)) % N + offset)
    truth = _outline(kept_u)
    outliers = rng.uniform(-1.6, 1.6, (200, 2))
    dense = _outline(np.linspace(0, 2 * np.pi, 2000))
    far = np.min(np.linalg.norm(outliers[:, None] - dense[None], axis=2), axis=1) > 3 * STEP
    outliers = outliers[far][:30]  # clutter away from the outline
    scale, angle, shift = 1.7, rng.uniform(0, 2 * np.pi), np.array([4.0, -9.0])
    moving = scale * np.vstack([truth, outliers]) @ _rotation(angle).T + shift
    correspondence, transform = match(moving, FIXED)
    err = np.linalg.norm(FIXED[correspondence[:45]] - truth, axis=1)
    assert np.all(correspondence[:45] >= 0) and np.all(err <= STEP * 1.3)  # one step (chord) of the outline
    assert np.all(correspondence[45:] == -1)
    # point-to-point fits between samples half a step apart: a pose within a few degrees
    assert transform.scale == pytest.approx(1 / scale, rel=0.03)
    np.testing.assert_allclose(transform.rotation, _rotation(-angle), atol=0.06)


def test_cpd_refinement_on_a_whole_noisy_resampled_outline():
    """CPD from the consensus pose (for whole sets: CPD's mixture pulls towards missing parts)."""
    rng = np.random.default_rng(7)
    truth = _outline(STEP * (np.arange(N) + 0.4))
    moving = _similar(truth + rng.normal(0, 0.1 * STEP, truth.shape), rng)
    result = match(moving, FIXED, refine="cpd")
    err = np.linalg.norm(FIXED[result.correspondence] - truth, axis=1)
    assert np.all(result.correspondence >= 0) and np.all(err <= STEP * 1.3)


def test_robust_beats_shape_context_when_a_part_is_missing():
    rng = np.random.default_rng(5)
    truth = _outline(STEP * (np.arange(40) + 0.5))  # a third missing, resampled
    moving = _similar(truth, rng)

    def accuracy(correspondence):
        ok = correspondence >= 0
        return np.mean(ok & (np.linalg.norm(FIXED[np.maximum(correspondence, 0)] - truth, axis=1) <= STEP * 1.3))

    robust = accuracy(match(moving, FIXED).correspondence)
    with pytest.warns(MatchingWarning, match="shape-context matching: the transform fitted to the 40 matched"):
        baseline = accuracy(match(moving, FIXED, method="shape-context").correspondence)  # and it says so
    assert robust == 1.0 and robust > baseline


def test_rigid_and_result_object():
    moving = FIXED @ _rotation(0.8).T + [3.0, 1.0]
    result = match(moving, FIXED, scale=False)
    assert isinstance(result, MatchResult)
    correspondence, transform = result
    np.testing.assert_array_equal(correspondence, np.arange(N))
    assert transform.scale == 1.0
    assert "hypotheses" in result.info
    before = moving.copy()
    match(moving, FIXED, method="shape-context", scale=False)
    np.testing.assert_array_equal(moving, before)  # inputs untouched


@settings(max_examples=12, deadline=None)
@given(exponent=st.integers(-300, 300), method=st.sampled_from(METHODS), seed=st.integers(0, 2**16))
def test_any_scale_gives_the_unit_scale_answer(exponent, method, seed):
    """Sets scaled by 10^k anywhere in float64's range: same correspondence, finite transform."""
    rng = np.random.default_rng(seed)
    perm = rng.permutation(N)
    moving = _similar(FIXED[perm], rng)
    factor = 10.0**exponent
    reference = match(moving, FIXED, method=method)
    scaled = match(moving * factor, FIXED * factor, method=method)
    np.testing.assert_array_equal(scaled.correspondence, reference.correspondence)
    assert scaled.transform.scale == pytest.approx(reference.transform.scale, rel=1e-6)
    assert np.all(np.isfinite(scaled.transform.translation))


@settings(max_examples=10, deadline=None)
@given(exponent=st.integers(100, 307), seed=st.integers(0, 2**16))
def test_mwme_match_3d_huge_coordinate_answers_or_refuses(exponent, seed):
    """The fuzz finding: a 3D set with a 1e155 coordinate looped forever in the SVD. Now it
    is matched, or refused with an error naming the dynamic range; never a hang or NaN."""
    rng = np.random.default_rng(seed)
    fixed = rng.random((8, 3))
    fixed[0, 0] = 10.0**exponent
    perm = rng.permutation(8)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MatchingWarning)
            correspondence, transform = mwme_match(fixed[perm] + 1.0, fixed)
    except ValueError as exc:
        assert "dynamic range" in str(exc) or "float64" in str(exc)
    else:
        assert correspondence.shape == (8,) and np.all(np.isfinite(transform.translation))
        # far beyond the extent the degrees can resolve: right, or said to be unreliable
        warned = any(issubclass(w.category, MatchingWarning) for w in caught)
        assert warned or np.array_equal(correspondence, perm)


def test_mwme_match_1e155_is_matched():
    fixed = np.random.default_rng(2).random((8, 3)) * 1e155
    perm = np.random.default_rng(3).permutation(8)
    correspondence, transform = mwme_match(fixed[perm] * 2.0, fixed)
    np.testing.assert_array_equal(correspondence, perm)
    assert transform.scale == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("kwargs", "error", "text"),
    [
        ({"method": "best"}, ValueError, "`method`"),
        ({"scale": "yes"}, TypeError, "`scale`"),
        ({"n_neighbors": 2}, ValueError, "`n_neighbors`"),
        ({"n_neighbors": 20}, ValueError, "`n_neighbors`"),
        ({"n_candidates": 0}, ValueError, "`n_candidates`"),
        ({"refine": "none"}, ValueError, "`refine`"),
        ({"w": 1.0}, ValueError, "`w`"),
    ],
)
def test_option_errors(kwargs, error, text):
    with pytest.raises(error, match=text):
        match(FIXED, FIXED, **kwargs)


@pytest.mark.parametrize(
    ("moving", "method", "text"),
    [
        (np.random.default_rng(0).random((10, 3)), "robust", "`moving` must have shape"),
        (np.random.default_rng(0).random((10, 3)), "shape-context", "`moving` must have shape"),
        (FIXED[:3], "robust", "at least 4 points"),
        (np.vstack([FIXED, FIXED[:1]]), "robust", "duplicate"),
        (np.where(np.arange(N)[:, None] == 3, np.nan, FIXED), "robust", "finite"),
        (FIXED[:30], "mwme", "same shape"),
        (np.array([[0, 0], [1e-200, 0], [1, 0], [0, 1], [1, 1.0]]), "robust", "rows 0 and 1 are 1e-200 apart"),
    ],
)
def test_data_errors(moving, method, text):
    with pytest.raises(ValueError, match=text):
        match(moving, FIXED, method=method)


def test_large_sets_use_the_prefiltered_candidates():
    """Above 256 fixed points each moving point compares signatures with 64 prefiltered ones."""
    from centrality_vision.matching import _robust

    u = np.sort(np.random.default_rng(0).uniform(0, 2 * np.pi, _robust.PREFILTER_ABOVE + 40))
    fixed = _outline(u)
    perm = np.random.default_rng(1).permutation(u.size)
    result = match(_similar(fixed[perm], np.random.default_rng(2)), fixed)
    np.testing.assert_array_equal(result.correspondence, perm)


def test_rigid_matching_of_sets_of_incomparable_extent_is_refused():
    """Fuzz finding: with scale=False, moving at 1e149 and fixed at 1e-301 overflowed inside the
    consensus scoring (a bare ValueError from scipy); it is an InputError naming `scale`."""
    from centrality_vision.exceptions import InputError
    from centrality_vision.matching import match

    points = np.random.default_rng(0).random((6, 2))
    with pytest.raises(InputError, match="`scale=False` needs `moving` and `fixed` of comparable extent"):
        match(points * 1e149, points * 1e-301, scale=False)
    result = match(points * 1e40, points * 1e-40)  # a similarity brings one onto the other
    assert result.correspondence.tolist() == list(range(6))
    assert result.transform.scale == pytest.approx(1e-80, rel=1e-9)


def test_shape_context_with_no_matched_pair_reports_no_mean_cost():
    """Every point to a dummy (a blob against a line): no pair, so no mean cost (never NaN)."""
    from centrality_vision.matching._shape_context import shape_context_assignment

    line = np.c_[np.linspace(0.0, 1.0, 12), np.zeros(12)]
    blob = np.random.default_rng(1).random((12, 2))
    correspondence, info = shape_context_assignment(blob, line)
    assert np.all(correspondence == -1)
    assert info["mean_cost"] is None
    correspondence, info = shape_context_assignment(blob, blob[::-1])
    assert np.all(correspondence >= 0) and np.isfinite(info["mean_cost"])


def _blob(t):
    return np.c_[np.cos(t) * (1 + 0.3 * np.cos(3 * t)), np.sin(t) * (1 + 0.3 * np.sin(2 * t))]


@pytest.mark.parametrize("factor", [1.1, 1.5, 0.7])
def test_a_rigid_match_of_sets_that_differ_in_scale_warns(factor):
    # a copy scaled 1.5 and rotated 30 degrees: 29 of 40 points matched, every pair wrong, no warning
    moving = _blob(np.linspace(0, 2 * np.pi, 40, endpoint=False))
    a = np.radians(30)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    fixed = factor * moving @ rot.T + [2.0, -1.0]
    with pytest.warns(MatchingWarning, match=rf"differ in scale: a similarity transform of scale {factor:g} "):
        match(moving, fixed, scale=False)
    assert np.array_equal(match(moving, fixed).correspondence, np.arange(40))  # the similarity is right


@pytest.mark.parametrize("seed", range(6))
def test_rigid_copies_with_noise_and_missing_parts_do_not_warn(seed):
    rng = np.random.default_rng(seed)
    moving = _blob(np.sort(rng.uniform(0, 2 * np.pi, 60)))
    a = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    kept = moving[: 40 + 3 * seed]
    fixed = kept @ rot.T + 3.0 + rng.normal(0, 0.01, kept.shape)
    with warnings.catch_warnings():
        warnings.simplefilter("error", MatchingWarning)
        result = match(moving, fixed, scale=False)
    assert result.transform.rotation == pytest.approx(rot, abs=0.05)


def test_cpd_refinement_that_collapses_is_dropped_with_a_warning():
    # fuzz round 6: w (then outlier_weight) 0.99 let CPD shrink an exact similar copy onto a few fixed
    # points (1 of 40 right, n_matched 40), sometimes without a warning
    rng = np.random.default_rng(3)
    fixed = rng.random((40, 2))
    perm = rng.permutation(40)
    moving = fixed[perm] * 2 + 1
    with pytest.warns(MatchingWarning, match="`refine='cpd'` with `w=0.99`.*consensus pose kept"):
        result = match(moving, fixed, refine="cpd", w=0.99)
    assert not result.info["cpd_kept"] and result.info["cpd_consensus"] < 0.75 * result.info["refined_consensus"]
    np.testing.assert_array_equal(result.correspondence, perm)
    assert result.transform.scale == pytest.approx(0.5, rel=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        kept = match(moving, fixed, refine="cpd", w=0.3)
    assert kept.info["cpd_kept"]
    np.testing.assert_array_equal(kept.correspondence, perm)


def test_mwme_exact_limit_names_mwme_solver():
    points = np.random.default_rng(0).random((25, 2))
    with pytest.raises(InputError, match=r"`mwme_solver='exact'` solves sets of up to 20 .* `mwme_solver='local'`"):
        match(points, points[::-1], method="mwme", mwme_solver="exact")


def test_mwme_solver_former_names_warn_and_agree():
    # API audit F13: `method` meant the matching method in match and the solver in mwme_match
    rng = np.random.default_rng(1)
    fixed = rng.random((10, 2))
    moving = fixed[::-1] @ np.array([[0.0, -1.0], [1.0, 0.0]]).T + 2.0
    with pytest.warns(FutureWarning, match="`mwme_method` of match\\(\\) is renamed `mwme_solver`"):
        old = match(moving, fixed, method="mwme", mwme_method="greedy")
    new = match(moving, fixed, method="mwme", mwme_solver="greedy")
    np.testing.assert_array_equal(old.correspondence, new.correspondence)
    assert new.info == {"mwme_solver": "greedy"}
    with pytest.warns(FutureWarning, match="`method` of mwme_match\\(\\) is renamed `solver`"):
        old_pairs, _ = mwme_match(moving, fixed, method="exact")
    np.testing.assert_array_equal(old_pairs, mwme_match(moving, fixed, solver="exact")[0])
    with pytest.raises(TypeError, match="give `solver` only"):
        mwme_match(moving, fixed, method="exact", solver="exact")


@pytest.mark.parametrize("method", ["robust", "mwme"])
def test_points_distinct_only_beyond_float64_resolution_are_named_by_rows(method):
    # the mwme path blamed `points` (an internal name) and printed normalised coordinates
    # never passed in; the robust path put the spacing at "0 of" the extent
    moving = np.array([[2.0**62, 0.0], [0.0, 2.0**62], [1.0, 1.0], [5.0, 7.0], [9.0, 3.0]])
    fixed = np.random.default_rng(1).random((5, 2))
    with pytest.raises(InputError, match=r"^`moving`: rows \d and \d are [\d.]+ apart, at coordinates up to 4.61e\+18"):
        match(moving, fixed, method=method)


def test_former_names_n_neighbours_and_outlier_weight_still_work_with_a_warning():
    # API audit F3/F4: match spelled CPD's w and the package's n_neighbors its own way
    rng = np.random.default_rng(4)
    fixed = rng.random((30, 2))
    moving = fixed[::-1] * 1.5
    new = match(moving, fixed, n_neighbors=6, refine="cpd", w=0.2)
    with pytest.warns(FutureWarning, match="`n_neighbours` of match\\(\\) is renamed `n_neighbors`"):
        old = match(moving, fixed, n_neighbours=6, refine="cpd", w=0.2)
    np.testing.assert_array_equal(old.correspondence, new.correspondence)
    with pytest.warns(FutureWarning, match="`outlier_weight` of match\\(\\) is renamed `w`"):
        old = match(moving, fixed, n_neighbors=6, refine="cpd", outlier_weight=0.2)
    np.testing.assert_array_equal(old.correspondence, new.correspondence)
    with pytest.raises(TypeError, match="`outlier_weight` is the former name of `w`; give `w` only"):
        match(moving, fixed, w=0.2, outlier_weight=0.2)


def test_match_results_compare_and_hash_without_raising():
    # fuzz round 6: == and `in` raised "truth value of an array is ambiguous", hash() TypeError
    points = np.random.default_rng(5).random((20, 2))
    a, b = match(points, points), match(points, points)
    assert a == a and a != b and a in [b, a] and b not in [a]
    assert len({a, b}) == 2
    np.testing.assert_array_equal(a.correspondence, b.correspondence)


@pytest.mark.parametrize("chunk", [1, 7 * 60, 1 << 22])
def test_shape_context_costs_in_blocks_equal_the_costs_of_all_pairs_at_once(monkeypatch, chunk):
    # fuzz round 6 (L6): the costs of all pairs at once took 1.7 GB of temporaries for
    # 1000 points against 1000; blocks of rows must not change a single cost
    from centrality_vision.matching import _shape_context

    rng = np.random.default_rng(3)
    a, b = rng.random((23, 60)), rng.random((17, 60))
    a[2, :5] = b[4, :5] = 0.0  # empty bins on both sides: 0/0 counts 0
    num, den = (a[:, None] - b[None]) ** 2, a[:, None] + b[None]
    whole = 0.5 * np.sum(np.divide(num, den, out=np.zeros_like(num), where=den > 0), axis=2)
    monkeypatch.setattr(_shape_context, "_CHUNK_VALUES", chunk)
    assert np.array_equal(_shape_context._chi2(a, b), whole)


@pytest.mark.parametrize("seed", range(20))
def test_shape_context_pairs_do_not_depend_on_the_order_of_the_points(seed):
    # fuzz round 6 (L5): costs of counted histograms tie exactly, and the Hungarian
    # algorithm broke the tie by row order (13 of 100 such noisy, partial sets with
    # outliers changed their pairs when both inputs were permuted)
    rng = np.random.default_rng(seed)
    n = int(rng.integers(30, 120))
    fixed = rng.random((n, 2))
    keep = rng.choice(n, int(0.7 * n), replace=False)
    moving = np.vstack([1.5 * fixed[keep] + rng.normal(0, 0.004, (keep.size, 2)), rng.random((10, 2)) * 1.5])
    p, q = rng.permutation(len(moving)), rng.permutation(n)
    with warnings.catch_warnings():  # random clouds, a third missing, clutter: most pairs are wrong, and said so
        warnings.simplefilter("ignore", MatchingWarning)
        first = match(moving, fixed, method="shape-context").correspondence
        again = match(moving[p], fixed[q], method="shape-context").correspondence
    expected = np.where(first[p] >= 0, np.argsort(q)[np.maximum(first[p], 0)], -1)
    np.testing.assert_array_equal(again, expected)


def test_robust_matching_does_not_depend_on_how_moving_is_turned():
    # its whole-outline poses sat at fixed angles, so which of them came closest to the truth,
    # and won, depended on the turn of `moving`: here a wrong pose (error ~2) at 0, 17 and 120
    # degrees and the right one at 111
    def outline(u):
        return np.c_[(1 + 0.3 * np.cos(3 * u + 0.4)) * np.cos(u), (1 + 0.2 * np.sin(2 * u)) * np.sin(u)]

    rng = np.random.default_rng(7)
    fixed = outline(np.sort(rng.uniform(0, 2 * np.pi, int(rng.integers(30, 70)))))
    inliers = outline(np.sort(rng.uniform(0, 1.6 * np.pi, 22))) + rng.normal(0, 0.01, (22, 2))
    moving = np.vstack([inliers, rng.uniform(-1.5, 1.5, (5, 2))])  # the truth: the identity
    results = []
    for degrees in (0, 17, 111, 120):
        a = np.deg2rad(degrees)
        turned = moving @ np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]).T
        result = match(turned, fixed)
        assert np.abs(result.transform(turned)[:22] - inliers).max() < 0.05
        results.append(result.correspondence)
    assert all(np.array_equal(results[0], other) for other in results[1:])


def test_shape_context_on_a_symmetric_set_says_its_pose_is_not_reliable():
    # every octagon point has the same descriptor: the assignment mixed the tied pairings and
    # the pose fitted to them shrank to a quarter of the true scale, silently
    octagon = np.c_[np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)]
    p = np.random.default_rng(0).permutation(8)
    moving = 2.0 * octagon[p] @ np.array([[0.6, -0.8], [0.8, 0.6]]).T + 5.0
    with pytest.warns(MatchingWarning, match="of the fixed partners' spread unexplained"):
        result = match(moving, octagon, method="shape-context")
    assert result.transform.scale < 0.3  # (0.5 is right)
    with warnings.catch_warnings():
        warnings.simplefilter("error", MatchingWarning)
        match(moving, octagon, method="robust")  # exact, and quiet


def test_shape_context_tangents_do_not_depend_on_the_order_of_equidistant_neighbours():
    # on a grid several neighbours tie with the k-th nearest; the k-d tree's choice among
    # them followed the row order and turned the tangent (and every descriptor with it)
    from centrality_vision.matching._shape_context import _tangent_angles

    grid = np.stack(np.meshgrid(np.arange(6.0), np.arange(4.0)), -1).reshape(-1, 2)
    for seed in range(5):
        p = np.random.default_rng(seed).permutation(len(grid))
        turned = np.mod(_tangent_angles(grid[p]) - _tangent_angles(grid)[p] + np.pi, 2 * np.pi) - np.pi
        np.testing.assert_allclose(turned, 0.0, atol=1e-9)


def test_points_that_coincide_once_centred_are_named_with_their_relative_spacing():
    good = np.random.default_rng(0).random((10, 2))
    near = np.vstack([good * 1e-3, [[1e14, 1e14]]])  # 1e-3 apart at 1e14: 1e-17 of the size
    with pytest.raises(InputError, match=r"`moving`: rows \d+ and \d+ .* \(a relative spacing of \d\.\de-1[78]\)"):
        match(near, good)
    # at 1e-200 apart and 1e200 in size the quotient underflows: it printed "0.0e+00"
    far = np.vstack([good * 1e-200, [[1e200, 1e200]]])
    with pytest.raises(InputError, match=r"\(a relative spacing of below 1e-308\)"):
        match(far, good)


@pytest.mark.parametrize("method", ["robust", "shape-context"])
def test_a_3d_set_given_to_a_2d_method_is_pointed_to_mwme(method):
    points = np.random.default_rng(0).random((10, 3))
    with pytest.raises(InputError, match=r"got shape \(10, 3\)\. method='[a-z-]+' matches 2D sets; method='mwme'"):
        match(points, points, method=method)
    with pytest.raises(InputError) as info:  # a wrong shape that is not 3D gets no such hint
        match(points[:, :1], points[:, :1], method=method)
    assert "mwme" not in str(info.value)


@pytest.mark.parametrize("method", ["robust", "mwme"])
def test_points_closer_than_the_graphs_resolve_are_refused_by_the_matchers_name(method):
    """The matchers measured the closest pair against the normalised coordinates' range, the
    graphs they build against the longest distance (up to 2 sqrt(d) of that range): a pair
    in between passed the first check and the second refused it, naming `point_sets[0]` or
    `points`, which the caller never passed."""
    square = np.array([[-1.0, -1], [1, -1], [-1, 1], [1, 1], [0, 0]])
    close, other = np.vstack([square, [2.4e-150, 0]]), np.vstack([square, [0.5, 0]])  # (mwme: equal sizes)
    with pytest.raises(InputError, match=r"^`moving` has points closer than 1e-150 times its diameter"):
        match(close, other, method=method)
    with pytest.raises(InputError, match=r"^`fixed` has points closer"):
        match(other, close, method=method)
    resolved = np.vstack([square, [1e-140, 0]])  # resolved by both: matched onto itself
    np.testing.assert_allclose(match(resolved, resolved, method=method).transform.scale, 1.0)


def test_shape_context_tangents_turn_with_a_collinear_set():
    """On a line the centroid lies on every tangent's line, so the sign that put it on the
    left was rounding's: turned copies flipped 264 of 500 tangents and the descriptor was not
    rotation-invariant. The tangent now points away from the centroid there."""
    from centrality_vision.matching._shape_context import _tangent_angles

    x = np.sort(np.random.default_rng(0).uniform(0, 10, 20))
    line = np.c_[x, 0.5 * x + 1]
    for angle in np.linspace(0.1, 6.0, 25):
        turned = line @ np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
        change = (_tangent_angles(turned) - _tangent_angles(line) - angle) % (2 * np.pi)
        np.testing.assert_allclose(np.minimum(change, 2 * np.pi - change), 0.0, atol=1e-9)


def test_shape_context_mean_cost_is_the_mean_chi2_of_the_matched_pairs():
    from centrality_vision.matching._shape_context import DUMMY_COST, shape_context, shape_context_assignment

    moving = FIXED + np.random.default_rng(3).normal(scale=0.02, size=FIXED.shape)
    correspondence, info = shape_context_assignment(moving, FIXED)
    a, b = shape_context(moving), shape_context(FIXED)
    costs = []
    for i in np.flatnonzero(correspondence >= 0):
        h, g = a[i].ravel(), b[correspondence[i]].ravel()
        both = h + g > 0
        costs.append(0.5 * np.sum((h[both] - g[both]) ** 2 / (h[both] + g[both])))
    assert info["mean_cost"] == pytest.approx(np.mean(costs), rel=1e-12)
    assert 0 < info["mean_cost"] <= 2 * DUMMY_COST  # (a dearer pair goes to two dummies)
    assert shape_context_assignment(FIXED, FIXED)[1]["mean_cost"] == 0.0

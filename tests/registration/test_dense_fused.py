"""The dense E-step kernel (rows grouped by four) against a plain numpy reference, and its
float32 option against float64 within the bound stated in ``_estep.PRECISIONS``."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from centrality_vision.exceptions import InputError
from centrality_vision.registration import GPD, AffineCPD, NonRigidCPD, RigidCPD
from centrality_vision.registration._estep import (
    CentralityPrior,
    _dense,
    _e_step,
    fixed_to_moving,
    log_outlier_constant,
)


def _reference(moving_t, fixed, sigma2, w, prior=None):
    """Every statistic from the full (M, N) matrix, each row shifted by its maximum and the
    exponent clamped at -700 as the kernel does; ``best`` by ``argmax`` (its first maximum)."""
    n_moving, n_dims = moving_t.shape
    n_fixed = fixed.shape[0]
    d2 = np.sum((fixed[None, :, :] - moving_t[:, None, :]) ** 2, axis=2)
    s = -d2 * (1.0 / (2.0 * sigma2))
    if prior is not None:
        s = s + prior.matrix()
    log_c = log_outlier_constant(sigma2, w, n_dims, n_moving, n_fixed)
    smax = s.max(axis=0)
    r = np.maximum(smax, log_c)
    e = np.exp(np.maximum(s - r, -700.0))
    den = e.sum(axis=0) + np.exp(log_c - r)
    p = e / den
    best = np.where(smax >= log_c, np.argmax(s, axis=0), -1)
    log_den = r + np.log(den)
    return p.sum(axis=1), p @ fixed, p.sum(axis=0), log_den, best


def _cases():
    rng = np.random.default_rng(7)
    for n_dims in (2, 3, 5):
        for n_moving, n_fixed in ((1, 1), (5, 3), (37, 53), (130, 97)):
            for sigma2 in (1.0, 1e-2, 1e-5, 1e-12):
                for w in (0.0, 0.2):
                    yield rng.random((n_moving, n_dims)), rng.random((n_fixed, n_dims)), sigma2, w


@pytest.mark.parametrize("single", [False, True])
def test_dense_matches_reference(single):
    """float64: every statistic to 1e-13 relative (of each array's largest entry) and the same
    ``best``; float32: within its stated bound."""
    for moving_t, fixed, sigma2, w in _cases():
        log_c = log_outlier_constant(sigma2, w, fixed.shape[1], moving_t.shape[0], fixed.shape[0])
        got = _dense(moving_t, fixed, 1.0 / (2.0 * sigma2), log_c, None, single)
        want = _reference(moving_t, fixed, sigma2, w)
        _check(got, want, fixed, single)


def _check(got, want, fixed, single):
    p1, px, pt1, log_den, best = got
    r_p1, r_px, r_pt1, r_log_den, r_best = want
    n_moving, n_fixed = p1.size, pt1.size
    if not single:
        for a, b in ((p1, r_p1), (px, r_px), (pt1, r_pt1), (log_den, r_log_den)):
            scale = max(float(np.max(np.abs(b))), 1e-300)
            assert np.max(np.abs(a - b)) <= 1e-13 * scale + 1e-290
        np.testing.assert_array_equal(best, r_best)
        return
    tiny = 3.4e-38 * (n_moving + 1) * n_fixed
    assert np.all(np.abs(p1 - r_p1) <= 1.1e-5 * r_p1 + tiny)
    assert np.all(np.abs(pt1 - r_pt1) <= 1.1e-5 * r_pt1 + tiny)
    # P X against P |X| (the reference's p @ |fixed| from p1 and px is not at hand: bound it by max |X|)
    assert np.all(np.abs(px - r_px) <= 1.1e-5 * r_p1[:, None] * np.max(np.abs(fixed)) + tiny * np.max(np.abs(fixed)))
    # log den = r + log(sum): the bound is on the log of the sum, plus the rounding of adding r
    assert np.all(np.abs(log_den - r_log_den) <= 5.5e-6 + 1.7e-38 * n_moving + 4e-16 * np.abs(r_log_den))
    np.testing.assert_array_equal(best, r_best)  # the scores and their maxima stay in float64


@pytest.mark.parametrize("single", [False, True])
def test_far_apart_sets_every_term_below_the_outlier_constant(single):
    """Sets 100 apart at sigma2 = 1e-3: every score is ~1e7 below log c. Each row is shifted by
    log c, its terms are all clamped (exp(-700) in float64, exp(-87) in float32), the outlier
    term takes the whole row (Pt1 ~ 0, log den = log c) and ``best`` is -1 everywhere."""
    rng = np.random.default_rng(3)
    moving_t = rng.random((70, 2))
    fixed = rng.random((40, 2)) + 100.0
    sigma2, w = 1e-3, 0.1
    log_c = log_outlier_constant(sigma2, w, 2, 70, 40)
    p1, px, pt1, log_den, best = _dense(moving_t, fixed, 1.0 / (2.0 * sigma2), log_c, None, single)
    floor = math.exp(-87.0) if single else math.exp(-700.0)
    np.testing.assert_allclose(pt1, 70 * floor / (1 + 70 * floor), rtol=1e-6)
    np.testing.assert_allclose(p1, 40 * floor, rtol=1e-6)
    np.testing.assert_allclose(log_den, log_c + math.log1p(70 * floor), rtol=1e-15)
    assert np.all(best == -1)
    assert np.all(np.isfinite(px))


def test_duplicates_and_ties_take_the_first_maximum():
    """Duplicated moving points tie exactly: ``best`` is the first of them, in both precisions;
    a fixed point on a moving point's duplicate pair and midway between two points too."""
    moving_t = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])
    fixed = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.0], [5.0, 5.0], [5.0, 5.0]])
    for single in (False, True):
        out = _dense(moving_t, fixed, 1.0 / (2.0 * 0.01), -math.inf, None, single)
        assert out[4].tolist() == [0, 1, 0, 4, 4]
        # ties share the posterior equally
        assert out[0][0] == pytest.approx(out[0][2], rel=1e-12)
        assert out[0][1] == pytest.approx(out[0][3], rel=1e-12)
    big = np.random.default_rng(0).random((300, 2))
    moving_big = np.vstack([big, big])  # 600 points, each twice: the first copy wins
    got = _dense(moving_big, big, 1.0 / (2.0 * 1e-6), -math.inf, None, False)
    np.testing.assert_array_equal(got[4], np.arange(300))


def test_prior_matches_reference():
    """GPD's centrality prior: the same kernel, scores plus prior before the maximum."""
    rng = np.random.default_rng(5)
    for n_dims in (2, 3):
        moving_t, fixed = rng.random((61, n_dims)), rng.random((45, n_dims))
        prior = CentralityPrior(np.log(rng.random(61) + 0.1), rng.random(61), rng.random(45), 3.0, 0.7)
        for sigma2 in (1.0, 1e-3):
            log_c = log_outlier_constant(sigma2, 0.1, n_dims, 61, 45)
            for single in (False, True):
                got = _dense(moving_t, fixed, 1.0 / (2.0 * sigma2), log_c, prior, single)
                _check(got, _reference(moving_t, fixed, sigma2, 0.1, prior), fixed, single)


@pytest.mark.parametrize("sizes", [(1100, 1000), (800, 700)])
def test_threads_do_not_change_the_result(sizes):
    """Above 2^20 pairs the rows are split over the pool, from 2^19 in two halves (one on
    the calling thread); the chunks do not depend on the thread count."""
    from centrality_vision._parallel import get_num_threads, set_num_threads

    rng = np.random.default_rng(11)
    moving_t, fixed = rng.random((sizes[0], 2)), rng.random((sizes[1], 2))
    before = get_num_threads()
    try:
        set_num_threads(1)
        one = _e_step(moving_t, fixed, 0.01, 0.1, method="dense", precision="float32")
        set_num_threads(2)
        two = _e_step(moving_t, fixed, 0.01, 0.1, method="dense", precision="float32")
        set_num_threads(3)
        three = _e_step(moving_t, fixed, 0.01, 0.1, method="dense", precision="float32")
    finally:
        set_num_threads(before)
    reference = _reference(moving_t, fixed, 0.01, 0.1, None)
    np.testing.assert_allclose(two.p1, reference[0], rtol=2e-5, atol=1e-30)
    for other in (two, three):
        np.testing.assert_array_equal(one.p1, other.p1)
        np.testing.assert_array_equal(one.px, other.px)
        assert one.neg_log_likelihood == other.neg_log_likelihood


def test_a_busy_pool_does_not_hold_up_the_e_step():
    """With every pool thread busy elsewhere, the calling thread runs both halves and
    returns at once, with the same statistics."""
    import threading
    import time

    from centrality_vision._parallel import _pool, get_num_threads, set_num_threads

    rng = np.random.default_rng(12)
    moving_t, fixed = rng.random((800, 2)), rng.random((700, 2))
    before = get_num_threads()
    release = threading.Event()
    try:
        set_num_threads(1)
        one = _e_step(moving_t, fixed, 0.01, 0.1, method="dense")
        set_num_threads(2)
        blockers = [_pool(2).submit(release.wait, 30.0) for _ in range(2)]
        start = time.perf_counter()
        busy = _e_step(moving_t, fixed, 0.01, 0.1, method="dense")
        elapsed = time.perf_counter() - start
    finally:
        release.set()
        set_num_threads(before)
    assert all(b.result() for b in blockers)
    assert elapsed < 10.0
    np.testing.assert_array_equal(one.p1, busy.p1)
    np.testing.assert_array_equal(one.px, busy.px)


def test_float32_registration_matches_float64():
    """A whole fit in float32 ends where float64 does (rigid and non-rigid)."""
    rng = np.random.default_rng(2)
    y = rng.random((150, 2))
    angle = 0.4
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    x = y @ rot.T + 0.2 + 0.005 * rng.standard_normal(y.shape)
    for make in (lambda p: RigidCPD(tol=1e-8, precision=p), lambda p: NonRigidCPD(tol=1e-6, precision=p)):
        a, b = make("float64").fit(y, x), make("float32").fit(y, x)
        assert np.max(np.abs(a.moving_transformed_ - b.moving_transformed_)) < 1e-4
        assert abs(a.n_iter_ - b.n_iter_) <= 2
        assert a.history_["method"][0] == "dense"


@pytest.mark.parametrize("bad", ["float16", "double", None, 32, np.float32])
def test_bad_precision_is_refused(bad):
    y = np.random.default_rng(0).random((10, 2))
    for estimator in (RigidCPD(precision=bad), AffineCPD(precision=bad), NonRigidCPD(precision=bad)):
        with pytest.raises(InputError, match="precision"):
            estimator.fit(y, y)
    with pytest.raises(InputError, match="precision"):
        GPD(RigidCPD(precision=bad)).fit(y, y)
    with pytest.raises(InputError, match="precision"):
        _e_step(y, y, 1.0, 0.0, precision=bad)


def test_precision_is_an_estimator_parameter():
    reg = NonRigidCPD(precision="float32")
    assert reg.get_params()["precision"] == "float32"
    assert RigidCPD().get_params()["precision"] == "float64"


def test_float32_exponential_is_within_its_bound():
    """``fast_exp_single`` on float32 inputs in [-87, 0]: relative error below 2e-7."""
    from numba import njit

    from centrality_vision.registration._kernels import fast_exp_single

    @njit
    def apply(values, out):
        for i in range(values.shape[0]):
            out[i] = fast_exp_single(values[i])

    t = np.linspace(-87.0, 0.0, 200_001).astype(np.float32)
    out = np.empty_like(t)
    apply(t, out)
    rel = np.abs(out.astype(float) / np.exp(t.astype(float)) - 1.0)
    assert rel.max() < 2e-7
    assert out[-1] == 1.0


def _band_cases():
    rng = np.random.default_rng(17)
    for n_dims in (2, 3):
        # (from ~1,200 moving points a narrow band restricts each row's scores too)
        for n_moving, n_fixed in ((300, 260), (700, 513), (2500, 200)):
            for sigma2 in (1e-2, 1e-4, 1e-8):
                for w in (0.0, 0.2):
                    fixed = rng.random((n_fixed, n_dims))
                    fixed[:5] += 3.0  # a few rows far outside the moving set
                    # rows far off across the band's axis: their nearest-point scan gives up
                    fixed[5:9, 1:] += 40.0
                    yield rng.random((n_moving, n_dims)) * [2.0, 1.0, 0.5][:n_dims], fixed, sigma2, w


@pytest.mark.parametrize("single", [False, True])
def test_band_of_exponentials_matches_every_term(single):
    """From 256 moving points with ``tau``, each row takes its exponentials over a band of the
    moving points sorted along their widest axis. Against the same kernel with every term:
    each posterior entry left out is below exp(-tau) of the row's reference term, so P1
    differs by at most N exp(-tau), P^T 1 and log den by M exp(-tau), P X by N exp(-tau)
    max |X| (plus rounding), and ``best`` is the same."""
    from centrality_vision.registration._estep import _band_axis, _default_tau

    banded = 0
    for moving_t, fixed, sigma2, w in _band_cases():
        n_moving, n_fixed = moving_t.shape[0], fixed.shape[0]
        tau = _default_tau(n_moving)
        inv2s2 = 1.0 / (2.0 * sigma2)
        banded += _band_axis(np.ptp(moving_t, axis=0), n_moving, inv2s2, tau) is not None
        log_c = log_outlier_constant(sigma2, w, fixed.shape[1], n_moving, n_fixed)
        p1, px, pt1, log_den, best = _dense(moving_t, fixed, inv2s2, log_c, None, single, tau)
        r_p1, r_px, r_pt1, r_log_den, r_best = _dense(moving_t, fixed, inv2s2, log_c, None, single)
        left_out = math.exp(-tau)
        rounding = 1e-13 if not single else 1e-6
        assert np.all(np.abs(p1 - r_p1) <= n_fixed * left_out + rounding * r_p1)
        assert np.all(np.abs(pt1 - r_pt1) <= n_moving * left_out + rounding * r_pt1)
        assert np.all(np.abs(log_den - r_log_den) <= n_moving * left_out + 1e-15 * (1.0 + np.abs(r_log_den)))
        bound = (n_fixed * left_out + rounding * r_p1) * np.max(np.abs(fixed))
        assert np.all(np.abs(px - r_px) <= bound[:, None] + 1e-300)
        np.testing.assert_array_equal(best, r_best)
    assert banded >= 12  # the small sigma2 of every size and dimension


def test_band_keeps_ties_to_the_first_point_and_threads_do_not_change_it():
    from centrality_vision._parallel import get_num_threads, set_num_threads

    for n in (400, 1300):  # 2,600 moving points: each row's scores over its band's run only
        big = np.random.default_rng(1).random((n, 2)) * [3.0, 1.0]
        moving_big = np.vstack([big, big])  # each point twice: the first copy wins, as without the band
        got = _dense(moving_big, big, 1.0 / (2.0 * 1e-6), -math.inf, None, False, 40.0)
        np.testing.assert_array_equal(got[4], np.arange(n))
    rng = np.random.default_rng(12)
    moving_t, fixed = rng.random((1100, 2)) * [4.0, 1.0], rng.random((1000, 2)) * [4.0, 1.0]
    before = get_num_threads()
    try:
        runs = []
        for threads in (1, 2, 3):
            set_num_threads(threads)
            runs.append(_e_step(moving_t, fixed, 1e-4, 0.1, method="dense"))
    finally:
        set_num_threads(before)
    for other in runs[1:]:
        np.testing.assert_array_equal(runs[0].p1, other.p1)
        np.testing.assert_array_equal(runs[0].px, other.px)
        np.testing.assert_array_equal(runs[0].best, other.best)
    reference = _reference(moving_t, fixed, 1e-4, 0.1)
    np.testing.assert_allclose(runs[0].p1, reference[0], rtol=1e-10, atol=1e-12 * reference[0].max())
    np.testing.assert_array_equal(runs[0].best, reference[4])


def test_fixed_to_moving_equals_the_e_step_best():
    """The E-steps of a fit skip ``best`` (``want_best=False``: None, every other statistic
    bit for bit the same) and :func:`fixed_to_moving` computes it for one state: the same as
    the dense E-step's, with and without the band, a prior, outliers and exact ties."""
    rng = np.random.default_rng(21)
    for n_dims in (2, 3, 4):
        base = rng.random((300, n_dims)) * np.r_[3.0, np.ones(n_dims - 1)]  # a band from 256
        moving_t = np.vstack([base, base[:40]])  # 40 exact ties: the first copy wins
        fixed = np.vstack([base[::2] + 1e-3 * rng.normal(size=base[::2].shape), rng.random((30, n_dims)) * 9])
        m = moving_t.shape[0]
        prior = CentralityPrior(np.log(rng.random(m) + 0.1), rng.random(m), rng.random(fixed.shape[0]), 2.0, 0.5)
        for sigma2 in (1.0, 1e-3, 1e-6):
            for w in (0.0, 0.3):
                for pri in (None, prior):
                    full = _e_step(moving_t, fixed, sigma2, w, pri, method="dense")
                    lean = _e_step(moving_t, fixed, sigma2, w, pri, method="dense", want_best=False)
                    assert lean.best is None
                    for name in ("p1", "pt1", "px"):
                        np.testing.assert_array_equal(getattr(lean, name), getattr(full, name))
                    assert lean.neg_log_likelihood == full.neg_log_likelihood
                    got = fixed_to_moving(moving_t, fixed, sigma2, w, pri)
                    np.testing.assert_array_equal(got, full.best)
                    reference = _reference(moving_t, fixed, sigma2, w, pri)[4]
                    np.testing.assert_array_equal(got, reference)


def test_fit_reports_the_last_e_step_best():
    """A fit's ``fixed_to_moving_`` (computed once at the end) is the dense E-step's ``best``
    at the fitted state, and ``posteriors_.best`` holds it too."""
    rng = np.random.default_rng(3)
    moving = rng.random((400, 2))
    fixed = (moving @ np.array([[0.9, -0.3], [0.3, 0.9]]))[rng.permutation(400)] + 0.005 * rng.normal(size=(400, 2))
    for est in (RigidCPD(method="dense", w=0.1), NonRigidCPD(method="dense", max_iter=300)):
        est.fit(moving, fixed)
        moving_t, fixed_n, sigma2, w, prior, _ = est._posterior_state
        want = _e_step(moving_t, fixed_n, sigma2, w, prior, method="dense").best
        np.testing.assert_array_equal(est.fixed_to_moving_, want)
        np.testing.assert_array_equal(est.posteriors_.best, want)
        assert (want >= 0).mean() > 0.9


def test_memo_of_sorted_fixed_points_changes_nothing():
    """A fit's memo (the dense path's fixed points sorted per band axis) gives bit-identical
    statistics, follows the band's axis when the moving set turns, and starts afresh for
    another fixed array."""
    rng = np.random.default_rng(8)
    fixed = rng.random((500, 2)) * [4.0, 1.0]
    other = rng.random((450, 2)) * [1.0, 4.0]
    memo = {}
    for fx in (fixed, other, fixed):
        for moving_t in (rng.random((600, 2)) * [4.0, 1.0], rng.random((600, 2)) * [1.0, 4.0]):
            for sigma2 in (1e-2, 1e-4):
                plain = _e_step(moving_t, fx, sigma2, 0.1, method="dense")
                kept = _e_step(moving_t, fx, sigma2, 0.1, method="dense", memo=memo)
                assert memo["fixed"] is fx
                for name in ("p1", "pt1", "px", "best"):
                    np.testing.assert_array_equal(getattr(kept, name), getattr(plain, name))
    assert set(memo["rows"]) == {0, 1}  # both axes were banded for the last fixed array


@settings(max_examples=60, deadline=None)
@given(
    values=st.lists(st.integers(-3, 3).map(float), min_size=1, max_size=60),
    seed=st.integers(0, 2**32 - 1),
    budget=st.integers(0, 400),
)
def test_refined_order_is_the_stable_argsort(values, seed, budget):
    """Insertion from any starting permutation ends at the stable argsort (ties by index),
    or reports that it ran out of moves."""
    from centrality_vision.registration import _kernels as K

    values = np.asarray(values)
    order = np.random.default_rng(seed).permutation(values.size)
    if K.refine_order(values, order, budget):
        np.testing.assert_array_equal(order, np.argsort(values, kind="stable"))
    else:
        assert sorted(order.tolist()) == list(range(values.size))  # still a permutation


def test_moving_order_from_the_memo_equals_a_fresh_sort():
    from centrality_vision.registration._estep import _moving_order

    rng = np.random.default_rng(2)
    memo = {}
    points = rng.random(800)
    for step in range(6):
        points = points + rng.normal(0.0, 10.0 ** -(step % 3 + 1), points.size)  # small and large moves
        points[:50] = points[50:100]  # exact ties
        got = _moving_order(points, 0, memo)
        np.testing.assert_array_equal(got, np.argsort(points, kind="stable"))


def _structured_set(kind, n, n_dims, rng):
    if kind == "uniform":
        return rng.random((n, n_dims)) * np.r_[3.0, np.ones(n_dims - 1)]
    if kind == "clumps":  # a few tight clusters: many points share a band
        centres = rng.random((5, n_dims)) * 3.0
        return centres[rng.integers(0, 5, n)] + 1e-3 * rng.normal(size=(n, n_dims))
    if kind == "line":  # every point on one line across the band's axis
        t = rng.random(n)
        return np.column_stack([3.0 * t, *(0.5 * t for _ in range(n_dims - 1))])
    base = rng.random((n // 4, n_dims)) * 3.0  # duplicates: each point four times
    return np.repeat(base, 4, axis=0)[rng.permutation(4 * (n // 4))]


@settings(max_examples=25, deadline=None)
@given(
    kind=st.sampled_from(["uniform", "clumps", "line", "duplicates"]),
    n_dims=st.sampled_from([2, 3]),
    log_sigma2=st.integers(-10, -1),
    w=st.sampled_from([0.0, 0.3]),
    seed=st.integers(0, 2**32 - 1),
)
def test_band_matches_every_pair_on_structured_sets(kind, n_dims, log_sigma2, w, seed):
    """The band (exponentials, and from ~1,200 moving points the scores too) against every
    pair on clustered, collinear and duplicated sets: within the stated bound, same ``best``."""
    from centrality_vision.registration._estep import _default_tau

    rng = np.random.default_rng(seed)
    moving_t = _structured_set(kind, 1600, n_dims, rng)
    fixed = moving_t[rng.permutation(moving_t.shape[0])[:300]] + 1e-3 * rng.normal(size=(300, n_dims))
    fixed[:3] += 7.0  # far rows: their nearest-point scan gives up
    sigma2 = 10.0**log_sigma2
    tau = _default_tau(moving_t.shape[0])
    inv2s2 = 1.0 / (2.0 * sigma2)
    log_c = log_outlier_constant(sigma2, w, n_dims, moving_t.shape[0], fixed.shape[0])
    p1, px, pt1, log_den, best = _dense(moving_t, fixed, inv2s2, log_c, None, False, tau)
    r_p1, r_px, r_pt1, r_log_den, r_best = _dense(moving_t, fixed, inv2s2, log_c, None, False)
    left_out = math.exp(-tau)
    assert np.all(np.abs(p1 - r_p1) <= fixed.shape[0] * left_out + 1e-13 * r_p1)
    assert np.all(np.abs(pt1 - r_pt1) <= moving_t.shape[0] * left_out + 1e-13 * r_pt1)
    assert np.all(np.abs(log_den - r_log_den) <= moving_t.shape[0] * left_out + 1e-15 * (1.0 + np.abs(r_log_den)))
    bound = (fixed.shape[0] * left_out + 1e-13 * r_p1) * np.max(np.abs(fixed))
    assert np.all(np.abs(px - r_px) <= bound[:, None] + 1e-300)
    np.testing.assert_array_equal(best, r_best)


def test_fixed_to_moving_by_nearest_points_on_large_sets():
    """From 2^20 pairs without a prior the most probable moving point comes from a
    nearest-point search: the dense E-step's own choice, with outliers at -1."""
    rng = np.random.default_rng(14)
    moving_t = rng.random((1100, 2)) * [3.0, 1.0]
    fixed = np.vstack(
        [moving_t[rng.permutation(1100)[:1000]] + 1e-3 * rng.normal(size=(1000, 2)), rng.random((20, 2)) + 9]
    )
    for sigma2, w in ((1e-2, 0.0), (1e-4, 0.2), (1e-6, 0.5)):
        got = fixed_to_moving(moving_t, fixed, sigma2, w)
        np.testing.assert_array_equal(got, _e_step(moving_t, fixed, sigma2, w, method="dense").best)
    assert np.all(fixed_to_moving(moving_t, fixed, 1e-6, 0.5)[-20:] == -1)

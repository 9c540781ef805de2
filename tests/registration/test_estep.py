"""The shared E-step: both paths against the dense posterior, log-space robustness."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from centrality_vision.registration._estep import (
    CentralityPrior,
    _e_step,
    dense_posterior,
    gauss_transform,
    log_outlier_constant,
)


def _brute(moving, fixed, sigma2, w, prior=None):
    """Posterior straight from the formula of SPEC section 3, in plain float64."""
    m, d = moving.shape
    n = fixed.shape[0]
    d2 = ((moving[:, None, :] - fixed[None, :, :]) ** 2).sum(-1)
    k = np.exp(-d2 / (2 * sigma2))
    if prior is not None:
        k = k * np.exp(prior.matrix())
    c = (2 * np.pi * sigma2) ** (d / 2) * w / (1 - w) * m / n
    den = k.sum(0) + c
    nll = -np.log(den).sum() + n * d / 2 * np.log(sigma2)
    return k / den, nll


def _prior(rng, m, n, scale=1.0):
    return CentralityPrior(np.log(rng.uniform(0.1, 1, m)), rng.random(m), rng.random(n), 2.5, scale)


@pytest.mark.parametrize("method", ["dense", "truncated"])
@pytest.mark.parametrize(
    ("m", "n", "d", "w", "sigma2"),
    [(30, 40, 2, 0.0, 0.3), (50, 35, 3, 0.2, 0.05), (80, 60, 2, 0.5, 0.002), (1, 1, 2, 0.0, 1.0), (1, 7, 3, 0.1, 0.5)],
)
@pytest.mark.parametrize("with_prior", [False, True])
def test_statistics_equal_brute_force(method, m, n, d, w, sigma2, with_prior):
    rng = np.random.default_rng(m * 100 + n)
    moving, fixed = rng.random((m, d)), rng.random((n, d))
    prior = _prior(rng, m, n) if with_prior else None
    p, nll = _brute(moving, fixed, sigma2, w, prior)
    post = _e_step(moving, fixed, sigma2, w, prior, method=method)
    assert post.method == method
    np.testing.assert_allclose(post.p1, p.sum(1), atol=1e-13)
    np.testing.assert_allclose(post.pt1, p.sum(0), atol=1e-13)
    np.testing.assert_allclose(post.px, p @ fixed, atol=1e-13)
    assert post.n_p == pytest.approx(p.sum(), abs=1e-12)
    assert post.neg_log_likelihood == pytest.approx(nll, rel=1e-12, abs=1e-10)
    np.testing.assert_allclose(dense_posterior(moving, fixed, sigma2, w, prior), p, atol=1e-14)
    # best: the argmax of each column, -1 where the outlier term c beats every moving point
    expect = p.argmax(0)
    expect[(1 - p.sum(0)) > p.max(0)] = -1  # the outlier term c / den beats every moving point
    np.testing.assert_array_equal(post.best, expect)


def test_log_outlier_constant_is_log_of_c():
    c = (2 * np.pi * 0.3) ** 1.5 * 0.2 / 0.8 * 40 / 50
    assert log_outlier_constant(0.3, 0.2, 3, 40, 50) == pytest.approx(np.log(c), rel=1e-14)
    assert log_outlier_constant(0.3, 0.0, 3, 40, 50) == -np.inf


def test_columns_sum_to_one_without_outliers():
    rng = np.random.default_rng(1)
    post = _e_step(rng.random((20, 2)), rng.random((25, 2)), 0.1, 0.0)
    np.testing.assert_allclose(post.pt1, 1.0, atol=1e-14)
    assert post.n_p == pytest.approx(25)


@pytest.mark.parametrize("method", ["dense", "truncated"])
def test_tiny_sigma2_gives_hard_assignments_not_nan(method):
    rng = np.random.default_rng(2)
    moving, fixed = rng.random((15, 2)), rng.random((12, 2))
    post = _e_step(moving, fixed, 1e-200, 0.0, method=method)
    nearest = ((moving[:, None] - fixed[None]) ** 2).sum(-1).argmin(0)
    assert np.all(np.isfinite(post.p1)) and np.isfinite(post.neg_log_likelihood)
    np.testing.assert_array_equal(post.best, nearest)
    np.testing.assert_allclose(post.px, np.array([fixed[nearest == j].sum(0) for j in range(15)]), atol=1e-12)
    np.testing.assert_allclose(post.p1, np.bincount(nearest, minlength=15), atol=1e-12)
    # with an outlier weight, a tiny sigma2 makes every fixed point an outlier: P -> 0, still finite
    post = _e_step(moving, fixed, 1e-200, 0.3, method=method)
    assert np.all(post.p1 < 1e-290) and np.all(post.best == -1) and np.isfinite(post.neg_log_likelihood)


def test_huge_sigma2_gives_uniform_posterior():
    rng = np.random.default_rng(3)
    post = _e_step(rng.random((10, 3)), rng.random((8, 3)), 1e12, 0.0)
    np.testing.assert_allclose(post.p1, 8 / 10, rtol=1e-9)


def test_truncated_path_matches_dense_on_a_large_set():
    rng = np.random.default_rng(4)
    moving, fixed = rng.random((3000, 2)), rng.random((2500, 2)) * 1.1
    prior = _prior(rng, 3000, 2500)
    for sigma2, w in ((1e-4, 0.0), (1e-3, 0.1), (0.05, 0.2)):
        dense = _e_step(moving, fixed, sigma2, w, prior, method="dense")
        trunc = _e_step(moving, fixed, sigma2, w, prior, method="truncated")
        for name in ("p1", "pt1", "px"):
            np.testing.assert_allclose(getattr(trunc, name), getattr(dense, name), atol=1e-12)
        assert trunc.neg_log_likelihood == pytest.approx(dense.neg_log_likelihood, rel=1e-13)
        np.testing.assert_array_equal(trunc.best, dense.best)


def test_auto_picks_truncated_only_when_it_visits_few_pairs():
    """The cost model (no planner): at a small sigma2 the truncated path beats every pair,
    not the dense path's band (2,500 points: dense 2.0 ms against truncated 3.9 at 1e-5
    without a prior; with a prior, which turns the band off, 5.7 against 4.4)."""
    rng = np.random.default_rng(5)
    moving, fixed = rng.random((2500, 2)), rng.random((2500, 2))
    prior = _prior(rng, 2500, 2500)
    assert _e_step(moving, fixed, 1e-5, 0.0, prior, method="auto").method == "truncated"
    assert _e_step(moving, fixed, 1e-5, 0.0, method="auto").method == "dense"  # its band
    assert _e_step(moving, fixed, 1.0, 0.0, method="auto").method in ("dense", "fgt")
    assert _e_step(moving, fixed, 1.0, 0.0, prior, method="auto").method == "dense"  # no FGT with a prior
    assert _e_step(moving[:100], fixed[:100], 1e-5, 0.0, method="auto").method == "dense"


def test_far_fixed_points_keep_their_nearest_moving_point():
    # a fixed point far from every moving point must still be explained (w = 0): the
    # truncation radius is relative to each point's nearest neighbour, not absolute
    moving = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    fixed = np.array([[0.1, 0.0], [100.0, 0.0]])
    post = _e_step(moving, fixed, 1e-3, 0.0, method="truncated")
    np.testing.assert_allclose(post.pt1, 1.0)
    assert post.best.tolist() == [0, 1]


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_gauss_transform_matches_the_direct_sum(dim):
    rng = np.random.default_rng(dim)
    src, tgt = rng.normal(size=(400, dim)), rng.normal(size=(300, dim)) * 1.5
    q = rng.random((400, 2))
    for h in (0.3, 1.0, 5.0):
        direct = np.exp(-((tgt[:, None] - src[None]) ** 2).sum(-1) / h**2) @ q
        fast = gauss_transform(src, q, tgt, h, eps=1e-10)
        assert np.abs(fast - direct).max() <= 1e-10 * q.sum(0).max()


def test_fgt_e_step_matches_dense():
    rng = np.random.default_rng(6)
    moving, fixed = rng.normal(size=(3000, 2)), rng.normal(size=(2800, 2)) * 1.1 + 0.2
    fixed[:3] += 40.0  # far points: their rows are redone exactly
    for sigma2, w in ((2.0, 0.0), (0.2, 0.1), (0.02, 0.3)):
        dense = _e_step(moving, fixed, sigma2, w, method="dense")
        fgt = _e_step(moving, fixed, sigma2, w, method="fgt", eps=1e-10)
        for name in ("p1", "pt1", "px"):
            ref = getattr(dense, name)
            assert np.abs(getattr(fgt, name) - ref).max() <= 1e-8 * np.abs(ref).max()
        assert fgt.neg_log_likelihood == pytest.approx(dense.neg_log_likelihood, rel=1e-10)
        np.testing.assert_array_equal(fgt.best, dense.best)


def test_fgt_refuses_a_prior():
    rng = np.random.default_rng(7)
    with pytest.raises(ValueError, match="fgt"):
        _e_step(rng.random((5, 2)), rng.random((5, 2)), 1.0, 0.0, _prior(rng, 5, 5), method="fgt")


def test_fgt_refuses_an_expansion_that_does_not_fit_in_memory():
    rng = np.random.default_rng(8)
    points = rng.random((60_000, 3))
    # one box per point, 24^3 terms each: about 6.6 GiB of coefficients, refused before allocating
    with pytest.raises(MemoryError, match="GiB"):
        gauss_transform(points, np.ones(60_000), points, 1e-4, eps=1e-14)


def test_fast_exp_is_within_its_stated_relative_error():
    from centrality_vision.registration._kernels import exp_array

    rng = np.random.default_rng(9)
    x = np.concatenate([rng.uniform(-700, 0, 200_000), rng.uniform(-1, 1, 100_000), np.arange(-700, 1.0)])
    out = np.empty_like(x)
    exp_array(x, out)
    assert np.max(np.abs(out - np.exp(x)) / np.exp(x)) < 4e-16
    assert out[x == 0].tolist() == [1.0] * int(np.sum(x == 0))  # the row maximum maps to exactly 1
    exp_array(np.array([-800.0, -1e300]), out[:2])  # clamped at -700: normal numbers, never 0 or NaN
    assert np.all(out[:2] == out[:2]) and np.all(out[:2] > 0)


@pytest.mark.parametrize("method", ["dense", "truncated", "fgt"])
def test_statistics_are_bit_identical_for_any_thread_count(method):
    import centrality_vision as cv

    rng = np.random.default_rng(10)
    moving, fixed = rng.random((1500, 2)), rng.random((1700, 2))
    results = []
    try:
        for threads in (1, 2, 3):
            cv.set_num_threads(threads)
            post = _e_step(moving, fixed, 0.003, 0.1, method=method)
            results.append((post.p1, post.px, post.pt1, post.n_p, post.neg_log_likelihood, post.best))
    finally:
        cv.set_num_threads(None)
    for other in results[1:]:
        for a, b in zip(results[0], other):
            assert np.array_equal(a, b)


def test_low_rank_nonrigid_fit_is_identical_for_any_thread_count():
    # issue: 69 iterations on 1 thread, 71 on 2, from partial sums added in a thread-dependent order
    import warnings

    import centrality_vision as cv
    from centrality_vision.exceptions import ConvergenceWarning
    from centrality_vision.registration import NonRigidCPD

    rng = np.random.default_rng(11)
    y = rng.random((520, 2))  # above 500 points: the low-rank kernel
    x = y + 0.05 * np.sin(3 * y[:, ::-1]) + 0.003 * rng.standard_normal(y.shape)
    fits = []
    try:
        for threads in (1, 2):
            cv.set_num_threads(threads)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)  # 40 iterations are enough to compare
                fits.append(NonRigidCPD(beta=0.5, lam=1.0, tol=1e-6, max_iter=40, method="dense").fit(y, x))
    finally:
        cv.set_num_threads(None)
    assert fits[0].n_iter_ == fits[1].n_iter_
    assert np.array_equal(fits[0].moving_transformed_, fits[1].moving_transformed_)


def test_planner_probes_once_per_sigma2_regime_and_matches_dense():
    from centrality_vision.registration._estep import EStepPlanner

    rng = np.random.default_rng(12)
    moving, fixed = rng.random((1200, 2)), rng.random((1000, 2))
    planner = EStepPlanner()
    for sigma2 in (1e-3, 1.1e-3, 0.9e-3):
        post = planner(moving, fixed, sigma2, 0.0)
        dense = _e_step(moving, fixed, sigma2, 0.0, method="dense")
        assert post.method == planner.winner
        for name in ("p1", "pt1", "px"):
            assert np.abs(getattr(post, name) - getattr(dense, name)).max() <= 1e-8 * np.abs(getattr(dense, name)).max()
    assert planner.probes == 1 and planner.winner in planner.timings
    planner(moving, fixed, 1e-5, 0.0)  # sigma2 moved 100x: the ranking may have changed
    assert planner.probes == 2
    small = EStepPlanner()
    assert small(moving[:50], fixed[:50], 1e-3, 0.0).method == "dense" and small.probes == 0


def test_auto_without_a_planner_considers_every_path_at_small_sizes():
    rng = np.random.default_rng(13)
    moving, fixed = rng.random((1100, 2)), rng.random((1100, 2))  # 1.2 million pairs, formerly always dense
    prior = _prior(rng, 1100, 1100)  # (with a prior the dense path scores every pair: no band)
    assert _e_step(moving, fixed, 1e-7, 0.0, prior, method="auto").method == "truncated"
    # without one the band leaves each row a few dozen points, cheaper than the truncated walk
    assert _e_step(moving, fixed, 1e-7, 0.0, method="auto").method == "dense"


def test_far_points_at_tiny_sigma2_do_not_walk_millions_of_empty_cells():
    # 200 fixed points far from every moving point: at sigma2 = 1e-9 their search boxes span
    # ~10^8 empty grid cells; the kernels scan the points instead (it used to hang here).
    rng = np.random.default_rng(0)
    fixed = rng.random((1200, 3))
    moving = fixed[:1000] + 1e-7 * rng.standard_normal((1000, 3))
    fixed[1000:] += 2.0
    for sigma2 in (1e-9, 1e-12):
        dense = _e_step(moving, fixed, sigma2, 0.1, method="dense")
        truncated = _e_step(moving, fixed, sigma2, 0.1, method="truncated")
        automatic = _e_step(moving, fixed, sigma2, 0.1, method="auto")  # its cost model counts candidates
        np.testing.assert_allclose(truncated.p1, dense.p1, rtol=1e-12, atol=1e-300)
        np.testing.assert_allclose(automatic.pt1, dense.pt1, rtol=1e-8, atol=1e-12)
        assert truncated.neg_log_likelihood == pytest.approx(dense.neg_log_likelihood, rel=1e-12)


def test_truncated_path_at_tiny_sigma2_matches_dense_and_sizes_its_cells_by_the_reach():
    # at sigma2 = 1e-12 every row's reach is its nearest distance (~1e-3), not the sigma2
    # term (~1e-5): cells of the latter would make each row walk ~10^5 empty cells
    from centrality_vision.registration._estep import _grid_for, _nearest, _reach_d2, _truncation_extra

    rng = np.random.default_rng(21)
    fixed = rng.random((3000, 2))
    moving = fixed[rng.permutation(3000)] + rng.normal(0, 1e-3, (3000, 2))
    for sigma2 in (1e-6, 1e-12):
        dense = _e_step(moving, fixed, sigma2, 0.0, method="dense")
        trunc = _e_step(moving, fixed, sigma2, 0.0, method="truncated")
        for name in ("p1", "pt1", "px"):
            np.testing.assert_allclose(getattr(trunc, name), getattr(dense, name), atol=1e-12)
        assert trunc.neg_log_likelihood == pytest.approx(dense.neg_log_likelihood, rel=1e-12)
        np.testing.assert_array_equal(trunc.best, dense.best)
    d2 = _reach_d2(_nearest(moving, fixed)[0])
    extra = _truncation_extra(1e-12, 40.0, None)
    assert _grid_for(moving, d2, extra).cell >= np.sqrt(np.median(d2)) / 4 * (1 - 1e-12)
    assert _grid_for(moving, d2, 1.0).cell == pytest.approx(0.25)  # the sigma2 term dominates: its cells


class _Scripted:
    """A fake clock and E-step: each path's calls take the scripted seconds in turn."""

    def __init__(self, durations, setup, work=(100.0, 0.0, 1.0, 0.0)):
        self.work = work  # truncated: candidates per row, median d_min^2, extra, row floor
        self.now = 0.0
        self.durations = {k: list(v) for k, v in durations.items()}
        self.setup = setup
        self.calls = []

    def perf_counter(self):
        return self.now

    def run(self, path, *args):
        self.calls.append(path)
        self.now += self.durations[path].pop(0)
        return path

    def model_costs(self, *args):
        return {"dense": 1.0, "truncated": 1.0}, {"setup": dict(self.setup), "truncated_work": self.work}


def _scripted_planner(monkeypatch, durations, setup, work=(100.0, 0.0, 1.0, 0.0), **kwargs):
    from centrality_vision.registration import _estep
    from centrality_vision.registration._estep import EStepPlanner

    fake = _Scripted(durations, setup, work)
    monkeypatch.setattr(_estep, "time", fake)
    monkeypatch.setattr(_estep, "_run", fake.run)
    monkeypatch.setattr(_estep, "_model_costs", fake.model_costs)
    planner = EStepPlanner(**kwargs)
    big = np.zeros((1100, 2))  # above the 2^20 pairs below which only 'dense' runs
    return planner, planner(big, big, 1e-3, 0.0), fake


def test_planner_retimes_a_close_calls_runner_up_and_keeps_its_least_time(monkeypatch):
    # first timings: dense 10, truncated 12 (a load spike); the runner-up again: truncated 8
    durations = {"dense": [10.0, 10.0], "truncated": [12.0, 8.0]}
    planner, result, fake = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 0.0})
    assert planner.winner == "truncated" and result == "truncated"
    assert planner.timings == {"dense": 10.0, "truncated": 8.0}
    assert sorted(fake.calls) == ["dense", "truncated", "truncated"]
    # without re-timing the spike decides
    planner, result, _ = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 0.0}, retime_factor=1.0)
    assert planner.winner == "dense" and result == "dense"
    # a clear gap is not re-timed
    clear = {"dense": [10.0], "truncated": [30.0]}
    planner, _, fake = _scripted_planner(monkeypatch, clear, {"dense": 0.0, "truncated": 0.0})
    assert planner.winner == "dense" and len(fake.calls) == 2


def test_planner_keeps_its_winner_within_the_switch_factor_and_while_held(monkeypatch):
    # probe at sigma2 = 1e-3: dense 10 s, truncated 16 s (not a close call)
    durations = {"dense": [10.0] * 5, "truncated": [16.0, 7.0]}
    planner, _, fake = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 0.0})
    assert planner.winner == "dense" and planner.probes == 1
    big = np.zeros((1100, 2))
    # at 0.6e-3 truncated is predicted 9.6 s: faster, but not 1.2x faster than dense's 10 s
    assert planner.predicted(0.6e-3, 2)["truncated"] == pytest.approx(9.6)
    planner(big, big, 0.6e-3, 0.0)
    assert planner.probes == 1 and fake.calls[-1] == "dense"
    # a held (speculative) call does not probe and keeps the winner, dense (it leaves the
    # winner only for the dense path predicted 2x faster: see the test below)
    planner.hold = True
    planner(big, big, 0.2e-3, 0.0)
    assert planner.probes == 1 and fake.calls[-1] == "dense"
    planner.hold = False
    planner(big, big, 0.2e-3, 0.0)
    assert planner.probes == 2 and planner.winner == "truncated"


def test_planner_charges_each_path_the_setup_it_pays_outside_a_probe(monkeypatch):
    # truncated runs in 8 s given the probe's nearest points and grid, which took 5 s to build
    durations = {"dense": [10.0, 10.0], "truncated": [8.0, 8.0]}
    planner, _, _ = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 5.0})
    assert planner.winner == "dense"
    assert planner.timings["truncated"] == pytest.approx(13.0)


def test_planner_probes_again_when_another_path_is_predicted_faster(monkeypatch):
    # probe at sigma2 = 1e-3: dense 10 s, truncated 12 s (measured twice, a close call)
    durations = {"dense": [10.0, 10.0, 10.0, 10.0], "truncated": [12.0, 12.0, 3.0, 3.0]}
    planner, _, fake = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 0.0})
    assert planner.winner == "dense" and planner.probes == 1
    big = np.zeros((1100, 2))
    # 2D: the truncated path's work scales as sigma2; at 0.9e-3 it is predicted 10.8 s > 10 s
    assert planner.predicted(0.9e-3, 2)["truncated"] == pytest.approx(10.8)
    planner(big, big, 0.9e-3, 0.0)
    assert planner.probes == 1 and fake.calls[-1] == "dense"
    # at 0.5e-3 it is predicted 6 s < 10 s: probe again (well inside the 10x reprobe_factor)
    planner(big, big, 0.5e-3, 0.0)
    assert planner.probes == 2 and planner.winner == "truncated"


def test_planner_does_not_expect_a_saturated_truncated_path_to_keep_speeding_up(monkeypatch):
    # the rows' reach is their nearest distance (d_min^2 = 1 >> extra = 1e-3) and the fixed
    # cost per row dominates: the truncated path's time hardly depends on sigma2 any more
    from centrality_vision.registration._estep import _COST_TRUNCATED

    durations = {"dense": [10.0, 10.0, 10.0], "truncated": [12.0, 12.0]}
    work = (1.0, 1.0, 1e-3, 100 * _COST_TRUNCATED)
    planner, _, fake = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 0.0}, work)
    assert planner.winner == "dense"
    guess = planner.predicted(1e-3 / 5, 2)
    assert guess["truncated"] == pytest.approx(12.0)  # at least one candidate per row
    planner(np.zeros((1100, 2)), np.zeros((1100, 2)), 1e-3 / 5, 0.0)
    assert planner.probes == 1 and fake.calls[-1] == "dense"


def test_planner_takes_up_an_earlier_probe_when_sigma2_swings_back(monkeypatch):
    durations = {"dense": [10.0, 10.0, 10.0, 10.0], "truncated": [12.0, 12.0, 1.0]}
    planner, _, fake = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 0.0})
    big = np.zeros((1100, 2))
    assert planner.winner == "dense"
    planner(big, big, 1e-6, 0.0)  # 1000x away: a new probe, where the truncated path wins
    assert planner.probes == 2 and planner.winner == "truncated"
    planner(big, big, 1.2e-3, 0.0)  # back near the first probe: its choice, without probing
    assert planner.probes == 2 and planner.reused == 1
    assert planner.winner == "dense" and fake.calls[-1] == "dense"


def test_planner_reuses_a_dense_time_from_a_nearby_larger_sigma2(monkeypatch):
    # first probe at 1e-3: dense 10 s, truncated 16 s (not a close call); dense wins
    durations = {"dense": [10.0, 10.0, 10.0], "truncated": [16.0, 4.0, 30.0, 30.0]}
    planner, _, fake = _scripted_planner(monkeypatch, durations, {"dense": 0.0, "truncated": 0.0})
    assert planner.winner == "dense" and fake.calls == ["dense", "truncated"]
    big = np.zeros((1100, 2))
    # at half the sigma2 the truncated path is predicted 8 s: a probe, in which dense's time
    # at 1e-3 bounds its time (it only falls as sigma2 shrinks): the truncated path runs
    # alone (4 s) and its statistics are returned
    assert planner(big, big, 0.5e-3, 0.0) == "truncated"
    assert planner.probes == 2 and planner.winner == "truncated"
    assert fake.calls == ["dense", "truncated", "truncated"]
    # 200x above: no dense time bounds it there, so dense is timed again, and it wins
    assert planner(big, big, 1e-1, 0.0) == "dense"
    assert planner.probes == 3 and fake.calls[3:] == ["dense", "truncated"]


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    dims=st.integers(1, 4),
    n_moving=st.integers(1, 120),
    n_fixed=st.integers(1, 60),
    layout=st.sampled_from(["uniform", "lattice", "curve", "far", "clump"]),
)
def test_nearest_points_equal_brute_force(seed, dims, n_moving, n_fixed, layout):
    # the grid search (1-3 D) and the k-d tree (4 D, clumped sets) alike: exact squared
    # distances and the smaller index on ties, whatever the layout
    from centrality_vision.registration._estep import _nearest

    rng = np.random.default_rng(seed)
    if layout == "lattice":  # many exact ties and duplicates
        moving = rng.integers(0, 4, (n_moving, dims)).astype(float)
        fixed = rng.integers(-1, 5, (n_fixed, dims)).astype(float)
    elif layout == "curve":  # a thin set: most cells empty
        t = rng.random(n_moving)
        moving = np.column_stack([np.cos(6 * t), *[np.sin(6 * t * (k + 1)) for k in range(dims - 1)]])[:, :dims]
        fixed = moving[rng.integers(0, n_moving, n_fixed)] + rng.normal(0, 0.05, (n_fixed, dims))
    else:
        moving = rng.random((n_moving, dims))
        fixed = rng.random((n_fixed, dims))
        if layout == "far":  # queries far outside the grid
            fixed = fixed * 1e4 - 5e3
        elif layout == "clump":  # all but one point in a tiny clump: a crowded cell
            moving[1:] *= 1e-9
    d2, index = _nearest(moving, fixed)
    brute = ((fixed[:, None, :] - moving[None, :, :]) ** 2).sum(-1)
    np.testing.assert_allclose(d2, brute.min(axis=1), rtol=1e-12, atol=0)
    best = brute[np.arange(n_fixed), index]
    assert np.all(best <= brute.min(axis=1) * (1 + 1e-12))
    # on the grid (1-3 D) ties go to the smaller index (integer coordinates: exact ties)
    if layout == "lattice" and dims <= 3:
        assert np.array_equal(index, np.argmin(brute, axis=1))


def test_nearest_points_of_a_set_spanning_more_than_float64s_range():
    # the extent overflows: the grid gives way to the k-d tree instead of failing
    from centrality_vision.registration._estep import _nearest

    moving = np.array([[-1e308, 0.0], [1e308, 0.0], [0.0, 1.0]])
    d2, index = _nearest(moving, np.array([[1.0, 1.0], [-2.0, 1.0]]))
    np.testing.assert_array_equal(index, [2, 2])
    np.testing.assert_allclose(d2, [1.0, 4.0])


def test_nearest_points_whose_squared_distances_overflow_return_promptly():
    # every squared distance is inf: the ring search used to wait forever for a finite one
    # once its box held the whole grid (found by fuzzing MultiscaleCPD); it now stops there
    import threading

    from centrality_vision.registration._estep import _nearest

    rng = np.random.default_rng(3)
    moving = 1e300 + rng.random((17, 2)) * 1e294
    fixed = 1e8 + rng.random((26, 2))
    out = {}
    worker = threading.Thread(target=lambda: out.update(result=_nearest(moving, fixed)), daemon=True)
    worker.start()
    worker.join(timeout=60)
    assert not worker.is_alive(), "the nearest-point search did not return"
    d2, index = out["result"]
    assert np.all(np.isinf(d2))
    assert np.all((index >= 0) & (index < moving.shape[0]))


def test_planner_predicts_the_dense_band_getting_cheaper_as_sigma2_shrinks():
    """After a probe, the dense path's predicted time follows its band's cost model: it
    falls as sigma2 shrinks (about as sigma2^(1/2) once the band is narrow), and stays put
    where no band applies (a prior)."""
    from centrality_vision.registration._estep import EStepPlanner

    rng = np.random.default_rng(31)
    moving = rng.random((1200, 2)) * [4.0, 1.0]
    fixed = moving + 1e-3 * rng.normal(size=moving.shape)
    for prior, falls in ((None, True), (_prior(rng, 1200, 1200), False)):
        planner = EStepPlanner()
        planner(moving, fixed, 1e-3, 0.0, prior)
        assert "dense" in planner._at_probe
        now = planner.predicted(1e-3, 2)["dense"]
        later = planner.predicted(1e-5, 2)["dense"]
        if falls:  # (the rows' own searches, 180 us of modelled work here, do not shrink)
            assert later < 0.8 * now
            assert later > 0.02 * now  # (not the volume's sigma2^(D/2): a band is one-dimensional)
        else:
            assert later == pytest.approx(now)


def test_planner_probe_starts_from_a_known_dense_time_and_skips_a_path_far_slower(monkeypatch):
    """A dense time the fit already took near this sigma2 (here by a held call that switched
    to the dense path) bounds the probe from its start: a path predicted more than
    ``skip_factor`` times slower is not run, even where the cost model ranks it first."""
    from centrality_vision.registration import _estep
    from centrality_vision.registration._estep import EStepPlanner

    fake = _Scripted({"dense": [10.0, 2.0, 2.0], "truncated": [1.0]}, {"dense": 0.0, "truncated": 0.0})
    fake.model_costs = lambda *args: (
        {"dense": 1.0, "truncated": 0.5},
        {"setup": {"dense": 0.0, "truncated": 0.0}, "truncated_work": fake.work},
    )
    monkeypatch.setattr(_estep, "time", fake)
    monkeypatch.setattr(_estep, "_run", fake.run)
    monkeypatch.setattr(_estep, "_model_costs", fake.model_costs)
    planner = EStepPlanner(skip_factor=2.0)
    big = np.zeros((1100, 2))
    planner(big, big, 1e-3, 0.0)  # truncated (1 s) first, then dense (10 s): truncated wins
    assert planner.winner == "truncated" and fake.calls == ["truncated", "dense"]
    planner._at_probe["dense"] = 1e-9  # pretend dense became far faster: a held call switches
    planner.hold = True
    planner(big, big, 0.9e-3, 0.0)
    assert fake.calls[-1] == "dense"
    planner.hold = False
    planner._calls = planner.reprobe_calls  # due: a probe
    planner._scale["truncated"] = 10.0  # truncated predicted at 0.5 x 10 = 5 s: over twice dense's known 2 s
    planner(big, big, 0.9e-3, 0.0)
    assert "truncated" not in fake.calls[2:] and planner.winner == "dense"

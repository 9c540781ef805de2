"""The rules inside CPD's fit that no end-to-end test pinned (a mutation round, audit 36):
the collapse checks' thresholds, the mixture's dimension, w='auto''s choice between its two
runs, accelerate's bookkeeping and the posteriors mapped back to the caller's units. Each
test fails if its rule is dropped or its constant moved."""

import warnings
from types import SimpleNamespace

import numpy as np
import pytest

from centrality_vision.exceptions import CollapseWarning, ConvergenceWarning
from centrality_vision.graphs._pointsets import _affine_rank
from centrality_vision.registration import AffineCPD, NonRigidCPD, RigidCPD
from centrality_vision.registration._cpd import _model_dims, _w_estimate


def _rotation(degrees):
    a = np.radians(degrees)
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


@pytest.fixture(scope="module")
def centred_fish(fish):
    return fish - fish.mean(axis=0)


def _matched(n_p, m):
    return SimpleNamespace(n_p=float(n_p), p1=np.full(m, n_p / m))


def _radius(points):
    return float(np.sqrt(np.mean(np.sum(points**2, axis=1))))


# --- the collapse checks, just inside and just outside each threshold ---------------------


@pytest.mark.parametrize(("ratio", "collapsed"), [(2.4, False), (2.6, True), (3.4, True)])
def test_gaussians_wider_than_two_and_a_half_radii_are_a_collapse(centred_fish, ratio, collapsed):
    """``sqrt(model_dims sigma2)`` against 2.5 times the transformed set's RMS radius."""
    y = centred_fish
    sigma2 = (ratio * _radius(y)) ** 2 / 2
    said = RigidCPD(w=0.0)._collapse(y, y, y, 0.0, _matched(len(y), len(y)), 2, sigma2)
    assert (said is not None and "times as wide" in said) == collapsed


def test_the_spread_check_counts_the_dimensions_the_sets_span(centred_fish):
    """A 2D problem lifted into 10D: Gaussians 1.5 radii wide in its plane are sound; read with
    all ten dimensions (sqrt(10 sigma2)) they were 3.4 radii, a collapse."""
    lifted = np.c_[centred_fish, np.zeros((len(centred_fish), 8))]
    sigma2 = (1.5 * _radius(lifted)) ** 2 / 2
    assert RigidCPD(w=0.0)._collapse(lifted, lifted, lifted, 0.0, _matched(len(lifted), len(lifted)), 2, sigma2) is None


@pytest.mark.parametrize(("shrink", "collapsed"), [(0.045, True), (0.055, False)])
def test_a_transformed_set_below_a_twentieth_of_the_radius_is_a_collapse(centred_fish, shrink, collapsed):
    y = centred_fish
    said = RigidCPD(w=0.0)._collapse(y, y, shrink * y, 0.0, _matched(len(y), len(y)), 2)
    assert (said is not None and "collapsed (RMS radius" in said) == collapsed


@pytest.mark.parametrize(("share", "collapsed"), [(0.22, True), (0.28, False)])
def test_fewer_than_a_quarter_of_the_expected_matches_is_a_collapse(centred_fish, share, collapsed):
    """With w=0.5, half the smaller set is expected to match."""
    y = centred_fish
    said = RigidCPD(w=0.5)._collapse(y, y, y, 0.5, _matched(share * 0.5 * len(y), len(y)), 2)
    assert (said is not None and "expected with w=0.5" in said) == collapsed


@pytest.mark.parametrize(("share", "collapsed"), [(0.12, True), (0.18, False)])
def test_w_auto_must_match_fifteen_percent_of_the_smaller_set(centred_fish, share, collapsed):
    """w='auto' at 0.8 expects a fifth of the points, a quarter of which (5%) the rule above
    would accept: w='auto' asks for 15%."""
    y = centred_fish
    said = RigidCPD(w="auto")._collapse(y, y, y, 0.8, _matched(share * len(y), len(y)), 2)
    assert (said is not None and "w='auto' estimated 0.8" in said) == collapsed


def test_a_fit_stopped_by_max_iter_is_not_also_called_a_collapse(centred_fish):
    """One iteration of a fish turned 90 degrees ends with Gaussians 2.8 radii wide: that fit
    did not converge (ConvergenceWarning), which says it all; the spread check is for fits
    that converged."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = RigidCPD(w=0.0, scale=True, max_iter=1).fit(centred_fish, centred_fish @ _rotation(90).T)
    assert not fit.converged_
    assert {w.category for w in caught} == {ConvergenceWarning}


# --- the mixture's dimension -----------------------------------------------------------------


def _line(n, length, degrees=0.0):
    return np.outer(np.linspace(-length / 2, length / 2, n), [np.cos(np.radians(degrees)), np.sin(np.radians(degrees))])


def test_two_lines_at_an_angle_span_a_plane_whatever_their_lengths():
    """Each set is scaled to unit radius before their spans are joined: a line 2e-4 long beside
    one 2 long at 60 degrees read as 1D, and a similarity fit took 119 iterations, not 12."""
    assert _model_dims(_line(21, 2e-4), _line(21, 2.0, 60.0)) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (a rotation of a line is not determined by it)
        fit = RigidCPD(scale=True, w=0.0, tol=1e-10).fit(_line(21, 2e-4), _line(21, 2.0, 60.0))
    assert fit.converged_ and fit.n_iter_ < 30


@pytest.mark.parametrize(("thickness", "dims"), [(5e-3, 3), (5e-4, 2)])
def test_a_side_below_a_thousandth_of_the_longest_is_not_spanned(fish, thickness, dims):
    """The fish, 1/200 of its extent thick, is 3D; 1/2000 thick, it is flat."""
    rng = np.random.default_rng(0)
    extent = float(np.ptp(fish, axis=0).max())
    slab = np.c_[fish, rng.uniform(0.0, thickness * extent, len(fish))]
    assert _model_dims(slab, slab) == dims


def test_one_repeated_point_spans_no_direction(fish):
    """Its box has every side 0, which is thin (<=): one point onto a flat 3D set is a 2D mixture."""
    assert _model_dims(np.tile([0.2, 0.1, 0.0], (5, 1)), np.c_[fish, np.zeros(len(fish))]) == 2


def test_a_plane_a_hundredth_of_a_billionth_thick_is_still_3d():
    """The graphs' span: principal extents above 1e-12 of the whole count."""
    rng = np.random.default_rng(0)
    turn = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    plane = np.c_[rng.uniform(-1, 1, (40, 2)), rng.uniform(-1e-11, 1e-11, 40)] @ turn.T
    assert _affine_rank(plane) == 3


def test_rounding_allowance_grows_with_the_square_root_of_the_count():
    """An exactly flat plane 1e4 from the origin, turned: its rounding adds a third extent that
    grows as sqrt(n); with 50,000 points it is still a plane."""
    rng = np.random.default_rng(1)
    turn = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    plane = np.c_[rng.uniform(-1, 1, (50_000, 2)), np.zeros(50_000)] @ turn.T + 1e4
    assert _affine_rank(plane) == 2


# --- w='auto' ----------------------------------------------------------------------------------


def test_w_estimate_is_never_negative():
    """More matched mass than fixed points (rounding) is a weight of 0, not -1e-15."""
    assert _w_estimate(10 + 1e-14, 10) == 0.0
    assert _w_estimate(7.5, 10) == pytest.approx(0.25)


@pytest.mark.parametrize("estimator", [RigidCPD, AffineCPD])
@pytest.mark.parametrize("max_iter", [5, 10])
def test_w_auto_stopped_early_chooses_the_same_run_in_any_units(fish, estimator, max_iter):
    """A held run stopped before EM settles is scored afresh; without the frame's Jacobian its
    score moved with the units, and at 1e3 the other run was kept (w_ 0.012 against 0.275)."""
    fixed = np.vstack([fish @ _rotation(30).T, np.random.default_rng(2).uniform(-1.5, 1.5, (20, 2))])
    fits = []
    for unit in (1e-3, 1.0, 1e3):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            fits.append(estimator(w="auto", max_iter=max_iter).fit(unit * fish, unit * fixed))
    for unit, fit in zip((1e-3, 1.0, 1e3), fits, strict=True):
        assert fit.w_ == pytest.approx(fits[1].w_, rel=1e-6)
        assert fit.sigma2_ / unit**2 == pytest.approx(fits[1].sigma2_, rel=1e-6)


@pytest.mark.parametrize("seed", [2, 3])
def test_w_auto_keeps_the_run_that_did_not_collapse(fish, seed):
    """The fish with 15 far outliers of its own, onto a turned copy missing 40%: the second
    run collapses with the lower objective. Ranked by objective alone, the collapsed run was
    kept (a CollapseWarning, and 20 degrees where the turn is 30)."""
    rng = np.random.default_rng(seed)
    fixed = fish[fish[:, 0] > np.quantile(fish[:, 0], 0.4)] @ _rotation(30).T
    moving = np.vstack([fish, rng.uniform(-4, 4, (15, 2))])
    with warnings.catch_warnings():
        warnings.simplefilter("error", CollapseWarning)
        fit = RigidCPD(w="auto").fit(moving, fixed)
    rotation = fit.transform_.rotation
    assert abs(np.degrees(np.arctan2(rotation[1, 0], rotation[0, 0])) - 30.0) < 1.0


# --- accelerate ---------------------------------------------------------------------------------


def _cluttered(fish):
    return np.vstack([fish @ _rotation(29).T, np.random.default_rng(3).uniform(-1.5, 1.5, (30, 2))])


@pytest.mark.parametrize(
    "estimator",
    [NonRigidCPD(tol=1e-8, max_iter=1000), AffineCPD(w=0.2, tol=1e-10), RigidCPD(w=0.2, scale=True, tol=1e-10)],
    ids=["nonrigid", "affine", "similarity"],
)
def test_an_accelerated_objective_never_rises(fish_pair, estimator):
    """A jump is kept only if the E-step there is no worse than the last plain step's: without
    that guard the non-rigid fish's objective rose by 175 in one step."""
    fixed = fish_pair.fixed if isinstance(estimator, NonRigidCPD) else _cluttered(fish_pair.moving)
    fit = estimator.set_params(accelerate=True).fit(fish_pair.moving, fixed)
    steps = np.diff(fit.history_["objective"])
    assert np.all(steps <= 1e-9 * np.abs(fit.history_["objective"][1:]))


def test_an_accelerated_fit_does_not_end_below_the_variance_floor(fish):
    """A jump's sigma2 is floored as an EM step's is: the jump once ended at 9.8e-15 where EM
    ends at its floor, 1.06e-14."""
    fixed = _cluttered(fish)
    plain = AffineCPD(w=0.2, tol=1e-10, max_iter=500).fit(fish, fixed)
    fast = AffineCPD(w=0.2, tol=1e-10, max_iter=500, accelerate=True).fit(fish, fixed)
    assert plain.sigma2_ < 1e-13  # (both fits reach the floor)
    assert fast.sigma2_ >= plain.sigma2_ * (1 - 1e-9)


# --- the posteriors in the caller's units ----------------------------------------------------------


@pytest.mark.parametrize("estimator", [RigidCPD(w=0.1), AffineCPD(w=0.1)], ids=["rigid", "affine"])
def test_posteriors_are_mapped_back_with_the_fixed_sets_centre_and_units(fish, estimator):
    """``posteriors_.px`` is ``P X`` in the caller's coordinates (it lost the fixed set's
    centre: 475 off) and its likelihood is the reported objective (it lost the frame's
    Jacobian: 1250.7 off) for data in other units and far from the origin."""
    moving = 1e3 * fish + [500.0, -300.0]
    fixed = 1e3 * fish @ _rotation(20).T + [800.0, 100.0]
    fit = estimator.fit(moving, fixed)
    np.testing.assert_allclose(fit.posteriors_.px, fit.posterior() @ fixed, atol=1e-9 * np.abs(fixed).max())
    assert fit.posteriors_.neg_log_likelihood == pytest.approx(fit.history_["objective"][-1], rel=1e-12)


# --- the normalised frame ---------------------------------------------------------------------------


def test_the_frame_is_the_rms_radius_of_all_points_about_their_centres(fish_pair):
    """Hand-computed: sqrt((|Y - mean Y|^2 + |X - mean X|^2) / (M + N)). The non-rigid fit's
    beta is read in this frame, so its divisor changes every result (M + N - 1: the fish
    pair's first point moved by 2.6e-5)."""
    from centrality_vision.registration._cpd import _Frame

    moving, fixed = fish_pair.moving * 3.0 + 7.0, fish_pair.fixed[:50] * 3.0 - 2.0
    frame = _Frame.of(moving, fixed, True)[0]
    total = np.sum((moving - moving.mean(axis=0)) ** 2) + np.sum((fixed - fixed.mean(axis=0)) ** 2)
    assert frame.scale == pytest.approx(np.sqrt(total / (len(moving) + len(fixed))), rel=1e-12)
    np.testing.assert_allclose(frame.moving_centre, moving.mean(axis=0), rtol=1e-12)


@pytest.mark.parametrize(("ratio", "moving_scale"), [(3e5, True), (3e6, False)])
def test_the_moving_sets_radius_is_the_frame_unless_the_fixed_set_is_a_million_times_larger(fish, ratio, moving_scale):
    """The k-NN model's frame: the moving set's radius, unless the fixed set's exceeds it a
    million times (its coordinates could then overflow when squared)."""
    from centrality_vision.registration._cpd import _Frame

    fixed = ratio * np.vstack([fish, np.random.default_rng(0).uniform(-1, 1, (30, 2))])
    frame = _Frame.of(fish, fixed, True, moving_scale=True)[0]
    assert (frame.scale == pytest.approx(_radius(fish - fish.mean(axis=0)), rel=1e-12)) == moving_scale

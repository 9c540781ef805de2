"""Fits that used to crash on degenerate or extreme inputs (found by fuzzing option combinations).

Each case now ends with finite results (or a named error where the input is out of range).
"""

import warnings

import numpy as np
import pytest

from centrality_vision.exceptions import CollapseWarning, ConvergenceWarning
from centrality_vision.registration import ICP, AffineCPD, NonRigidCPD, RigidCPD
from centrality_vision.registration._estep import Posteriors
from centrality_vision.registration._mstep import gaussian_kernel, nonrigid_m_step


def test_auto_w_on_a_fixed_set_with_almost_no_bounding_box_volume():
    # fixed points on a line in 3D: the box floors two axes at 1e-12, the odds of an outlier
    # pass 1e16 and w rounded to 1 (CPD's outlier constant then divided by zero)
    rng = np.random.default_rng(0)
    t = rng.random(20)
    fixed = np.column_stack([t, np.zeros(20), np.zeros(20)])
    moving = np.column_stack([rng.random(5), rng.random(5), rng.random(5)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reg = AffineCPD(max_iter=9, w="auto").fit(moving, fixed)
    assert np.all(np.isfinite(reg.moving_transformed_)) and np.isfinite(reg.sigma2_)
    assert 0.0 <= reg.w_ < 1.0


def test_singular_nonrigid_system_takes_the_least_squares_solution():
    # lam sigma2 = 0, a moving point without posterior mass and a repeated moving point: the
    # system d(P1) G + lam sigma2 I is singular (LinAlgError before)
    moving = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    fixed = np.array([[0.1, 0.0], [1.1, 0.1], [0.0, 1.2]])
    p1 = np.array([0.0, 0.5, 0.5, 1.0])
    px = np.array([[0.0, 0.0], [0.55, 0.05], [0.55, 0.05], [0.0, 1.2]])
    post = Posteriors(p1=p1, pt1=np.ones(3), px=px, n_p=2.0, neg_log_likelihood=0.0, best=None)
    kernel = gaussian_kernel(moving, moving, 2.0)
    w, moved, sigma2, g_term = nonrigid_m_step(post, moving, fixed, kernel, 3.0, 0.0)
    assert np.all(np.isfinite(w)) and np.all(np.isfinite(moved)) and np.isfinite(sigma2)
    # it solves the system in the least-squares sense: the residual is orthogonal to its range
    system = p1[:, None] * kernel
    residual = system @ w - (px - p1[:, None] * moving)
    np.testing.assert_allclose(system.T @ residual, 0.0, atol=1e-9)


def test_forced_fgt_at_a_sigma2_too_fine_for_its_grid_falls_back_to_the_truncated_path():
    rng = np.random.default_rng(1)
    moving = rng.random((40, 3))
    a = 0.3
    rotation = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    fixed = moving @ rotation.T
    # (silently: the truncated path is exact, and the history says which path each E-step took;
    # the RuntimeWarning it raised was undocumented)
    reg = RigidCPD(method="fgt", tol=0.0, max_iter=80).fit(moving, fixed)
    np.testing.assert_allclose(reg.moving_transformed_, fixed, atol=1e-6)
    assert set(reg.history_["method"]) == {"fgt", "truncated"}


def test_a_fits_forced_fgt_takes_the_exact_path_where_the_expansion_would_cost_far_more():
    # audit 27 F6: 4,500 3D points under method='fgt' took 8 s per E-step and growing (not done
    # in 90 s) where the dense fit took 0.6 s; the expansion costs p^3 terms per box in 3D
    rng = np.random.default_rng(2)
    moving = rng.normal(size=(1100, 3))  # (over 2^20 pairs: below, a forced FGT costs little anyway)
    reg = RigidCPD(method="fgt", max_iter=5, tol=0.0).fit(moving, moving + 0.05)
    assert set(reg.history_["method"]) == {"truncated"}
    exact = RigidCPD(method="truncated", max_iter=5, tol=0.0).fit(moving, moving + 0.05)
    np.testing.assert_array_equal(reg.moving_transformed_, exact.moving_transformed_)
    plane = RigidCPD(method="fgt", max_iter=3, tol=0.0).fit(moving[:, :2], moving[:, :2] + 0.05)
    assert "fgt" in plane.history_["method"]  # in 2D the expansion is cheap: kept


def test_forced_fgt_refuses_more_than_three_dimensions():
    # its work grows as p^D: 300 4D points ran for minutes
    points = np.random.default_rng(0).random((300, 4))
    with pytest.raises(ValueError, match=r"`method` 'fgt' is for 2D and 3D sets; got 4D points"):
        RigidCPD(method="fgt").fit(points, points + 0.01)


def test_fgt_outlier_constant_beyond_exp_range_is_finite():
    # normalize=False at a scale of 1e140: (2 pi sigma2)^(3/2) w/(1-w) M/N passes 1e308
    rng = np.random.default_rng(2)
    moving = rng.random((30, 3)) * 1e140
    fixed = moving + 1e138
    # (unnormalised, CPD's outlier constant is in the data's units: at sigma2 ~ 1e279 the
    # uniform term outweighs every Gaussian, which the fit says instead of overflowing)
    with pytest.warns(ConvergenceWarning) as record:
        reg = RigidCPD(method="fgt", normalize=False, w=0.5, max_iter=5, tol=0.0).fit(moving, fixed)
    assert any("every fixed point was explained by the outlier term" in str(r.message) for r in record)
    assert any(issubclass(r.category, CollapseWarning) for r in record)
    assert np.all(np.isfinite(reg.moving_transformed_))
    reg = RigidCPD(method="fgt", normalize=False, max_iter=50, tol=0.0).fit(moving, fixed)  # w=0: found
    np.testing.assert_allclose(reg.moving_transformed_, fixed, rtol=0, atol=1e-10 * 1e140)


def test_knn_frame_of_sets_far_apart_relative_to_the_moving_radius():
    # n_neighbors centres both sets on the fixed mean: a moving set of radius 1 at 1e300 from
    # it had coordinates of 1e300 in its own units, squared to inf (IndexError from the k-NN
    # query before); the frame now falls back to the joint radius, out of range here
    rng = np.random.default_rng(3)
    moving = rng.random((20, 3)) + 1e8
    fixed = np.repeat(rng.random((1, 3)) * 1e300, 15, axis=0)
    with pytest.raises(ValueError, match="RMS radius"):
        RigidCPD(n_neighbors=5).fit(moving, fixed)
    # and a far but representable offset still registers
    reg = NonRigidCPD(n_neighbors=5, max_iter=5, tol=0.0).fit(moving, moving + 1e12)
    assert np.all(np.isfinite(reg.moving_transformed_))


def test_sigma2_in_the_callers_units_stays_finite_at_the_edge_of_the_scale_range():
    # a fixed set spanning 1e149 passed the old limit (1e150) and ended with sigma2_ = inf
    rng = np.random.default_rng(4)
    moving = rng.random((35, 2)) + 1e8
    fixed = rng.random((8, 2)) * 1e149
    with pytest.raises(ValueError, match="RMS radius"):
        RigidCPD(n_neighbors=3, w="auto", max_iter=2).fit(moving, fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reg = RigidCPD(n_neighbors=3, w="auto", max_iter=5).fit(moving * 1e136, fixed * 1e-9)
    assert np.isfinite(reg.sigma2_) and np.all(np.isfinite(reg.moving_transformed_))


def test_knn_posterior_skips_neighbours_the_tree_cannot_place():
    # a moving point whose every distance overflows gets no neighbour from the k-d tree
    # (index N, distance inf); it now claims nothing instead of indexing past the end
    from centrality_vision.registration._estep import knn_posterior

    moving = np.array([[0.0, 0.0], [1e200, 1e200]])
    fixed = np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]])
    post = knn_posterior(moving, fixed, 1.0, 0.0, k=2)
    assert post.p1[1] == 0.0 and np.isclose(post.p1[0], 2.0)  # its two nearest fixed points
    assert np.all(np.isfinite(post.px)) and np.isfinite(post.neg_log_likelihood)


@pytest.mark.parametrize(
    ("moving", "spanning"),
    [
        (np.array([[0.3, 0.4]]), 0),
        (np.array([[0.3, 0.4], [0.9, 0.1]]), 1),
        (np.c_[np.arange(6.0), 2 * np.arange(6.0) + 1], 1),  # collinear
    ],
)
def test_affine_cpd_warns_when_the_moving_points_do_not_determine_the_linear_map(moving, spanning):
    # one point gave the zero matrix and two a rank-1 map, silently, reported as converged
    from centrality_vision.registration import GPD

    fixed = np.random.default_rng(0).random((30, 2))
    message = f"`moving` spans {spanning} of 2 dimensions .* `transform_` is right on `moving` only"
    for estimator in (AffineCPD(), GPD(AffineCPD(), graph="complete")):
        with pytest.warns(UserWarning, match=message):
            estimator.fit(moving, fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        AffineCPD().fit(fixed[:3], fixed)  # three points in general position: no warning


@pytest.mark.parametrize("n_fixed", [1, 10])
@pytest.mark.parametrize("estimator", [RigidCPD(), AffineCPD(), NonRigidCPD(), ICP()], ids=lambda e: type(e).__name__)
def test_a_fixed_set_of_one_point_is_not_reported_as_a_registration(estimator, n_fixed):
    # found by fuzz round 7: AffineCPD shrank 30 spread points onto the one fixed point and
    # reported converged_=True with sigma2 1.5e-14 (the collapse check needed a fixed radius)
    moving = np.random.default_rng(0).normal(size=(30, 2))
    fixed = np.ones((n_fixed, 2))
    with pytest.warns(CollapseWarning, match="`fixed` is (a single point|one point repeated 10 times)"):
        estimator.fit(moving, fixed)
    assert not estimator.converged_


@pytest.mark.parametrize("estimator", [RigidCPD(), RigidCPD(scale=False), ICP()], ids=repr)
def test_a_fixed_set_that_leaves_a_turn_free_is_named(estimator):
    # audit 27 F4/F5: a moving blob fitted onto 2 points, 3 collinear points or a line of 50 in
    # 3D came back converged_=True with no warning (the turn about the line is arbitrary), and
    # ICP said nothing where RigidCPD warned of a moving set on one line
    rng = np.random.default_rng(4)
    blob = rng.normal(size=(40, 3))
    for fixed in (np.array([[0.0, 0, 0], [1, 2, 3]]), np.outer(np.linspace(-1, 1, 50), [1.0, 0.5, -2])):
        with pytest.warns(UserWarning, match=r"`fixed` spans 1 of 3 dimensions \(\d+ points\): a rotation onto it"):
            estimator.fit(blob, fixed)
    with pytest.warns(UserWarning, match=r"`moving` spans 1 of 3 dimensions \(40 points\)"):
        estimator.fit(np.outer(np.linspace(-1, 1, 40), [1.0, 2, 0]), blob)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        estimator.fit(blob, blob[:, [1, 2, 0]] + 0.1)  # a plane or more on both sides: determined
        estimator.fit(blob[:, :2], blob[::2, :2])  # and in 2D


def test_an_affine_fit_onto_a_flat_fixed_set_is_named():
    blob = np.random.default_rng(5).normal(size=(40, 3))
    plane = blob.copy()
    plane[:, 2] = 0
    with pytest.warns(UserWarning, match=r"`fixed` spans 2 of 3 dimensions \(40 points\): an affine map onto it"):
        AffineCPD().fit(blob, plane)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        AffineCPD().fit(blob, blob @ np.diag([1.0, 2, 0.5]))


def test_rigid_cpd_warns_when_the_moving_points_do_not_determine_a_rotation():
    fixed = np.random.default_rng(1).random((20, 3))
    line = np.c_[np.arange(5.0), 2 * np.arange(5.0), np.zeros(5)]
    with pytest.warns(UserWarning, match=r"`moving` spans 1 of 3 dimensions \(5 points\): a rotation is not"):
        RigidCPD().fit(line, fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        RigidCPD().fit(np.c_[line[:, :2], [0, 1, 0, 1, 0]], fixed)  # off the line: determined


def test_estimate_normals_needs_a_plane_in_3d_and_says_when_a_normal_is_arbitrary():
    from centrality_vision.registration import estimate_normals

    points = np.random.default_rng(2).random((12, 3))
    with pytest.raises(ValueError, match=r"`n_neighbors` must be an int in \[3, "):  # two points: any normal
        estimate_normals(points, n_neighbors=2)
    with pytest.raises(ValueError, match="`points` must have at least 3 points in 3D"):
        estimate_normals(points[:2])
    doubled = np.repeat(points, 3, axis=0)  # every point three times: k=3 sees one position
    with pytest.warns(UserWarning, match="36 of 36 points have neighbourhoods of one point or one line"):
        estimate_normals(doubled, n_neighbors=3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        estimate_normals(doubled, n_neighbors=9)  # three positions: a plane
        estimate_normals(points[:, :2], n_neighbors=2)  # a line through two points has a normal in 2D


def test_a_field_whose_rounding_shows_says_so():
    # at a tiny lam an exact fit interpolates without smoothing: coefficients of 1e10 and more,
    # and transform_(moving) missed moving_transformed_ by 6e-5 (lam 1e-8) with no warning
    from centrality_vision.registration import NonRigidCPD

    rng = np.random.default_rng(1)
    y = rng.normal(size=(200, 2))
    x = y + 0.2 * np.sin(1.5 * y[:, ::-1]) + 0.1
    with pytest.warns(UserWarning, match=r"carry rounding of about \de-0\d of the moving set's RMS radius"):
        reg = NonRigidCPD(lam=1e-8).fit(y, x)
    gap = np.abs(reg.transform_(y) - reg.moving_transformed_).max()
    assert gap > 1e-6  # what it warns about
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reg = NonRigidCPD().fit(y, x)  # lam 2: quiet, and within rounding
    assert np.abs(reg.transform_(y) - reg.moving_transformed_).max() < 1e-7


@pytest.mark.parametrize("offset", [1e2, 1e4, 1e8, 1e10])
def test_a_line_far_from_the_origin_is_a_line(offset):
    """Far from the origin the caller's rounding made a collinear moving set a thin plane: the
    rank warning stopped at an offset of 100, and at 1e8 AffineCPD fitted a linear map of 5e7
    to the rounding (the result moved by 0.41 of the extent; at 1e10 it said converged with
    ``transform_(moving)`` 1.7 extents from ``moving_transformed_``)."""
    rng = np.random.default_rng(0)
    direction, along, fixed = rng.normal(size=2), rng.random(20), rng.random((25, 2))
    line = np.outer(along, direction)
    with pytest.warns(UserWarning, match="spans 1 of 2 dimensions"):
        origin = AffineCPD(tol=1e-12).fit(line, fixed)
    with pytest.warns(UserWarning, match="spans 1 of 2 dimensions"):
        far = AffineCPD(tol=1e-12).fit(line + offset, fixed + offset)
    rounding = 1e3 * np.finfo(float).eps * offset  # the inputs' own rounding, with a margin
    assert far.converged_ and far.n_iter_ == origin.n_iter_
    np.testing.assert_allclose(far.moving_transformed_ - offset, origin.moving_transformed_, atol=rounding)
    np.testing.assert_allclose(far.transform_(line + offset), far.moving_transformed_, atol=rounding)
    assert np.abs(far.transform_.linear).max() < 2 * np.abs(origin.transform_.linear).max()
    line3 = np.outer(along, rng.normal(size=3)) + offset
    with pytest.warns(UserWarning, match="spans 1 of 3 dimensions"):
        RigidCPD().fit(line3, line3[::-1].copy())


def test_a_callback_stops_the_fit_with_numpy_s_true_too():
    """``return np.linalg.norm(...) < tol`` gives numpy.True_, which the check ``is True``
    ignored: the fit ran on without a word."""
    rng = np.random.default_rng(0)
    fixed = rng.random((30, 2))
    for estimator in (RigidCPD, ICP):
        calls = []

        def stop_at_three(info, calls=calls):
            calls.append(info.iteration)
            return np.bool_(len(calls) >= 3)

        estimator(callback=stop_at_three).fit(fixed @ np.array([[0.0, -1.0], [1.0, 0.0]]) * 0.5, fixed)
        assert len(calls) == 3


@pytest.mark.parametrize(
    ("moving", "fixed", "match"),
    [
        (np.arange(12.0)[:, None], np.arange(12.0)[:, None] + 1, r"searches rotations in 2D and 3D; got 1D sets"),
        (np.eye(2), np.eye(2)[::-1], r"needs at least 3 points in each set; got 2 moving and 2 fixed"),
        (
            np.ones((5, 2)),
            3 * np.eye(5, 2),
            r"needs at least two distinct points in each set; got RMS radii 0 \(moving\) and 1.7 \(fixed\)",
        ),
    ],
)
def test_what_the_global_search_needs_is_named_with_it(moving, fixed, match):
    """A plain fit takes these sets; the search's own refusals named only `moving` (and gave
    radii in the normalised frame)."""
    with pytest.raises(ValueError, match=r"`RigidCPD.init`='global' " + match), warnings.catch_warnings():
        warnings.filterwarnings("ignore", "`moving` spans 0 of 2", UserWarning)  # (one point: rightly)
        RigidCPD(init="global", random_state=0).fit(moving, fixed)


def test_a_mirror_image_is_fitted_by_affine_cpd_from_a_mirrored_start_only():
    # audit 27 F2, as docs/conventions.rst states it: the determinant cannot pass through 0
    from centrality_vision.datasets import load_fish
    from centrality_vision.transforms import AffineTransform

    y = load_fish().moving
    c, s = np.cos(0.4), np.sin(0.4)
    x = y @ (np.array([[c, -s], [s, c]]) @ np.diag([-1.0, 1.0])).T + [3.0, 1.0]
    proper = AffineCPD().fit(y, x)
    assert np.linalg.det(proper.transform_.linear) > 0 and np.abs(proper.moving_transformed_ - x).max() > 0.5
    mirrored = AffineCPD(init=AffineTransform(np.diag([-1.0, 1.0]), np.zeros(2))).fit(y, x)
    np.testing.assert_allclose(mirrored.moving_transformed_, x, atol=1e-9)

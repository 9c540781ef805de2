"""Sets that span fewer dimensions than their coordinates: a 2D problem lifted into 3D."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone

from centrality_vision.exceptions import CollapseWarning, InputError
from centrality_vision.registration import GPD, AffineCPD, MultiscaleCPD, NonRigidCPD, RigidCPD
from centrality_vision.transforms import random_rotation

_TURN = random_rotation(3, seed=5)
_OFFSET = np.array([3.0, -2.0, 7.0])


def _lifted(points, turned):
    """``points`` with z = 0 added; ``turned``: then rotated into another plane and moved."""
    lifted = np.c_[points, np.zeros(len(points))]
    return lifted @ _TURN.T + _OFFSET if turned else lifted


def _in_plane(points, turned):
    return ((points - _OFFSET) @ _TURN)[:, :2] if turned else points[:, :2]


def _iterations(fit):
    return [level["n_iter"] for level in fit.levels_] if isinstance(fit, MultiscaleCPD) else [fit.n_iter_]


def _cluttered_fish(fish_pair):
    rng = np.random.default_rng(1)
    x = fish_pair.fixed
    return fish_pair.moving, np.vstack([x, rng.uniform(x.min(0), x.max(0), (20, 2))])


@pytest.mark.parametrize(
    "estimator",
    [
        RigidCPD(),
        RigidCPD(w=0.2, scale=False),
        RigidCPD(w="auto"),
        NonRigidCPD(w="auto"),
        NonRigidCPD(w=0.1, n_neighbors=10),
        GPD(RigidCPD(w=0.1), graph="emst"),
        GPD(NonRigidCPD(w="auto"), graph="knn"),
        MultiscaleCPD(RigidCPD(w=0.1), sizes=(40, 80)),
    ],
    ids=repr,
)
@pytest.mark.parametrize("turned", [False, True], ids=["z=0", "turned"])
def test_a_2d_problem_lifted_into_a_plane_of_3d_registers_as_in_2d(fish_pair, estimator, turned):
    """With D = 3 the Gaussians' sigma2 was 2/3 of the in-plane residual's and c took one
    more factor of the Gaussians' width: the lifted fish ended up to 0.36 away from its 2D
    fit (non-rigid, w=0), and rigid w='auto' collapsed with w_ 0.895 against 0.459 in 2D."""
    moving, fixed = _cluttered_fish(fish_pair)
    flat = estimator.fit(moving, fixed)
    expected = (flat.moving_transformed_, flat.transform(fixed), _iterations(flat), flat.sigma2_)
    lifted = estimator.fit(_lifted(moving, turned), _lifted(fixed, turned))
    assert _iterations(lifted) == expected[2]
    assert lifted.sigma2_ == pytest.approx(expected[3], rel=1e-9)
    np.testing.assert_allclose(_in_plane(lifted.moving_transformed_, turned), expected[0], atol=1e-9)
    np.testing.assert_allclose(_in_plane(lifted.transform(_lifted(fixed, turned)), turned), expected[1], atol=1e-9)


def test_the_lifted_fit_reports_the_same_weight_and_likelihood(fish_pair):
    moving, fixed = _cluttered_fish(fish_pair)
    flat = RigidCPD(w="auto").fit(moving, fixed)
    lifted = RigidCPD(w="auto").fit(_lifted(moving, True), _lifted(fixed, True))
    assert lifted.w_ == pytest.approx(flat.w_, rel=1e-9)
    for name in ("neg_log_likelihood", "n_p"):
        assert getattr(lifted.posteriors_, name) == pytest.approx(getattr(flat.posteriors_, name), rel=1e-9)
    np.testing.assert_allclose(lifted.history_["objective"], flat.history_["objective"], rtol=1e-9)
    np.testing.assert_array_equal(lifted.fixed_to_moving_, flat.fixed_to_moving_)
    np.testing.assert_allclose(lifted.posterior(), flat.posterior(), atol=1e-12)


def test_rigid_auto_w_on_the_lifted_cluttered_fish_does_not_collapse(fish_pair):
    moving, fixed = _cluttered_fish(fish_pair)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CollapseWarning)
        fit = RigidCPD(w="auto").fit(_lifted(moving, True), _lifted(fixed, True))
    assert fit.converged_
    assert fit.w_ == pytest.approx(20 / len(fixed), abs=0.3)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_points=st.integers(8, 40),
    offset=st.floats(-1e3, 1e3),
    scale=st.floats(1e-3, 1e3),
    w=st.sampled_from([0.0, 0.1, "auto"]),
)
def test_any_lifted_rigid_problem_registers_as_in_2d(seed, n_points, offset, scale, w):
    rng = np.random.default_rng(seed)
    moving = rng.normal(size=(n_points, 2)) * scale + offset
    angle = rng.uniform(-0.5, 0.5)
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    fixed = (moving @ turn.T + rng.normal(scale=0.02 * scale, size=moving.shape))[rng.permutation(n_points)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (a few random problems stop at max_iter: alike in both)
        flat = RigidCPD(w=w).fit(moving, fixed)
        lifted = RigidCPD(w=w).fit(_lifted(moving, True), _lifted(fixed, True))
    assert lifted.n_iter_ == flat.n_iter_
    extent = np.ptp(fixed, axis=0).max()
    in_plane = _in_plane(lifted.moving_transformed_, True)
    np.testing.assert_allclose(in_plane, flat.moving_transformed_, atol=1e-7 * extent)


def test_a_set_that_spans_more_keeps_the_full_dimension():
    """A 3D blob onto a line: the blob's residual off the line is real. Taken as a 1D mixture
    (the line's span), its sigma2 tripled and the similarity fit shrank the blob to 0.4% of
    its radius; with the blob's 3 dimensions the scale stays near 1."""
    rng = np.random.default_rng(4)
    blob = rng.normal(size=(40, 3))
    line = np.outer(np.linspace(-1, 1, 50), [1.0, 0.5, -2])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (the turn about the line is not determined)
        fit = RigidCPD().fit(blob, line)
    assert 0.3 < fit.transform_.scale < 3


@pytest.mark.parametrize("n_dims", [2, 3])
@pytest.mark.parametrize("degrees", [60, 85])
def test_two_lines_at_an_angle_are_a_problem_in_their_plane(n_dims, degrees):
    """Each line spans 1 dimension, the two together a plane: taken as 1D, the non-rigid fit
    read the distance off the line as the Gaussians' width and ended 0.42 off, 'converged'."""
    t = np.linspace(-1, 1, 40)
    along = t + 0.3 * t**3  # uneven spacing
    angle = np.radians(degrees)
    moving = np.zeros((40, n_dims))
    moving[:, 0] = along
    fixed = np.zeros((40, n_dims))
    fixed[:, 0], fixed[:, 1] = along * np.cos(angle), along * np.sin(angle)
    fit = NonRigidCPD().fit(moving, fixed)
    np.testing.assert_allclose(fit.moving_transformed_, fixed, atol=1e-6)


def test_a_lifted_fit_that_reaches_the_variance_floor_ends_as_in_2d():
    """The floor followed the fixed set's spread per coordinate: a lifted exact fit ended at
    2/3 of the 2D sigma2_."""
    moving = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 2.0], [1.5, 1.2]])
    fixed = moving @ np.array([[0.9, -0.3], [0.3, 0.9]]).T + [0.2, 0.1]  # an exact similarity
    for estimator in (RigidCPD(), NonRigidCPD(w=0.1)):
        flat = estimator.fit(moving, fixed)
        expected = (flat.sigma2_, flat.n_iter_, flat.posteriors_.neg_log_likelihood)
        lifted = estimator.fit(_lifted(moving, True), _lifted(fixed, True))
        assert lifted.n_iter_ == expected[1]
        assert lifted.sigma2_ == pytest.approx(expected[0], rel=1e-9)
        # (c goes to the E-step as a weight: at the floor its odds are ~1e6 times w's, whose
        # rounding costs ~1e-10 of the objective)
        assert lifted.posteriors_.neg_log_likelihood == pytest.approx(expected[2], rel=1e-9)


def _box_volume(sides, sigma2, model_dims):
    """The volume of w='auto''s outlier box (what ``_box_weight`` divides the odds by)."""
    from centrality_vision.registration._cpd import _box_sides

    return float(np.prod(_box_sides(sides, sigma2, model_dims)))


def test_the_outlier_box_floors_every_thin_side_at_the_gaussians_width():
    """w='auto''s box: a side up to a tenth of the longest at least the Gaussians' width
    sqrt(2 pi sigma2) (from there to a fifth, a falling share of it). Floored only below
    1/1000 of the longest side, a side just above that cut (2.2e-3 of 2) gave a box 48
    times smaller than one just below it."""
    sigma2 = 0.01 / (2.0 * np.pi)  # width 0.1
    volumes = [_box_volume(np.array([2.0, 1.0, side]), sigma2, 3) for side in (0.0, 1.9e-3, 2.1e-3, 0.05, 0.1)]
    assert volumes == pytest.approx([0.2] * 5)
    assert _box_volume(np.array([2.0, 1.0, 0.15]), sigma2, 3) == pytest.approx(0.3)  # wider than the Gaussians
    # between a tenth and a fifth: at least a share of the width falling to 0
    assert _box_volume(np.array([2.0, 1.0, 0.25]), 1e6, 3) == pytest.approx(2.0 * 0.75 * (2.0 * np.pi * 1e6) ** 0.5)
    assert _box_volume(np.array([2.0, 0.05, 0.4]), sigma2, 2) == pytest.approx(0.8)  # the 2 longest
    # over a fifth of the longest: the set's own extent, however wide the Gaussians
    assert _box_volume(np.array([2.0, 1.0, 0.41]), 1e6, 3) == pytest.approx(0.82)
    # a one-point set (every side 0): a box of the Gaussians' width
    assert _box_volume(np.zeros(2), 1.0, 2) == pytest.approx(2.0 * np.pi)
    assert _box_volume(np.array([2.0, 1.0, 0.0]), 1e6, 3) == pytest.approx(2.0 * (2.0 * np.pi * 1e6) ** 0.5)


@pytest.mark.parametrize("sigma2", [1e-4, 0.01, 1.0, 1e4])
def test_the_outlier_box_changes_continuously_with_a_side(sigma2):
    """The floor falls to 0 between a tenth and a fifth of the longest side. Cut off at the
    tenth, sides 0.0999999999 and 0.1000000001 of the longest gave boxes up to 25 times
    apart, and non-rigid w='auto' fits of a cluttered scan ended 0.0285 and 0.0324 off."""
    shares = np.linspace(0.0, 0.4, 4001)
    volumes = np.array([_box_volume(np.array([1.0, 0.5, share]), sigma2, 3) for share in shares])
    width = np.sqrt(2.0 * np.pi * sigma2)
    # Lipschitz in the side: a step of 1e-4 moves the box by at most 0.5 (the other sides)
    # times (1 + the floor's slope, width / 0.1) times the step
    assert np.max(np.abs(np.diff(volumes))) <= 0.5 * (1.0 + width / 0.1) * 1e-4 * (1.0 + 1e-9)
    for cut in (0.1, 0.2):
        at_cut = [_box_volume(np.array([1.0, 0.5, cut + step]), sigma2, 3) for step in (-1e-10, 1e-10)]
        assert at_cut[0] == pytest.approx(at_cut[1], rel=1e-6)
    assert volumes[0] == pytest.approx(0.5 * width)  # floored
    assert volumes[-1] == pytest.approx(0.2)  # the set's own side


@pytest.mark.parametrize("estimator", [AffineCPD(w="auto"), RigidCPD(w="auto"), NonRigidCPD(w="auto")], ids=repr)
def test_one_fixed_point_in_many_dimensions_gets_a_fit(estimator):
    """The box of one fixed point in 50D is 50 sides of the Gaussians' width at the variance
    floor: its volume rounded to 0, and AffineCPD raised ZeroDivisionError from 46D on."""
    rng = np.random.default_rng(0)
    moving, fixed = rng.standard_normal((100, 50)), rng.standard_normal((1, 50))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (one fixed point: not a registration)
        fit = clone(estimator).fit(moving, fixed)
    assert np.all(np.isfinite(fit.moving_transformed_))
    assert 0.0 <= fit.w_ < 1.0


@pytest.mark.parametrize("sides", [[1e-310], [1e-154, 1e-154], [1e-300, 1e-300], [1e-200] * 50])
def test_a_box_too_small_for_floats_gives_the_weights_bound(sides):
    """Odds past float's range: a box of 1e-310 gave odds of inf and a NaN weight (and NaN
    objectives, without a warning); one whose volume rounded to 0 divided by zero."""
    from centrality_vision.registration._cpd import _AUTO_W_E_MAX, _box_weight

    assert _box_weight(0.5, 3, np.array(sides)) == _AUTO_W_E_MAX
    assert _box_weight(1e-300, 3, np.array([1.0, 2.0])) == pytest.approx(1.5e-300)  # (small odds as such)


@pytest.mark.parametrize("off_plane", ["one point 1% off", "thickness 1e-3"])
def test_rigid_auto_w_on_a_nearly_flat_cluttered_set_finds_the_pose(fish_pair, off_plane):
    """A flat set with one clutter point 1% of its extent off the plane, or a scan 1e-3 of its
    extent thick, spans 3D: with the box's thin side taken as it is, rigid w='auto' ended
    0.25 to 0.7 off the true pose in 6 and 7 of 40 such problems, without a warning (the flat
    ones: none)."""
    moving = fish_pair.moving
    for seed in range(10):
        rng = np.random.default_rng(seed)
        angle = rng.uniform(-0.6, 0.6)
        truth = moving @ np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]).T + [0.3, -0.2]
        fixed = truth + rng.normal(scale=0.02, size=truth.shape)
        fixed = np.vstack([fixed, rng.uniform(fixed.min(0), fixed.max(0), (30, 2))])
        extent = np.ptp(fixed, axis=0).max()
        if off_plane == "one point 1% off":
            lifted_moving = np.c_[moving, np.zeros(len(moving))]
            lifted_fixed = np.vstack([np.c_[fixed, np.zeros(len(fixed))], [*fixed.mean(axis=0), 0.01 * extent]])
        else:
            lifted_moving = np.c_[moving, rng.normal(scale=1e-3 * extent, size=len(moving))]
            lifted_fixed = np.c_[fixed, rng.normal(scale=1e-3 * extent, size=len(fixed))]
        fit = RigidCPD(w="auto").fit(lifted_moving, lifted_fixed)
        error = np.sqrt(np.mean(np.sum((fit.moving_transformed_[:, :2] - truth) ** 2, axis=1)))
        assert error < 0.02, (seed, error)


@pytest.mark.parametrize("n_dims", [10, 20])
@pytest.mark.parametrize(
    "estimator", [NonRigidCPD(w=0.1), RigidCPD(w="auto"), NonRigidCPD(w=0.1, n_neighbors=10)], ids=repr
)
def test_a_2d_problem_lifted_into_many_dimensions_registers_as_in_2d(fish_pair, estimator, n_dims):
    """The mixture's dimension goes to the E-step as such. Passed as an outlier weight whose
    odds carry (2 pi sigma2)^(-lift/2), the weight rounded to 1 in 14 or more dimensions:
    the fit ended 0.04 to 0.06 from the 2D one."""
    moving, fixed = _cluttered_fish(fish_pair)
    turn = np.linalg.qr(np.random.default_rng(n_dims).normal(size=(n_dims, n_dims)))[0]

    def up(points):
        return np.c_[points, np.zeros((len(points), n_dims - 2))] @ turn.T

    flat = clone(estimator).fit(moving, fixed)
    if isinstance(estimator, RigidCPD):
        with pytest.warns(UserWarning) as record:  # (the rotation is undetermined off the plane)
            lifted = clone(estimator).fit(up(moving), up(fixed))
        assert sorted(str(r.message).split(" ")[0] for r in record) == ["`fixed`", "`moving`"]
        assert all(f"not all on one {n_dims - 2}-dimensional flat" in str(r.message) for r in record)
    else:
        lifted = clone(estimator).fit(up(moving), up(fixed))
    np.testing.assert_allclose((lifted.moving_transformed_ @ turn)[:, :2], flat.moving_transformed_, atol=1e-9)
    assert lifted.sigma2_ == pytest.approx(flat.sigma2_, rel=1e-6)
    assert lifted.w_ == pytest.approx(flat.w_, abs=1e-9)
    assert lifted.posteriors_.neg_log_likelihood == pytest.approx(flat.posteriors_.neg_log_likelihood, rel=1e-9)
    np.testing.assert_array_equal(lifted.fixed_to_moving_, flat.fixed_to_moving_)
    np.testing.assert_allclose(lifted.posterior(), flat.posterior(), atol=1e-9)


@pytest.mark.parametrize(
    ("estimator", "n_dims"),
    [
        (RigidCPD(w=0.1, accelerate=True), 3),
        (RigidCPD(w=0.1, accelerate=True), 4),
        (RigidCPD(w=0.1, scale=True, accelerate=True), 5),
        (AffineCPD(w=0.1, accelerate=True), 3),
        (AffineCPD(w=0.1, accelerate=True), 5),
    ],
    ids=repr,
)
def test_an_accelerated_lifted_fit_jumps_as_the_2d_one(fish_pair, estimator, n_dims):
    """accelerate extrapolates a linear map on the set's span only. Off it, the rotation's
    block (4D and up) and the affine map's column (the identity's at the start, 0 after an
    M-step) are undetermined; extrapolated with the rest they set the jump's length: the
    lifted fish took 35 iterations against the 2D fit's 18 and ended 1.1e-2 from it (affine
    in 3D: 3.5e-4)."""
    moving, fixed = _cluttered_fish(fish_pair)
    turn = np.linalg.qr(np.random.default_rng(n_dims).normal(size=(n_dims, n_dims)))[0]
    shift = np.arange(1.0, n_dims + 1.0)

    def up(points):
        return np.c_[points, np.zeros((len(points), n_dims - 2))] @ turn.T + shift

    flat = clone(estimator).fit(moving, fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (a rotation off the plane is undetermined in 4D and up)
        lifted = clone(estimator).fit(up(moving), up(fixed))
    assert lifted.n_iter_ == flat.n_iter_
    in_plane = ((lifted.moving_transformed_ - shift) @ turn)[:, :2]
    np.testing.assert_allclose(in_plane, flat.moving_transformed_, atol=1e-9)
    assert lifted.sigma2_ == pytest.approx(flat.sigma2_, rel=1e-9)


@pytest.mark.parametrize(
    "estimator",
    [
        RigidCPD(w=0.1, scale=True, accelerate=True, normalize=False, tol=1e-10, max_iter=1000),
        AffineCPD(w=0.1, accelerate=True, normalize=False, tol=1e-10, max_iter=1000),
    ],
    ids=repr,
)
def test_an_accelerated_fit_off_the_origin_jumps_as_in_2d(fish_pair, estimator):
    """With ``normalize=False`` the moving set lies off the working origin (by its offset
    from the fixed set). A full-span set's translation was extrapolated itself, and a flat
    one's about its centre: 5 units away, the similarity fit took 48 iterations in 2D and 36
    lifted into 3D, the affine one 47 and 39 (audit 36). Both now extrapolate the image of
    the set's centre."""
    moving, fixed = _cluttered_fish(fish_pair)
    fixed = fixed + [5.0, 0.0]
    flat = clone(estimator).fit(moving, fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (an affine map off the plane is undetermined)
        lifted = clone(estimator).fit(np.c_[moving, np.zeros(len(moving))], np.c_[fixed, np.zeros(len(fixed))])
    assert lifted.n_iter_ == flat.n_iter_
    np.testing.assert_allclose(lifted.moving_transformed_[:, :2], flat.moving_transformed_, atol=1e-9)
    plain = clone(estimator).set_params(accelerate=False).fit(moving, fixed)
    assert flat.n_iter_ < plain.n_iter_
    np.testing.assert_allclose(flat.moving_transformed_, plain.moving_transformed_, atol=1e-4)  # (tol 1e-10 of L)


@pytest.mark.parametrize("graph", ["delaunay", "gabriel", "emst"])
@pytest.mark.parametrize("offset", [0.0, 1e4], ids=["at the origin", "turned, at 1e4"])
def test_gpd_builds_the_graphs_of_a_flat_set_in_its_plane(fish_pair, graph, offset):
    """A flat 3D set's graphs are built in the plane it spans. The default Delaunay graph of
    any flat 3D set was refused, and at 1e4 the centred set's rounding made a 3D Delaunay
    triangulation fail Qhull's check: GPD raised for every graph."""
    moving, fixed = _cluttered_fish(fish_pair)

    def up(points):
        lifted = np.c_[points, np.zeros(len(points))]
        return lifted @ _TURN.T + offset * np.array([1.0, -2.0, 0.5]) if offset else lifted

    def down(points):
        return ((points - offset * np.array([1.0, -2.0, 0.5])) @ _TURN)[:, :2] if offset else points[:, :2]

    flat = GPD(RigidCPD(w=0.1), graph=graph).fit(moving, fixed)
    lifted = GPD(RigidCPD(w=0.1), graph=graph).fit(up(moving), up(fixed))
    np.testing.assert_allclose(down(lifted.moving_transformed_), flat.moving_transformed_, atol=1e-8)
    np.testing.assert_allclose(lifted.moving_centrality_, flat.moving_centrality_, atol=1e-9)


@pytest.mark.parametrize("n_dims", [2, 3, 5])
@pytest.mark.parametrize("offset", [0.0, 1e6], ids=["at the origin", "at 1e6"])
def test_gpd_builds_the_graphs_of_a_line_on_the_line(n_dims, offset):
    """A line's graphs are built on the line (with a second coordinate of 0). Centred, a
    turned line 1e6 from the origin kept its rounding as a second dimension: GPD's Delaunay
    graph of 30 points had 137 edges (the path has 29), and at the origin it was refused."""
    turn = np.linalg.qr(np.random.default_rng(n_dims).normal(size=(n_dims, n_dims)))[0]
    t = np.linspace(0.0, 1.0, 30)[:, None] ** 1.5  # (unequal gaps: one path)

    def up(points):
        return np.c_[points, np.zeros((len(points), n_dims - 1))] @ turn.T + offset

    moving, fixed = up(t), up(1.1 * t + 0.05)
    with pytest.raises(InputError, match="30 collinear points"):
        GPD(RigidCPD(w=0.1), graph="delaunay").fit(moving, fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (a rotation about the line is undetermined)
        fit = GPD(RigidCPD(w=0.1), graph="gabriel").fit(moving, fixed)
    path = {(i, i + 1) for i in range(29)}
    for graph in (fit.moving_graph_, fit.fixed_graph_):
        rows, cols = graph.nonzero()
        assert {(int(i), int(j)) for i, j in zip(rows, cols) if i < j} == path

"""normalize=True: equivariance under translation and scaling, unit-free defaults, collapse warnings."""

import warnings

import numpy as np
import pytest

from centrality_vision.exceptions import CollapseWarning, ConvergenceWarning
from centrality_vision.registration import GPD, AffineCPD, MultiscaleCPD, NonRigidCPD, RigidCPD, RigidTransform
from centrality_vision.transforms import SimilarityTransform


def _on_grid(points):
    """Rounded to multiples of 2^-20, so that adding an offset up to 2^32 is exact."""
    return np.round(np.asarray(points) * 2.0**20) / 2.0**20


@pytest.fixture(scope="module")
def exact_pair(fish_pair):
    y = _on_grid(fish_pair.moving)
    a = np.radians(35.0)
    r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    x = _on_grid(1.3 * y @ r.T + [0.4, -0.2])
    return y, x, r


def _size(points):
    return float(np.sqrt(np.mean(np.sum((points - points.mean(0)) ** 2, axis=1))))


# (factor, offset): offsets up to 1e8, scales 1e-6 to 1e6; powers of two and grid data keep
# the transformed inputs exact where an offset is added (a shape of size 1e-6 at 1e3 would
# already lose 1e-7 of its size to rounding before any registration)
EQUIVARIANCE_CASES = [
    (1.0, 1e3),
    (1.0, 1e6),
    (1.0, 1e8),
    (1e-6, 0.0),
    (1e6, 0.0),
    (2.0**-20, 1e3),
    (2.0**20, 1e8),
    (2.0**20, -1e8),
]


@pytest.mark.parametrize(("factor", "offset"), EQUIVARIANCE_CASES)
def test_similarity_cpd_is_equivariant_on_exact_copies(exact_pair, offset, factor):
    y, x, r = exact_pair
    ref = RigidCPD(scale=True, tol=1e-12).fit(y, x)
    reg = RigidCPD(scale=True, tol=1e-12).fit(factor * y + offset, factor * x + offset)
    assert ref.converged_ and reg.converged_
    np.testing.assert_allclose(ref.transform_.rotation, r, atol=1e-6)  # x was rounded to the grid
    np.testing.assert_allclose(reg.transform_.rotation, ref.transform_.rotation, atol=1e-9, rtol=0)
    assert reg.transform_.scale == pytest.approx(ref.transform_.scale, rel=1e-9)
    # positions: relative 1e-9 of the shape, plus the rounding of coordinates of size `offset`
    tolerance = 1e-9 * factor * _size(x) + 4 * np.spacing(offset + factor * np.abs(x).max())
    np.testing.assert_allclose(
        reg.moving_transformed_, factor * ref.moving_transformed_ + offset, atol=tolerance, rtol=0
    )
    np.testing.assert_allclose(reg.transform(factor * y + offset), reg.moving_transformed_, atol=tolerance, rtol=0)
    assert reg.sigma2_ == pytest.approx(factor**2 * ref.sigma2_, rel=1e-6, abs=1e-9 * (factor * _size(x)) ** 2)


@pytest.mark.parametrize("cls", [AffineCPD, NonRigidCPD])
def test_affine_and_nonrigid_are_equivariant(fish_pair, cls):
    y, x = _on_grid(fish_pair.moving), _on_grid(fish_pair.fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # 60 iterations are enough to compare
        ref = cls(tol=1e-9, max_iter=60).fit(y, x)
        runs = [(f, o, cls(tol=1e-9, max_iter=60).fit(f * y + o, f * x + o)) for f, o in EQUIVARIANCE_CASES[2:]]
    for factor, offset, reg in runs:
        assert reg.n_iter_ == ref.n_iter_
        tolerance = 1e-9 * factor * _size(x) + 4 * np.spacing(abs(offset) + factor * np.abs(x).max())
        np.testing.assert_allclose(
            reg.moving_transformed_, factor * ref.moving_transformed_ + offset, atol=tolerance, rtol=0
        )
        np.testing.assert_allclose(reg.history_["sigma2"], factor**2 * ref.history_["sigma2"], rtol=1e-6)


@pytest.mark.parametrize("cls", [RigidCPD, AffineCPD, NonRigidCPD])
def test_unnormalised_fits_are_translation_equivariant(fish_pair, cls):
    """normalize=False keeps the caller's units but not the caller's origin: far from it the
    M-step's moments cancelled (at an offset of 1e8 rigid CPD stopped after one iteration,
    3.8 off; non-rigid 0.63 off; 5e-4 already at 1e4)."""
    y, x = _on_grid(fish_pair.moving), _on_grid(fish_pair.fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        ref = cls(tol=1e-9, max_iter=60, normalize=False).fit(y, x)
        for offset in (1e4, 1e6, -1e8):
            reg = cls(tol=1e-9, max_iter=60, normalize=False).fit(y + offset, x + offset)
            assert reg.n_iter_ == ref.n_iter_
            tolerance = 1e-9 * _size(x) + 4 * np.spacing(abs(offset) + np.abs(x).max())
            np.testing.assert_allclose(
                reg.moving_transformed_, ref.moving_transformed_ + offset, atol=tolerance, rtol=0
            )
            np.testing.assert_allclose(reg.transform_(y + offset), reg.moving_transformed_, atol=tolerance, rtol=0)
            np.testing.assert_allclose(reg.history_["sigma2"], ref.history_["sigma2"], rtol=1e-6)


def test_nonrigid_default_is_unit_free_on_the_fish(fish_pair):
    """The fish in metres, millimetres and pixels (origin at a corner) gives the same field."""
    y, x = fish_pair.moving, fish_pair.fixed
    metres = NonRigidCPD().fit(y, x)
    corner = np.minimum(y.min(0), x.min(0))
    for factor, offset in ((1000.0, np.zeros(2)), (512 / 4.0, -corner * 512 / 4.0 + 20)):
        reg = NonRigidCPD().fit(factor * y + offset, factor * x + offset)
        np.testing.assert_allclose(
            (reg.moving_transformed_ - offset) / factor, metres.moving_transformed_, atol=1e-9 * _size(x)
        )
    rms = np.sqrt(np.mean(np.min(((metres.moving_transformed_[:, None] - x[None]) ** 2).sum(-1), axis=1)))
    assert rms < 0.01 * _size(x)


def test_pixel_outline_with_outliers_keeps_its_scale(fish):
    """Issue example: a 100-pixel outline, w=0.2, clutter: the raw frame shrinks, the normalised one does not."""
    y = (fish - fish.min(0)) / np.ptp(fish, axis=0).max() * 100
    a = np.radians(20)
    r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    x = 1.25 * y @ r.T + [30, -10]
    x = np.vstack([x, np.random.default_rng(0).uniform(x.min(0), x.max(0), (20, 2))])
    reg = RigidCPD(w=0.2).fit(y, x)
    assert reg.converged_ and reg.transform_.scale == pytest.approx(1.25, rel=1e-6)
    np.testing.assert_allclose(reg.transform_.rotation, r, atol=1e-6)
    with pytest.warns(CollapseWarning, match=r"fixed points were matched.*Try normalize=True, a smaller `w`"):
        raw = RigidCPD(w=0.2, normalize=False).fit(y, x)
    assert not raw.converged_ and raw.transform_.scale < 1.0


def test_far_offset_fish_is_registered_exactly(fish, rot2):
    x = fish @ rot2(20).T
    reg = RigidCPD(tol=1e-12, max_iter=300).fit(fish + 1e6, x + 1e6)
    assert reg.converged_
    assert np.sqrt(np.mean(np.sum((reg.moving_transformed_ - x - 1e6) ** 2, axis=1))) < 1e-9


def test_collapse_of_the_moving_set_is_reported(fish):
    # a dense blob and a few far points: the similarity shrinks the fish onto the blob
    rng = np.random.default_rng(1)
    x = np.vstack([rng.normal(0.0, 1e-3, (80, 2)), [[50.0, 0.0], [-50.0, 0.0], [0.0, 50.0], [0.0, -50.0]]])
    # normalize is already on: the advice does not suggest it
    with pytest.warns(CollapseWarning, match=r"collapsed.*Try a smaller `w`, or a starting pose \(`init`\)\.$"):
        reg = RigidCPD(w=0.1, tol=1e-8).fit(fish, x)
    assert not reg.converged_ and reg.transform_.scale < 1e-6


def _outline(n):
    u = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    r = 1.0 + 0.3 * np.cos(3.0 * u)
    return np.column_stack([np.cos(u) * r, np.sin(u) * r])


def _turn(degrees):
    a = np.radians(degrees)
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


@pytest.mark.parametrize("model", ["similarity", "affine"])
def test_a_moving_set_shrunk_onto_the_fixed_set_s_centre_is_reported(model):
    """A moving set with far outliers of its own and a part the fixed set lacks: started at
    the exact pose, the similarity fit shrank to a scale of 0.03 (true: 0.5) with sigma2 at
    the fixed set's own variance, and said converged without a word."""
    fixed = _outline(60)
    far = np.random.default_rng(1).uniform(4.0, 6.0, (10, 2))
    turn, offset = _turn(40.0), np.array([3.0, -1.0])
    moving = 2.0 * np.vstack([fixed[:40], far]) @ turn.T + offset
    true = SimilarityTransform(turn.T, -0.5 * turn.T @ offset, scale=0.5)
    np.testing.assert_allclose(true(moving[:40]), fixed[:40], atol=1e-12)
    reg = AffineCPD(w=0.3, init=true) if model == "affine" else RigidCPD(scale=True, w=0.3, init=true)
    with pytest.warns(CollapseWarning, match=r"Gaussians [\d.]+ times as wide as the transformed moving set.*`init`"):
        reg.fit(moving, fixed)
    assert not reg.converged_
    assert np.sqrt(2.0 * reg.sigma2_) > 2.5 * _size(reg.moving_transformed_)


def test_data_far_noisier_than_the_shape_is_still_a_registration(fish):
    """The spread check leaves a sound fit alone: Gaussian noise of the shape's own RMS radius
    per axis (ten noisy copies of the fish) still gives the rotation within a few degrees."""
    rng = np.random.default_rng(0)
    turn = _turn(30.0)
    moving = np.vstack([fish] * 10)
    fixed = moving @ turn.T + rng.normal(scale=_size(fish), size=moving.shape)
    reg = RigidCPD(scale=True).fit(moving, fixed)  # warnings are errors in the tests
    assert reg.converged_
    error = np.degrees(np.arccos(np.clip(np.trace(reg.transform_.rotation.T @ turn) / 2.0, -1.0, 1.0)))
    assert error < 10.0
    assert np.sqrt(2.0 * reg.sigma2_) > 1.0 * _size(reg.moving_transformed_)  # the Gaussians are wide


@pytest.mark.parametrize("factor", [1e-10, 1e-6, 1e-2, 1e2, 1e6, 1e10])
@pytest.mark.parametrize("model", ["similarity", "affine"])
def test_sets_in_different_units_register(fish, model, factor):
    """A moving set in other units than the fixed set (metres against centimetres): the fit
    started at scale 1 and the smaller set became a dot inside the larger one's Gaussians
    (0.01: CollapseWarning, error 0.62 of the extent); a fixed set 1e6 times smaller stopped
    at sigma2's floor, a tenth of its radius off."""
    turn = _turn(25.0)
    fixed = fish @ turn.T + [0.3, -0.2]
    reg = (RigidCPD(tol=1e-10) if model == "similarity" else AffineCPD(tol=1e-10)).fit(factor * fish, fixed)
    assert reg.converged_
    np.testing.assert_allclose(reg.moving_transformed_, fixed, atol=1e-9 * _size(fixed))
    if model == "similarity":
        assert reg.transform_.scale == pytest.approx(1.0 / factor, rel=1e-9)


def test_a_rigid_fit_onto_a_far_smaller_fixed_set_is_reported(fish):
    """The fixed set in other units (0.01 of the moving set) under a rigid model: every fixed
    point sat on one moving point, 70 extents off, and the fit said converged."""
    with pytest.warns(CollapseWarning, match=r"explained by about 1(\.\d+)? of the 91 moving points.*other units"):
        reg = RigidCPD(scale=False).fit(fish, 0.01 * fish)
    assert not reg.converged_
    similarity = RigidCPD(scale=True).fit(fish, 0.01 * fish)  # what the advice offers
    np.testing.assert_allclose(similarity.moving_transformed_, 0.01 * fish, atol=1e-12)


def test_collapse_advice_offers_only_what_the_settings_allow(fish):
    rng = np.random.default_rng(1)
    x = np.vstack([rng.normal(0.0, 1e-3, (80, 2)), [[50.0, 0.0], [-50.0, 0.0], [0.0, 50.0], [0.0, -50.0]]])
    with pytest.warns(CollapseWarning, match=r"Try a fixed `w`, or a starting pose \(`init`\)\.$"):
        RigidCPD(w="auto", tol=1e-8).fit(fish, x)
    with pytest.warns(CollapseWarning, match=r"Try normalize=True, a smaller `w`, or a starting pose"):
        RigidCPD(w=0.1, tol=1e-8, normalize=False).fit(fish, x)


def test_identical_moving_points_onto_a_shifted_copy():
    y = np.ones((6, 2))
    with pytest.warns(UserWarning, match="spans 0 of 2 dimensions .* a rotation is not determined"):
        reg = RigidCPD().fit(y, y + [2.0, 3.0])
    np.testing.assert_allclose(reg.moving_transformed_, y + [2.0, 3.0], atol=1e-12)
    assert reg.converged_
    with pytest.warns(UserWarning, match="spans 0 of 2 dimensions"):  # one position: no linear map
        reg = AffineCPD().fit(y, y + [2.0, 3.0])
    np.testing.assert_allclose(reg.moving_transformed_, y + [2.0, 3.0], atol=1e-12)
    assert reg.converged_


@pytest.mark.parametrize("factor", [1e-120, 1e120])
def test_nonrigid_at_extreme_scales_is_finite_and_equivariant(fish_pair, factor):
    y, x = fish_pair.moving, fish_pair.fixed
    ref = NonRigidCPD(max_iter=20, tol=0).fit(y, x)
    reg = NonRigidCPD(max_iter=20, tol=0).fit(factor * y, factor * x)
    assert np.all(np.isfinite(reg.moving_transformed_)) and np.isfinite(reg.sigma2_)
    np.testing.assert_allclose(reg.moving_transformed_ / factor, ref.moving_transformed_, atol=1e-9)


def test_out_of_range_spread_is_refused(fish):
    with pytest.raises(ValueError, match="RMS radius"):
        RigidCPD().fit(fish * 1e200, fish * 1e200)


@pytest.mark.parametrize(
    "make",
    [
        lambda: RigidCPD(normalize=False),
        lambda: NonRigidCPD(max_iter=5, tol=0, normalize=False),
        lambda: MultiscaleCPD(NonRigidCPD(max_iter=5, tol=0, normalize=False), sizes=(10, 40), refine_max_iter=2),
    ],
    ids=["rigid", "nonrigid", "multiscale"],
)
def test_unnormalised_coordinates_whose_squares_overflow_are_refused(fish, make):
    # without normalize, sigma2 is a variance in the caller's units: past a span of 1e150 it
    # would be inf (a plain fit returned sigma2_ = inf; MultiscaleCPD's next level never started)
    # (in float64 each moving set below is one point, 1e300: a rank warning, rightly, for rigid)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "`moving` spans 0 of 2 dimensions", UserWarning)
        with pytest.raises(ValueError, match="absolute value with `normalize=False`"):
            make().fit(fish * 1e-6 + 1e300, fish)
        # both sets far out but close together (a small span): the coordinates' squares overflow
        # all the same (overflow warnings, then an error about a cross-covariance, before)
        with pytest.raises(ValueError, match="absolute value with `normalize=False`"):
            make().fit(fish + 1e300, fish + 1e300)
    assert np.isfinite(make().fit(fish * 1e6, fish * 1e6 + 1.0).sigma2_)


def test_gpd_is_equivariant(fish_pair):
    y, x = _on_grid(fish_pair.moving), _on_grid(fish_pair.fixed)
    ref = GPD(RigidCPD(tol=1e-9)).fit(y, x)
    reg = GPD(RigidCPD(tol=1e-9)).fit(1e4 * y + 1e7, 1e4 * x + 1e7)
    np.testing.assert_array_equal(reg.moving_centrality_, ref.moving_centrality_)
    np.testing.assert_allclose(reg.moving_transformed_, 1e4 * ref.moving_transformed_ + 1e7, atol=1e-9 * 1e4 + 1e-8)


def test_init_transform_starts_from_a_given_pose(fish, rot2):
    x = fish @ rot2(150).T + [0.3, 0.1]
    plain = RigidCPD(scale=False, tol=1e-10).fit(fish, x)
    assert np.linalg.norm(plain.moving_transformed_ - x) > 1.0  # the wrong basin
    guess = RigidTransform(rot2(130), [0.0, 0.0])
    started = RigidCPD(scale=False, tol=1e-10, init=guess).fit(fish, x)
    np.testing.assert_allclose(started.moving_transformed_, x, atol=1e-6)
    # affine and non-rigid accept a pose too; the non-rigid field then acts on init(Y)
    affine = AffineCPD(tol=1e-10, init=guess).fit(fish, x)
    np.testing.assert_allclose(affine.moving_transformed_, x, atol=1e-6)
    field = NonRigidCPD(tol=1e-8, init=guess).fit(fish, x)
    np.testing.assert_allclose(field.transform(fish), field.moving_transformed_, atol=1e-10)
    assert np.linalg.norm(field.moving_transformed_ - x) < 0.05 * np.linalg.norm(plain.moving_transformed_ - x)


def test_bad_init_and_parameters_are_named(fish):
    with pytest.raises(TypeError, match="init"):
        RigidCPD(init="nearby").fit(fish, fish)
    with pytest.raises(ValueError, match="init"):
        RigidCPD(init=RigidTransform(np.eye(3), np.zeros(3))).fit(fish, fish)
    with pytest.raises(TypeError, match="normalize"):
        RigidCPD(normalize="yes").fit(fish, fish)
    with pytest.raises(ValueError, match="beta"):
        NonRigidCPD(beta=1e-300).fit(fish, fish)
    with pytest.raises(ValueError, match="w"):
        RigidCPD(w="often").fit(fish, fish)

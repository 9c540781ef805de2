"""CPD: recovery of known transforms, agreement with pycpd, invariants and bad input."""

import warnings

import numpy as np
import pytest

from centrality_vision.exceptions import ConvergenceWarning
from centrality_vision.registration import (
    AffineCPD,
    AffineTransform,
    IterationInfo,
    NonRigidCPD,
    RigidCPD,
    RigidTransform,
    SimilarityTransform,
    alignment_error,
    initial_sigma2,
)

TIGHT = dict(tol=1e-12, max_iter=300)


# ------------------------------------------------------------------ recovery of known transforms
@pytest.mark.parametrize("scale", [False, True])
def test_rigid_and_similarity_recovered_on_the_fish(fish, rot2, scale):
    rng = np.random.default_rng(10)
    r, s, t = rot2(40), (1.0 if not scale else 0.7), rng.normal(size=2)
    x = s * fish @ r.T + t
    reg = RigidCPD(scale=scale, **TIGHT).fit(fish, x)
    assert reg.converged_
    assert isinstance(reg.transform_, RigidTransform if not scale else SimilarityTransform)
    np.testing.assert_allclose(reg.transform_.rotation, r, atol=1e-6)
    np.testing.assert_allclose(reg.transform_.translation, t, atol=1e-6)
    assert reg.transform_.scale == pytest.approx(s, abs=1e-6)
    np.testing.assert_allclose(reg.moving_transformed_, x, atol=1e-6)


@pytest.mark.parametrize("scale", [False, True])
def test_rigid_and_similarity_recovered_on_the_3d_face(face, rot3, scale):
    r, s, t = rot3(35, [1, 2, 0.5]), (1.0 if not scale else 1.4), np.array([0.3, -0.2, 0.5])
    x = s * face @ r.T + t
    reg = RigidCPD(scale=scale, **TIGHT).fit(face, x)
    np.testing.assert_allclose(reg.transform_.rotation, r, atol=1e-6)
    np.testing.assert_allclose(reg.transform_.translation, t, atol=1e-6)
    assert reg.transform_.scale == pytest.approx(s, abs=1e-6)


@pytest.mark.parametrize("which", ["fish", "face"])
def test_affine_recovered_in_2d_and_3d(fish, face, which):
    y = fish if which == "fish" else face
    d = y.shape[1]
    rng = np.random.default_rng(11)
    a = np.eye(d) + 0.2 * rng.normal(size=(d, d))
    t = rng.normal(size=d)
    x = y @ a.T + t
    reg = AffineCPD(**TIGHT).fit(y, x)
    assert isinstance(reg.transform_, AffineTransform)
    np.testing.assert_allclose(reg.transform_.linear, a, atol=1e-6)
    np.testing.assert_allclose(reg.transform_.translation, t, atol=1e-6)


def test_outliers_and_missing_points_with_w(fish, rot2):
    rng = np.random.default_rng(12)
    r = rot2(25)
    x = fish[10:] @ r.T + 0.4  # nine points missing
    x = np.vstack([x, rng.uniform(-2, 2, size=(15, 2))])  # fifteen outliers
    reg = RigidCPD(scale=False, w=0.2, tol=1e-10).fit(fish, x)
    np.testing.assert_allclose(reg.transform_.rotation, r, atol=2e-2)
    assert alignment_error(fish @ r.T + 0.4, reg.moving_transformed_) / np.sqrt(len(fish)) < 0.02


def test_fitted_transform_applies_to_new_points(fish, rot2):
    x = 1.2 * fish @ rot2(20).T + 1.0
    reg = RigidCPD(tol=1e-10).fit(fish[:60], x[:60])
    np.testing.assert_allclose(reg.transform(fish[60:]), x[60:], atol=1e-6)


# ------------------------------------------------------------------ against pycpd
@pytest.mark.parametrize("kind", ["rigid", "affine", "nonrigid"])
@pytest.mark.parametrize("w", [0.0, 0.1])
def test_same_iterates_as_pycpd_at_matched_settings(fish_pair, rot2, kind, w):
    pycpd = pytest.importorskip("pycpd")
    y = fish_pair.moving
    # the second fish (not an exact copy: pycpd divides by zero once sigma2 reaches 0)
    x = 1.3 * fish_pair.fixed @ rot2(30).T + [0.5, -0.3] if kind != "nonrigid" else fish_pair.fixed
    iterations = 25
    if kind == "rigid":
        theirs = pycpd.RigidRegistration(X=x, Y=y, max_iterations=iterations, tolerance=0.0, w=w)
        ours = RigidCPD(scale=True, w=w, max_iter=iterations, tol=0.0, normalize=False)
    elif kind == "affine":
        theirs = pycpd.AffineRegistration(X=x, Y=y, max_iterations=iterations, tolerance=0.0, w=w)
        ours = AffineCPD(w=w, max_iter=iterations, tol=0.0, normalize=False)
    else:
        theirs = pycpd.DeformableRegistration(
            X=x, Y=y, max_iterations=iterations, tolerance=0.0, w=w, alpha=2.0, beta=2.0
        )
        ours = NonRigidCPD(beta=2.0, lam=2.0, low_rank=None, w=w, max_iter=iterations, tol=0.0, normalize=False)
    ty, _ = theirs.register()
    ours.fit(y, x)
    assert ours.n_iter_ == theirs.iteration == iterations
    np.testing.assert_allclose(ours.moving_transformed_, ty, atol=1e-6)
    assert ours.sigma2_ == pytest.approx(theirs.sigma2, rel=1e-6)


def test_nonrigid_fish_reaches_pycpd_accuracy(fish_pair):
    pycpd = pytest.importorskip("pycpd")
    y, x = fish_pair.moving, fish_pair.fixed
    theirs = pycpd.DeformableRegistration(X=x, Y=y, alpha=2.0, beta=2.0, max_iterations=150, tolerance=1e-8)
    ty, _ = theirs.register()
    ours = NonRigidCPD(beta=2.0, lam=2.0, tol=1e-8, max_iter=150).fit(y, x)

    def mean_nearest(points):
        return np.sqrt(((points[:, None] - x[None]) ** 2).sum(-1).min(1)).mean()

    assert mean_nearest(ours.moving_transformed_) <= mean_nearest(ty) * 1.01 + 1e-9
    assert mean_nearest(ours.moving_transformed_) < 0.05 * mean_nearest(y)


# ------------------------------------------------------------------ non-rigid specifics
def test_low_rank_kernel_converges_to_the_exact_solution(fish_pair):
    y, x = fish_pair.moving, fish_pair.fixed
    exact = NonRigidCPD(beta=2.0, lam=2.0, low_rank=None, max_iter=30, tol=0).fit(y, x)
    # a Gaussian kernel of width 2 on the fish has a fast-decaying spectrum
    approx = NonRigidCPD(beta=2.0, lam=2.0, low_rank=40, max_iter=30, tol=0).fit(y, x)
    with pytest.warns(ConvergenceWarning, match=r"`low_rank=5`: the 5 eigenpairs kept leave .* of the kernel's trace"):
        coarse = NonRigidCPD(beta=2.0, lam=2.0, low_rank=5, max_iter=30, tol=0).fit(y, x)
    err40 = np.abs(approx.moving_transformed_ - exact.moving_transformed_).max()
    err5 = np.abs(coarse.moving_transformed_ - exact.moving_transformed_).max()
    assert err40 < 1e-6 < err5
    # the fitted transform moves the moving points exactly as the fit did, at any rank
    # (weights projected on the kept eigenvectors matched only up to the rest of G: 0.047
    # of a 0.05 displacement at rank 10 of 60 points, found by a fuzz run)
    for fitted in (approx, coarse):
        np.testing.assert_allclose(fitted.transform(y), fitted.moving_transformed_, rtol=0, atol=1e-10)


def test_low_rank_auto_solves_a_narrow_kernel_exactly_up_to_5000_points():
    # at beta 0.3, 50 eigenpairs of 600 points left 6% of G's trace out and the fit differed
    rng = np.random.default_rng(0)
    y = rng.random((600, 2))
    x = y + 0.05 * np.sin(6 * y[:, ::-1])
    auto = NonRigidCPD(beta=0.3, max_iter=20, tol=0).fit(y, x)
    exact = NonRigidCPD(beta=0.3, max_iter=20, tol=0, low_rank=None).fit(y, x)
    np.testing.assert_allclose(auto.moving_transformed_, exact.moving_transformed_, rtol=0, atol=1e-10)


def test_low_rank_auto_says_when_its_exact_fallback_is_slow():
    """Above 2,000 points the exact fallback solves an M x M system at every step (4,500 points:
    65 s for 60 steps, without a word); a fit that asked for it is quiet (and a smaller one:
    the 600-point test above runs with warnings as errors)."""
    rng = np.random.default_rng(1)
    y = rng.random((2100, 2))
    with pytest.warns(UserWarning, match=r"`beta=0.1` is too narrow .* exact 2,100 x 2,100 system at every EM step"):
        NonRigidCPD(beta=0.1, max_iter=1, tol=0).fit(y, y + 0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        NonRigidCPD(beta=0.1, max_iter=1, tol=0, low_rank=None).fit(y, y + 0.01)


def test_nonrigid_transform_moves_the_moving_points_like_the_fit(fish_pair):
    y, x = fish_pair.moving, fish_pair.fixed
    reg = NonRigidCPD(beta=2.0, lam=2.0, tol=1e-6).fit(y, x)
    np.testing.assert_allclose(reg.transform(y), reg.moving_transformed_, atol=1e-10)
    # the field is smooth: a point between two moving points moves like them
    mid = (y[:1] + y[1:2]) / 2
    moved = reg.transform(mid)
    assert np.linalg.norm(moved - (reg.moving_transformed_[0] + reg.moving_transformed_[1]) / 2) < 0.05


def test_objective_includes_the_regulariser(fish_pair):
    y, x = fish_pair.moving, fish_pair.fixed
    reg = NonRigidCPD(beta=2.0, lam=2.0, max_iter=5, tol=0).fit(y, x)
    from centrality_vision.registration._estep import _e_step

    post = _e_step(reg.moving_transformed_, x, reg.sigma2_, 0.0)
    assert reg.history_["objective"][-1] > post.neg_log_likelihood


# ------------------------------------------------------------------ invariants
def test_negative_log_likelihood_never_increases_for_rigid_em(fish_pair):
    reg = RigidCPD(w=0.1, tol=0, max_iter=60).fit(fish_pair.moving, fish_pair.fixed)
    objective = reg.history_["objective"]
    assert np.all(np.diff(objective) <= 1e-9 * np.abs(objective[1:]))


def test_truncated_and_dense_paths_give_the_same_registration(fish, rot2):
    x = 1.1 * fish @ rot2(30).T + 0.2
    dense = RigidCPD(method="dense", tol=1e-9).fit(fish, x)
    trunc = RigidCPD(method="truncated", tol=1e-9).fit(fish, x)
    assert dense.n_iter_ == trunc.n_iter_
    np.testing.assert_allclose(trunc.moving_transformed_, dense.moving_transformed_, atol=1e-10)
    assert set(trunc.history_["method"]) == {"truncated"}


def test_history_has_one_entry_per_state(fish, rot2):
    x = fish @ rot2(30).T
    reg = RigidCPD(tol=1e-6).fit(fish, x, true_moving=x)
    for key in ("objective", "sigma2", "error"):
        assert len(reg.history_[key]) == reg.n_iter_ + 1
    start = fish - fish.mean(0) + x.mean(0)  # normalize=True starts with the centroids aligned
    assert reg.history_["error"][0] == pytest.approx(alignment_error(x, start))
    assert reg.history_["error"][-1] == pytest.approx(alignment_error(x, reg.moving_transformed_))
    assert reg.history_["sigma2"][0] == pytest.approx(initial_sigma2(start, x))
    raw = RigidCPD(tol=1e-6, normalize=False).fit(fish, x)
    assert raw.history_["sigma2"][0] == pytest.approx(initial_sigma2(fish, x))


def test_correspondence_recovers_a_permutation(fish, rot2):
    perm = np.random.default_rng(13).permutation(len(fish))
    x = (fish @ rot2(20).T)[perm]
    reg = RigidCPD(tol=1e-10).fit(fish, x)
    np.testing.assert_array_equal(reg.fixed_to_moving_, perm)
    with pytest.warns(FutureWarning, match="fixed_to_moving_"):
        np.testing.assert_array_equal(reg.correspondence_, perm)


def test_posterior_matrix_matches_the_statistics(fish, rot2):
    x = fish @ rot2(20).T
    reg = RigidCPD(w=0.1, max_iter=5, tol=0).fit(fish, x)
    p = reg.posterior()
    assert p.shape == (len(fish), len(x))
    np.testing.assert_allclose(p.sum(1), reg.posteriors_.p1, atol=1e-12)
    np.testing.assert_allclose(p.sum(0), reg.posteriors_.pt1, atol=1e-12)


def test_identical_sets_converge_to_the_identity_without_nan(fish):
    reg = RigidCPD().fit(fish, fish)
    assert reg.converged_ and np.isfinite(reg.sigma2_)
    np.testing.assert_allclose(reg.moving_transformed_, fish, atol=1e-8)
    reg = NonRigidCPD(beta=1.0, lam=1.0).fit(fish, fish)
    assert reg.converged_ and np.all(np.isfinite(reg.moving_transformed_))


def test_one_point_sets_translate():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        with pytest.warns(UserWarning, match=r"spans 0 of 2 dimensions \(1 point\): a rotation is not determined"):
            reg = RigidCPD().fit([[0.0, 0.0]], [[1.0, 2.0]])
        np.testing.assert_allclose(reg.moving_transformed_, [[1.0, 2.0]], atol=1e-12)
        with pytest.warns(UserWarning, match="spans 0 of 2 dimensions"):  # its linear part is not determined
            reg = AffineCPD().fit([[0.0, 0.0]], [[1.0, 2.0]])
        np.testing.assert_allclose(reg.moving_transformed_, [[1.0, 2.0]], atol=1e-12)
    with pytest.warns(UserWarning, match="a rotation is not determined"):
        reg = RigidCPD().fit([[0.0, 0.0]], [[1.0, 2.0], [3.0, 2.0]])
    np.testing.assert_allclose(reg.moving_transformed_, [[2.0, 2.0]], atol=1e-12)


def test_tiny_initial_sigma2_gives_a_finite_answer(fish, rot2):
    x = fish @ rot2(5).T
    reg = RigidCPD(sigma2=1e-300, tol=1e-8).fit(fish, x)
    assert np.all(np.isfinite(reg.moving_transformed_)) and np.isfinite(reg.sigma2_)
    np.testing.assert_allclose(reg.moving_transformed_, x, atol=1e-10)  # (and the right one)


def test_inputs_are_not_modified(fish, rot2):
    y = fish.copy()
    x = fish @ rot2(10).T
    x_copy = x.copy()
    for reg in (RigidCPD(max_iter=3, tol=0), AffineCPD(max_iter=3, tol=0), NonRigidCPD(max_iter=3, tol=0)):
        reg.fit(y, x, true_moving=x)
        np.testing.assert_array_equal(y, fish)
        np.testing.assert_array_equal(x, x_copy)


def test_callback_sees_every_state_and_can_stop(fish, rot2):
    x = fish @ rot2(30).T
    seen = []
    reg = RigidCPD(tol=1e-8, callback=seen.append).fit(fish, x)
    assert [info.iteration for info in seen] == list(range(reg.n_iter_ + 1))
    assert isinstance(seen[0], IterationInfo) and seen[0].error is None
    reg = RigidCPD(tol=1e-8, callback=lambda info: info.iteration == 3).fit(fish, x)
    assert reg.n_iter_ == 3 and not reg.converged_


def test_convergence_warning_at_max_iter(fish, rot2):
    with pytest.warns(ConvergenceWarning, match="max_iter=2"):
        reg = RigidCPD(max_iter=2).fit(fish, fish @ rot2(40).T)
    assert reg.n_iter_ == 2 and not reg.converged_


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(w=1.0), "w"),
        (dict(w=-0.1), "w"),
        (dict(tol=-1.0), "tol"),
        (dict(max_iter=-1), "max_iter"),
        (dict(sigma2=0.0), "sigma2"),
        (dict(method="fast"), "method"),
    ],
)
def test_bad_parameters_are_named(fish, kwargs, match):
    with pytest.raises(ValueError, match=match):
        RigidCPD(**kwargs).fit(fish, fish)


def test_bad_types_are_named(fish):
    with pytest.raises(TypeError, match="scale"):
        RigidCPD(scale="yes").fit(fish, fish)
    with pytest.raises(TypeError, match="callback"):
        RigidCPD(callback=3).fit(fish, fish)
    with pytest.raises(TypeError, match="max_iter"):
        RigidCPD(max_iter=2.5).fit(fish, fish)
    with pytest.raises(ValueError, match="beta"):
        NonRigidCPD(beta=0).fit(fish, fish)
    with pytest.raises(ValueError, match="lam"):
        NonRigidCPD(lam=-1).fit(fish, fish)
    with pytest.raises(ValueError, match="low_rank"):
        NonRigidCPD(low_rank=0).fit(fish, fish)


def test_bad_point_sets(fish):
    bad = fish.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="`moving` must be finite"):
        RigidCPD().fit(bad, fish)
    with pytest.raises(ValueError, match="`fixed` must be finite"):
        RigidCPD().fit(fish, bad)
    with pytest.raises(ValueError, match="same number of dimensions"):
        RigidCPD().fit(fish, np.zeros((5, 3)))
    with pytest.raises(ValueError, match="true_moving"):
        RigidCPD().fit(fish, fish, true_moving=fish[:5])
    with pytest.raises(ValueError, match="at least 1 point;"):
        RigidCPD().fit(np.zeros((0, 2)), fish)
    with pytest.raises(ValueError, match="not fitted"):
        RigidCPD().transform(fish)
    with pytest.raises(ValueError, match="not fitted"):
        RigidCPD().posterior()


def test_repr_lists_changed_parameters():
    assert repr(RigidCPD(w=0.1)) == "RigidCPD(w=0.1)"
    assert repr(NonRigidCPD(beta=3.0)) == "NonRigidCPD(beta=3.0)"

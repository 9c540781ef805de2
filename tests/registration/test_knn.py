"""n_neighbors: the k-nearest-neighbour E-step (each moving point explains only its k nearest fixed points)."""

import math

import numpy as np
import pytest

from centrality_vision.exceptions import InputError
from centrality_vision.registration import GPD, NonRigidCPD, RigidCPD
from centrality_vision.registration._estep import CentralityPrior, _e_step, knn_posterior, knn_posterior_matrix

MOVING = np.array([[0.0, 0.0], [1.0, 0.0]])
FIXED = np.array([[0.0, 0.5], [1.0, 0.5], [5.0, 5.0]])


def test_one_neighbour_by_hand():
    # m0's nearest fixed point is f0, m1's is f1; f2 = (5, 5) is nobody's neighbour
    post = knn_posterior(MOVING, FIXED, 1.0, 0.0, k=1)
    np.testing.assert_array_equal(post.p1, [1.0, 1.0])
    np.testing.assert_array_equal(post.pt1, [1.0, 1.0, 0.0])
    np.testing.assert_allclose(post.px, [[0.0, 0.5], [1.0, 0.5]])
    assert post.n_p == 2.0
    np.testing.assert_array_equal(post.best, [0, 1, -1])
    # objective: f0 and f1 at d^2 = 1/4 (term -1/8 each); f2 by its nearest moving point (1, 0), d^2 = 41
    assert post.neg_log_likelihood == pytest.approx(0.125 + 0.125 + 20.5, rel=1e-14)


def test_two_neighbours_by_hand():
    # both moving points have f0 and f1 as their 2 nearest: each of f0, f1 is shared by both
    post = knn_posterior(MOVING, FIXED, 1.0, 0.0, k=2)
    near = 1.0 / (1.0 + math.exp(-0.5))  # exp(-1/8) / (exp(-1/8) + exp(-5/8))
    p = knn_posterior_matrix(MOVING, FIXED, 1.0, 0.0, k=2)
    np.testing.assert_allclose(p, [[near, 1 - near, 0.0], [1 - near, near, 0.0]], rtol=1e-14)
    np.testing.assert_allclose(post.p1, p.sum(1), rtol=1e-14)
    np.testing.assert_allclose(post.px, p @ FIXED, rtol=1e-14)


def test_outlier_term_by_hand():
    # w > 0 adds c = (2 pi sigma2)^(D/2) w/(1-w) M/N to each claimed column's denominator
    w = 0.2
    for sigma2, best in ((0.1, [0, 1, -1]), (1.0, [-1, -1, -1])):
        c = 2 * math.pi * sigma2 * (w / (1 - w)) * (2 / 3)
        e = math.exp(-0.25 / (2 * sigma2))
        post = knn_posterior(MOVING, FIXED, sigma2, w, k=1)
        np.testing.assert_allclose(post.pt1, [e / (e + c), e / (e + c), 0.0], rtol=1e-14)
        assert post.best.tolist() == best  # the moving point wins where e > c (0.287 > 0.105; 0.882 < 1.047)


@pytest.mark.parametrize("w", [0.0, 0.3])
@pytest.mark.parametrize("with_prior", [False, True])
def test_all_neighbours_is_the_dense_e_step(w, with_prior):
    rng = np.random.default_rng(3)
    moving, fixed = rng.random((30, 2)), rng.random((25, 2))
    prior = (
        CentralityPrior(np.log(rng.uniform(0.1, 1, 30)), rng.random(30), rng.random(25), 2.5, 1.0)
        if with_prior
        else None
    )
    dense = _e_step(moving, fixed, 0.05, w, prior, method="dense")
    knn = knn_posterior(moving, fixed, 0.05, w, prior, k=25)
    np.testing.assert_allclose(knn.p1, dense.p1, atol=1e-13)
    np.testing.assert_allclose(knn.pt1, dense.pt1, atol=1e-13)
    np.testing.assert_allclose(knn.px, dense.px, atol=1e-13)
    assert knn.neg_log_likelihood == pytest.approx(dense.neg_log_likelihood, rel=1e-12)
    np.testing.assert_array_equal(knn.best, dense.best)
    # and a fit with n_neighbors >= N is the dense fit
    a = RigidCPD(w=w, tol=1e-10).fit(moving, fixed)
    b = RigidCPD(w=w, tol=1e-10, n_neighbors=100, normalize=False).fit(moving, fixed)
    c = RigidCPD(w=w, tol=1e-10, normalize=False).fit(moving, fixed)
    np.testing.assert_allclose(b.moving_transformed_, c.moving_transformed_, atol=1e-9)
    assert a.n_iter_ > 0


def test_far_clutter_is_ignored(fish, rot2):
    # a dense cluster of 91 clutter points away from the shape pulls dense CPD (w=0) off;
    # with 10 neighbours no moving point claims it, whatever w
    rng = np.random.default_rng(5)
    x = fish @ rot2(10).T + 0.1
    clutter = rng.normal(size=(91, 2)) * 0.1 + x.max(0) + 1.0
    fixed = np.vstack([x, clutter])
    knn = RigidCPD(scale=False, tol=1e-10, n_neighbors=10).fit(fish, fixed)
    dense = RigidCPD(scale=False, tol=1e-10).fit(fish, fixed)
    np.testing.assert_allclose(knn.moving_transformed_, x, atol=1e-6)
    assert np.abs(dense.moving_transformed_ - x).max() > 0.05
    assert knn.posteriors_.pt1[len(x) :].max() == 0.0
    np.testing.assert_array_equal(knn.fixed_to_moving_[len(x) :], -1)
    p = knn.posterior()
    np.testing.assert_allclose(p.sum(1), knn.posteriors_.p1, atol=1e-12)


def test_units_and_start_pose(fish_pair):
    # equivariant under a common scale and offset; the start is the caller's pose (not
    # "centroids aligned"), so a set with a missing part is not shifted before EM starts
    y, x = fish_pair.moving, fish_pair.fixed[15:]
    a = NonRigidCPD(n_neighbors=8, tol=1e-8).fit(y, x)
    b = NonRigidCPD(n_neighbors=8, tol=1e-8).fit(1e3 * y + 5e5, 1e3 * x + 5e5)
    np.testing.assert_allclose((b.moving_transformed_ - 5e5) / 1e3, a.moving_transformed_, atol=1e-8)
    seen = []
    NonRigidCPD(n_neighbors=8, callback=lambda info: seen.append(info.moving_transformed) or True).fit(y, x)
    np.testing.assert_allclose(seen[0], y, atol=1e-12)


def test_gpd_over_the_knn_model(fish, rot2):
    x = fish @ rot2(20).T
    gpd = GPD(RigidCPD(scale=False, tol=1e-10, n_neighbors=10)).fit(fish, x)
    np.testing.assert_allclose(gpd.moving_transformed_, x, atol=1e-6)


@pytest.mark.parametrize("bad", [0, -3, 2.5, "ten", True])
def test_bad_n_neighbors(fish, bad):
    with pytest.raises((InputError, TypeError), match="n_neighbors"):
        RigidCPD(n_neighbors=bad).fit(fish, fish)


def test_n_neighbors_refuses_another_e_step_path(fish):
    with pytest.raises(InputError, match="n_neighbors"):
        RigidCPD(n_neighbors=10, method="fgt").fit(fish, fish)


def test_the_frame_is_the_moving_sets_so_clutter_does_not_widen_beta(fish_pair):
    # Under n_neighbors the unit of beta is the moving set's RMS radius: clutter far away
    # from the shape (nobody's neighbour) leaves the fit unchanged, while the frame of the
    # dense model (both sets' radius) grows with it.
    from centrality_vision.registration._cpd import _Frame

    y, x = fish_pair.moving, fish_pair.fixed
    rng = np.random.default_rng(3)
    clutter = rng.uniform(-1.0, 1.0, (200, 2)) * 40.0 + [60.0, 0.0]
    cluttered = np.vstack([x, clutter])
    radius = math.sqrt(np.mean(np.sum((y - y.mean(0)) ** 2, axis=1)))
    for fixed in (x, cluttered):
        frame, moving_n, _ = _Frame.of(y, fixed, True, same_centre=True, moving_scale=True)
        assert frame.scale == pytest.approx(radius, rel=1e-12)
    pooled, _, _ = _Frame.of(y, cluttered, True, same_centre=True)
    assert pooled.scale > 5 * radius
    a = NonRigidCPD(n_neighbors=8, tol=1e-9).fit(y, x)
    b = NonRigidCPD(n_neighbors=8, tol=1e-9).fit(y, cluttered[rng.permutation(len(cluttered))])
    # the clutter moves the fixed set's mean, so the start differs by that shift only
    shift = cluttered.mean(0) - x.mean(0)
    assert np.linalg.norm(shift) > 10
    np.testing.assert_allclose(b.moving_transformed_, a.moving_transformed_, atol=1e-4)


def test_moving_frame_falls_back_to_both_sets_radius():
    from centrality_vision.registration._cpd import _Frame

    one_point = np.zeros((5, 2))
    fixed = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])
    frame, _, _ = _Frame.of(one_point, fixed, True, same_centre=True, moving_scale=True)
    assert frame.scale > 0 and np.isfinite(frame.scale)
    tiny = np.array([[0.0, 0.0], [1e-9, 0.0], [0.0, 1e-9]])
    frame, moving_n, fixed_n = _Frame.of(tiny, fixed * 1e9, True, same_centre=True, moving_scale=True)
    assert np.all(np.abs(fixed_n) < 10) and np.all(np.isfinite(moving_n))

"""Registration options at the edges of float64 (a fuzz round's findings): named errors, not
overflow warnings, garbage fits reported as converged, or calls that fail inside."""

import warnings

import numpy as np
import pytest

from centrality_vision.exceptions import ConvergenceWarning
from centrality_vision.registration import GPD, AffineCPD, NonRigidCPD, RigidCPD

MOVING = np.random.default_rng(0).random((20, 2))
FIXED = MOVING + 0.01


@pytest.fixture(autouse=True)
def _strict():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", ConvergenceWarning)
        yield


def test_landmark_weight_is_bounded_where_the_fit_stays_accurate():
    # 1e100 gave a scale of 3.6e16 reported as converged; the pinned residual grows as the
    # weight times the rounding
    with pytest.raises(ValueError, match=r"`RigidCPD.landmark_weight` must be a finite number in \(0, 1e\+06\]"):
        RigidCPD(landmark_weight=1e100).fit(MOVING, FIXED, landmarks=[[0, 0]])
    fit = RigidCPD(landmark_weight=1e6, tol=1e-10).fit(MOVING, FIXED, landmarks=[[0, 0]])
    assert np.abs(fit.moving_transformed_ - FIXED).max() < 1e-9


@pytest.mark.parametrize(
    "make",
    [
        lambda: RigidCPD(sigma2=1e300),
        lambda: RigidCPD(sigma2=1e300, accelerate=True),
        lambda: NonRigidCPD(sigma2=1e300),
    ],
)
def test_a_sigma2_far_beyond_the_data_is_a_named_error(make):
    # it overflowed the history's units and SQUAREM's norms (RuntimeWarning)
    with pytest.raises(ValueError, match=r"\.sigma2` must be at most 1e\+10 times the sets' own spread"):
        make().fit(1e6 * MOVING, 1e6 * FIXED)


def test_a_large_given_sigma2_still_works_and_far_apart_raw_sets_are_not_refused():
    assert RigidCPD(sigma2=1e9).fit(MOVING, FIXED).n_iter_ >= 1
    # (the bound is on a given sigma2 only: the default one of sets 1e6 apart is 1e12 x their spread)
    assert RigidCPD(normalize=False).fit(MOVING, FIXED + 1e6).n_iter_ >= 1


def test_affine_cpd_near_float_max_is_refused_by_name():
    # its rank check took the mean of coordinates near 1e308 first: an overflow warning
    with pytest.raises(ValueError, match=r"RMS radius between 1e-145 and 1e\+145"):
        AffineCPD().fit(1e308 * MOVING, MOVING)


@pytest.mark.parametrize("centrality", ["degree", "eigenvector", "pagerank", "katz"])
def test_gpd_weights_apply_to_path_centralities_only(centrality):
    # degree and eigenvector raised a DeprecationWarning from inside, PageRank and Katz a
    # TypeError about an option the user never passed
    with pytest.raises(ValueError, match=r"`weights=True` \(shortest paths by edge length\) applies to betweenness"):
        GPD(RigidCPD(), centrality=centrality, weights=True).fit(MOVING, FIXED)
    assert GPD(RigidCPD(), centrality="closeness", weights=True).fit(MOVING, FIXED).estimator_.n_iter_ >= 1


def test_the_dense_kernel_keeps_its_digits_far_from_the_origin_and_at_tiny_beta():
    # |a|^2 + |b|^2 - 2 a.b cancelled: transform_ and moving_transformed_ disagreed by 3.2 at an
    # offset of 1e8 (normalize=False) and by 0.65 with beta=1e-8, where the kernel's diagonal
    # came out exp(-0.5) instead of 1
    from centrality_vision.registration._mstep import gaussian_kernel

    points = np.random.default_rng(0).random((50, 2)) * 3
    for offset in (0.0, 1e8):
        shifted = points + offset  # (rounded to 1.5e-8 at 1e8: the reference takes the same points)
        kernel = gaussian_kernel(shifted, shifted, 1.0)
        direct = np.exp(-(((shifted[:, None] - shifted[None]) ** 2).sum(-1)) / 2.0)
        np.testing.assert_allclose(kernel, direct, rtol=1e-12, atol=1e-300)
    np.testing.assert_array_equal(np.diag(gaussian_kernel(points, points, 1e-8)), 1.0)
    bent = points + 0.1 * np.sin(points[:, ::-1])
    fit = NonRigidCPD(normalize=False, beta=1.0, low_rank=None, tol=1e-8).fit(points + 1e8, bent + 1e8)
    np.testing.assert_allclose(fit.transform_(points + 1e8), fit.moving_transformed_, rtol=0, atol=1e-6)
    tiny = NonRigidCPD(beta=1e-8, low_rank=None).fit(points, points + 0.01)
    np.testing.assert_allclose(tiny.transform_(points), tiny.moving_transformed_, rtol=0, atol=1e-12)


def test_a_one_point_moving_set_has_no_scale_or_linear_part_under_the_knn_frame():
    # the k-NN frame centres the moving set on the fixed set's mean: its spread about its own
    # weighted mean was rounding noise, and the M-step divided by it (scale 8.3e15, affine
    # linear part 1.6e7 at an offset of -1e8)
    moving = np.repeat([[0.2063360661024647, 0.8318022863330304]], 5, axis=0)
    fixed = np.random.default_rng(3).random((5, 2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (AffineCPD: the moving set spans 0 dimensions)
        rigid = RigidCPD(w="auto", n_neighbors=5).fit(moving, fixed)
        affine = AffineCPD(n_neighbors=5).fit(moving - 1e8, fixed - 1e8)
    assert rigid.transform_.scale == 1.0
    np.testing.assert_array_equal(affine.transform_.linear, 0.0)
    for fit, start in ((rigid, moving), (affine, moving - 1e8)):
        np.testing.assert_allclose(fit.transform_(start), fit.moving_transformed_, rtol=0, atol=1e-6)

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
    with pytest.raises(ValueError, match=r"`RigidCPD.landmark_weight` must be a finite number in \(0.0, 1000000.0\]"):
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

import numpy as np
import pytest

from centrality_vision.registration import ICP, RigidTransform, SimilarityTransform


def test_icp_recovers_a_small_rigid_motion(fish, rot2):
    x = fish @ rot2(8).T + [0.05, -0.02]
    icp = ICP(tol=1e-12).fit(fish, x, true_moving=x)
    assert icp.converged_ and isinstance(icp.transform_, RigidTransform)
    np.testing.assert_allclose(icp.moving_transformed_, x, atol=1e-10)
    np.testing.assert_array_equal(icp.correspondence_, np.arange(len(fish)))
    assert icp.history_["error"][-1] < 1e-9 < icp.history_["error"][0]


def test_icp_with_scale(face, rot3):
    x = 1.05 * face @ rot3(4, [0, 0, 1]).T + 0.01
    icp = ICP(scale=True, tol=1e-14, max_iter=200).fit(face, x)
    assert isinstance(icp.transform_, SimilarityTransform)
    assert icp.transform_.scale == pytest.approx(1.05, abs=1e-8)


def test_icp_objective_never_increases(fish_pair):
    icp = ICP(max_iter=50, tol=0).fit(fish_pair.moving, fish_pair.fixed)
    obj = icp.history_["objective"]
    assert np.all(np.diff(obj) <= 1e-12)


def test_icp_bad_input(fish):
    with pytest.raises(TypeError, match="scale"):
        ICP(scale=1).fit(fish, fish)
    with pytest.raises(ValueError, match="tol"):
        ICP(tol=-1).fit(fish, fish)
    with pytest.raises(ValueError, match="`fixed` must have shape"):
        ICP().fit(fish, np.zeros((4, 3)))
    with pytest.raises(ValueError, match="not fitted"):
        ICP().transform(fish)

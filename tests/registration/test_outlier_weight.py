"""w='auto': the outlier fraction estimated by EM, and its effect on the registration."""

import numpy as np
import pytest

from centrality_vision.registration import GPD, NonRigidCPD, RigidCPD


def _angle(rotation):
    return float(np.degrees(np.arctan2(rotation[1, 0], rotation[0, 0])))


@pytest.mark.parametrize(("n_outliers", "n_missing"), [(0, 0), (18, 0), (45, 10), (91, 20)])
def test_auto_w_estimates_the_outlier_fraction_and_registers(fish, rot2, n_outliers, n_missing):
    rng = np.random.default_rng(7)
    x = (fish @ rot2(30).T + 0.2)[n_missing:]
    x = np.vstack([x, rng.uniform(x.min(0) - 0.5, x.max(0) + 0.5, (n_outliers, 2))])
    auto = RigidCPD(scale=False, w="auto", tol=1e-9).fit(fish, x)
    assert auto.w_ == pytest.approx(n_outliers / len(x), abs=0.01)
    assert abs(_angle(auto.transform_.rotation) - 30) < 1e-3
    np.testing.assert_allclose(auto.history_["w"][0], 0.1)
    if n_outliers:
        fixed_w = RigidCPD(scale=False, w=0.0, tol=1e-9).fit(fish, x)
        assert abs(_angle(fixed_w.transform_.rotation) - 30) > 1.0  # w=0 is pulled off by the clutter


def test_auto_w_nonrigid_and_through_gpd(fish_pair, fish, rot2):
    y, x = fish_pair.moving, fish_pair.fixed
    rng = np.random.default_rng(8)
    cluttered = np.vstack([x, rng.uniform(x.min(0), x.max(0), (30, 2))])
    reg = NonRigidCPD(w="auto").fit(y, cluttered)
    assert reg.w_ == pytest.approx(30 / 121, abs=0.01)
    # GPD forwards it (estimated from CPD's posterior); on rigid data it is as exact as CPD's
    rigid = np.vstack([fish @ rot2(30).T, rng.uniform(-1.5, 1.5, (30, 2))])
    gpd = GPD(RigidCPD(w="auto", scale=False, tol=1e-9)).fit(fish, rigid)
    assert gpd.w_ == gpd.estimator_.w_ == pytest.approx(30 / 121, abs=0.01)
    assert abs(_angle(gpd.transform_.rotation) - 30) < 1e-3
    p = gpd.posterior()
    np.testing.assert_allclose(p.sum(0), gpd.posteriors_.pt1, atol=1e-12)

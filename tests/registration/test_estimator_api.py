"""The registration estimators as scikit-learn estimators; names and errors of issue 15."""

import numpy as np
import pytest
from scipy import sparse
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.model_selection import GridSearchCV

from centrality_vision.registration import GPD, ICP, AffineCPD, MultiscaleCPD, NonRigidCPD, RigidCPD

ESTIMATORS = [
    RigidCPD(scale=False, w=0.1),
    AffineCPD(max_iter=7),
    NonRigidCPD(beta=1.5),
    ICP(max_iter=5),
    GPD(RigidCPD(w=0.05), graph_neighbors=4),
    MultiscaleCPD(RigidCPD(w=0.05), sizes=(50, 80)),
]


@pytest.mark.parametrize("estimator", ESTIMATORS, ids=lambda e: type(e).__name__)
def test_clone_get_and_set_params(estimator):
    copy = clone(estimator)
    assert type(copy) is type(estimator) and copy is not estimator
    assert repr(copy) == repr(estimator)
    params = estimator.get_params(deep=True)
    # a meta-estimator's base is cloned too: a new object with the same parameters
    assert params == copy.get_params(deep=True) or type(estimator) in (GPD, MultiscaleCPD)
    first = next(iter(estimator.get_params(deep=False)))
    assert copy.set_params(**{first: params[first]}) is copy
    with pytest.raises(ValueError, match="Invalid parameter"):
        copy.set_params(nonsense=1)


def test_gpd_nested_parameters():
    gpd = GPD(RigidCPD(w=0.1))
    assert gpd.get_params(deep=True)["base_cpd__w"] == 0.1
    gpd.set_params(base_cpd__w=0.2, centrality="degree")
    assert gpd.base_cpd.w == 0.2 and gpd.centrality == "degree"
    # audit 27 F8: on the default GPD (base_cpd=None, meaning RigidCPD()) a grid search over
    # base_cpd__* raised a bare AttributeError about None
    from sklearn.base import clone

    default = GPD()
    tuned = clone(default).set_params(base_cpd__w=0.3, base_cpd__scale=False)
    assert tuned.base_cpd.w == 0.3 and tuned.base_cpd.scale is False and default.base_cpd is None
    assert GPD().set_params(base_cpd=AffineCPD(), base_cpd__w=0.1).base_cpd.get_params()["w"] == 0.1


@pytest.mark.parametrize("estimator", ESTIMATORS, ids=lambda e: type(e).__name__)
def test_one_not_fitted_error(estimator, fish):
    with pytest.raises(NotFittedError, match="not fitted"):
        estimator.transform(fish)


def test_grid_search_picks_the_outlier_weight(fish, rot2):
    # equal sizes: the clutter replaces part of the fixed set, so rows pair up for the splitter
    rng = np.random.default_rng(3)
    x = fish @ rot2(20).T + 0.1
    x[rng.choice(len(x), 20, replace=False)] = rng.uniform(-2, 2, (20, 2))
    index = np.arange(len(fish))
    search = GridSearchCV(RigidCPD(scale=False, tol=1e-8), {"w": [0.0, 0.3]}, cv=[(index, index)]).fit(fish, x)
    assert search.best_params_ == {"w": 0.3}
    assert search.best_estimator_.converged_


def test_gpd_fits_a_clone_and_reads_its_attributes(fish_pair):
    base = RigidCPD(max_iter=4, tol=0)
    gpd = GPD(base).fit(fish_pair.moving, fish_pair.fixed)
    assert gpd.estimator_ is not base and not hasattr(base, "transform_")
    assert gpd.transform_ is gpd.estimator_.transform_ and gpd.n_iter_ == 4
    with pytest.raises(AttributeError):
        _ = gpd.no_such_attribute_


def test_correspondence_names_and_deprecated_alias(fish, rot2):
    x = fish @ rot2(10).T
    reg = RigidCPD().fit(fish, x)
    assert reg.fixed_to_moving_.shape == (len(x),)
    with pytest.warns(FutureWarning, match="fixed_to_moving_"):
        np.testing.assert_array_equal(reg.correspondence_, reg.fixed_to_moving_)
    icp = ICP().fit(fish, x)
    assert icp.moving_to_fixed_.shape == (len(fish),) and icp.fixed_to_moving_.shape == (len(x),)
    with pytest.warns(FutureWarning, match="fixed_to_moving_"):
        np.testing.assert_array_equal(icp.correspondence_, icp.fixed_to_moving_)


def test_gpd_callable_graph_with_the_wrong_node_count(fish_pair):
    with pytest.raises(ValueError, match=r"graph\(points\)` must return a graph with one node per point \(91\); got 4"):
        GPD(graph=lambda p: sparse.eye(4, format="csr")).fit(fish_pair.moving, fish_pair.fixed)


@pytest.mark.parametrize("method", ["icp", "similarity"])
def test_huge_coordinates_do_not_hang_the_svd(method):
    from centrality_vision.transforms import fit_similarity

    y = np.random.default_rng(0).random((20, 3))
    y[0, 0] = 1e155
    if method == "icp":
        with pytest.raises(ValueError, match="RMS radius"):
            ICP().fit(y, y + 1.0)
    else:
        t = fit_similarity(y, y)
        assert np.all(np.isfinite(t.rotation)) and t.scale == pytest.approx(1.0)


def test_neighbour_counts_are_renamed_with_the_old_names_still_working():
    from centrality_vision.registration import estimate_normals

    rng = np.random.default_rng(5)
    surface = rng.random((120, 3)) * [1.0, 1.0, 0.05]
    with pytest.warns(FutureWarning, match=r"`k` of estimate_normals\(\) is renamed `n_neighbors`"):
        old = estimate_normals(surface, k=7)
    np.testing.assert_array_equal(old, estimate_normals(surface, n_neighbors=7))
    with pytest.raises(TypeError, match="`k` is the former name of `n_neighbors`"):
        estimate_normals(surface, k=7, n_neighbors=7)

    rot = np.array([[np.cos(0.1), -np.sin(0.1), 0], [np.sin(0.1), np.cos(0.1), 0], [0, 0, 1]])
    fixed = surface @ rot.T + 0.01
    new = ICP(metric="point_to_plane", normal_neighbors=7, tol=1e-10).fit(surface, fixed)
    with pytest.warns(FutureWarning, match="`k_normals` of ICP is renamed `normal_neighbors`"):
        old = ICP(metric="point_to_plane", k_normals=7, tol=1e-10).fit(surface, fixed)
    np.testing.assert_array_equal(old.moving_transformed_, new.moving_transformed_)
    assert not np.array_equal(
        new.moving_transformed_, ICP(metric="point_to_plane", tol=1e-10).fit(surface, fixed).moving_transformed_
    )
    with pytest.raises(TypeError, match="`ICP.k_normals` is the former name of `normal_neighbors`"):
        ICP(k_normals=7, normal_neighbors=8).fit(surface, fixed)
    with pytest.warns(FutureWarning), pytest.raises(ValueError, match=r"`ICP.k_normals` must be an int in \[3, "):
        ICP(k_normals=2).fit(surface, fixed)

    y = rng.random((40, 2))
    x = y + 0.05
    new = GPD(RigidCPD(tol=1e-8), graph="knn", graph_neighbors=3).fit(y, x)
    with pytest.warns(FutureWarning, match="`k` of GPD is renamed `graph_neighbors`"):
        old = GPD(RigidCPD(tol=1e-8), graph="knn", k=3).fit(y, x)
    assert (old.moving_graph_ != new.moving_graph_).nnz == 0
    assert new.moving_graph_.nnz != GPD(RigidCPD(tol=1e-8), graph="knn").fit(y, x).moving_graph_.nnz
    with pytest.raises(TypeError, match="`GPD.k` is the former name of `graph_neighbors`"):
        GPD(graph="knn", k=3, graph_neighbors=4).fit(y, x)
    assert clone(GPD(k=3)).get_params()["k"] == 3


def test_centrality_prior_fields_are_renamed_with_the_old_names_still_working():
    from centrality_vision.registration import CentralityPrior

    args = (np.log([0.5, 0.5]), np.array([0.0, 1.0]), np.array([0.2, 0.9, 0.4]), 2.0)
    prior = CentralityPrior(*args, strength=0.5)
    with pytest.warns(FutureWarning, match=r"`scale` of CentralityPrior\(\) is renamed `strength`"):
        old = CentralityPrior(*args, scale=0.5)
    np.testing.assert_array_equal(old.matrix(), prior.matrix())
    assert not np.array_equal(prior.matrix(), CentralityPrior(*args).matrix())
    with pytest.raises(TypeError, match="`scale` is the former name of `strength`"):
        CentralityPrior(*args, scale=0.5, strength=0.5)
    for old_name, new_name in (
        ("v_moving", "moving_centrality"),
        ("v_fixed", "fixed_centrality"),
        ("scale", "strength"),
    ):
        with pytest.warns(FutureWarning, match=f"`CentralityPrior.{old_name}` is renamed `{new_name}`"):
            assert np.array_equal(getattr(prior, old_name), getattr(prior, new_name))

"""GPD: Theorem 1, the prior of eq. 5.10, faster convergence on the fish (thesis fig. 5.3)."""

import numpy as np
import pytest
from scipy import sparse

from centrality_vision.centrality import CENTRALITIES
from centrality_vision.exceptions import InputError
from centrality_vision.graphs import delaunay_graph
from centrality_vision.registration import GPD, GRAPHS, AffineCPD, NonRigidCPD, RigidCPD, centrality_prior
from centrality_vision.registration._estep import dense_posterior


def _same_run(a, b):
    np.testing.assert_array_equal(a.moving_transformed_, b.moving_transformed_)
    np.testing.assert_array_equal(a.history_["objective"], b.history_["objective"])
    np.testing.assert_array_equal(a.history_["sigma2"], b.history_["sigma2"])
    assert a.n_iter_ == b.n_iter_


@pytest.mark.parametrize("graph", ["complete", "edgeless"])
@pytest.mark.parametrize("centrality", CENTRALITIES)
def test_theorem_1_complete_or_edgeless_graph_gives_cpd_exactly(fish_pair, rot2, graph, centrality):
    y = fish_pair.moving
    x = 1.2 * fish_pair.fixed @ rot2(30).T + 0.3
    base = RigidCPD(w=0.1, tol=1e-8)
    cpd = base.fit(y, x)
    gpd = GPD(base, centrality=centrality, graph=graph).fit(y, x)
    _same_run(gpd, cpd)
    assert not np.any(gpd.moving_centrality_) and not np.any(gpd.fixed_centrality_)


@pytest.mark.parametrize("base", [AffineCPD(w=0.05, max_iter=20, tol=0), NonRigidCPD(max_iter=10, tol=0)])
def test_theorem_1_holds_for_every_base(fish_pair, base):
    y, x = fish_pair.moving, fish_pair.fixed
    _same_run(GPD(base, graph="complete").fit(y, x), base.fit(y, x))


def test_kappa_one_is_cpd(fish_pair):
    y, x = fish_pair.moving, fish_pair.fixed
    base = RigidCPD(w=0.1, max_iter=15, tol=0)
    _same_run(GPD(base, kappa=1.0).fit(y, x), base.fit(y, x))


def test_posterior_is_equation_5_10(fish_pair):
    """P_g(m|x) = h(m) exp(psi) / (sum_k h(k) exp(psi_k) + c), from the normalised centralities."""
    y, x = fish_pair.moving, fish_pair.fixed
    # in the caller's units (c depends on the units of sigma2)
    gpd = GPD(RigidCPD(w=0.2, max_iter=3, tol=0, normalize=False), centrality="closeness", bins=8).fit(y, x)
    vy, vx = gpd.moving_centrality_, gpd.fixed_centrality_
    assert vy.min() == 0 and vy.max() == 1 and vx.min() == 0 and vx.max() == 1
    counts, edges = np.histogram(vy, bins=8, range=(0, 1))
    h = counts[np.clip(np.digitize(vy, edges) - 1, 0, 7)]  # the thesis' bin counts
    phi2 = np.var(vx)
    t = gpd.moving_transformed_
    s2 = gpd.sigma2_
    m, n, d = len(y), len(x), 2
    psi = -(((x[None] - t[:, None]) ** 2).sum(-1) / (2 * s2) + (vx[None] - vy[:, None]) ** 2 / (2 * phi2))
    c = (2 * np.pi * s2) ** (d / 2) * 0.2 / 0.8 * m / n
    # h / M (our normalisation) with c: the thesis' counts h with c * M
    expected = h[:, None] * np.exp(psi) / ((h[:, None] * np.exp(psi)).sum(0) + c * m)
    np.testing.assert_allclose(gpd.posterior(), expected, rtol=1e-10, atol=1e-300)


def test_prior_is_the_thesis_one_when_w_is_zero(fish_pair):
    # with w = 0 dividing h by M cancels: the posterior is the thesis' eq. 5.10 with raw counts
    vy = np.array([0.0, 0.1, 0.9, 1.0, 0.15])
    vx = np.array([0.0, 0.5, 1.0])
    prior = centrality_prior(vy, vx, bins=2)
    y = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0.5]], float)
    x = np.array([[0.1, 0], [0.9, 0.2], [0.5, 0.6]])
    p = dense_posterior(y, x, 0.5, 0.0, prior)
    h = np.array([3, 3, 2, 2, 3])
    psi = -((x[None] - y[:, None]) ** 2).sum(-1) / 1.0 - (vx[None] - vy[:, None]) ** 2 / (2 * np.var(vx))
    expected = h[:, None] * np.exp(psi) / (h[:, None] * np.exp(psi)).sum(0)
    np.testing.assert_allclose(p, expected, rtol=1e-12)


def test_closeness_gpd_needs_fewer_iterations_than_cpd_on_the_fish(fish, rot2):
    """Thesis fig. 5.3: the fish under a similarity transform."""
    x = 1.5 * fish @ rot2(50).T + [0.5, -0.3]
    base = RigidCPD(scale=True, tol=1e-8)
    cpd = base.fit(fish, x, true_moving=x)
    gpd = GPD(base, centrality="closeness").fit(fish, x, true_moving=x)
    target = 0.05 * cpd.history_["error"][0]

    def first_below(history):
        return int(np.argmax(history["error"] < target))

    assert first_below(gpd.history_) < first_below(cpd.history_)
    np.testing.assert_allclose(gpd.moving_transformed_, x, atol=1e-6)


def test_precomputed_graphs_and_centralities(fish_pair):
    y, x = fish_pair.moving, fish_pair.fixed
    base = RigidCPD(max_iter=5, tol=0)
    built = GPD(base, centrality="degree").fit(y, x)
    given_graph = GPD(base, centrality="degree").fit(
        y, x, moving_graph=delaunay_graph(y), fixed_graph=delaunay_graph(x)
    )
    _same_run(built, given_graph)
    raw = np.asarray((delaunay_graph(y) > 0).sum(axis=1))  # degrees
    given_values = GPD(base).fit(
        y, x, moving_centrality=raw, fixed_centrality=np.asarray((delaunay_graph(x) > 0).sum(axis=1))
    )
    _same_run(built, given_values)
    custom = GPD(base, centrality=lambda g: np.asarray((g > 0).sum(axis=1)), graph=delaunay_graph).fit(y, x)
    _same_run(built, custom)


@pytest.mark.parametrize("graph", GRAPHS)
def test_every_graph_runs(fish_pair, fish, rot2, graph):
    y, x = fish_pair.moving, fish_pair.fixed
    gpd = GPD(RigidCPD(max_iter=5, tol=0), graph=graph).fit(y, x)
    assert gpd.moving_graph_.shape == (len(y), len(y)) and np.all(np.isfinite(gpd.moving_transformed_))
    turned = fish @ rot2(20).T + 0.1  # and registers a turned copy with it
    np.testing.assert_allclose(
        GPD(RigidCPD(tol=1e-10), graph=graph).fit(fish, turned).moving_transformed_, turned, atol=1e-6
    )


def test_base_estimator_is_left_unfitted(fish_pair):
    base = RigidCPD(max_iter=3, tol=0)
    GPD(base).fit(fish_pair.moving, fish_pair.fixed)
    assert not hasattr(base, "transform_")


def test_bad_gpd_input(fish_pair):
    y, x = fish_pair.moving, fish_pair.fixed
    with pytest.raises(ValueError, match="centrality"):
        GPD(centrality="nonsense").fit(y, x)
    with pytest.raises(ValueError, match="graph"):
        GPD(graph="voronoi").fit(y, x)
    with pytest.raises(TypeError, match="base_cpd"):
        GPD("cpd").fit(y, x)
    with pytest.raises(ValueError, match="kappa"):
        GPD(kappa=0.0).fit(y, x)
    with pytest.raises(ValueError, match="phi"):
        GPD(phi=-1.0).fit(y, x)
    with pytest.raises(ValueError, match="moving_centrality"):
        GPD().fit(y, x, moving_centrality=np.ones(3))
    with pytest.raises(ValueError, match="fixed_graph"):
        GPD().fit(y, x, fixed_graph=sparse.eye(4, format="csr"))
    with pytest.raises(ValueError, match="not fitted"):
        GPD().transform(y)
    with pytest.raises(ValueError, match="`moving`: GPD could not build its 'delaunay' graph: .*collinear"):
        GPD().fit([[0.0, 0.0], [1, 0], [2, 0], [3, 0]], [[0.0, 1.0], [1, 2], [2, 0], [3, 1]])
    with pytest.raises(ValueError, match="normalised"):
        centrality_prior([0.0, 2.0], [0.0, 1.0])


# ------------------------------------------------------------------ prior schedules (issue 10)
@pytest.mark.parametrize("schedule", ["anneal", 0.1])
def test_prior_schedules(fish_pair, schedule):
    y, x = fish_pair.moving, fish_pair.fixed
    base = RigidCPD(w=0.1, max_iter=30, tol=0)
    # Theorem 1 holds for a scheduled prior too
    _same_run(GPD(base, graph="complete", prior_schedule=schedule).fit(y, x), base.fit(y, x))
    full = GPD(base, centrality="closeness").fit(y, x)
    scheduled = GPD(base, centrality="closeness", prior_schedule=schedule).fit(y, x)
    # the same first E-step (the prior at full weight while sigma2 = sigma2_0), then a different path
    assert scheduled.history_["objective"][0] == full.history_["objective"][0]
    assert not np.array_equal(scheduled.moving_transformed_, full.moving_transformed_)
    np.testing.assert_allclose(scheduled.posterior().sum(0), scheduled.posteriors_.pt1, atol=1e-12)


def test_prior_switched_off_below_the_sigma2_fraction(fish_pair):
    y, x = fish_pair.moving, fish_pair.fixed
    base = RigidCPD(max_iter=40, tol=0)
    gpd = GPD(base, centrality="degree", prior_schedule=0.5).fit(y, x)
    assert gpd.history_["sigma2"][-1] < 0.5 * gpd.history_["sigma2"][0]
    # at the end the posterior is CPD's (no prior) at the final state
    moving_t, fixed, sigma2, w, prior, _ = gpd.estimator_._posterior_state
    assert prior is None
    np.testing.assert_array_equal(gpd.posterior(), dense_posterior(moving_t, fixed, sigma2, w, None))
    full = GPD(base, centrality="degree").fit(y, x)
    assert full.estimator_._posterior_state[4] is not None


def test_bad_prior_schedule(fish_pair):
    for bad in ("cosine", 0.0, 1.0):
        with pytest.raises(ValueError, match="prior_schedule"):
            GPD(prior_schedule=bad).fit(fish_pair.moving, fish_pair.fixed)


def test_histogram_rule_names_are_checked():
    # a string that is no numpy rule ('50', not 50) raised numpy's own ValueError before
    from centrality_vision.registration._gpd import centrality_prior

    v = np.linspace(0.0, 1.0, 30)
    with pytest.raises(InputError, match="`bins`"):
        centrality_prior(v, v, bins="50")
    assert centrality_prior(v, v, bins="sturges").log_weight.shape == (30,)


@pytest.mark.parametrize("rule", ["fd", "auto"])
def test_spread_rules_on_centralities_bunched_within_1e_11_are_refused(rule):
    # 'fd' takes bins of 2 IQR / n^(1/3): an IQR of 1e-11 asked numpy for 1e11 bins (a
    # MemoryError of terabytes, found by fuzzing GPD's options); now a named error
    from centrality_vision.registration._gpd import centrality_prior

    v = np.r_[0.0, 0.5 + 1e-12 * np.arange(38), 1.0]
    with pytest.raises(InputError, match="`bins` rule"):
        centrality_prior(v, v, bins=rule)
    assert np.all(np.isfinite(centrality_prior(v, v, bins=10).log_weight))


def test_centrality_prior_takes_the_names_gpd_fit_uses():
    # API audit F10: centrality_prior said v_moving/v_fixed for GPD.fit's moving_centrality/fixed_centrality
    from centrality_vision.registration import centrality_prior

    new = centrality_prior(moving_centrality=[0.0, 0.5, 1.0], fixed_centrality=[0.2, 0.9], bins=2)
    with pytest.warns(FutureWarning, match=r"`v_moving` and `v_fixed` of centrality_prior\(\) are renamed"):
        old = centrality_prior(v_moving=[0.0, 0.5, 1.0], v_fixed=[0.2, 0.9], bins=2)
    np.testing.assert_array_equal(old.log_weight, new.log_weight)
    with pytest.raises(ValueError, match="`fixed_centrality` must be normalised to"):
        centrality_prior([0.0, 1.0], [0.0, 2.0])


def test_centrality_prior_names_nan_values():
    # found by fuzz round 7: a NaN was reported as "got shape (11,)", a valid shape
    from centrality_vision.registration import centrality_prior

    values = np.linspace(0, 1, 11)
    values[3] = np.nan
    with pytest.raises(ValueError, match="`moving_centrality` must be finite; got 1 NaN or inf"):
        centrality_prior(values, np.linspace(0, 1, 5))

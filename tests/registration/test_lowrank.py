"""Pivoted Cholesky / Nystrom kernels and the coarse-to-fine registration built on them."""

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError

from centrality_vision.exceptions import InputError
from centrality_vision.registration import AffineCPD, NonRigidCPD, RigidCPD, _lowrank
from centrality_vision.registration._lowrank import PivotedCholesky, low_rank_eigh, nystrom_field, weighted_gram
from centrality_vision.registration._multiscale import ComposedTransform, MultiscaleCPD, compress_field
from centrality_vision.transforms import NonRigidTransform


def _kernel(a, b, beta):
    return np.exp(-((a[:, None] - b[None]) ** 2).sum(-1) / (2 * beta**2))


@pytest.mark.parametrize(("dim", "beta"), [(2, 0.3), (3, 0.8), (1, 0.05)])
def test_pivoted_cholesky_error_is_within_its_residual_trace(dim, beta):
    y = np.random.default_rng(dim).random((150, dim))
    g = _kernel(y, y, beta)
    for rank in (5, 40, 150):
        pc = PivotedCholesky(y, beta, max_rank=rank, tol=0.0)
        residual = g - pc.factor.T @ pc.factor
        assert np.linalg.eigvalsh(residual).min() > -1e-10  # G - L L^T stays positive semi-definite
        assert np.linalg.norm(residual, 2) <= pc.residual_trace + 1e-10
        assert pc.residual_trace == pytest.approx(np.trace(residual), abs=1e-9)
        assert len(set(pc.pivots.tolist())) == len(pc.pivots)


def test_pivoted_cholesky_past_its_first_width_equals_the_plain_factorisation():
    """L is stored 64 columns wide at first and widened when full: a factorisation of more
    columns equals plain Cholesky on its pivots (L[S] is the Cholesky factor of G[S, S])."""
    y = np.random.default_rng(5).random((200, 1))
    pc = PivotedCholesky(y, 0.004, max_rank=150, tol=0.0)
    assert pc.factor.shape == (150, 200)
    g = _kernel(y, y, 0.004)
    s = pc.pivots
    chol = np.linalg.cholesky(g[np.ix_(s, s)])
    np.testing.assert_allclose(pc.factor[:, s].T, chol, atol=1e-10)
    np.testing.assert_allclose(pc.factor.T @ pc.factor[:, s], g[:, s], atol=1e-10)


def test_pivoted_cholesky_stops_at_its_tolerance():
    y = np.random.default_rng(0).random((300, 2))
    pc = PivotedCholesky(y, 1.0, max_rank=300, tol=1e-6)
    assert pc.residual_trace <= 1e-6 * 300 and pc.factor.shape[0] < 40


def test_low_rank_eigh_matches_the_exact_leading_eigenpairs():
    y = np.random.default_rng(1).random((300, 2)) * 3
    g = _kernel(y, y, 2.0)
    exact_values, exact_vectors = np.linalg.eigh(g)
    values, vectors = low_rank_eigh(y, 2.0, 60)
    np.testing.assert_allclose(values[:8], exact_values[::-1][:8], rtol=1e-9)
    np.testing.assert_allclose(vectors.T @ vectors, np.eye(values.size), atol=1e-6)
    # residual trace (tol 1e-12 x 300) plus the dropped values (below 1e-10 of the largest, ~220)
    assert np.linalg.norm(g - (vectors * values) @ vectors.T, 2) < 300e-12 + 220e-10


def test_nystrom_field_reproduces_the_low_rank_displacement_everywhere_on_the_points():
    rng = np.random.default_rng(2)
    y = rng.random((400, 2))
    w = rng.standard_normal((400, 2))
    pc = PivotedCholesky(y, 0.4, max_rank=400, tol=1e-14)
    centres, a = nystrom_field(y, pc.pivots, pc.factor, w)
    np.testing.assert_allclose(_kernel(y, centres, 0.4) @ a, pc.factor.T @ (pc.factor @ w), atol=1e-7)
    np.testing.assert_allclose(_kernel(y, centres, 0.4) @ a, _kernel(y, y, 0.4) @ w, atol=1e-6)


def test_compress_field_keeps_the_field_and_the_pre_map():
    rng = np.random.default_rng(3)
    c = rng.random((500, 3))
    t = NonRigidTransform(c, 0.02 * rng.standard_normal((500, 3)), 0.7, linear=2 * np.eye(3), translation=[1.0, 0, 0])
    small = compress_field(t)
    assert small.control_points.shape[0] < 300
    z = rng.random((100, 3))  # u = 2 z + (1, 0, 0): partly outside the centres' cube
    assert np.abs(small(z) - t(z)).max() < 1e-6
    assert np.abs(small(c) - t(c)).max() < 1e-6


@pytest.mark.parametrize("bad", [0, -1.0, np.nan])
def test_pivoted_cholesky_rejects_a_bad_beta(bad):
    with pytest.raises((InputError, ValueError), match="beta"):
        PivotedCholesky(np.zeros((3, 2)), bad, max_rank=2)


def _rotation(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def test_multiscale_rigid_recovers_a_known_transform():
    rng = np.random.default_rng(4)
    y = rng.random((4000, 2))
    x = 1.1 * y @ _rotation(0.4).T + [0.2, -0.3]
    reg = MultiscaleCPD(RigidCPD(tol=1e-9), sizes=(400, 4000), refine_max_iter=30).fit(y, x[rng.permutation(4000)])
    assert [level["n_moving"] for level in reg.levels_] == [400, 4000]
    assert np.abs(reg.moving_transformed_ - x).max() < 1e-6
    assert reg.transform_.scale == pytest.approx(1.1, rel=1e-8)


def test_multiscale_affine_stops_at_the_first_level_covering_the_sets():
    rng = np.random.default_rng(5)
    y = rng.random((900, 3))
    a = np.array([[1.1, 0.1, 0.0], [0.0, 0.9, 0.2], [0.1, 0.0, 1.0]])
    reg = MultiscaleCPD(AffineCPD(tol=1e-10), sizes=(300, 2000, 5000)).fit(y, y @ a.T)
    assert [level["n_moving"] for level in reg.levels_] == [300, 900]
    np.testing.assert_allclose(reg.transform_.linear, a, atol=1e-6)


@pytest.mark.slow
def test_multiscale_nonrigid_composes_fields_and_the_refinement_gets_closer():
    # at 200 points the subsample's spacing (~0.07) is the deformation's size: the coarse
    # level alone barely helps; the full-resolution level on top of it must
    rng = np.random.default_rng(6)
    y = rng.random((800, 2))
    truth = y + 0.08 * np.sin(2 * y[:, ::-1])
    est = NonRigidCPD(beta=1.0, lam=3.0, tol=1e-5, max_iter=300)
    coarse = MultiscaleCPD(est, sizes=(200,)).fit(y, truth)
    fine = MultiscaleCPD(est, sizes=(200, 800), refine_max_iter=20).fit(y, truth)
    assert isinstance(fine.transform_, ComposedTransform) and len(fine.transform_.transforms) == 2
    err0 = np.sqrt(np.mean((y - truth) ** 2))
    err_coarse = np.sqrt(np.mean((coarse.moving_transformed_ - truth) ** 2))
    err_fine = np.sqrt(np.mean((fine.moving_transformed_ - truth) ** 2))
    assert err_fine < err_coarse and err_fine < 0.8 * err0
    np.testing.assert_allclose(fine.transform(y), fine.moving_transformed_)


@pytest.mark.parametrize("units", [1e-3, 1e4])
def test_multiscale_is_unit_free(units):
    # each level starts at the previous level's sigma2 read in its own (normalised) frame,
    # so the same data in other units gives the same levels and the same registration
    rng = np.random.default_rng(8)
    y = rng.random((2000, 2))
    x = (y @ _rotation(0.5).T + 0.05 * rng.normal(size=y.shape))[rng.permutation(2000)]
    make = lambda: MultiscaleCPD(RigidCPD(tol=1e-8), sizes=(200, 2000), refine_max_iter=4)  # noqa: E731
    a, b = make().fit(y, x), make().fit(units * y, units * x)
    assert [lv["n_iter"] for lv in b.levels_] == [lv["n_iter"] for lv in a.levels_]
    np.testing.assert_allclose(
        [lv["sigma2"] for lv in b.levels_], [units**2 * lv["sigma2"] for lv in a.levels_], rtol=1e-6
    )
    np.testing.assert_allclose(b.moving_transformed_ / units, a.moving_transformed_, rtol=0, atol=1e-8)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"sizes": (100, 50)}, "sizes"),
        ({"sizes": ()}, "sizes"),
        ({"refine_max_iter": 0}, "refine_max_iter"),
        ({"random_state": -1}, "random_state"),
        ({"sizes": (1.5,)}, "sizes"),
    ],
)
def test_multiscale_rejects_bad_parameters(kwargs, match):
    y = np.random.default_rng(7).random((50, 2))
    with pytest.raises((InputError, TypeError), match=match):
        MultiscaleCPD(RigidCPD(), **kwargs).fit(y, y)


def test_multiscale_takes_random_state_as_the_cpd_estimators_do():
    # audit F11: None and a Generator raised "must be an int", where RigidCPD takes both
    rng = np.random.default_rng(8)
    y = rng.random((300, 2))
    x = y @ _rotation(0.3).T
    # the dense E-step: method='auto' picks a path by timing, whose results differ by ~1e-9
    cpd = RigidCPD(method="dense")
    fits = {
        "seed": MultiscaleCPD(cpd, sizes=(100, 300), random_state=5).fit(y, x),
        "again": MultiscaleCPD(cpd, sizes=(100, 300), random_state=5).fit(y, x),
        "generator": MultiscaleCPD(cpd, sizes=(100, 300), random_state=np.random.default_rng(5)).fit(y, x),
        "none": MultiscaleCPD(cpd, sizes=(100, 300), random_state=None).fit(y, x),
    }
    for name, fit in fits.items():
        if name == "none":  # fresh subsamples: on uniform noise 14 of 200 seeds end elsewhere
            assert np.all(np.isfinite(fit.moving_transformed_)) and len(fit.levels_) == 2
        else:
            np.testing.assert_allclose(fit.moving_transformed_, x, atol=1e-6)
    # an int and a Generator seeded with it draw the same subsamples
    np.testing.assert_array_equal(fits["seed"].moving_transformed_, fits["again"].moving_transformed_)
    np.testing.assert_array_equal(fits["seed"].moving_transformed_, fits["generator"].moving_transformed_)


def test_multiscale_rejects_a_non_cpd_estimator_and_unfitted_use():
    with pytest.raises(TypeError, match="estimator"):
        MultiscaleCPD(object()).fit(np.zeros((5, 2)), np.zeros((5, 2)))
    with pytest.raises(NotFittedError, match="not fitted"):  # the one not-fitted error of every estimator
        MultiscaleCPD(RigidCPD()).transform(np.zeros((2, 2)))


@pytest.mark.parametrize("n, rank", [(1, 1), (7, 3), (511, 4), (512, 5), (1300, 47), (2049, 10)])
def test_weighted_gram_matches_numpy_and_is_symmetric(n, rank):
    """Q^T d(p) Q by blocks of 512 points and 2 x 2 tiles: odd and even ranks, a block's
    edge, fewer points than one block; exactly symmetric."""
    rng = np.random.default_rng(n + rank)
    q = rng.normal(size=(n, rank))
    p = rng.random(n)
    got = weighted_gram(np.ascontiguousarray(q.T), p)
    want = q.T @ (p[:, None] * q)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    np.testing.assert_array_equal(got, got.T)


def test_weighted_gram_in_chunks_is_the_same_for_any_thread_count(monkeypatch):
    from centrality_vision._parallel import get_num_threads, set_num_threads

    rng = np.random.default_rng(4)
    q = rng.normal(size=(5000, 9))
    p = rng.random(5000)
    serial = weighted_gram(np.ascontiguousarray(q.T), p)
    monkeypatch.setattr(_lowrank, "_SERIAL_WEIGHTED_GRAM", 0)  # the chunked path at this size
    before = get_num_threads()
    runs = []
    try:
        for threads in (1, 2, 3):
            set_num_threads(threads)
            runs.append(weighted_gram(np.ascontiguousarray(q.T), p))
    finally:
        set_num_threads(before)
    for other in runs[1:]:
        np.testing.assert_array_equal(runs[0], other)
    np.testing.assert_allclose(runs[0], serial, rtol=1e-12, atol=1e-12 * np.abs(serial).max())


def test_multiscale_refine_iter_is_renamed_refine_max_iter():
    # API audit F12: the package's iteration limit is max_iter
    rng = np.random.default_rng(9)
    y = rng.random((400, 2))
    x = y @ _rotation(0.2).T
    cpd = RigidCPD(method="dense")
    new = MultiscaleCPD(cpd, sizes=(100, 400), refine_max_iter=3).fit(y, x)
    with pytest.warns(FutureWarning, match="`refine_iter` of MultiscaleCPD is renamed `refine_max_iter`"):
        old = MultiscaleCPD(cpd, sizes=(100, 400), refine_iter=3).fit(y, x)
    np.testing.assert_array_equal(old.moving_transformed_, new.moving_transformed_)
    assert old.levels_[1]["n_iter"] <= 3
    with pytest.raises(TypeError, match="give `refine_max_iter` only; got both"):
        MultiscaleCPD(cpd, sizes=(100, 400), refine_iter=3, refine_max_iter=4).fit(y, x)
    with pytest.warns(FutureWarning), pytest.raises(TypeError, match="`MultiscaleCPD.refine_iter` must be an int"):
        MultiscaleCPD(cpd, sizes=(100, 400), refine_iter=2.5).fit(y, x)
    assert clone(MultiscaleCPD(cpd, refine_iter=3)).get_params()["refine_iter"] == 3


def _woodbury_m_step(kernel, post, moving, ls2):
    """The textbook Woodbury form of the low-rank M-step: ``W = (R - d(P1) Q z) / ls2``."""
    q, values, p1 = kernel.vectors, kernel.values, post.p1
    rhs = post.px - p1[:, None] * moving
    z = np.linalg.solve(q.T @ (p1[:, None] * q) + ls2 * np.diag(1.0 / values), q.T @ rhs)
    return (rhs - p1[:, None] * (q @ z)) / ls2


@pytest.mark.parametrize("sigma2", [1e-2, 1e-6, 1e-12])
def test_low_rank_m_step_is_the_woodbury_solution_without_its_cancellation(sigma2):
    # audit round 23: W = (R - d(P1) Q z) / (lam sigma2) cancels as sigma2 shrinks; the step
    # takes the field Q z and W = Q diag(1 / values) z, which have the same Q^T W exactly
    from centrality_vision.registration._estep import _e_step
    from centrality_vision.registration._mstep import LowRankKernel, nonrigid_m_step

    rng = np.random.default_rng(11)
    moving = rng.random((300, 2))
    fixed = moving + 0.05 * np.sin(3 * moving[:, ::-1])
    kernel = LowRankKernel(moving, 0.5, 40)
    post = _e_step(moving, fixed, 0.01, 0.0, None, method="dense")
    lam = 2.0
    w, moved, _, penalty = nonrigid_m_step(post, moving, fixed, kernel, lam, sigma2)
    field = moved - moving
    # W is the field's coefficients (to the rounding of G's spread of eigenvalues, 1e-10 here)
    gw = kernel.apply(w)
    np.testing.assert_allclose(gw, field, rtol=0, atol=1e-8 * np.abs(field).max())
    assert penalty == pytest.approx(float(np.sum(w * gw)), rel=1e-6)
    textbook = _woodbury_m_step(kernel, post, moving, lam * sigma2)
    # the same model: the textbook field agrees up to its own rounding, eps |R| / (lam sigma2)
    rounding = np.finfo(float).eps * np.abs(post.px).max() / (lam * sigma2)
    np.testing.assert_allclose(kernel.apply(textbook), field, rtol=0, atol=1e-10 + 1e3 * rounding)


def test_knn_fit_on_the_low_rank_kernel_settles_whatever_the_blas_threads():
    # audit round 23: with n_neighbors the fit drives sigma2 to ~1e-12, where the Woodbury
    # difference's rounding jumped sigma2 around, ran to max_iter and differed by 3e-4
    # between one and two BLAS threads
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(3)
    moving = rng.random((1200, 3))
    fixed = moving + 0.05 * np.sin(3 * moving[:, ::-1])
    fits = []
    for threads in (1, 2):
        with threadpool_limits(threads):
            fits.append(NonRigidCPD(n_neighbors=8, max_iter=40).fit(moving, fixed))
    assert all(fit.converged_ for fit in fits)
    np.testing.assert_allclose(fits[0].moving_transformed_, fits[1].moving_transformed_, rtol=0, atol=1e-12)
    assert np.abs(fits[0].moving_transformed_ - fixed).max() < 1e-4

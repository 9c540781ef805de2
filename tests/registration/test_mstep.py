"""The M-steps' compiled moments against the CPD paper's centred formulas."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from centrality_vision.registration._estep import _e_step
from centrality_vision.registration._mstep import _moments, affine_m_step, rigid_m_step
from centrality_vision.transforms import RigidTransform, SimilarityTransform


def _paper_moments(post, moving, fixed):
    """mu_x, mu_y, A, tr(Xh^T d(P^T 1) Xh) and Yh^T d(P1) Yh straight from the paper (fig. 2)."""
    p = post
    mu_x = fixed.T @ p.pt1 / p.n_p
    mu_y = moving.T @ p.p1 / p.n_p
    x_hat, y_hat = fixed - mu_x, moving - mu_y
    # P X with X centred: P (X - 1 mu_x^T) = P X - P1 mu_x^T
    a = (p.px - np.outer(p.p1, mu_x)).T @ y_hat
    x_px = float(np.sum(p.pt1[:, None] * x_hat * x_hat))
    y_py = (y_hat * p.p1[:, None]).T @ y_hat
    return mu_x, mu_y, a, x_px, y_py


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    dims=st.sampled_from([2, 3, 4]),
    sizes=st.tuples(st.integers(1, 40), st.integers(1, 40)),
    w=st.sampled_from([0.0, 0.3]),
)
def test_moments_equal_the_papers_formulas(seed, dims, sizes, w):
    rng = np.random.default_rng(seed)
    moving = rng.normal(size=(sizes[0], dims))
    fixed = rng.normal(size=(sizes[1], dims))
    post = _e_step(moving, fixed, 0.5, w, method="dense")
    n_p, *ours = _moments(post, moving, fixed)
    assert n_p == post.n_p
    for got, want in zip(ours, _paper_moments(post, moving, fixed)):
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12 * max(1.0, np.max(np.abs(want))))


def test_moments_keep_their_digits_far_from_the_origin():
    # the same posterior on sets shifted by 1e8: centred products lose nothing to cancellation
    rng = np.random.default_rng(3)
    moving = rng.normal(size=(200, 2))
    fixed = moving @ np.array([[0.8, -0.6], [0.6, 0.8]]).T + 0.01 * rng.normal(size=(200, 2))
    post = _e_step(moving, fixed, 0.1, 0.0, method="dense")
    near = _moments(post, moving, fixed)
    shift = np.array([1e8, -3e7])
    far = _moments(post, moving + shift, fixed + shift)
    np.testing.assert_allclose(far[1], near[1] + shift, rtol=1e-15)
    for i in (3, 5):  # A and Yh^T d(P1) Yh
        np.testing.assert_allclose(far[i], near[i], rtol=1e-7, atol=1e-7 * np.max(np.abs(near[i])))
    assert far[4] == pytest.approx(near[4], rel=1e-7)


@pytest.mark.parametrize("scale", [True, False])
def test_rigid_m_step_recovers_a_transform_from_exact_correspondences(scale):
    rng = np.random.default_rng(5)
    moving = rng.normal(size=(50, 3))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    rotation = q * np.sign(np.linalg.det(q))
    s = 1.7 if scale else 1.0
    fixed = s * moving @ rotation.T + np.array([1.0, -2.0, 0.5])
    # the E-step at the true pose: P is the identity to rounding
    post = _e_step(fixed, fixed, 1e-6, 0.0, method="dense")
    transform, sigma2 = rigid_m_step(post, moving, fixed, scale=scale)
    assert type(transform) is (SimilarityTransform if scale else RigidTransform)
    np.testing.assert_allclose(transform.rotation, rotation, atol=1e-10)
    assert transform.scale == pytest.approx(s, rel=1e-10)
    np.testing.assert_allclose(transform(moving), fixed, atol=1e-9)
    assert abs(sigma2) < 1e-12
    assert not transform.rotation.flags.writeable  # the trusted constructor freezes like the checked one


def test_affine_m_step_recovers_an_affine_map():
    rng = np.random.default_rng(6)
    moving = rng.normal(size=(40, 2))
    linear = np.array([[1.3, 0.4], [-0.2, 0.7]])
    fixed = moving @ linear.T + np.array([0.3, 0.1])
    post = _e_step(fixed, fixed, 1e-6, 0.0, method="dense")
    transform, _ = affine_m_step(post, moving, fixed)
    np.testing.assert_allclose(transform.linear, linear, atol=1e-10)
    np.testing.assert_allclose(transform(moving), fixed, atol=1e-9)

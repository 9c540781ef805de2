import numpy as np
import pytest

from centrality_vision.transforms import (
    AffineTransform,
    NonRigidTransform,
    RigidTransform,
    SimilarityTransform,
    random_rotation,
)


@pytest.mark.parametrize("dim", [2, 3])
def test_inverse_round_trips(dim):
    rng = np.random.default_rng(dim)
    pts = rng.random((10, dim))
    r = random_rotation(dim, seed=1)
    for t in (
        RigidTransform(r, rng.random(dim)),
        SimilarityTransform(r, rng.random(dim), 2.5),
        AffineTransform(np.eye(dim) + 0.3 * rng.random((dim, dim)), rng.random(dim)),
    ):
        np.testing.assert_allclose(t.inverse()(t(pts)), pts, atol=1e-12)
        homogeneous = np.c_[pts, np.ones(10)] @ t.matrix.T
        np.testing.assert_allclose(homogeneous[:, :dim], t(pts), atol=1e-12)
        assert type(t.inverse()) is type(t)


def test_random_rotation_is_proper_and_seeded():
    for dim in (2, 3, 4):
        r = random_rotation(dim, seed=5)
        np.testing.assert_allclose(r @ r.T, np.eye(dim), atol=1e-12)
        assert np.linalg.det(r) == pytest.approx(1.0)
        np.testing.assert_array_equal(r, random_rotation(dim, seed=5))


def test_transforms_are_frozen():
    t = RigidTransform(np.eye(2), [0.0, 0.0])
    with pytest.raises(AttributeError):
        t.translation = np.ones(2)
    with pytest.raises(ValueError):
        t.rotation[0, 0] = 2.0


def test_bad_transforms():
    with pytest.raises(ValueError, match="proper rotation"):
        RigidTransform(np.diag([1.0, -1.0]), [0.0, 0.0])
    with pytest.raises(ValueError, match="proper rotation"):
        SimilarityTransform(2 * np.eye(2), [0.0, 0.0])
    with pytest.raises(ValueError, match="scale"):
        RigidTransform(np.eye(2), [0.0, 0.0], 2.0)
    with pytest.raises(ValueError, match="not invertible"):
        AffineTransform(np.zeros((2, 2)), [0.0, 0.0]).inverse()
    with pytest.raises(ValueError, match="beta"):
        NonRigidTransform(np.zeros((2, 2)), np.zeros((2, 2)), beta=0.0)
    with pytest.raises(ValueError, match="points"):
        RigidTransform(np.eye(2), [0.0, 0.0])(np.zeros((3, 3)))


def test_nonrigid_field_by_hand():
    t = NonRigidTransform([[0.0, 0.0], [1.0, 0.0]], [[1.0, 0.0], [0.0, 2.0]], beta=1.0)
    z = np.array([[0.5, 0.0]])
    k = np.exp(-0.25 / 2)
    np.testing.assert_allclose(t(z), [[0.5 + k, 2 * k]])

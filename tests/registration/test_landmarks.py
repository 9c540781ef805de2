"""Landmarks: pinned pairs (extended CPD) on every variant and through GPD."""

import numpy as np
import pytest

from centrality_vision.registration import GPD, AffineCPD, NonRigidCPD, RigidCPD

PINS = np.array([0, 30, 60])


@pytest.fixture(scope="module")
def turned(fish_pair, rot2):
    """The deformed fish rotated by 150 degrees: plain CPD ends in a wrong basin."""
    return fish_pair.moving, fish_pair.fixed @ rot2(150).T + [0.3, 0.1]


def _rms(a, b):
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


@pytest.mark.parametrize("cls", [RigidCPD, AffineCPD])
def test_three_landmarks_escape_the_wrong_basin_exactly(fish, rot2, cls):
    x = fish @ rot2(150).T + [0.3, 0.1]
    plain = cls(tol=1e-8).fit(fish, x)
    pinned = cls(tol=1e-8).fit(fish, x, landmarks=[(i, i) for i in PINS])
    assert _rms(plain.moving_transformed_, x) > 1.0
    assert _rms(pinned.moving_transformed_, x) < 1e-8 and pinned.converged_


def test_nonrigid_landmarks_are_pinned_and_escape(turned):
    y, x = turned
    plain = NonRigidCPD().fit(y, x)
    pinned = NonRigidCPD().fit(y, x, landmarks=np.c_[PINS, PINS])
    assert np.abs(pinned.moving_transformed_[PINS] - x[PINS]).max() < 1e-3
    assert _rms(plain.moving_transformed_, x) > 1.0 > 10 * _rms(pinned.moving_transformed_, x)
    # a rigid start from the same landmarks, then the field: as close as without the rotation
    pose = RigidCPD(scale=False).fit(y, x, landmarks=np.c_[PINS, PINS]).transform_
    staged = NonRigidCPD(init=pose).fit(y, x, landmarks=np.c_[PINS, PINS])
    assert _rms(staged.moving_transformed_, x) < 0.02
    assert np.abs(staged.moving_transformed_[PINS] - x[PINS]).max() < 1e-3


def test_landmarks_on_shuffled_rows_and_through_gpd(turned):
    y, x = turned
    order = np.random.default_rng(2).permutation(len(x))
    shuffled = x[order]
    where = np.argsort(order)  # fixed row of each original point
    pairs = [(int(i), int(where[i])) for i in PINS]
    gpd = GPD(NonRigidCPD(), centrality="degree").fit(y, shuffled, landmarks=pairs)
    assert np.abs(gpd.moving_transformed_[PINS] - x[PINS]).max() < 1e-3
    assert _rms(gpd.moving_transformed_, x) < 0.1


def test_weak_landmarks_give_way_to_the_data(fish, rot2):
    x = fish @ rot2(10).T
    wrong = [(0, 45)]  # a single wrong pair
    strong = RigidCPD(tol=1e-8).fit(fish, x, landmarks=wrong)
    weak = RigidCPD(tol=1e-8, landmark_weight=0.01).fit(fish, x, landmarks=wrong)
    assert _rms(weak.moving_transformed_, x) < 0.1 * _rms(strong.moving_transformed_, x)


@pytest.mark.parametrize(
    ("landmarks", "error", "match"),
    [
        ([(0, 1, 2)], ValueError, "shape"),
        ([(0, 500)], ValueError, "fixed indices"),
        ([(-1, 0)], ValueError, "moving indices"),
        ([(0, 1), (0, 2)], ValueError, "at most once"),
        # audit 27 F9: two moving points pinned to one fixed point were accepted (a rigid fit
        # ended 0.36 apart, converged_=True)
        (
            [(5, 0), (3, 7), (30, 0)],
            ValueError,
            "each fixed point at most once; got fixed index 0 for moving points 5 and 30",
        ),
        ([(0.5, 1)], ValueError, "integer"),
        ("ab", TypeError, "landmarks"),
        # found by a fuzz run: an overflow, numpy's messages, or read as indices before
        ([(10**20, 0)], ValueError, "moving indices must be in"),
        ([(np.inf, 0)], ValueError, "integer indices; got inf"),
        ([(None, 0)], TypeError, "integer indices; got None"),
        ([(True, False)], TypeError, "integer indices; got True"),
        (np.array([["3", "4"]], dtype=object), TypeError, "integer indices; got '3'"),
        ([(0, 1), (2,)], ValueError, "pairs, shape"),
        # fuzz round 12: a masked entry read as None, and containers described as "shape ()"
        (np.ma.masked_array([[0, 1]], mask=[[False, True]]), TypeError, "a masked array with masked entries"),
        ({0: 1}, TypeError, "got a value of type dict"),
        ({(0, 1)}, TypeError, "got a value of type set"),
        (((i, i) for i in range(2)), TypeError, "got a value of type generator"),
    ],
)
def test_bad_landmarks_are_named(fish, landmarks, error, match):
    with pytest.raises(error, match=match):
        RigidCPD().fit(fish, fish, landmarks=landmarks)
    with pytest.raises(ValueError, match="landmark_weight"):
        RigidCPD(landmark_weight=0).fit(fish, fish, landmarks=[(0, 0)])

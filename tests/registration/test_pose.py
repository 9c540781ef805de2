import math
import warnings

import numpy as np
import pytest

from centrality_vision.exceptions import InputError
from centrality_vision.registration import RigidCPD, RigidTransform, SimilarityTransform
from centrality_vision.registration._pose import global_pose_search, rotation_lattice


def angle_degrees(r1, r2):
    d = r1.T @ r2
    cos = (np.trace(d) - 1) / 2 if d.shape[0] == 3 else np.trace(d) / 2
    return math.degrees(math.acos(np.clip(cos, -1.0, 1.0)))


@pytest.fixture(scope="module")
def blob3d():
    """An asymmetric 3D set: three anisotropic clusters of different sizes (no symmetry)."""
    rng = np.random.default_rng(7)
    parts = [
        rng.normal(size=(60, 3)) * [0.6, 0.2, 0.1],
        rng.normal(size=(30, 3)) * [0.1, 0.4, 0.1] + [0.8, 0.5, 0.0],
        rng.normal(size=(15, 3)) * [0.1, 0.1, 0.3] + [-0.5, 0.0, 0.7],
    ]
    return np.vstack(parts)


@pytest.mark.parametrize("degrees", [0, 90, 180])
def test_recovers_2d_rotation_from_any_angle(fish, rot2, degrees):
    r = rot2(degrees)
    x = fish @ r.T + [3.0, -2.0]
    pose = global_pose_search(fish, x, scale=False, w=0.0, random_state=0)
    assert isinstance(pose, RigidTransform)
    assert angle_degrees(pose.rotation, r) < 1.0
    np.testing.assert_allclose(pose(fish), x, atol=0.05)


@pytest.mark.parametrize("degrees", [0, 90, 180])
def test_recovers_3d_rotation_from_any_angle(blob3d, rot3, degrees):
    r = rot3(degrees, [1.0, 2.0, -0.5])
    x = blob3d @ r.T + [10.0, 0.0, -5.0]
    pose = global_pose_search(blob3d, x, scale=False, w=0.0, random_state=0)
    assert angle_degrees(pose.rotation, r) < 1.0
    # a plain CPD from the found pose lands exactly; from the identity it does not at 180
    fitted = RigidCPD(scale=False, tol=1e-10).fit(pose(blob3d), x)
    assert angle_degrees(fitted.transform_.rotation @ pose.rotation, r) < 1e-4


def test_plain_cpd_fails_where_the_search_succeeds(fish, rot2):
    r = rot2(150)
    x = fish @ r.T
    plain = RigidCPD(scale=False, tol=1e-8).fit(fish, x)
    assert angle_degrees(plain.transform_.rotation, r) > 5.0  # the reason for the search
    pose = global_pose_search(fish, x, scale=False, w=0.0, random_state=0)
    assert angle_degrees(pose.rotation, r) < 1.0


def test_similarity_scale_units_and_clutter(fish, rot2):
    # pixel-like units, an offset of 1e4, scale 40, noise, a missing part and outliers
    rng = np.random.default_rng(3)
    r = rot2(-135)
    x = 40.0 * fish @ r.T + 1e4
    keep = np.argsort(x[:, 0])[15:]  # the 15 leftmost points are missing
    x = x[keep] + rng.normal(scale=0.4, size=(keep.size, 2))
    x = np.vstack([x, rng.uniform(x.min(0), x.max(0), size=(15, 2))])
    x = x[rng.permutation(len(x))]
    pose = global_pose_search(fish, x, scale=True, w=0.2, random_state=1)
    assert isinstance(pose, SimilarityTransform)
    assert angle_degrees(pose.rotation, r) < 3.0
    assert pose.scale == pytest.approx(40.0, rel=0.05)
    visible = pose(fish)[np.argsort((fish @ r.T)[:, 0])[15:]]
    assert np.median(np.min(np.linalg.norm(visible[:, None] - x[None], axis=2), axis=1)) < 2.0  # 0.05 of the size


def test_same_seed_same_pose_and_inputs_untouched(blob3d, rot3):
    x = blob3d @ rot3(120, [0, 1, 1]).T
    big_y, big_x = np.repeat(blob3d, 2, axis=0), np.repeat(x, 2, axis=0)  # above max_points: subsampled
    before_y, before_x = big_y.copy(), big_x.copy()
    a = global_pose_search(big_y, big_x, scale=False, w=0.1, random_state=5, max_points=60)
    b = global_pose_search(big_y, big_x, scale=False, w=0.1, random_state=5, max_points=60)
    g = global_pose_search(big_y, big_x, scale=False, w=0.1, random_state=np.random.default_rng(5), max_points=60)
    np.testing.assert_array_equal(a.rotation, b.rotation)
    np.testing.assert_array_equal(a.translation, b.translation)
    np.testing.assert_array_equal(a.rotation, g.rotation)
    np.testing.assert_array_equal(big_y, before_y)
    np.testing.assert_array_equal(big_x, before_x)


@pytest.mark.parametrize("n_dims, n", [(2, 16), (3, 72), (3, 500)])
def test_rotation_lattice_is_proper_and_covers(n_dims, n):
    lattice = rotation_lattice(n_dims, n)
    assert lattice.shape == (n, n_dims, n_dims)
    np.testing.assert_allclose(lattice[0], np.eye(n_dims), atol=1e-15)
    np.testing.assert_allclose(
        lattice @ lattice.transpose(0, 2, 1), np.broadcast_to(np.eye(n_dims), lattice.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(lattice), 1.0, atol=1e-12)
    # every rotation lies near one of the lattice: the covering radius shrinks as n grows
    from centrality_vision.transforms import random_rotation

    rng = np.random.default_rng(0)
    queries = np.stack([random_rotation(n_dims, rng) for _ in range(200)])
    trace = np.einsum("qij,lij->ql", queries, lattice)  # tr(Q^T R) for every pair
    cos = (trace - 1) / 2 if n_dims == 3 else trace / 2
    worst = np.degrees(np.arccos(np.clip(cos.max(axis=1), -1, 1))).max()
    bound = 180.0 / n + 1e-9 if n_dims == 2 else {72: 50.0, 500: 25.0}[n]
    assert worst <= bound


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"moving": np.zeros((5, 4)), "fixed": np.zeros((5, 4))}, InputError, "moving"),
        ({"fixed": np.zeros((5, 3))}, InputError, "fixed"),
        ({"fixed": np.ones((5, 2))}, InputError, "distinct"),
        ({"moving": [[0.0, 0.0], [1.0, 1.0]]}, InputError, "at least 3"),
        ({"moving": [[0.0, np.nan], [1.0, 1.0], [2.0, 0.0]]}, InputError, "finite"),
        ({"scale": 1}, TypeError, "scale"),
        ({"w": 1.0}, InputError, "w"),
        ({"random_state": -1}, TypeError, "`random_state`"),
        ({"n_rotations": 0}, InputError, "n_rotations"),
        ({"n_rotations": 10**12}, InputError, r"n_rotations.*\[1, 100000\]"),  # a MemoryError before
        ({"n_hypotheses": 0}, InputError, "n_hypotheses"),
        ({"max_points": 2}, InputError, "max_points"),
    ],
)
def test_bad_inputs(fish, kwargs, error, match):
    args = {"moving": fish, "fixed": fish + 1.0, "scale": False, "w": 0.0, **kwargs}
    with pytest.raises(error, match=match):
        global_pose_search(args.pop("moving"), args.pop("fixed"), **args)


def test_rotation_lattice_bad_inputs():
    with pytest.raises(InputError, match="n_dims"):
        rotation_lattice(4, 10)
    with pytest.raises(InputError, match="n_rotations"):
        rotation_lattice(3, 0)


@pytest.mark.parametrize("degrees", [90, 180])
def test_rigid_cpd_init_global_and_gpd_over_it(fish, rot2, degrees):
    from centrality_vision.registration import GPD

    r = rot2(degrees)
    x = 3.0 * (fish @ r.T) + [100.0, -50.0]  # any units: fit normalises before the search
    plain = RigidCPD(scale=True, tol=1e-8).fit(fish, x)
    assert angle_degrees(plain.transform_.rotation, r) > 5.0
    cpd = RigidCPD(scale=True, tol=1e-8, init="global", random_state=0).fit(fish, x)
    assert angle_degrees(cpd.transform_.rotation, r) < 1e-3
    np.testing.assert_allclose(cpd.moving_transformed_, x, atol=1e-4)
    gpd = GPD(RigidCPD(scale=True, tol=1e-8, init="global", random_state=0), centrality="closeness").fit(fish, x)
    assert angle_degrees(gpd.transform_.rotation, r) < 1e-3


@pytest.mark.parametrize("n_dims", [2, 3])
def test_batched_e_step_equals_the_library_e_step_per_pose(n_dims):
    """The search's compiled E-step over K poses gives, pose by pose, the library's dense E-step."""
    from centrality_vision.registration._estep import _e_step
    from centrality_vision.registration._pose import _batch_e_step

    rng = np.random.default_rng(3)
    fixed = rng.normal(size=(37, n_dims))
    moving = rng.normal(size=(5, 29, n_dims)) * [[[1.0] * (n_dims - 1) + [0.3]]]
    sigma2 = np.array([1e-4, 0.01, 0.1, 1.0, 50.0])
    p1, pt1, px, nll = _batch_e_step(moving, fixed, sigma2, 0.2)
    for k in range(5):
        post = _e_step(moving[k], fixed, sigma2[k], 0.2, method="dense")
        np.testing.assert_allclose(p1[k], post.p1, rtol=1e-12, atol=1e-300)
        np.testing.assert_allclose(pt1[k], post.pt1, rtol=1e-12, atol=1e-300)
        np.testing.assert_allclose(px[k], post.px, rtol=1e-11, atol=1e-13)
        assert nll[k] == pytest.approx(post.neg_log_likelihood, rel=1e-12, abs=1e-9)


def test_global_search_does_not_depend_on_the_thread_count(blob3d):
    from centrality_vision._parallel import get_num_threads, set_num_threads

    rng = np.random.default_rng(11)
    moving = np.vstack([blob3d, rng.normal(size=(95, 3)) * 0.3])  # 200 points: the poses run in parallel
    r = rotation_lattice(3, 40)[17]
    fixed = moving @ r.T + [1.0, -2.0, 0.5]
    before = get_num_threads()
    poses = []
    try:
        for threads in (1, 2, 3):
            set_num_threads(threads)
            poses.append(global_pose_search(moving, fixed, scale=True, w=0.1, random_state=4))
    finally:
        set_num_threads(before)
    for pose in poses[1:]:
        assert np.array_equal(pose.rotation, poses[0].rotation)
        assert np.array_equal(pose.translation, poses[0].translation) and pose.scale == poses[0].scale
    assert angle_degrees(poses[0].rotation, r) < 1.0


def _potato_scan(rng, n_points):
    """A smooth, lopsided closed surface (an ellipsoid with 8 bumps of fixed places and heights),
    sampled at random, with a 20% slab cut off across a random direction."""
    shape = np.random.default_rng(99)
    bumps = shape.normal(size=(8, 3))
    bumps /= np.linalg.norm(bumps, axis=1, keepdims=True)
    heights = shape.uniform(0.2, 0.8, 8)
    u = rng.normal(size=(n_points, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    radius = 1 + (heights * np.exp(-np.sum((u[:, None] - bumps) ** 2, axis=2) / 0.15)).sum(axis=1)
    points = u * radius[:, None] * [1.6, 1.2, 0.9]
    direction = rng.normal(size=3)
    along = points @ direction
    return points[along < np.quantile(along, 0.8)]


def test_global_search_finds_the_basin_of_two_partial_scans():
    """Two scans that each lack a different 20% of a surface: CPD with a small outlier weight
    is biased there, and the search, at weight 0.1 with 3 hypotheses, started the fit in the
    right basin (within 15 degrees) in 7 of these 16 seeded problems; at weight 0.8 with 6
    hypotheses, in 11."""
    from centrality_vision.transforms import random_rotation

    found = 0
    for seed in range(16):
        rng = np.random.default_rng([5, seed])
        moving, fixed = _potato_scan(rng, 300), _potato_scan(rng, 300)
        rotation = random_rotation(3, seed=rng)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # (a fit may stop at max_iter)
            fit = RigidCPD(scale=False, w="auto", init="global", random_state=0).fit(moving, fixed @ rotation.T + 1.0)
        found += angle_degrees(fit.transform_.rotation, rotation) < 15
    assert found >= 10


def test_the_search_on_flat_3d_sets_keeps_proper_rotations():
    """On a planar set the cross-covariance has a zero singular value: without the sign
    correction, 2 of 20 batched M-steps turned a pose into a reflection."""
    from centrality_vision.transforms import random_rotation

    rng = np.random.default_rng(1)
    for trial in range(20):
        moving = np.c_[rng.random((40, 2)) * [1.0, 2.0], np.zeros(40)]
        fixed = moving @ random_rotation(3, seed=trial).T
        pose = global_pose_search(moving, fixed, scale=False, w=0.0, random_state=0)
        assert np.linalg.det(pose.rotation) == pytest.approx(1.0, abs=1e-12)


def test_the_hypotheses_refined_are_distinct_poses(fish, monkeypatch):
    """The second stage refines n_hypotheses poses at least _DISTINCT_DEGREES apart (not the
    same basin found from neighbouring lattice rotations)."""
    from centrality_vision.registration import _pose

    starts = []
    real = _pose._em

    def recording(moving, fixed, rotation, *args):
        starts.append(rotation.copy())
        return real(moving, fixed, rotation, *args)

    monkeypatch.setattr(_pose, "_em", recording)
    turned = fish @ np.array([[0.0, -1.0], [1.0, 0.0]]).T
    global_pose_search(fish, turned, scale=False, w=0.1, n_hypotheses=6, random_state=0)
    refined = starts[1]
    assert len(refined) == 6
    for i in range(6):
        for j in range(i):
            assert _pose._angle_between(refined[i], refined[j]) >= _pose._DISTINCT_DEGREES

"""Reachability map: index in [0, 1], consistent with batched IK, cached on disk."""

import numpy as np
import pytest

from mavac.inspection import reachability as R
from mavac.params import ReachabilityMapParams

SMALL = ReachabilityMapParams(voxel_size=0.1, n_directions=26, n_samples=20_000, n_rotations=32, seed=1)


@pytest.fixture(scope="module")
def robot():
    from mavac.robots.models import ur10_mobile

    return ur10_mobile()


@pytest.fixture(scope="module")
def rmap(robot):
    return R.reachability_map(robot, SMALL, cache=False)


def test_index_in_unit_interval(rmap):
    idx = rmap.index
    assert idx.shape == rmap.shape
    assert idx.min() >= 0.0 and idx.max() <= 1.0
    assert idx.max() > 0.5


def test_reachable_cells_agree_with_ik(robot, rmap):
    from mavac.robots.kinematics import ik_axis

    rng = np.random.default_rng(0)
    cells = np.argwhere(rmap.reachable)
    pick = cells[rng.choice(len(cells), 150, replace=False)]
    centres = rmap.voxel_centres()[pick[:, 0], pick[:, 1], pick[:, 2]]
    axes = rmap.directions[pick[:, 3]]
    assert np.all(rmap.is_reachable(centres, axes))
    res = ik_axis(robot, centres, axes, frame=robot.camera_frame, frame_axis=R.OPTICAL_AXIS, rng=rng)
    assert res.success.mean() > 0.85


def test_far_points_are_unreachable(rmap):
    far = np.array([[3.0, 0.0, 1.0], [0.0, -4.0, 0.5], [0.0, 0.0, 5.0]])
    assert not rmap.is_reachable(far, np.tile([0, 0, 1.0], (3, 1))).any()
    assert np.all(rmap.index_at(far) == 0.0)


def test_world_lookup_matches_base_lookup(rmap):
    from mavac.inspection.spots import se2_matrices

    T = se2_matrices(np.array([[1.0, -2.0, 0.7]]))[0]
    rng = np.random.default_rng(2)
    p_base = rng.uniform(-1, 1, (200, 3)) + [0, 0, 0.8]
    a_base = rng.normal(size=(200, 3))
    p_world = p_base @ T[:3, :3].T + T[:3, 3]
    a_world = a_base @ T[:3, :3].T
    assert np.array_equal(rmap.is_reachable_from(T, p_world, a_world), rmap.is_reachable(p_base, a_base))


def test_direction_bins_are_nearest_directions():
    d = R.sphere_directions(50)
    a = np.random.default_rng(3).normal(size=(2000, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    exact = np.argmax(a @ d.T, axis=1)
    got = R.direction_bins(d, a)
    # identical except within a LUT cell of a border: then the two candidates are near-equidistant
    diff = got != exact
    assert diff.mean() < 0.05
    dots = np.sort(a[diff] @ d.T, axis=1)
    assert np.all(dots[:, -1] - (a[diff] * d[got[diff]]).sum(1) < 0.03)


def test_cached_on_disk(robot):
    from mavac import cache

    key = R.robot_fingerprint(robot, robot.camera_frame)
    tiny = ReachabilityMapParams(voxel_size=0.2, n_directions=8, n_samples=500, n_rotations=4, seed=5)
    a = R.reachability_map(robot, tiny)
    fn = cache.memory().cache(R._build, ignore=["robot"])
    assert fn.check_call_in_cache(None, key, robot.camera_frame, tiny, R.OPTICAL_AXIS)
    b = R.reachability_map(robot, tiny)
    assert np.array_equal(a.reachable, b.reachable)


def test_default_map_is_the_camera_optical_axis(robot, rmap):
    explicit = R.reachability_map(robot, SMALL, frame=robot.camera_frame, axis_column=R.OPTICAL_AXIS, cache=False)
    assert rmap.frame == robot.camera_frame
    assert np.array_equal(rmap.reachable, explicit.reachable)
    # the tool z axis is not the camera x axis: a different map
    tool = R.reachability_map(robot, SMALL, frame=robot.tool_frame, cache=False)
    assert tool.reachable.shape != rmap.reachable.shape or not np.array_equal(tool.reachable, rmap.reachable)


def test_bad_parameters(robot):
    with pytest.raises(ValueError, match="voxel_size"):
        ReachabilityMapParams(voxel_size=0.0)
    with pytest.raises(ValueError, match="n_directions"):
        ReachabilityMapParams(n_directions=2)
    with pytest.raises(ValueError, match="params"):
        R.reachability_map(robot, params=0.05)
    with pytest.raises(ValueError, match="frame"):
        R.reachability_map(robot, SMALL, frame="nope", cache=False)
    with pytest.raises(ValueError, match="axis_column"):
        R.reachability_map(robot, SMALL, axis_column=3, cache=False)

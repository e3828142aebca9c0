import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mavac.params import CameraParams
from mavac.tolerances import FAR_PLANE_TOL
from mavac.vision.camera import (
    camera_pose_looking_at,
    fov_mask,
    fov_masks,
    fov_pyramid_corners,
    fov_pyramid_lines,
    points_in_camera,
)

CAM = CameraParams()


def random_poses(rng, m):
    T = np.tile(np.eye(4), (m, 1, 1))
    T[:, :3, :3] = Rotation.random(m, random_state=rng.integers(2**31)).as_matrix()
    T[:, :3, 3] = rng.uniform(-1, 1, (m, 3))
    return T


def fov_by_angles(points_camera, camera):
    """MAVAC's three conditions written literally with atan2 (far plane with its 1 mm tolerance)."""
    x, y, z = points_camera[..., 0], points_camera[..., 1], points_camera[..., 2]
    return (
        (x > 0)
        & (x <= camera.L_d + FAR_PLANE_TOL)
        & (np.abs(np.arctan2(y, x)) <= camera.theta_a)
        & (np.abs(np.arctan2(z, x)) <= camera.theta_b)
    )


@pytest.mark.parametrize(
    "field, value",
    [
        ("theta_a", 0.0),
        ("theta_a", math.pi / 2),
        ("theta_b", -0.1),
        ("theta_b", 2.0),
        ("L_d", 0.0),
        ("L_d", -1.0),
    ],
)
def test_camera_params_reject_bad_values(field, value):
    with pytest.raises(ValueError, match=field):
        CameraParams(**{field: value})


def test_camera_params_defaults_are_kinect_overlap():
    assert math.isclose(math.degrees(2 * CAM.theta_a), 75.0)
    assert math.isclose(math.degrees(2 * CAM.theta_b), 59.0)
    assert CAM.L_d > 0


def test_fov_mask_each_face_of_the_pyramid():
    """Identity camera: probe just inside and just outside every face."""
    x = 0.5 * CAM.L_d
    ya, zb = x * math.tan(CAM.theta_a), x * math.tan(CAM.theta_b)
    inside = np.array(
        [
            [x, 0, 0],
            [x, 0.99 * ya, 0],
            [x, -0.99 * ya, 0],
            [x, 0, 0.99 * zb],
            [x, 0, -0.99 * zb],
            [x, 0.99 * ya, 0.99 * zb],
            [0.999 * CAM.L_d, 0, 0],
            [CAM.L_d + 0.5 * FAR_PLANE_TOL, 0, 0],  # an IK residual past the far plane
        ]
    )
    outside = np.array(
        [
            [x, 1.01 * ya, 0],
            [x, -1.01 * ya, 0],
            [x, 0, 1.01 * zb],
            [x, 0, -1.01 * zb],
            [1.01 * CAM.L_d, 0, 0],  # beyond the detection limit
            [CAM.L_d + 2 * FAR_PLANE_TOL, 0, 0],  # beyond it by more than the tolerance
            [-x, 0, 0],  # behind the camera
            [0, 0, 0],  # at the camera
            [-x, 0.1 * ya, 0.1 * zb],
        ]
    )
    assert fov_mask(inside, np.eye(4), CAM).all()
    assert not fov_mask(outside, np.eye(4), CAM).any()


def test_fov_masks_match_literal_atan2_conditions_under_random_poses():
    rng = np.random.default_rng(0)
    T = random_poses(rng, 7)
    pts = rng.uniform(-1.5, 1.5, (3000, 3))
    masks = fov_masks(pts, T, CAM)
    assert masks.shape == (7, 3000)
    assert masks.any()  # the comparison is not vacuous
    np.testing.assert_array_equal(masks, fov_by_angles(points_in_camera(pts, T), CAM))
    for i in range(len(T)):
        np.testing.assert_array_equal(masks[i], fov_mask(pts, T[i], CAM))


def test_points_in_camera_round_trip():
    rng = np.random.default_rng(1)
    T = random_poses(rng, 3)
    pts = rng.normal(size=(20, 3))
    pc = points_in_camera(pts, T)
    back = np.einsum("mij,mnj->mni", T[:, :3, :3], pc) + T[:, None, :3, 3]
    np.testing.assert_allclose(back, np.broadcast_to(pts, back.shape), atol=1e-12)


def test_camera_pose_looking_at_puts_target_on_axis_at_distance():
    rng = np.random.default_rng(2)
    normals = rng.normal(size=(50, 3))
    normals = np.vstack([normals, [[0, 0, 1], [0, 0, -1], [1, 0, 0]]])
    targets = rng.uniform(-2, 2, (len(normals), 3))
    for p, n in zip(targets, normals):
        T = camera_pose_looking_at(p, n, 0.7)
        R = T[:3, :3]
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        np.testing.assert_allclose(points_in_camera(p, T)[0, 0], [0.7, 0, 0], atol=1e-12)
        np.testing.assert_allclose(R[:, 0], -n / np.linalg.norm(n), atol=1e-12)
        assert R[2, 2] >= -1e-12  # image "up" never points down
        # The target lies on the far plane when distance = L_d and must count as inside.
        assert fov_mask(p, camera_pose_looking_at(p, n, CAM.L_d), CAM)[0]


def test_camera_pose_looking_at_is_deterministic_for_vertical_normals():
    a = camera_pose_looking_at([0, 0, 0], [0, 0, 1], 1.0)
    b = camera_pose_looking_at([0, 0, 0], [0, 0, 2], 1.0)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a[:3, 2], [1, 0, 0])


def test_flat_wall_on_far_plane_is_inside():
    """A wall facing a guard at distance L_d lies on the far plane: keep all of it."""
    rng = np.random.default_rng(3)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    target = np.array([0.3, -0.2, 1.1])
    T = camera_pose_looking_at(target, n, CAM.L_d)
    half_y, half_z = 0.9 * CAM.L_d * math.tan(CAM.theta_a), 0.9 * CAM.L_d * math.tan(CAM.theta_b)
    uv = rng.uniform(-1, 1, (500, 2)) * [half_y, half_z]
    wall = target + uv[:, :1] * T[:3, 1] + uv[:, 1:] * T[:3, 2]
    assert fov_mask(wall, T, CAM).all()


def test_camera_pose_looking_at_rejects_bad_input():
    with pytest.raises(ValueError, match="normal"):
        camera_pose_looking_at([0, 0, 0], [0, 0, 0], 1.0)
    with pytest.raises(ValueError, match="distance"):
        camera_pose_looking_at([0, 0, 0], [0, 0, 1], 0.0)
    with pytest.raises(ValueError, match="target"):
        camera_pose_looking_at([0, 0], [0, 0, 1], 1.0)


def test_fov_rejects_non_rigid_transform():
    bad = np.eye(4)
    bad[0, 0] = 2.0
    with pytest.raises(ValueError, match="world_T_camera"):
        fov_mask(np.zeros((1, 3)), bad, CAM)
    with pytest.raises(ValueError, match="world_T_cameras"):
        fov_masks(np.zeros((1, 3)), np.eye(3), CAM)
    with pytest.raises(ValueError, match="points_world"):
        fov_mask(np.zeros((4, 2)), np.eye(4), CAM)


def test_pyramid_corners_and_lines_bound_the_fov():
    rng = np.random.default_rng(4)
    T = random_poses(rng, 1)[0]
    cam = replace(CAM, L_d=0.8)
    corners = fov_pyramid_corners(T, cam)
    np.testing.assert_allclose(corners[0], T[:3, 3])
    lines = fov_pyramid_lines(T, cam)
    assert lines.shape == (8, 2, 3)
    # Every segment endpoint is an apex or a corner; every corner is used three times.
    ends = lines.reshape(-1, 3)
    uses = [np.sum(np.all(np.isclose(ends, c), axis=1)) for c in corners]
    assert uses == [4, 3, 3, 3, 3]
    # Pulled slightly towards the optical axis a corner is inside, pushed out it is not.
    axis_point = T[:3, 3] + 0.8 * T[:3, 0]
    shrunk = axis_point + 0.99 * (corners[1:] - axis_point) - 1e-3 * T[:3, 0]
    grown = axis_point + 1.01 * (corners[1:] - axis_point) - 1e-3 * T[:3, 0]
    assert fov_mask(shrunk, T, cam).all()
    assert not fov_mask(grown, T, cam).any()

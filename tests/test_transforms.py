"""Rigid transforms: the one checker, SE(2) poses, composition and frame changes."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mavac.geometry import transforms as tf


def random_transforms(rng, n):
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = Rotation.random(n, random_state=rng).as_matrix()
    T[:, :3, 3] = rng.normal(size=(n, 3))
    return T


def test_check_transforms_accepts_rigid_and_promotes_one():
    T = random_transforms(np.random.default_rng(0), 5)
    assert tf.check_transforms("T", T).shape == (5, 4, 4)
    assert tf.check_transforms("T", T[0]).shape == (1, 4, 4)
    assert tf.check_transform("T", T[0]).shape == (4, 4)


@pytest.mark.parametrize("bad, match", [
    (np.eye(3), "world_T_x must have shape"),
    (np.full((4, 4), np.nan), "NaN"),
    (np.diag([2.0, 1.0, 1.0, 1.0]), "world_T_x must be rigid"),
    (np.diag([1.0, 1.0, -1.0, 1.0]), "reflection"),
    (np.vstack([np.eye(4)[:3], [0.0, 0.0, 1.0, 1.0]]), "last row"),
])
def test_check_transforms_refuses_what_is_not_rigid(bad, match):
    with pytest.raises(ValueError, match=match):
        tf.check_transforms("world_T_x", bad)


def test_check_transform_wants_exactly_one():
    with pytest.raises(ValueError, match="base_T_tool must have shape \\(4, 4\\)"):
        tf.check_transform("base_T_tool", np.tile(np.eye(4), (2, 1, 1)))


def test_rz_and_se2_agree_with_scipy():
    theta = np.array([-2.0, 0.0, 0.3, np.pi])
    np.testing.assert_allclose(tf.rz(theta), Rotation.from_rotvec(np.outer(theta, [0, 0, 1])).as_matrix(), atol=1e-15)
    assert tf.rz(0.3).shape == (3, 3)
    poses = np.array([[1.0, -2.0, 0.7], [0.0, 0.5, -3.0]])
    T = tf.se2_matrices(poses)
    np.testing.assert_allclose(T[:, :3, :3], tf.rz(poses[:, 2]))
    np.testing.assert_allclose(T[:, :2, 3], poses[:, :2])
    np.testing.assert_array_equal(T[:, 2, 3], 0.0)
    np.testing.assert_array_equal(T[1], tf.se2_to_matrix(*poses[1]))
    with pytest.raises(ValueError, match="theta"):
        tf.se2_to_matrix(0.0, 0.0, np.nan)


def test_compose_and_frame_changes_are_inverse():
    rng = np.random.default_rng(1)
    a_T_b, b_T_c = random_transforms(rng, 2)
    p_c = rng.normal(size=(7, 3))
    a_T_c = tf.compose(a_T_b, b_T_c)
    np.testing.assert_allclose(tf.transform_points(a_T_c, p_c),
                               tf.transform_points(a_T_b, tf.transform_points(b_T_c, p_c)))
    np.testing.assert_allclose(tf.points_in_frame(a_T_c, tf.transform_points(a_T_c, p_c)), p_c, atol=1e-12)
    v = rng.normal(size=(7, 3))
    np.testing.assert_allclose(tf.vectors_in_frame(a_T_b, tf.rotate_vectors(a_T_b, v)), v, atol=1e-12)
    stack = np.stack([a_T_b, b_T_c])
    both = tf.points_in_frame(stack, p_c)
    assert both.shape == (2, 7, 3)
    np.testing.assert_allclose(both[1], tf.points_in_frame(b_T_c, p_c))
    with pytest.raises(ValueError, match="at least one"):
        tf.compose()


def test_old_import_paths_still_work():
    from mavac.inspection.spots import se2_matrices
    from mavac.robots.models import se2_to_matrix
    from mavac.vision.camera import check_transforms

    assert se2_matrices is tf.se2_matrices and se2_to_matrix is tf.se2_to_matrix
    assert check_transforms is tf.check_transforms


def test_look_at_points_the_optical_axis_at_the_target():
    from mavac.geometry.transforms import look_at

    T = look_at([1.0, -2.0, 1.5], [0.2, 0.1, 0.3])
    z = T[:3, 2]
    d = np.array([0.2, 0.1, 0.3]) - np.array([1.0, -2.0, 1.5])
    assert np.allclose(z, d / np.linalg.norm(d))
    assert np.allclose(T[:3, :3].T @ T[:3, :3], np.eye(3)) and np.linalg.det(T[:3, :3]) > 0
    assert T[:3, 1] @ np.array([0.0, 0.0, 1.0]) < 0  # image y (down) points away from world up
    with pytest.raises(ValueError, match="differ"):
        look_at([0, 0, 0], [0, 0, 0])


def test_transform_each_point_moves_point_k_by_pose_k():
    rng = np.random.default_rng(4)
    poses = np.tile(np.eye(4), (5, 1, 1))
    poses[:, :3, :3] = tf.rz(rng.uniform(-3, 3, 5))
    poses[:, :3, 3] = rng.normal(size=(5, 3))
    points = rng.normal(size=(5, 3))
    expected = np.array([tf.transform_points(T, p[None])[0] for T, p in zip(poses, points)])
    assert np.allclose(tf.transform_each_point(poses, points), expected)


def test_matrix_to_se2_inverts_se2_to_matrix():
    for pose in ([0.3, -1.2, 0.0], [2.0, 0.5, 3.0], [-1.0, 4.0, -2.5], [0.0, 0.0, np.pi]):
        back = tf.matrix_to_se2(tf.se2_to_matrix(*pose))
        np.testing.assert_allclose(back, pose, atol=1e-12)
    with pytest.raises(ValueError, match="world_T_base"):
        tf.matrix_to_se2(np.eye(3))

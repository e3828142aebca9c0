"""TinyRenderer RGB-D: metric depth, intrinsics and back-projection agree with the scene."""

import numpy as np
import pytest
import trimesh

from mavac.sim.render import intrinsics_from_fov, mavac_T_opencv, render_rgbd
from mavac.sim.world import SimWorld
from mavac.vision.rgbd import back_project


def _looking_down(height: float) -> np.ndarray:
    """OpenCV camera at (0, 0, height) looking down -z."""
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[2, 3] = height
    return T


def test_depth_of_a_plane_at_known_distance():
    with SimWorld() as world:
        world.add_floor()
        _, depth, seg = render_rgbd(world.client, _looking_down(1.234), width=64, height=48, fov_y_deg=50,
                                    near=0.1, far=5.0)
    assert depth.shape == (48, 64) and seg.shape == (48, 64)
    np.testing.assert_allclose(depth, 1.234, atol=1e-3)


def test_background_is_infinite_depth():
    with SimWorld() as world:
        _, depth, seg = render_rgbd(world.client, _looking_down(1.0), width=32, height=24, fov_y_deg=50,
                                    near=0.1, far=5.0)
    assert np.all(np.isinf(depth)) and np.all(seg == -1)


def test_back_projected_centroid_of_a_sphere_is_where_it_was_placed():
    centre = np.array([0.12, -0.07, 0.0])
    with SimWorld() as world:
        body = world.add_visual_spheres(centre[None], 0.03, (0, 1, 0, 1))[0]
        T = _looking_down(0.8)
        rgb, depth, seg = render_rgbd(world.client, T, width=320, height=240, fov_y_deg=60, near=0.1, far=3.0)
    mask = seg == body
    assert mask.sum() > 50
    assert np.all(rgb[mask][:, 1] > rgb[mask][:, 0])  # green
    v, u = np.nonzero(mask)
    K = intrinsics_from_fov(320, 240, 60)
    # the blob centroid is (nearly) the ray through the centre, which lies one radius beyond
    # the nearest depth
    got = back_project(np.column_stack([u, v]).mean(0)[None], [depth[mask].min() + 0.03], K, T)[0]
    np.testing.assert_allclose(got, centre, atol=3e-3)


def test_mavac_frame_conversion_keeps_the_optical_axis():
    R = mavac_T_opencv()[:3, :3]
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_allclose(R[:, 2], [1.0, 0.0, 0.0])  # OpenCV z = MAVAC x (optical axis)


def test_degenerate_inputs_are_refused_before_the_renderer():
    with SimWorld() as world:
        bad = _looking_down(1.0)
        bad[0, 3] = np.nan
        with pytest.raises(ValueError, match="world_T_camera"):
            render_rgbd(world.client, bad, width=8, height=8, fov_y_deg=50, near=0.1, far=1.0)
        with pytest.raises(ValueError, match="far"):
            render_rgbd(world.client, _looking_down(1.0), width=8, height=8, fov_y_deg=50, near=1.0, far=0.5)
        with pytest.raises(ValueError, match="width"):
            render_rgbd(world.client, _looking_down(1.0), width=100000, height=8, fov_y_deg=50, near=0.1, far=1.0)
        with pytest.raises(ValueError, match="fov_y_deg"):
            render_rgbd(world.client, _looking_down(1.0), width=8, height=8, fov_y_deg=180, near=0.1, far=1.0)
        client = world.client
    with pytest.raises(ValueError, match="client"):
        render_rgbd(client, _looking_down(1.0), width=8, height=8, fov_y_deg=50, near=0.1, far=1.0)


def test_intrinsics_and_back_projection_of_the_principal_point():
    K = intrinsics_from_fov(5, 3, 90)
    assert K[0, 2] == 2.0 and K[1, 2] == 1.0 and K[0, 0] == pytest.approx(1.5)
    np.testing.assert_allclose(back_project([[2.0, 1.0]], [2.0], K), [[0.0, 0.0, 2.0]])
    with pytest.raises(ValueError, match="depth"):
        back_project([[2.0, 1.0]], [-1.0], K)


def test_static_mesh_is_seen_by_the_camera():
    box = trimesh.creation.box(bounds=[[-0.2, -0.2, 0.0], [0.2, 0.2, 0.5]])
    with SimWorld() as world:
        body = world.add_static_mesh(box.vertices, box.faces)
        _, depth, seg = render_rgbd(world.client, _looking_down(1.5), width=40, height=30, fov_y_deg=30,
                                    near=0.1, far=5.0)
    assert np.all(seg[10:20, 15:25] == body)
    np.testing.assert_allclose(depth[10:20, 15:25], 1.0, atol=1e-3)

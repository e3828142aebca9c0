import pickle

import numpy as np
import pytest
import trimesh

from mavac.params import CameraParams
from mavac.vision.camera import camera_pose_looking_at, fov_masks
from mavac.vision.visibility import (
    VisibilityScene,
    hpr_error_rates,
    hpr_visible,
    raycast_visible,
    visible_from,
)


@pytest.fixture(scope="module")
def walled_box():
    """Unit cube at the origin and, at x in [0.95, 1.05], a wall covering y < 0."""
    cube = trimesh.creation.box((1.0, 1.0, 1.0))
    wall = trimesh.creation.box((0.1, 1.0, 2.0)).apply_translation((1.0, -0.5, 0.0))
    return trimesh.util.concatenate([cube, wall])


VIEWPOINT = np.array([2.0, 0.0, 0.0])
# On the cube's +x face: the line to VIEWPOINT crosses x = 1 at y' = 2/3 y.
FRONT_VISIBLE = np.array([[0.5, 0.3, 0.1], [0.5, 0.45, -0.3]])
FRONT_HIDDEN = np.array([[0.5, -0.3, 0.1], [0.5, -0.45, -0.3]])
BACK = np.array([[-0.5, 0.2, 0.0]])  # far face: hidden by the cube itself


@pytest.fixture(scope="module")
def sphere_sample():
    mesh = trimesh.creation.icosphere(3, radius=0.3)
    pts, face = trimesh.sample.sample_surface_even(mesh, 1500, seed=0)
    return mesh, pts, mesh.face_normals[face]


def test_raycast_wall_hides_points_behind_it(walled_box):
    pts = np.vstack([FRONT_VISIBLE, FRONT_HIDDEN, BACK])
    normals = np.tile([1.0, 0.0, 0.0], (len(pts), 1))
    normals[-1] = [-1.0, 0.0, 0.0]
    expected = np.array([True, True, False, False, False])
    for n in (normals, None):
        vis = raycast_visible(walled_box, pts, n, VIEWPOINT)
        assert vis.shape == (1, len(pts))
        np.testing.assert_array_equal(vis[0], expected)


def test_raycast_normals_reject_back_facing_points(walled_box):
    # A visible point whose declared normal faces away from the camera is not visible.
    vis = raycast_visible(walled_box, FRONT_VISIBLE, -np.tile([1.0, 0, 0], (2, 1)), VIEWPOINT)
    assert not vis.any()


def test_visibility_scene_is_reusable_and_picklable(walled_box):
    scene = VisibilityScene(walled_box)
    pts = np.vstack([FRONT_VISIBLE, FRONT_HIDDEN])
    viewpoints = np.array([VIEWPOINT, [2.0, -4.0, 0.0], [0.0, 0.0, 3.0]])
    first = scene.visible(pts, None, viewpoints)
    np.testing.assert_array_equal(first, scene.visible(pts, None, viewpoints))
    clone = pickle.loads(pickle.dumps(scene))
    np.testing.assert_array_equal(first, clone.visible(pts, None, viewpoints))
    np.testing.assert_array_equal(first[0], [True, True, False, False])
    assert first[1, 2:].all()  # from y < 0 the wall is no longer in the way of y < 0 points
    assert not first[2].any()  # from above, the cube's top face occludes its +x face
    cand = np.zeros_like(first)
    cand[0, 0] = True
    only = scene.visible(pts, None, viewpoints, candidates=cand)
    assert only.sum() == 1 and only[0, 0]


def test_unoccluded_segments(walled_box):
    scene = VisibilityScene(walled_box)
    origins = np.array([VIEWPOINT, VIEWPOINT, VIEWPOINT])
    targets = np.array([[1.5, -0.3, 0.0], [0.5, -0.3, 0.0], [2.0, 0.0, 0.0]])
    # before the wall / through the wall / zero-length segment
    np.testing.assert_array_equal(scene.unoccluded(origins, targets), [True, False, True])
    with pytest.raises(ValueError, match="targets"):
        scene.unoccluded(origins, targets[:2])


def test_visible_from_raycast_with_camera_pose(walled_box):
    cam = CameraParams(L_d=2.0)
    T = camera_pose_looking_at([0.5, 0.0, 0.0], [1.0, 0.0, 0.0], 1.5)
    pts = np.vstack([FRONT_VISIBLE, FRONT_HIDDEN, BACK])
    normals = np.tile([1.0, 0.0, 0.0], (len(pts), 1))
    vis = visible_from(pts, normals, T, cam, method="raycast", mesh=walled_box)
    np.testing.assert_array_equal(vis[0], [True, True, False, False, False])
    # With a short detection limit nothing is in the FOV, hence nothing visible.
    short = visible_from(pts, normals, T, CameraParams(L_d=0.5), method="raycast", mesh=walled_box)
    assert not short.any()


def test_hpr_agrees_with_raycast_on_convex_sphere(sphere_sample):
    mesh, pts, normals = sphere_sample
    rng = np.random.default_rng(0)
    dirs = rng.normal(size=(6, 3))
    viewpoints = dirs / np.linalg.norm(dirs, axis=1)[:, None]  # 1 m from the centre
    exact = raycast_visible(mesh, pts, normals, viewpoints)
    hpr = np.array([hpr_visible(pts, v) for v in viewpoints])
    assert 0.3 < exact.mean() < 0.5  # roughly the near hemisphere minus the horizon
    assert (hpr == exact).mean() > 0.9
    assert not (exact & ~hpr).any()  # on a convex body HPR never hides a visible point


def test_hpr_error_rates_on_sphere(sphere_sample):
    mesh, pts, normals = sphere_sample
    cam = CameraParams(L_d=2.0)  # whole sphere inside the FOV from 0.7 m
    rng = np.random.default_rng(1)
    dirs = rng.normal(size=(5, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    T = np.array([camera_pose_looking_at(0.3 * d, d, 0.7) for d in dirs])
    for hpr_input in ("surface", "fov"):
        r = hpr_error_rates(mesh, pts, normals, T, cam, hpr_input=hpr_input)
        assert 0.0 <= r["false_visible"] <= 1.0 and 0.0 <= r["false_hidden"] <= 1.0
        assert r["false_visible"] < 0.2 and r["false_hidden"] < 0.05
        assert r["n_in_fov"] == r["n_ray_visible"] + r["n_ray_hidden"] == 5 * len(pts)
        assert r["n_false_visible"] == pytest.approx(r["false_visible"] * r["n_ray_hidden"])
        assert r["hpr_seconds"] >= 0 and r["raycast_seconds"] >= 0
        assert 0.0 <= r["agreement"] <= 1.0


def test_visible_from_is_inside_fov_and_matches_raycast_on_sphere(sphere_sample):
    mesh, pts, normals = sphere_sample
    cam = CameraParams()
    idx = [0, 100, 700]
    T = np.array([camera_pose_looking_at(pts[i], normals[i], cam.L_d) for i in idx])
    fov = fov_masks(pts, T, cam)
    scene = VisibilityScene(mesh)
    ray = visible_from(pts, normals, T, cam, method="raycast", mesh=scene)
    for hpr_input in ("surface", "fov"):
        hpr = visible_from(pts, normals, T, cam, method="hpr", hpr_input=hpr_input)
        assert hpr.shape == (3, len(pts)) and not (hpr & ~fov).any()
        np.testing.assert_array_equal(hpr[np.arange(3), idx], True)  # targets are seen
    assert not (ray & ~fov).any()
    np.testing.assert_array_equal(ray[np.arange(3), idx], True)


def test_hpr_degenerate_clouds_are_all_visible():
    """Fewer than 3-D (with the viewpoint): the hull has no interior, every point is on it."""
    rng = np.random.default_rng(5)
    plane = np.c_[rng.uniform(size=(50, 2)), np.zeros(50)]
    assert hpr_visible(plane, [2.0, 2.0, 0.0]).all()  # viewpoint in the plane: edge-on
    assert hpr_visible(np.tile([1.0, 0, 0], (10, 1)), [0, 0, 0]).all()  # one repeated point
    assert hpr_visible(np.array([[1.0, 0, 0], [0, 1.0, 0]]), [0, 0, 0]).all()
    assert hpr_visible(np.zeros((0, 3)), [0, 0, 0]).shape == (0,)
    # Same plane seen from above is a proper 3-D problem and still fully visible.
    assert hpr_visible(plane, [0.5, 0.5, 1.0]).all()


def test_bad_input_is_refused(walled_box):
    pts = FRONT_VISIBLE
    with pytest.raises(ValueError, match="radius_factor"):
        hpr_visible(pts, VIEWPOINT, radius_factor=1.0)
    with pytest.raises(ValueError, match="viewpoint"):
        hpr_visible(pts, [[0, 0, 0], [1, 1, 1]])
    with pytest.raises(ValueError, match="method"):
        visible_from(pts, None, np.eye(4), CameraParams(), method="zbuffer")
    with pytest.raises(ValueError, match="mesh"):
        visible_from(pts, None, np.eye(4), CameraParams(), method="raycast")
    with pytest.raises(ValueError, match="hpr_input"):
        visible_from(pts, None, np.eye(4), CameraParams(), hpr_input="all")
    with pytest.raises(ValueError, match="normals"):
        raycast_visible(walled_box, pts, np.zeros((3, 3)), VIEWPOINT)
    with pytest.raises(ValueError, match="mesh"):
        VisibilityScene(trimesh.Trimesh())


def test_hpr_input_choice_on_a_concave_scene():
    # A box with an open pocket, seen from above the pocket's rim: the two HPR inputs are
    # different classifiers here, so each must be exactly the one its name says.
    box = trimesh.creation.box(bounds=[[-0.6, -0.4, 0.0], [0.6, 0.4, 0.9]])
    pocket = trimesh.creation.box(bounds=[[-0.3, -0.2, 0.5], [0.3, 0.2, 1.0]])
    mesh = trimesh.boolean.difference([box, pocket], engine="manifold")
    pts, _ = trimesh.sample.sample_surface_even(mesh, 4000, seed=0)
    T = camera_pose_looking_at([0.25, 0.0, 0.5], [-0.3, 0.0, 1.0], 0.6)
    cam = CameraParams()
    fov = fov_masks(pts, T, cam)[0]
    surface = visible_from(pts, None, T, cam, hpr_input="surface")[0]
    cropped = visible_from(pts, None, T, cam, hpr_input="fov")[0]
    # "surface": HPR of the whole sample from the camera, intersected with the FOV
    np.testing.assert_array_equal(surface, fov & hpr_visible(pts, T[:3, 3], radius_factor=cam.hpr_radius_factor))
    # "fov": HPR of the in-FOV points alone
    idx = np.flatnonzero(fov)
    expected = np.zeros(len(pts), dtype=bool)
    expected[idx] = hpr_visible(pts[idx], T[:3, 3], radius_factor=cam.hpr_radius_factor)
    np.testing.assert_array_equal(cropped, expected)
    assert fov.sum() > 100 and np.any(surface != cropped)

import pickle

import numpy as np
import pytest
import trimesh

from mavac.params import VISIBILITY_METHODS, CameraParams
from mavac.vision.camera import camera_pose_looking_at, fov_masks
from mavac.vision.visibility import (
    Visibility,
    VisibilityScene,
    hpr_error_rates,
    hpr_visible,
    raycast_visible,
    visible_each,
    visible_from,
    visible_points,
)

HPR = Visibility("hpr")
RAYCAST = Visibility("raycast")


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
    vis = visible_from(pts, normals, T, cam, RAYCAST, scene=walled_box)
    np.testing.assert_array_equal(vis[0], [True, True, False, False, False])
    # With a short detection limit nothing is in the FOV, hence nothing visible.
    short = visible_from(pts, normals, T, CameraParams(L_d=0.5), RAYCAST, scene=walled_box)
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
        r = hpr_error_rates(mesh, pts, normals, T, cam, visibility=Visibility("hpr", hpr_input=hpr_input))
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
    ray = visible_from(pts, normals, T, cam, RAYCAST, scene=scene)
    for hpr_input in ("surface", "fov"):
        hpr = visible_from(pts, normals, T, cam, Visibility("hpr", hpr_input=hpr_input))
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
    with pytest.raises(ValueError, match="scene"):
        visible_from(pts, None, np.eye(4), CameraParams(), RAYCAST)
    with pytest.raises(TypeError, match="visibility"):
        visible_from(pts, None, np.eye(4), CameraParams(), "hpr")
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
    surface = visible_from(pts, None, T, cam, HPR)[0]
    cropped = visible_from(pts, None, T, cam, Visibility("hpr", hpr_input="fov"))[0]
    # "surface": HPR of the whole sample from the camera, intersected with the FOV
    np.testing.assert_array_equal(surface, fov & hpr_visible(pts, T[:3, 3], radius_factor=HPR.radius_factor))
    # "fov": HPR of the in-FOV points alone
    idx = np.flatnonzero(fov)
    expected = np.zeros(len(pts), dtype=bool)
    expected[idx] = hpr_visible(pts[idx], T[:3, 3], radius_factor=HPR.radius_factor)
    np.testing.assert_array_equal(cropped, expected)
    assert fov.sum() > 100 and np.any(surface != cropped)


# ---- Visibility: one value for the method and HPR's radius ----


def test_visibility_defaults_and_the_one_list_of_methods():
    v = Visibility()
    assert v.method == "raycast" and v.radius is None and v.hpr_input == "surface"
    assert (v.radius_factor, v.spot_radius_factor) == (10.0, 30.0)
    assert set(VISIBILITY_METHODS) == {"hpr", "raycast"}
    assert v.at_spots().radius_factor == 30.0 and v.at_spots().spot_radius_factor == 30.0
    assert Visibility("hpr", radius=10.0).at_spots().radius == 10.0  # an absolute radius holds everywhere


@pytest.mark.parametrize("kwargs, field", [
    (dict(method="zbuffer"), "method"), (dict(radius_factor=1.0), "radius_factor"),
    (dict(spot_radius_factor=0.5), "spot_radius_factor"), (dict(radius=0.0), "radius"),
    (dict(radius=-10.0), "radius"), (dict(hpr_input="all"), "hpr_input"),
])
def test_visibility_bad_values_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        Visibility(**kwargs)


def test_visibility_bad_types_are_type_errors():
    with pytest.raises(TypeError, match="radius"):
        Visibility("hpr", radius="10")
    with pytest.raises(TypeError, match="method"):
        Visibility(3)


def test_visible_dispatches_to_hpr_and_raycast(walled_box):
    pts = np.vstack([FRONT_VISIBLE, FRONT_HIDDEN, BACK])
    normals = np.tile([1.0, 0.0, 0.0], (len(pts), 1))
    ray = RAYCAST.visible(pts, normals, VIEWPOINT[None], scene=walled_box)
    np.testing.assert_array_equal(ray, raycast_visible(walled_box, pts, normals, VIEWPOINT))
    hpr = HPR.visible(pts, normals, VIEWPOINT[None])
    np.testing.assert_array_equal(hpr[0], hpr_visible(pts, VIEWPOINT))
    assert visible_points(HPR, pts, None, VIEWPOINT[None]).shape == (1, len(pts))
    with pytest.raises(ValueError, match="scene"):
        RAYCAST.visible(pts, normals, VIEWPOINT[None])
    with pytest.raises(ValueError, match="candidates"):
        HPR.visible(pts, None, VIEWPOINT[None], candidates=np.ones((2, len(pts)), bool))


def test_absolute_hpr_radius_differs_from_a_factor():
    """R = 10 m is a different classifier from R = 10 x the farthest distance: with the smaller
    radius HPR hides more points of a bumpy surface, and it matches hpr_visible's radius keyword."""
    rng = np.random.default_rng(3)
    xy = rng.uniform(-1.0, 1.0, size=(3000, 2))
    pts = np.c_[xy, 0.15 * np.sin(6 * xy[:, 0]) * np.cos(5 * xy[:, 1])]
    view = np.array([[0.0, 0.0, 1.0]])
    factor = Visibility("hpr", radius_factor=100.0).visible(pts, None, view)[0]
    absolute = Visibility("hpr", radius=2.0).visible(pts, None, view)[0]
    assert factor.sum() > absolute.sum() > 0
    np.testing.assert_array_equal(absolute, hpr_visible(pts, view[0], radius=2.0))
    max_distance = np.linalg.norm(pts - view, axis=1).max()
    assert Visibility("hpr", radius=2.0).hpr_radius(max_distance) == 2.0
    assert Visibility("hpr").hpr_radius(max_distance) == pytest.approx(10.0 * max_distance)


def test_absolute_radius_must_exceed_the_farthest_point():
    pts = np.array([[5.0, 0, 0], [0, 5.0, 0], [0, 0, 5.0], [3.0, 3.0, 3.0]])
    with pytest.raises(ValueError, match="radius"):
        Visibility("hpr", radius=1.0).visible(pts, None, np.zeros((1, 3)))


def test_visible_each_is_the_diagonal_of_visible(walled_box):
    pts = np.vstack([FRONT_VISIBLE, FRONT_HIDDEN, BACK])
    normals = np.tile([1.0, 0.0, 0.0], (len(pts), 1))
    views = np.tile(VIEWPOINT, (len(pts), 1)) + 0.01 * np.arange(len(pts))[:, None]
    for vis in (HPR, RAYCAST):
        full = vis.visible(pts, normals, views, scene=walled_box)
        np.testing.assert_array_equal(vis.visible_each(pts, normals, views, scene=walled_box), np.diag(full))
        np.testing.assert_array_equal(visible_each(vis, pts, normals, views, scene=walled_box), np.diag(full))
    with pytest.raises(ValueError, match="viewpoints"):
        HPR.visible_each(pts, None, views[:2])


@pytest.mark.parametrize("shift", [10.0, 10_000.0])
def test_visibility_does_not_depend_on_where_the_mesh_sits(sphere_sample, shift):
    mesh, pts, normals = sphere_sample
    views = np.array([[1.0, 0.2, 0.1], [-0.8, 0.5, 0.3]])
    here = VisibilityScene(mesh).visible(pts, normals, views)
    there = VisibilityScene(mesh.copy().apply_translation([shift, shift, 0])).visible(pts + [shift, shift, 0],
                                                                                      normals, views + [shift, shift, 0])
    assert (here == there).all()


def test_surface_sampling_does_not_depend_on_where_the_mesh_sits():
    from mavac.geometry.surface import sample_surface

    mesh = trimesh.creation.icosphere(3, radius=0.3)
    here = sample_surface(mesh, 0.03, seed=0)
    there = sample_surface(mesh.copy().apply_translation([1e4, 1e4, 0]), 0.03, seed=0)
    np.testing.assert_allclose(there.points - [1e4, 1e4, 0], here.points, atol=1e-6)
    assert (there.face_index == here.face_index).all()


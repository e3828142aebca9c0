"""Spot candidates on rings, collision filter, accessible sets, greedy spot selection."""

import numpy as np
import pytest
import trimesh

from mavac.inspection import spots as SP
from mavac.params import CameraParams, InspectionParams, ReachabilityMapParams, SpotParams, Visibility

RECT = np.array([[-1.0, -0.5], [1.0, -0.5], [1.0, 0.5], [-1.0, 0.5]])


def _dist_to_rect(xy):
    dx = np.maximum(np.abs(xy[:, 0]) - 1.0, 0)
    dy = np.maximum(np.abs(xy[:, 1]) - 0.5, 0)
    return np.hypot(dx, dy)


def test_candidates_lie_on_rings_and_park_alongside():
    p = SpotParams(ring_distances=(0.5, 0.9), ring_spacing=0.2, jitter_xy=0.0, jitter_theta=0.0)
    c = SP.candidate_spots(RECT, p, np.random.default_rng(0))
    d = _dist_to_rect(c[:, :2])
    assert np.all(np.isclose(d, 0.5, atol=1e-6) | np.isclose(d, 0.9, atol=1e-6))
    # about perimeter / spacing poses per ring
    per = [2 * (2 + 1) + 2 * np.pi * r for r in (0.5, 0.9)]
    assert len(c) == sum(round(x / 0.2) for x in per)
    # on the long straight edges the base is parallel to the machine
    south = (c[:, 1] < -0.99) & (np.abs(c[:, 0]) < 0.9)
    assert south.any()
    assert np.allclose(np.abs(np.sin(c[south, 2])), 0.0, atol=1e-9)


def test_candidates_are_seeded():
    p = SpotParams()
    a = SP.candidate_spots(RECT, p, np.random.default_rng(1))
    b = SP.candidate_spots(RECT, p, np.random.default_rng(1))
    c = SP.candidate_spots(RECT, p, np.random.default_rng(2))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    # jitter stays within its bounds around the rings
    d = _dist_to_rect(a[:, :2])
    assert np.all(np.min(np.abs(d[:, None] - np.array(p.ring_distances)[None]), axis=1) <= np.sqrt(2) * p.jitter_xy + 1e-9)


def test_clockwise_footprint_is_accepted():
    p = SpotParams(jitter_xy=0.0, jitter_theta=0.0)
    a = SP.candidate_spots(RECT, p, np.random.default_rng(0))
    b = SP.candidate_spots(RECT[::-1], p, np.random.default_rng(0))
    assert np.allclose(_dist_to_rect(a[:, :2]), _dist_to_rect(b[:, :2]))


def test_se2_matrices_match_robot_convention():
    from mavac.robots.models import se2_to_matrix

    poses = np.array([[0.3, -1.0, 0.4], [2.0, 1.0, -2.5]])
    for T, p in zip(SP.se2_matrices(poses), poses):
        assert np.allclose(T, se2_to_matrix(*p))


@pytest.fixture(scope="module")
def box():
    return trimesh.creation.box(bounds=[[-1.0, -0.5, 0.0], [1.0, 0.5, 0.8]])


def test_collision_free_spots(box):
    from mavac.robots.models import ur10_mobile

    robot = ur10_mobile()
    poses = np.array([[0.0, 0.0, 0.0], [0.0, -1.5, 0.0], [0.0, -0.6, 0.0]])
    free = SP.collision_free_spots(robot, box, poses)
    assert free.tolist() == [False, True, False]


def test_spot_visibility_and_accessibility(box):
    from mavac.inspection.reachability import reachability_map
    from mavac.robots.models import ur10_mobile
    from mavac.vision.visibility import VisibilityScene

    pts = np.array([[0.0, -0.5, 0.4], [0.0, 0.5, 0.4], [0.0, 0.0, 0.8], [0.9, -0.5, 0.4]])
    nrm = np.array([[0, -1.0, 0], [0, 1.0, 0], [0, 0, 1.0], [0, -1.0, 0]])
    spot = np.array([[0.0, -1.1, 0.0]])
    vis = SP.spot_visibility(pts, nrm, spot, SpotParams(view_heights=(0.8, 1.6)), Visibility("raycast"),
                             vis_scene=VisibilityScene(box))
    assert vis.tolist() == [[True, False, True, True]]
    rmap = reachability_map(ur10_mobile(), ReachabilityMapParams(voxel_size=0.1, n_directions=26,
                                                                 n_samples=20_000, n_rotations=32))
    acc = SP.accessible_sets(rmap, spot, pts, nrm, vis, CameraParams().L_d)
    assert acc[0, 0]  # front face, right in front of the base
    assert not acc[0, 1]  # back face: not visible
    far = SP.accessible_sets(rmap, np.array([[0.0, -4.0, 0.0]]), pts, nrm, np.ones((1, 4), bool), CameraParams().L_d)
    assert not far.any()  # out of reach


def test_spot_hpr_uses_the_radius_calibrated_for_spots(box):
    """Spot visibility runs HPR with Visibility.spot_radius_factor (calibrated at spot distances),
    not with the guards' factor, which was calibrated at the guards' L_d = 0.5 m."""
    from mavac.vision.visibility import hpr_visible

    pts, fi = trimesh.sample.sample_surface_even(box, 800, seed=2)
    spots = np.array([[0.0, -1.1, 0.0], [1.6, 0.3, 1.0]])
    params = SpotParams(view_heights=(0.8, 1.6))
    hpr = Visibility("hpr")
    assert hpr.spot_radius_factor != hpr.radius_factor
    vis = SP.spot_visibility(pts, box.face_normals[fi], spots, params, hpr)
    views = SP.spot_viewpoints(spots, params.view_heights)
    np.testing.assert_allclose(views[:2], [[0.0, -1.1, 0.8], [0.0, -1.1, 1.6]])
    expected = np.array([hpr_visible(pts, v, radius_factor=hpr.spot_radius_factor) for v in views])
    np.testing.assert_array_equal(vis, expected.reshape(2, 2, -1).any(axis=1))
    # an absolute radius replaces both factors
    vis10 = SP.spot_visibility(pts, box.face_normals[fi], spots, params, Visibility("hpr", radius=10.0))
    expected10 = np.array([hpr_visible(pts, v, radius=10.0) for v in views])
    np.testing.assert_array_equal(vis10, expected10.reshape(2, 2, -1).any(axis=1))


def test_spot_visibility_defaults_to_exact_ray_casting_with_back_faces(box):
    from mavac.vision.visibility import VisibilityScene

    assert InspectionParams().visibility.method == "raycast"
    pts, fi = trimesh.sample.sample_surface_even(box, 800, seed=3)
    nrm = box.face_normals[fi]
    spot = np.array([[0.0, -1.1, 0.0]])
    vis = SP.spot_visibility(pts, nrm, spot, SpotParams(view_heights=(1.6,)), InspectionParams().visibility,
                             vis_scene=VisibilityScene(box))[0]
    assert vis.any() and not vis[np.einsum("ij,ij->i", nrm, np.array([0.0, -1.1, 1.6]) - pts) <= 0].any()
    np.testing.assert_array_equal(vis, (nrm[:, 1] < -0.9) | (nrm[:, 2] > 0.9))  # front face and top


def test_guard_clearance(box):
    from mavac.inspection.nos import raycasting_scene

    scene = raycasting_scene(box)
    pts = np.array([[0.0, -0.5, 0.4], [0.0, 0.0, 0.0]])
    nrm = np.array([[0, -1.0, 0], [0, 0, -1.0]])
    assert SP.guard_clearance(scene, pts, nrm, 0.5).tolist() == [True, False]  # floor blocks the bottom


def test_select_spots_is_the_greedy_choice():
    acc = np.array([[1, 1, 1, 0, 0, 0], [0, 0, 1, 1, 0, 0], [0, 0, 0, 0, 1, 1]], dtype=bool)
    sel = SP.select_spots(acc, np.zeros((3, 3)), 0.5)
    assert sel.greedy.selected.tolist() == [0, 2]  # then spot 1 adds 1 < 0.5 x 3
    sel = SP.select_spots(acc, np.zeros((3, 3)), 0.3)
    assert sel.greedy.selected.tolist() == [0, 2, 1]
    assert sel.C == pytest.approx(1.0) and sel.O == pytest.approx(1 / 6)
    assert sel.O_pairwise == pytest.approx((1 / 3) / 6)  # one shared element over three pairs
    sel = SP.select_spots(acc, np.zeros((3, 3)), 0.9)
    assert sel.greedy.selected.tolist() == [0]
    assert sel.spots.shape == (1, 3)


def test_bad_input():
    with pytest.raises(ValueError, match="footprint"):
        SP.candidate_spots(RECT[:2], SpotParams(), np.random.default_rng(0))
    with pytest.raises(ValueError, match="scene"):
        SP.spot_visibility(np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((1, 3)),
                           SpotParams(view_heights=(1.0,)), Visibility("raycast"))
    with pytest.raises(TypeError, match="visibility"):
        SP.spot_visibility(np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((1, 3)), SpotParams(), "raycast")
    with pytest.raises(ValueError, match="standoff"):
        SP.reachable_sets(None, np.zeros((1, 3)), np.zeros((4, 3)), np.zeros((4, 3)), 0.0)
    with pytest.raises(ValueError, match="jitter_theta"):
        SpotParams(jitter_theta=4.0)
    with pytest.raises(ValueError, match="heading_offsets"):
        SpotParams(heading_offsets=())
    with pytest.raises(ValueError, match="spot_radius_factor"):
        Visibility(spot_radius_factor=1.0)

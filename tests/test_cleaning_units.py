"""MAVAC online building blocks: detection, filters, areas, eq. 5, base travel, miss causes, params."""

import dataclasses
import math

import numpy as np
import pytest

from mavac.cleaning.approach import approach_orientations, approach_poses
from mavac.cleaning.clustering import areas_from_nodes, tsp_order
from mavac.cleaning.detection import detect_dust, dust_mask, match_nodes
from mavac.cleaning.filters import filter_nodes
from mavac.cleaning.heaps import DustField
from mavac.cleaning.misses import HeapEvents, cause_counts, in_frustum, mark_blobs, miss_causes, near_frustum
from mavac.cleaning.timing import TrialTimes, base_path_length
from mavac.cleaning.vacuum import spiral_path
from mavac.params import ApproachParams, DetectionParams, DustParams, OnlineParams, VacuumParams
from mavac.sim.render import intrinsics_from_fov, render_rgbd
from mavac.sim.world import SimWorld


def _image_with_two_blobs():
    rgb = np.full((60, 80, 3), 128, dtype=np.uint8)
    rgb[10:14, 10:14] = (25, 200, 25)   # green heap, 16 px
    rgb[40:43, 60:63] = (25, 200, 25)   # green heap, 9 px
    rgb[30, 30] = (25, 200, 25)          # 1 px: noise
    rgb[20:25, 40:45] = (200, 30, 30)    # red: not dust
    depth = np.full((60, 80), 0.4)
    depth[40:43, 60:63] = np.inf         # second blob has no depth
    return rgb, depth


def test_hsv_blobs_become_nodes_on_the_back_projected_ray():
    rgb, depth = _image_with_two_blobs()
    params = DetectionParams()
    assert dust_mask(rgb, params).sum() == 16 + 9 + 1
    K = intrinsics_from_fov(80, 60, 59.0)
    det = detect_dust(rgb, depth, K, np.eye(4), params)
    assert len(det) == 2 and sorted(det.pixels.tolist()) == [9, 16]
    first = int(np.argmax(det.pixels))
    np.testing.assert_allclose(det.centroids[first], [11.5, 11.5])
    assert det.nodes[first, 2] == pytest.approx(0.4)
    assert det.nodes[first, 0] == pytest.approx((11.5 - K[0, 2]) / K[0, 0] * 0.4)
    assert np.isnan(det.depth[1 - first]) and np.all(np.isnan(det.nodes[1 - first]))


def test_nothing_green_gives_no_nodes():
    det = detect_dust(np.zeros((20, 20, 3), np.uint8), np.ones((20, 20)), intrinsics_from_fov(20, 20, 60), np.eye(4),
                      DetectionParams())
    assert len(det) == 0 and det.nodes.shape == (0, 3)


def test_filters_drop_bad_depth_out_of_reach_and_duplicates():
    nodes = np.array([[0.3, 0, 0], [np.nan] * 3, [5.0, 0, 0], [0.0, 0.3, 0.0], [0.0, -0.3, 0.0]])
    depth = np.array([0.4, np.nan, 0.4, 0.45, 3.5])
    vacuumed = np.array([[0.0, 0.32, 0.0]])
    params = DetectionParams(duplicate=True)
    why = filter_nodes(nodes, depth, shoulder=np.zeros(3), vacuumed=vacuumed, params=params)
    assert why.tolist() == ["", "depth", "reach", "duplicate", "depth"]


def test_depth_is_valid_over_the_sensor_range_not_cut_at_L_d():
    nodes = np.array([[0.3, 0, 0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.3]])
    why = filter_nodes(nodes, [1.0, 3.0, 0.2], shoulder=np.zeros(3), vacuumed=np.zeros((0, 3)),
                       params=DetectionParams())
    assert why.tolist() == ["", "depth", "depth"]  # 1.0 m kept: beyond L_d = 0.5 m, inside 0.25-2.88 m


def test_duplicate_filter_is_off_by_default():
    assert DetectionParams().duplicate is False
    why = filter_nodes([[0.0, 0.3, 0.0]], [0.45], shoulder=np.zeros(3), vacuumed=[[0.0, 0.31, 0.0]],
                       params=DetectionParams())
    assert why.tolist() == [""]


def test_tip_filter_keeps_nodes_strictly_within_the_distance():
    params = DetectionParams(max_tip_distance=0.5)
    nodes = np.array([[0.0, 0.0, 0.4], [0.0, 0.0, 0.6], [0.0, 0.0, 0.5]])
    tip = np.array([0.0, 0.0, 0.0])
    why = filter_nodes(nodes, [0.9, 0.9, 0.9], shoulder=np.zeros(3), vacuumed=np.zeros((0, 3)), params=params, tip=tip)
    assert why.tolist() == ["", "tip", "tip"]
    assert DetectionParams().max_tip_distance is None
    with pytest.raises(ValueError, match="tip"):
        filter_nodes(nodes, [0.9] * 3, shoulder=np.zeros(3), vacuumed=np.zeros((0, 3)), params=params)
    with pytest.raises(ValueError, match="max_tip_distance"):
        DetectionParams(max_tip_distance=-1.0)


def test_dbscan_areas_are_ordered_and_complete():
    nodes = np.array([[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [2, 0, 0], [2.1, 0, 0]], dtype=float)
    areas = areas_from_nodes(nodes, eps=0.15)
    assert [sorted(a.tolist()) for a in areas] == [[0, 1, 2], [3, 4]]
    assert areas[0][0] == 1  # starts at the node nearest the centroid
    assert areas_from_nodes(np.zeros((0, 3)), eps=0.1) == []


def test_eq5_approach_point_readings_and_orientation_tolerance():
    R = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]])  # tool z pointing down
    rng = np.random.default_rng(0)
    Rs = approach_orientations(R, math.radians(10), 20, rng)
    np.testing.assert_allclose(Rs[0], R, atol=1e-12)
    angles = [np.degrees(np.arccos(np.clip((np.trace(R.T @ Ri) - 1) / 2, -1, 1))) for Ri in Rs]
    assert max(angles) <= 10 * math.sqrt(3) + 1e-6 and max(angles) > 1.0
    node = np.array([0.5, 0.2, 0.8])
    tool = approach_poses(node, Rs[:1], 0.1, "tool")[0]
    np.testing.assert_allclose(tool[:3, 3], node + [0, 0, 0.1])  # back along the downward tool axis
    world = approach_poses(node, Rs[1:2], 0.1, "world")[0]
    np.testing.assert_allclose(world[:3, 3], node + [0, 0, 0.1])
    np.testing.assert_allclose(world[:3, :3], Rs[1])


def test_base_path_goes_around_the_machine():
    square = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    straight = base_path_length([-2, -2], [2, -2], square, 0.1)
    assert straight == pytest.approx(4.0)
    around = base_path_length([-2, 0], [2, 0], square, 0.1)
    assert around > 4.0 + 0.5
    assert TrialTimes(1.0, 2.0, 3.0, 99.0).sim_time_s == 6.0


def test_miss_cause_is_the_furthest_stage():
    ev = HeapEvents.empty(9)
    ev.mark("in_skipped_view", [1, 2])
    ev.mark("in_frustum", [2, 3, 4, 5, 6, 7, 8])
    ev.mark("in_image", [3, 4, 5, 6, 7, 8, -1])
    ev.mark("merged", [4, 8])
    ev.mark("own_blob", [3, 8])  # heap 8 had a blob of its own in another image: not merged
    ev.mark("no_approach", [5])
    ev.mark("planner_failed", [6])
    ev.mark("attempted", [7])
    causes = miss_causes(ev, [False] * 8 + [True])
    assert causes.tolist() == ["never in view", "guard not reached", "hidden", "filtered", "merged blob",
                               "no approach found", "planner failed", "vacuum missed", ""]
    assert sum(cause_counts(causes).values()) == 8


def test_merged_blob_is_told_from_a_blob_of_its_own():
    """Blob 0 holds heaps 1 and 2, its node matched heap 2: heap 1 is merged. Blob 1 holds only
    heap 3 (its node matched nothing): its own. Heap 4 is drawn outside every kept blob."""
    blobs = np.array([[0, 0, -1, 1], [0, 0, -1, 1], [-1, -1, -1, -1]])
    seg = np.array([[1, 2, 4, 3], [1, 2, -1, 3], [-1, -1, -1, -1]])
    ev = HeapEvents.empty(5)
    ev.mark("in_image", [1, 2, 3, 4])
    mark_blobs(ev, blobs, seg, np.array([2, -1]))
    assert ev.merged.tolist() == [False, True, False, False, False]
    assert ev.own_blob.tolist() == [False, False, True, True, False]
    assert miss_causes(ev, np.zeros(5, dtype=bool)).tolist() == ["never in view", "merged blob", "filtered",
                                                                 "filtered", "filtered"]
    mark_blobs(ev, blobs, seg, np.array([-1, -1]))  # a node that matched neither: both merged
    assert ev.merged[2]


def test_frustum_and_matching():
    K = intrinsics_from_fov(40, 30, 60)
    pts = np.array([[0, 0, 1.0], [0, 0, -1.0], [5.0, 0, 1.0]])
    assert in_frustum(pts, np.eye(4), K, 40, 30, 0.05, 5.0).tolist() == [True, False, False]
    assert match_nodes([[0, 0, 1.01], [9, 9, 9], [np.nan] * 3], pts, 0.05).tolist() == [0, -1, -1]


@pytest.mark.parametrize("cls, field", [(VacuumParams, "suction_radius"), (ApproachParams, "alpha"),
                                        (ApproachParams, "delta"), (VacuumParams, "stiffness"),
                                        (DustParams, "spacing")])
def test_negative_parameters_are_refused_by_name(cls, field):
    with pytest.raises(ValueError, match=field):
        cls(**{field: -0.1})


@pytest.mark.parametrize("value", [0, 2.5, -1])
def test_retry_factor_is_a_positive_int(value):
    with pytest.raises((ValueError, TypeError), match="rrt_retry_factor"):
        ApproachParams(rrt_retry_factor=value)


def test_approach_reading_must_be_known():
    with pytest.raises(ValueError, match="approach_reading"):
        ApproachParams(approach_reading="sideways")
    assert dataclasses.replace(OnlineParams(), base_speed=0.5).base_speed == 0.5


def _tour_length(P, order):
    return float(np.linalg.norm(P[order] - P[np.roll(order, -1)], axis=1).sum())


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tsp_order_is_optimal_against_brute_force_and_deterministic(seed):
    import itertools

    P = np.random.default_rng(seed).uniform(0.0, 0.5, size=(8, 3))
    order = tsp_order(P)
    assert order[0] == 0 and sorted(order.tolist()) == list(range(8))
    best = min(_tour_length(P, np.array((0,) + p)) for p in itertools.permutations(range(1, 8)))
    assert _tour_length(P, order) <= best + 8 * 1e-4  # 0.1 mm rounding per edge
    np.testing.assert_array_equal(tsp_order(P), order)


def test_tsp_order_of_a_large_set_is_a_deterministic_tour():
    P = np.random.default_rng(3).uniform(0.0, 1.0, size=(30, 3))
    order = tsp_order(P)
    assert order[0] == 0 and sorted(order.tolist()) == list(range(30))
    np.testing.assert_array_equal(tsp_order(P), order)
    assert _tour_length(P, order) < _tour_length(P, np.arange(30))


def test_areas_in_tsp_order_and_node_orders():
    # a ring of 6 nodes given out of order: the tour goes round the ring
    angles = np.array([0, 3, 1, 4, 2, 5]) * np.pi / 3
    ring = 0.1 * np.c_[np.cos(angles), np.sin(angles), np.zeros(6)]
    (area,) = areas_from_nodes(ring, eps=0.15, node_order="tsp")
    steps = np.diff(np.r_[angles[area], angles[area][0]])
    assert np.allclose(np.abs(np.angle(np.exp(1j * steps))), np.pi / 3)
    assert sorted(areas_from_nodes(ring, eps=0.15, node_order="path")[0].tolist()) == list(range(6))
    far = np.array([[0, 0, 0], [3, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    assert [a.tolist() for a in areas_from_nodes(far, eps=0.1, area_order="tsp")] in ([[0], [2], [3], [1]],
                                                                                   [[0], [1], [3], [2]])
    with pytest.raises(ValueError, match="node_order"):
        areas_from_nodes(far, eps=0.1, node_order="random")


def test_dbscan_min_samples_two_drops_lone_nodes_as_noise():
    nodes = np.array([[0, 0, 0], [0.05, 0, 0], [1.0, 0, 0]], dtype=float)
    assert [sorted(a.tolist()) for a in areas_from_nodes(nodes, eps=0.1, min_samples=2)] == [[0, 1]]


def test_spiral_path_geometry():
    center = np.array([0.3, -0.2, 0.8])
    path = spiral_path(center, radius=0.01, turns=2.0, n=801)
    np.testing.assert_allclose(path[0], center)
    r = np.linalg.norm(path - center, axis=1)
    assert r.max() == pytest.approx(0.01) and r[-1] == pytest.approx(0.01)
    assert np.all(np.diff(r) >= 0)  # Archimedean: radius grows with the angle
    np.testing.assert_allclose(path[:, 2], center[2])  # in the plane normal to world z
    phi = np.unwrap(np.arctan2(path[1:, 1] - center[1], path[1:, 0] - center[0]))
    assert abs(phi[-1] - phi[0]) == pytest.approx(2 * 2 * np.pi, abs=0.05)
    np.testing.assert_allclose(r[400], 0.005, atol=1e-12)  # half way in angle, half the radius
    tilted = spiral_path(center, radius=0.02, turns=1.0, n=50, axis=(1.0, 0, 0))
    np.testing.assert_allclose(tilted[:, 0], center[0])
    with pytest.raises(ValueError, match="radius"):
        spiral_path(center, radius=0.0, turns=1.0, n=10)


def test_vacuum_pattern_and_orders_are_checked_by_name():
    with pytest.raises(ValueError, match="pattern"):
        VacuumParams(pattern="zigzag")
    with pytest.raises(ValueError, match="spiral_nodes"):
        VacuumParams(spiral_nodes="first")
    with pytest.raises(ValueError, match="area_order"):
        ApproachParams(area_order="random")


def _oblique_camera() -> np.ndarray:
    """OpenCV camera 1 m above the floor at x = -0.6, looking down and forward (+x) at 50 deg."""
    a = np.radians(50.0)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([[0.0, -1.0, 0.0], [-np.sin(a), 0.0, -np.cos(a)], [np.cos(a), 0.0, -np.sin(a)]])
    T[:3, 3] = (-0.6, 0.0, 1.0)
    return T


def _render(world, T):
    return render_rgbd(world.client, T, width=96, height=72, fov_y_deg=60, near=0.05, far=5.0)


def _render_heaps(dust, world, T, where=None):
    with dust.in_view(world, where) as bodies:
        rgb, depth, seg = _render(world, T)
    return rgb, depth, dust.index_of_bodies(seg, bodies).reshape(seg.shape), bodies


def test_heaps_enter_the_world_only_to_be_rendered_and_culling_keeps_the_image():
    rng = np.random.default_rng(4)
    heaps = np.column_stack([rng.uniform(-2.0, 2.0, (1500, 2)), np.full(1500, 0.01)])
    dust = DustField.of(heaps, DustParams())
    T = _oblique_camera()
    K = intrinsics_from_fov(96, 72, 60)
    with SimWorld() as world:
        floor = world.add_floor()
        dust.suck(heaps[0], 1e-6)
        rgb, depth, heap_of, bodies = _render_heaps(dust, world, T)
        assert bodies[0] == -1 and np.count_nonzero(bodies >= 0) == 1499  # the vacuumed heap is not drawn
        assert 0 not in heap_of and len(np.unique(heap_of)) > 10
        assert set(np.unique(_render(world, T)[2])) <= {-1, floor}  # gone after the render
        near = near_frustum(heaps, T, K, 96, 72, 0.05, 5.0, dust.radius + 0.05)
        seen = in_frustum(heaps, T, K, 96, 72, 0.05, 5.0)
        assert np.all(near[seen]) and near.sum() < 1000  # a superset of the frustum, not everything
        culled = _render_heaps(dust, world, T, near)
        for a, b in zip((rgb, depth, heap_of), culled[:3]):
            np.testing.assert_array_equal(a, b)
        # heaps centred just outside the frustum still show at the image's edges
        assert not np.array_equal(heap_of, _render_heaps(dust, world, T, seen)[2])


def test_suck_removes_each_heap_once():
    dust = DustField.of(np.array([[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [1.0, 0.0, 0.0]]), DustParams())
    assert dust.suck(np.array([0.01, 0.0, 0.0]), 0.03).tolist() == [0]
    assert dust.suck(np.array([0.01, 0.0, 0.0]), 0.045).tolist() == [1]  # 0 is gone already
    assert dust.suck(np.array([0.01, 0.0, 0.0]), 0.045).tolist() == []
    assert dust.suck(np.array([1.0, 0.0, 0.02]), 0.03).tolist() == [2]
    assert dust.cleaned.all() and dust.suck(np.zeros(3), 10.0).tolist() == []


def test_suck_along_a_path_equals_testing_every_heap_at_every_step():
    rng = np.random.default_rng(2)
    heaps = rng.uniform(0.0, 0.5, (60, 3))
    dust = DustField.of(heaps, DustParams())
    present = np.ones(len(heaps), dtype=bool)
    tip, got, expected = np.full(3, 0.25), [], []
    for step in range(4000):
        tip = np.clip(tip + rng.normal(0.0, 0.008, 3), 0.0, 0.5)
        radius = 0.03 if step < 3000 else 0.05  # a new radius is tested afresh
        got.append(dust.suck(tip, radius).tolist())
        hit = np.flatnonzero(present & (np.linalg.norm(heaps - tip, axis=1) <= radius))  # the test it replaces
        present[hit] = False
        expected.append(hit.tolist())
    assert got == expected and 10 < (~present).sum() < len(heaps)

"""MAVAC online building blocks: detection, filters, areas, eq. 5, base travel, miss causes, params."""

import dataclasses
import math

import numpy as np
import pytest

from mavac.cleaning.approach import approach_orientations, approach_poses
from mavac.cleaning.clustering import areas_from_nodes
from mavac.cleaning.detection import detect_dust, dust_mask, match_nodes
from mavac.cleaning.filters import filter_nodes
from mavac.cleaning.misses import HeapEvents, cause_counts, in_frustum, miss_causes
from mavac.cleaning.timing import TrialTimes, base_path_length
from mavac.params import ApproachParams, DetectionParams, DustParams, OnlineParams, VacuumParams
from mavac.sim.render import intrinsics_from_fov


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
    depth = np.array([0.4, np.nan, 0.4, 0.45, 0.9])
    why = filter_nodes(nodes, depth, shoulder=np.zeros(3), vacuumed=np.array([[0.0, 0.32, 0.0]]),
                       params=DetectionParams())
    assert why.tolist() == ["", "depth", "reach", "duplicate", "depth"]


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
    ev = HeapEvents.empty(7)
    ev.mark("in_frustum", [1, 2, 3, 4, 5, 6])
    ev.mark("in_image", [2, 3, 4, 5, 6, -1])
    ev.mark("no_approach", [3])
    ev.mark("planner_failed", [4])
    ev.mark("attempted", [5, 6])
    causes = miss_causes(ev, [False, False, False, False, False, False, True])
    assert causes.tolist() == ["never in view", "hidden", "filtered", "no approach found", "planner failed",
                               "vacuum missed", ""]
    assert sum(cause_counts(causes).values()) == 6


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


def test_approach_reading_must_be_known():
    with pytest.raises(ValueError, match="approach_reading"):
        ApproachParams(approach_reading="sideways")
    assert dataclasses.replace(OnlineParams(), base_speed=0.5).base_speed == 0.5

"""The world departing from the plan: the frames stay consistent (the robot plans, detects and
filters where it believes; the simulator places, renders and scores in the truth), the draws are
the ones declared, and an unperturbed trial draws nothing."""

import dataclasses
import warnings

import numpy as np
import pytest
import trimesh

from mavac.cleaning import perturbation as P
from mavac.cleaning import trial as T
from mavac.cleaning.scene import build_cell
from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.machines import machine_from_mesh
from mavac.geometry.transforms import se2_to_matrix, transform_points
from mavac.inspection.inspection_plan import plan_inspection
from mavac.params import DustParams, OnlineParams, PerturbationParams
from mavac.robots.kinematics import fk
from mavac.robots.models import ur10_mobile
from mavac.sim.world import SimWorld

PARAMS = OnlineParams(dust=DustParams(spacing=0.2))
BOX = trimesh.creation.box(bounds=[[-0.5, -0.3, 0.0], [0.5, 0.3, 0.6]])


def _with(**fields) -> OnlineParams:
    return dataclasses.replace(PARAMS, perturbation=PerturbationParams(**fields))


@pytest.fixture(scope="module")
def small():
    """The box and the first three poses of its fast-mode plan."""
    machine = machine_from_mesh(BOX, name="box")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_inspection(machine, params=fast_params())
    return machine, dataclasses.replace(plan, pose_set=plan.pose_set.head(3))


def test_machine_motion_shifts_and_turns_by_the_sizes_asked_about_the_bounds_centre():
    assert np.array_equal(P.machine_motion(BOX, PerturbationParams(), 4), np.eye(4))
    shift = P.machine_motion(BOX, PerturbationParams(machine_shift=0.2), 4)
    assert np.allclose(shift[:3, :3], np.eye(3)) and np.isclose(np.linalg.norm(shift[:2, 3]), 0.2)
    assert shift[2, 3] == 0.0
    turn = P.machine_motion(BOX, PerturbationParams(machine_rotation=10.0), 4)
    assert np.isclose(np.degrees(abs(np.arctan2(turn[1, 0], turn[0, 0]))), 10.0)
    assert np.allclose(transform_points(turn, [[0.0, 0.0, 0.3]]), [[0.0, 0.0, 0.3]])  # the box's centre stays
    # the direction is the seed's, whatever the size: 0.1 m goes half as far the same way
    half = P.machine_motion(BOX, PerturbationParams(machine_shift=0.1), 4)
    assert np.allclose(2.0 * half[:2, 3], shift[:2, 3])
    assert not np.allclose(P.machine_motion(BOX, PerturbationParams(machine_shift=0.2), 5), shift)


def test_localisation_error_has_the_declared_spread_and_is_none_at_zero():
    assert np.array_equal(P.localisation_error(PerturbationParams(), 1, 0), np.eye(4))
    p = PerturbationParams(base_position_sigma=0.02, base_heading_sigma=2.0)
    errors = np.array([P.localisation_error(p, 1, k) for k in range(2000)])
    assert np.allclose(errors[:, :2, 3].std(axis=0), 0.02, rtol=0.1)
    assert np.isclose(np.degrees(np.arctan2(errors[:, 1, 0], errors[:, 0, 0])).std(), 2.0, rtol=0.1)
    assert np.array_equal(P.localisation_error(p, 1, 7), errors[7])


def test_the_machine_moved_is_the_base_moved_the_other_way():
    """A machine point seen from where the base really is equals the moved machine's point seen
    from where the base believes it is."""
    moved = P.machine_motion(BOX, PerturbationParams(machine_shift=0.1, machine_rotation=7.0), 2)
    error = P.localisation_error(PerturbationParams(base_position_sigma=0.03, base_heading_sigma=3.0), 2, 0)
    believed = se2_to_matrix(1.2, -0.4, 2.5)
    truth = P.true_base_pose(believed, moved, error)
    point = np.array([[0.3, -0.2, 0.6]])  # on the machine, true frame
    seen_truly = transform_points(np.linalg.inv(truth), point)
    seen_believed = transform_points(np.linalg.inv(believed @ error), transform_points(moved, point))
    assert np.allclose(seen_truly, seen_believed)


def test_image_noise_has_its_sigma_keeps_types_and_leaves_no_hit_unhit():
    rgb = np.full((60, 80, 3), 128, np.uint8)
    depth = np.full((60, 80), 1.0)
    depth[0] = np.inf
    same = P.noisy_images(rgb, depth, PerturbationParams(), 0, 0)
    assert same[0] is rgb and same[1] is depth
    noisy_rgb, noisy_depth = P.noisy_images(rgb, depth, PerturbationParams(colour_noise=10.0, depth_noise=0.005), 0, 0)
    assert noisy_rgb.dtype == np.uint8 and np.isclose(noisy_rgb.astype(float).std(), 10.0, rtol=0.1)
    assert np.all(np.isinf(noisy_depth[0])) and np.isclose(noisy_depth[1:].std(), 0.005, rtol=0.1)
    again = P.noisy_images(rgb, depth, PerturbationParams(colour_noise=10.0, depth_noise=0.005), 0, 0)
    assert np.array_equal(again[0], noisy_rgb)
    other = P.noisy_images(rgb, depth, PerturbationParams(colour_noise=10.0, depth_noise=0.005), 0, 1)
    assert not np.array_equal(other[0], noisy_rgb)


def test_decoys_lie_on_the_machine_surface():
    points = P.decoy_positions(BOX, 50, 3)
    assert points.shape == (50, 3)
    assert np.allclose(trimesh.proximity.ProximityQuery(BOX).signed_distance(points), 0.0, atol=1e-9)
    assert np.array_equal(points, P.decoy_positions(BOX, 50, 3))
    assert P.decoy_positions(BOX, 0, 3).shape == (0, 3)


def test_the_cell_plans_where_it_believes_and_the_simulator_holds_the_truth():
    robot = ur10_mobile()
    machine = machine_from_mesh(BOX, name="box")
    believed, truth = se2_to_matrix(1.5, 0.0, np.pi), se2_to_matrix(1.55, 0.03, np.pi + 0.05)
    with SimWorld() as world:
        cell = build_cell(world, machine, robot, np.zeros((0, 3)), PARAMS, believed)
        cell.move_base(believed, true_world_T_base=truth)
        base_T_tool = fk(robot, robot.q_home, robot.tool_frame)
        assert np.allclose(cell.sim.world_T_link(robot.tool_frame), truth @ base_T_tool, atol=1e-6)
        assert np.allclose(cell.world_T_tool(), believed @ base_T_tool, atol=1e-6)
        assert np.allclose(cell.checker.world_T_base, believed)


def test_a_moved_machine_is_detected_and_scored_in_consistent_frames(small):
    """Nodes are placed with the camera pose the robot believes and matched to heaps in the truth:
    mixing the frames would put every node 10 cm from its heap (beyond the 5 cm match radius)."""
    machine, plan = small
    result = T.run_trial(machine, plan, params=_with(machine_shift=0.1), seed=3)
    assert result.detected > 0 and result.precision == 1.0


def test_decoys_are_detected_as_dust_and_counted_as_false(small):
    machine, plan = small
    clean = T.run_trial(machine, plan, params=PARAMS, seed=3)
    decoyed = T.run_trial(machine, plan, params=_with(decoys=40), seed=3)
    assert clean.precision == 1.0
    assert decoyed.detected > decoyed.true_positives and decoyed.precision < 1.0



def test_every_tracked_motion_that_touches_the_machine_is_logged_with_its_force():
    """The planner's model is where the robot believes; the arm pressed into the real machine
    shows in ``transit_contacts``, a motion in free space does not."""
    robot = ur10_mobile()
    machine = machine_from_mesh(BOX, name="box")
    with SimWorld() as world:
        cell = build_cell(world, machine, robot, np.zeros((0, 3)), PARAMS, se2_to_matrix(1.3, 0.0, np.pi))
        free = robot.q_home + np.r_[0.3, 0.0, 0.0, 0.0, 0.0, 0.0]
        cell.track([free, robot.q_home], PARAMS)
        assert cell.transit_contacts == []
        into = robot.q_home + np.r_[0.0, 0.5, 0.0, 0.0, 0.0, 0.0]  # the tool 30 cm inside the box
        cell.track([into], PARAMS)
        assert len(cell.transit_contacts) == 1 and cell.transit_contacts[0] > 10.0


def test_a_spot_the_moved_machine_occupies_is_not_driven_to_and_its_poses_are_skipped(small):
    """Shifted 0.5 m (direction of seed 0: towards the spot), the machine stands where the robot
    would park: its scanners stop it, the spot's poses are skipped and counted, nothing is
    touched."""
    machine, plan = small
    result = T.run_trial(machine, plan, params=_with(machine_shift=0.5), seed=0)
    assert len(set(plan.pose_spot.tolist())) == 1
    assert result.spots_blocked == 1 and result.poses_skipped == len(plan.poses) and result.guards == 0
    assert result.n_cleaned == 0 and result.transit_contacts == [] and result.times.base_s == 0.0
    assert any("the base cannot stop at its spot" in w for w in result.warnings)

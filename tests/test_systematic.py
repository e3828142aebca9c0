"""The systematic baseline: a raster over every surface dust can rest on, the fewest passes
(brute force), reach by IK round trip, and a run that vacuums what it passes and nothing else."""

import itertools
import warnings

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from mavac.cleaning import systematic as S
from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.machines import machine_from_mesh
from mavac.inspection.inspection_plan import plan_inspection
from mavac.params import DustParams, OnlineParams, SystematicParams, VacuumParams
from mavac.robots.collision import CollisionChecker
from mavac.robots.kinematics import fk
from mavac.robots.models import TOOL_SPHERE_RADIUS, ur10_mobile
from mavac.seeding import rng_for
from mavac.geometry.transforms import se2_to_matrix

PARAMS = OnlineParams(dust=DustParams(spacing=0.1))
BOX = trimesh.creation.box(bounds=[[-0.4, -0.25, 0.0], [0.4, 0.25, 0.6]])


@pytest.fixture(scope="module")
def box_plan():
    """A 0.8 x 0.5 x 0.6 m box and its fast-mode plan."""
    machine = machine_from_mesh(BOX, name="box")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return machine, plan_inspection(machine, params=fast_params())


def test_line_spacing_is_the_width_the_suction_sweeps():
    online = OnlineParams(vacuum=VacuumParams(suction_radius=0.05))
    assert S.line_spacing(SystematicParams(), online) == pytest.approx(2 * np.sqrt(0.05**2 - TOOL_SPHERE_RADIUS**2))
    assert S.line_spacing(SystematicParams(line_spacing=0.03), online) == 0.03
    with pytest.raises(ValueError, match="suction_radius must exceed"):
        S.line_spacing(SystematicParams(), OnlineParams(vacuum=VacuumParams(suction_radius=0.02)))
    with pytest.raises(ValueError, match="line_spacing"):
        SystematicParams(line_spacing=0.0)


def test_raster_covers_the_top_and_only_surfaces_dust_rests_on():
    machine = machine_from_mesh(BOX, name="box")
    lines = S.raster_lines(machine, 0.08, 0.02)
    W = np.vstack(lines)
    assert np.allclose(W[:, 2], 0.6)  # the top only: the sides are vertical
    grid = np.stack(np.meshgrid(np.linspace(-0.4, 0.4, 41), np.linspace(-0.25, 0.25, 26)), -1).reshape(-1, 2)
    gap, _ = cKDTree(W[:, :2]).query(grid)
    assert gap.max() <= np.hypot(0.04, 0.01) + 1e-6  # half a line spacing across, half a step along
    assert all(np.linalg.norm(np.diff(line, axis=0), axis=1).max() <= 0.02 + 1e-9 for line in lines)
    # back and forth: consecutive lines start at opposite ends of the long (x) axis
    starts = [np.sign(line[-1, 0] - line[0, 0]) for line in lines]
    assert all(a == -b for a, b in zip(starts, starts[1:]))


def test_a_machine_without_upward_faces_has_no_raster():
    spire = machine_from_mesh(trimesh.creation.cone(radius=0.2, height=2.0, sections=8), name="spire")
    assert S.raster_lines(spire, 0.08, 0.02) == []


def test_tool_axes_tilt_by_alpha_around_straight_down():
    axes = S.tool_axes(np.radians(20.0), 8)
    assert axes.shape == (8, 3) and np.allclose(axes[0], [0, 0, -1])
    assert np.allclose(np.linalg.norm(axes, axis=1), 1.0)
    assert np.allclose(np.degrees(np.arccos(-axes[1:, 2])), 20.0)
    assert S.tool_axes(0.0, 8).shape == (1, 3) and S.tool_axes(0.3, 1).shape == (1, 3)


def _fewest_runs_brute_force(reach) -> int:
    """Least number of runs over every assignment of a reaching column to each reachable waypoint."""
    options = [np.flatnonzero(r) if r.any() else [-1] for r in reach]
    best = np.inf
    for choice in itertools.product(*options):
        runs = sum(1 for i, c in enumerate(choice) if c >= 0 and (i == 0 or choice[i - 1] != c))
        best = min(best, runs)
    return best


@pytest.mark.parametrize("seed", range(40))
def test_runs_of_line_are_the_fewest_by_brute_force(seed):
    rng = np.random.default_rng(seed)
    reach = rng.random((int(rng.integers(1, 8)), 3)) < 0.5
    runs = S.runs_of_line(reach)
    assert len(runs) == _fewest_runs_brute_force(reach)
    covered = np.zeros(len(reach), dtype=bool)
    for a, b, c in runs:
        assert reach[a:b, c].all()
        covered[a:b] = True
    assert np.array_equal(covered, reach.any(axis=1))


def test_passes_group_by_spot_in_raster_order():
    lines = [np.zeros((4, 3)) + i for i in range(3)]
    # columns: spot 0 axis 0, spot 0 axis 1, spot 1 axis 0, spot 1 axis 1
    reach = np.zeros((12, 4), dtype=bool)
    reach[0:4, 2] = True  # line 0: spot 1
    reach[4:6, 0] = True  # line 1: spot 0, then a gap, then spot 0 with the other axis
    reach[7:8, 1] = True
    reach[8:12, 0] = True  # line 2: spot 0
    q = np.arange(12 * 4 * 6, dtype=float).reshape(12, 4, 6)
    passes = S.passes_from_raster(lines, reach, q, 2)
    assert [(p.spot, len(p.waypoints), float(p.waypoints[0, 0])) for p in passes] == [
        (0, 2, 1.0), (0, 1, 1.0), (0, 4, 2.0), (1, 4, 0.0)]
    assert np.array_equal(passes[0].q_start, q[4, 0]) and np.array_equal(passes[3].q_start, q[0, 2])


def test_reach_is_an_ik_round_trip_clear_of_the_machine(box_plan):
    machine, plan = box_plan
    robot = ur10_mobile()
    W = np.vstack(S.raster_lines(machine, 0.1, 0.05))
    axes = S.tool_axes(np.radians(20.0), 4)
    checker = CollisionChecker(robot, machine.mesh, margin=0.01, floor=True)
    reach, q_back = S.reach_matrix(robot, checker, plan.spots[:2], W, axes, 0.05, rng=np.random.default_rng(0))
    assert reach.shape == (len(W), 2 * len(axes)) and reach.any()
    for s in range(2):
        world_T_base = se2_to_matrix(*plan.spots[s])
        checker.set_base(world_T_base)
        for j, axis in enumerate(axes):
            ok = reach[:, s * len(axes) + j]
            if not ok.any():
                continue
            T = world_T_base @ fk(robot, q_back[ok, s * len(axes) + j])
            assert np.allclose(T[:, :3, 3], W[ok] - 0.05 * axis, atol=1e-3)
            assert np.allclose(T[:, :3, 2], axis, atol=1e-3)
            assert not checker.in_collision(q_back[ok, s * len(axes) + j]).any()


def test_a_run_vacuums_what_it_passes_and_nothing_else(box_plan):
    machine, plan = box_plan
    a = S.run_systematic(machine, plan, params=PARAMS, seed=2)
    b = S.run_systematic(machine, plan, params=PARAMS, seed=2)
    assert a.row() == b.row()
    assert a.n_heaps > 0 and a.times.vacuum_s > 0 and a.times.arm_s > 0
    assert a.passes_run == a.passes > 0 and a.passes_unplanned == a.passes_skipped == 0  # the box is easy
    # heaps under the raster's reachable waypoints are gone (the sphere rides rho above them)
    robot = ur10_mobile()
    checker = CollisionChecker(robot, machine.mesh, margin=PARAMS.approach.collision_margin, floor=True)
    W = np.vstack(S.raster_lines(machine, S.line_spacing(SystematicParams(), PARAMS), 0.02))
    axes = S.tool_axes(PARAMS.approach.alpha, PARAMS.approach.n_orientations)
    reach, _ = S.reach_matrix(robot, checker, S.spots_of_poses(plan), W, axes, PARAMS.approach.delta,
                              rng=rng_for(2, "raster reach"))  # the run's own draws
    under, _ = cKDTree(W[reach.any(axis=1)]).query(a.heaps)
    assert a.cleaned[under < 0.02].all() and (under < 0.02).any()
    # and heaps the tool never came near stay: every key of the replay, planned moves included
    keys = np.array([se2_to_matrix(*base) @ fk(robot, q) for base, q in zip(a.replay.bases, a.replay.qs)])
    near, _ = cKDTree(keys[:, :3, 3]).query(a.heaps)
    r_s = PARAMS.vacuum.suction_radius
    assert not a.cleaned[near > r_s + 0.015].any()  # vacuuming keys are 1 cm apart at 0.1 m/s


def test_density_keeps_a_seeded_subset_of_the_layout(box_plan):
    from mavac.cleaning.heaps import heaps_for_trial

    machine, _ = box_plan
    full = heaps_for_trial(machine, DustParams(spacing=0.05), 4)
    part = heaps_for_trial(machine, DustParams(spacing=0.05, density=0.3), 4)
    assert len(part) == round(0.3 * len(full))
    assert {tuple(p) for p in part} <= {tuple(p) for p in full}
    assert np.array_equal(part, heaps_for_trial(machine, DustParams(spacing=0.05, density=0.3), 4))
    with pytest.raises(ValueError, match=r"density must be in \(0.0, 1.0\]"):
        DustParams(density=1.5)


def test_bad_input_names_the_parameter(box_plan):
    machine, plan = box_plan
    with pytest.raises(TypeError, match="systematic"):
        S.run_systematic(machine, plan, systematic="raster")
    with pytest.raises(ValueError, match="seed"):
        S.run_systematic(machine, plan, seed=-1)


def test_held_passes_end_where_the_arm_backs_out_with_the_start_orientation(box_plan):
    machine, plan = box_plan
    robot = ur10_mobile()
    lines = S.raster_lines(machine, 0.1, 0.05)
    axes = S.tool_axes(np.radians(20.0), 4)
    checker = CollisionChecker(robot, machine.mesh, margin=0.01, floor=True)
    reach, q_back = S.reach_matrix(robot, checker, plan.spots[:2], np.vstack(lines), axes, 0.05,
                                   rng=np.random.default_rng(0))
    raw = S.passes_from_raster(lines, reach, q_back, len(axes))
    held = S.held_passes(robot, checker, plan.spots, raw, rng=np.random.default_rng(1))
    assert len(held) == len(raw) and any(len(p.waypoints) > 1 for p in held)
    for before, p in zip(raw, held):
        k = len(p.waypoints)
        assert k <= len(before.waypoints) and np.array_equal(p.waypoints, before.waypoints[:k])
        start, end = fk(robot, p.q_start), fk(robot, p.q_end)
        assert np.allclose(end[:3, :3], start[:3, :3], atol=1e-3)  # the orientation is held
        world_T_base = se2_to_matrix(*plan.spots[p.spot])
        offset = (world_T_base @ start)[:3, 3] - p.waypoints[0]
        assert np.allclose((world_T_base @ end)[:3, 3], p.waypoints[-1] + offset, atol=1e-3)
        checker.set_base(world_T_base)
        assert not checker.in_collision(p.q_end)


def test_the_baseline_stops_where_the_online_loop_would(box_plan):
    import dataclasses

    _, plan = box_plan
    spots = S.spots_of_poses(plan)
    assert len(spots) == len(np.unique(plan.pose_spot)) and len(spots) > 1
    np.testing.assert_allclose(spots, plan.spots[list(dict.fromkeys(plan.pose_spot.tolist()))])
    first = dataclasses.replace(plan, pose_set=plan.pose_set.head(1))
    np.testing.assert_allclose(S.spots_of_poses(first), plan.poses[:1, :3])

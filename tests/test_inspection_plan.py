"""plan_inspection end to end on a small box machine, determinism, empty plans, bad input."""

import dataclasses
import json
import warnings

import numpy as np
import pytest
import trimesh

from mavac.inspection.inspection_plan import plan_from_context, plan_inspection, prepare_offline
from mavac.planning.tour import short_open_path
from mavac.params import (GuardParams, InspectionParams, NoSParams, ReachabilityMapParams, SpotParams, Visibility)
from mavac.tolerances import BURIED_TOLERANCE

FAST = InspectionParams(
    surface_spacing=0.1,
    reach=ReachabilityMapParams(voxel_size=0.1, n_directions=26, n_samples=20_000, n_rotations=32),
    spot=SpotParams(ring_spacing=0.6),
    guard=GuardParams(guard_spacing=0.2),
    nos=NoSParams(n_rays=200, rrt_max_iterations=5_000),
)


def _box_machine():
    """A 1.2 x 0.8 x 0.9 m box with an open-top pocket (a concavity for NoS)."""
    from mavac.geometry.machines import machine_from_mesh

    box = trimesh.creation.box(bounds=[[-0.6, -0.4, 0.0], [0.6, 0.4, 0.9]])
    pocket = trimesh.creation.box(bounds=[[-0.3, -0.2, 0.5], [0.3, 0.2, 1.0]])
    return machine_from_mesh(trimesh.boolean.difference([box, pocket], engine="manifold"), name="pocket_box")


@pytest.fixture(scope="module")
def robot():
    from mavac.robots.models import ur10_mobile

    return ur10_mobile()


@pytest.fixture(scope="module")
def ctx(robot):
    return prepare_offline(_box_machine(), robot=robot, params=FAST)


@pytest.fixture(scope="module")
def plan(ctx):
    return plan_from_context(ctx)


def test_context_keeps_the_callers_robot(ctx, robot):
    # no modified copy of the pinocchio model: workers pickle the robot by name
    assert ctx.robot is robot


def test_robot_without_camera_is_refused():
    from mavac.robots.models import puma560

    with pytest.raises(ValueError, match="camera_frame"):
        prepare_offline(_box_machine(), robot=puma560(), params=FAST)


def test_plan_end_to_end(plan, robot):
    from mavac.inspection.spots import se2_matrices
    from mavac.robots.kinematics import fk

    assert plan.n_spots >= 1 and plan.n_guards >= 1
    assert 0.0 < plan.C <= 1.0 and 0.0 <= plan.O <= plan.C
    h, n = plan.visible.shape
    assert h == len(plan.poses) == plan.n_guards + plan.n_nos_guards and n == len(plan.points)
    # each pose row = its spot + a configuration whose camera is the stored camera pose
    assert np.allclose(plan.poses[:, :3], plan.spots[plan.pose_spot])
    T = se2_matrices(plan.poses[:, :3]) @ fk(robot, plan.poses[:, 3:], robot.camera_frame)
    assert np.allclose(T, plan.world_T_camera, atol=1e-9)
    # a regular guard's camera sits L_d out along its target's normal, looking back at it
    g = np.flatnonzero(plan.pose_kind == "guard")
    tgt = plan.pose_target[g]
    L = plan.params.camera.L_d
    assert np.allclose(plan.world_T_camera[g, :3, 3], plan.points[tgt] + L * plan.normals[tgt], atol=1e-4)
    assert np.allclose(plan.world_T_camera[g, :3, 0], -plan.normals[tgt], atol=1e-3)
    # guards of a spot are contiguous in T, spots in tour order
    assert np.all(np.diff(plan.pose_spot) >= 0)
    assert np.all((plan.maneuverability >= 0) & (plan.maneuverability <= 1))


def test_guard_configurations_are_collision_free(plan, ctx):
    from mavac.inspection.spots import se2_matrices

    for k, T in enumerate(se2_matrices(plan.spots)):
        ctx.checker.set_base(T)
        q = plan.poses[plan.pose_spot == k, 3:]
        if len(q):
            assert not np.any(ctx.checker.in_collision(q))


def test_nos_attempts_are_reported(plan):
    for a in plan.nos_attempts:
        assert a["solved"] <= a["ik"]
    assert plan.n_nos_guards == sum(a["solved"] for a in plan.nos_attempts)
    # NoS guards only add coverage
    assert plan.C >= plan.C_guards


def test_json_export_round_trip(plan, tmp_path):
    path = plan.to_json(tmp_path / "plan.json")
    data = json.loads(path.read_text())
    assert data["machine"] == "pocket_box"
    assert len(data["poses"]) == len(plan.poses)
    assert np.allclose([p["q"] for p in data["poses"]], plan.poses[:, 3:])
    assert np.allclose([p["base"] for p in data["poses"]], plan.poses[:, :3])
    assert data["C"] == pytest.approx(plan.C)
    assert data["params"]["guard"]["P_g"] == plan.params.guard.P_g


def test_same_seed_same_plan(ctx, plan, robot):
    again = plan_inspection(_box_machine(), robot=robot, params=FAST)
    assert np.array_equal(again.poses, plan.poses)
    assert again.C == plan.C and again.O == plan.O
    assert np.array_equal(again.visible, plan.visible)


def test_P_g_sweep_on_a_context_changes_only_guards(ctx):
    lo = plan_from_context(ctx, dataclasses.replace(ctx.params, guard=dataclasses.replace(ctx.params.guard, P_g=0.0)))
    hi = plan_from_context(ctx, dataclasses.replace(ctx.params, guard=dataclasses.replace(ctx.params.guard, P_g=0.9)))
    assert np.array_equal(lo.spots, hi.spots)
    assert lo.n_guards >= hi.n_guards
    assert lo.C_guards >= hi.C_guards


def test_unreachable_machine_gives_empty_plan(robot):
    from mavac.geometry.machines import Machine

    m = _box_machine()
    # a keep-out zone 6 m around the machine: no base pose comes within the arm's reach
    fence = np.array([[-6.0, -6.0], [6.0, -6.0], [6.0, 6.0], [-6.0, 6.0]])
    far = Machine("fenced", m.mesh, fence)
    with pytest.warns(UserWarning, match="empty plan"):
        plan = plan_inspection(far, robot=robot, params=FAST)
    assert plan.n_spots == 0 and len(plan.poses) == 0
    assert plan.C == 0.0 and plan.O == 0.0
    assert plan.visible.shape == (0, len(plan.points))
    assert plan.warnings


def test_bad_input(ctx):
    with pytest.raises(ValueError, match="mesh_or_machine"):
        plan_inspection("test_bench")
    with pytest.raises(ValueError, match="params"):
        plan_inspection(_box_machine(), params=SpotParams())
    with pytest.raises(ValueError, match="context"):
        plan_from_context(ctx, dataclasses.replace(ctx.params, surface_spacing=0.2))
    with pytest.raises(ValueError, match="start"):
        short_open_path(np.zeros((2, 2)), 5)


@pytest.mark.parametrize("cls,kw,name", [
    (SpotParams, dict(P_s=1.2), "P_s"), (SpotParams, dict(P_s=-0.01), "P_s"),
    (GuardParams, dict(P_g=1.5), "P_g"), (GuardParams, dict(P_g=-0.5), "P_g"),
    (GuardParams, dict(k1=1.1), "k1"), (GuardParams, dict(k1=-0.1), "k1"),
    (GuardParams, dict(k2=2.0), "k2"), (GuardParams, dict(k2=-1.0), "k2"),
    (GuardParams, dict(standoff=0.0), "standoff"), (GuardParams, dict(standoff=-0.4), "standoff"),
    (GuardParams, dict(guard_spacing=0.0), "guard_spacing"),
    (SpotParams, dict(ring_distances=()), "ring_distances"), (SpotParams, dict(ring_distances=(-1.0,)), "ring_distances"),
    (Visibility, dict(method="x"), "method"), (Visibility, dict(hpr_input="all"), "hpr_input"),
    (Visibility, dict(radius=0.0), "radius"), (SpotParams, dict(view_heights=(0.0,)), "view_heights"),
    (NoSParams, dict(eps_factor=0.0), "eps_factor"), (NoSParams, dict(n_rays=2), "n_rays"),
    (NoSParams, dict(rrt_time_limit=0.0), "rrt_time_limit"), (NoSParams, dict(max_ray_tries=0), "max_ray_tries"),
    (NoSParams, dict(rrt_max_iterations=0), "rrt_max_iterations"),
    (InspectionParams, dict(surface_spacing=-0.1), "surface_spacing"), (InspectionParams, dict(spot=0.02), "spot"),
    (InspectionParams, dict(visibility="hpr"), "visibility"),
])
def test_parameter_validation(cls, kw, name):
    with pytest.raises(ValueError, match=name):
        cls(**kw)


def test_camera_validation_reaches_inspection_params():
    from mavac.params import CameraParams

    with pytest.raises(ValueError, match="L_d"):
        InspectionParams(camera=CameraParams(L_d=0.0))
    with pytest.raises(ValueError, match="theta_a"):
        CameraParams(theta_a=2.0)


def test_guards_of_later_spots_count_only_elements_not_seen_at_earlier_spots(ctx, plan):
    from mavac.inspection.inspection_plan import guards_at_spots, spot_tour

    spots, rows = spot_tour(plan.spot_selection)
    assert np.array_equal(spots, plan.spots)
    selections = guards_at_spots(ctx, rows, ctx.params.guard)
    seen = np.zeros(len(ctx.points), dtype=bool)
    overlap = False
    for s in selections:
        for i in range(len(s.guards)):
            # the greedy gain of a guard is what it adds to every guard chosen before it,
            # at this spot and at the spots before
            assert s.greedy.gains[i] == np.count_nonzero(s.visible[i] & ~seen)
            overlap |= bool(np.any(s.visible[i] & seen))
            seen |= s.visible[i]
    # the fixture must let a later guard see something seen before, or this proves nothing
    assert len(selections) >= 2 and overlap
    assert np.array_equal(seen, selections[-1].greedy.covered)


def test_pose_set_attributes_of_the_plan(plan):
    ps = plan.pose_set
    assert len(ps) == len(plan.poses)
    for name, column in (("poses", "poses"), ("pose_spot", "spot"), ("pose_kind", "kind"),
                         ("pose_target", "target"), ("world_T_camera", "world_T_camera"),
                         ("maneuverability", "maneuverability"), ("visible", "visible")):
        assert getattr(plan, name) is getattr(ps, column)


def test_exact_ray_casting_is_the_default_and_hpr_is_one_call_away(ctx, plan):
    """Users get exact ray casting with a back-face test; the paper's HPR is selected explicitly."""
    assert InspectionParams().visibility == Visibility("raycast") and plan.visibility == "raycast"
    hpr = InspectionParams().with_visibility("hpr")
    assert hpr.visibility == Visibility("hpr") and hpr.spot == SpotParams() and hpr.guard == GuardParams()
    authors = InspectionParams().with_visibility(Visibility("hpr", radius=10.0))
    assert authors.visibility.radius == 10.0
    with pytest.raises(ValueError, match="method"):
        InspectionParams().with_visibility("exact")
    # no pose sees an element that faces away from its camera
    cams = plan.world_T_camera[:, :3, 3]
    facing = np.einsum("hnd,nd->hn", cams[:, None, :] - plan.points[None], plan.normals) > 0
    assert not np.any(plan.visible & ~facing)


def test_accessible_sets_with_other_visibility_from_one_context(ctx):
    np.testing.assert_array_equal(ctx.accessible_with(ctx.params.visibility), ctx.accessible)
    hpr = ctx.accessible_with(Visibility("hpr"))
    assert hpr.shape == ctx.accessible.shape and not np.array_equal(hpr, ctx.accessible)
    assert not np.any(hpr & ~ctx.reachable)  # visibility only removes elements from the reachable ones


def test_the_authors_offline_settings_run_through_the_pipeline(robot):
    """The MAVAC authors' ROS code (will-44/cleaning): 45 x 35 deg pyramid 0.7 m deep, guards
    0.4 m along the normal, HPR at an absolute radius of 10 m. Every guard camera then stands
    0.4 m from its target, and the plan's coverage is counted with that HPR."""
    import math

    from mavac.params import CameraParams

    params = dataclasses.replace(
        FAST, camera=CameraParams(theta_a=math.radians(45), theta_b=math.radians(35), L_d=0.7),
        guard=dataclasses.replace(FAST.guard, standoff=0.4), visibility=Visibility("hpr", radius=10.0),
        nos=dataclasses.replace(FAST.nos, enabled=False))
    assert params.guard_standoff == 0.4
    authors = plan_inspection(_box_machine(), robot=robot, params=params)
    guards = np.flatnonzero(authors.pose_kind == "guard")
    assert len(guards) > 0 and authors.visibility == "hpr"
    dist = np.linalg.norm(authors.world_T_camera[guards, :3, 3] - authors.points[authors.pose_target[guards]], axis=1)
    np.testing.assert_allclose(dist, 0.4, atol=1e-3)
    # the same plan with the radius as a factor of the farthest distance counts other elements
    factor = plan_inspection(_box_machine(), robot=robot, params=params.with_visibility(Visibility("hpr")))
    assert not np.array_equal(factor.visible, authors.visible)


@pytest.mark.parametrize("shift", [10.0, 10_000.0])
def test_moving_the_machine_far_from_the_origin_changes_no_result(plan, robot, shift):
    """Where the file puts the machine changes no result (issue 33: C fell from 0.79 to 0.67 at
    10 km, vertices cast to float32 losing ~1 mm): machine_from_mesh moves it by whole metres
    to the origin, and ray casting and guard voxels are relative to the mesh."""
    from mavac.geometry.machines import machine_from_mesh

    mesh = _box_machine().mesh.copy().apply_translation([shift, -shift, 0.0])
    machine = machine_from_mesh(mesh, name="pocket_box")
    np.testing.assert_array_equal(machine.file_offset, [shift, -shift, 0.0])
    moved = plan_inspection(machine, robot=robot, params=FAST)
    assert moved.C == pytest.approx(plan.C, abs=1e-9) and moved.O == pytest.approx(plan.O, abs=1e-9)
    np.testing.assert_allclose(moved.poses, plan.poses, atol=1e-9)


@pytest.mark.parametrize("method", ["raycast", "hpr"])
def test_a_plan_read_back_from_its_json_is_the_plan(plan, ctx, method):
    from mavac.inspection.inspection_plan import InspectionPlan

    if method == "hpr":  # HPR's cover sets come from the same poses on another visibility
        plan = plan_from_context(prepare_offline(ctx.machine, robot=ctx.robot, params=FAST.with_visibility("hpr")))
    back = InspectionPlan.from_dict(json.loads(json.dumps(plan.to_dict())), ctx.machine)
    np.testing.assert_array_equal(back.visible, plan.visible)
    np.testing.assert_array_equal(back.poses, plan.poses)
    np.testing.assert_array_equal(back.points, plan.points)
    assert (back.C, back.O, back.C_guards, back.O_guards) == (plan.C, plan.O, plan.C_guards, plan.O_guards)
    assert back.params == plan.params and back.visibility == method
    assert back.pose_kind.tolist() == plan.pose_kind.tolist() and back.pose_spot.tolist() == plan.pose_spot.tolist()
    assert back.to_dict() == plan.to_dict()


def test_a_plan_file_on_another_machine_or_tampered_is_refused(plan, ctx):
    from mavac.geometry.machines import machine_from_mesh
    from mavac.inspection.inspection_plan import InspectionPlan

    doc = json.loads(json.dumps(plan.to_dict()))
    bigger = machine_from_mesh(ctx.machine.mesh.copy().apply_scale(1.3), name="pocket_box")
    with pytest.raises(ValueError, match="another mesh, unit or up axis"):
        InspectionPlan.from_dict(doc, bigger)
    moved = json.loads(json.dumps(doc))
    moved["poses"][0]["q"][0] += 0.5
    with pytest.raises(ValueError, match="joints do not give its camera poses"):
        InspectionPlan.from_dict(moved, ctx.machine)
    for broken in ({k: v for k, v in doc.items() if k != "poses"}, {**doc, "spots": "none"}, []):
        with pytest.raises(ValueError, match="not an inspection plan"):
            InspectionPlan.from_dict(broken, ctx.machine)
    with pytest.raises(ValueError, match="made for robot 'puma'"):
        InspectionPlan.from_dict({**doc, "robot": "puma"}, ctx.machine)
    with pytest.raises(ValueError, match="has no parameter 'P_x'"):
        InspectionPlan.from_dict({**doc, "params": {**doc["params"], "P_x": 1}}, ctx.machine)


def _two_overlapping_boxes():
    """Two watertight boxes written as one mesh (their faces cross, no boolean union): box a
    reaches x = 1.0 m, inside box b (x from 0.5 m), and b's lower end lies inside a."""
    a = trimesh.creation.box(bounds=[[0.0, 0.0, 0.0], [1.0, 0.6, 0.6]])
    b = trimesh.creation.box(bounds=[[0.5, 0.0, 0.0], [1.5, 0.6, 0.9]])
    return a, b, trimesh.util.concatenate([a, b])


def _strictly_inside(box, points, margin=BURIED_TOLERANCE):
    lo, hi = box.bounds
    return np.all((points > lo + margin) & (points < hi - margin), axis=1)


def test_surface_elements_buried_inside_another_body_are_dropped():
    from mavac.geometry.machines import on_floor
    from mavac.geometry.surface import sample_surface
    from mavac.inspection.inspection_plan import surface_elements

    a, b, mesh = _two_overlapping_boxes()
    with pytest.warns(UserWarning, match=r"(\d+) of \d+ surface elements lie inside another body") as said:
        S = surface_elements(mesh, 0.05, 0)
    assert not (_strictly_inside(a, S.points) | _strictly_inside(b, S.points)).any()
    sampled = sample_surface(mesh, 0.05, seed=0)
    exposed = sampled.subset(~on_floor(sampled.points[:, 2], sampled.normals[:, 2]))
    buried = _strictly_inside(a, exposed.points) | _strictly_inside(b, exposed.points)
    assert buried.sum() > 50  # a's x = 1 end and b's part of a's top lie inside the other box
    assert len(S) == len(exposed) - buried.sum()
    np.testing.assert_array_equal(S.points, exposed.points[~buried])  # boundary points (y = 0, 0.6) kept
    assert str(said[0].message).startswith(f"{buried.sum()} of {len(exposed)} ")


def test_surface_elements_of_a_single_body_are_the_exposed_samples():
    from mavac.geometry.machines import on_floor
    from mavac.geometry.surface import sample_surface
    from mavac.inspection.inspection_plan import surface_elements

    mesh = _box_machine().mesh
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no buried elements to report
        S = surface_elements(mesh, 0.05, 0)
    sampled = sample_surface(mesh, 0.05, seed=0)
    exposed = sampled.subset(~on_floor(sampled.points[:, 2], sampled.normals[:, 2]))
    np.testing.assert_array_equal(S.points, exposed.points)
    np.testing.assert_array_equal(S.normals, exposed.normals)

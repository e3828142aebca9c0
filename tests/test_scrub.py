"""The simulated two-arm cell (mavac.scrubbing.scene, .scrub, .coupon)."""

import dataclasses

import numpy as np
import pybullet as p
import pytest

from mavac.experiments.kabir_bimanual import paper_lissajous, run_paper_part
from mavac.params import BimanualCellParams, ToolpathParams
from mavac.robots.kinematics import ik_axis
from mavac.scrubbing.cell import HOLDER_SEED, cell_robots, holder_ik
from mavac.scrubbing.coupon import CouponCell, coupon_part
from mavac.scrubbing.scene import move_holder, open_cell, world_T_part
from mavac.scrubbing.scrub import Schedule, approach, check_force_limits, run_schedule, schedule_for_pass
from mavac.scrubbing.toolpath import PassPath
from mavac.scrubbing.wear import lissajous_from_vector
from mavac.setups.reach import base_T_part
from mavac.sim.world import SimWorld

CELL = BimanualCellParams()
BOWL = paper_lissajous("bowl")


def _connected() -> int:
    return sum(p.isConnected(physicsClientId=c) for c in range(64))


def _stroke(seed=0):
    """Open the coupon cell, approach, run one 60 mm stroke with the paper's bowl parameters."""
    with CouponCell(CELL, seed=seed) as coupon:
        sched = schedule_for_pass(coupon.stroke, BOWL, ToolpathParams(), coupon.world.time_step)
        approach(coupon.cell, sched, 0.02, BOWL)
        log = run_schedule(coupon.cell, sched, stiffness=BOWL.kappa_x)
    return log


@pytest.fixture(scope="module")
def stroke_log():
    return _stroke()


def test_normal_force_is_tracked_within_20_percent(stroke_log):
    assert stroke_log.contact_s > 1.0
    assert abs(stroke_log.mean_contact_force - BOWL.f_n) <= 0.2 * BOWL.f_n


def test_wear_comes_from_measured_contact(stroke_log):
    part = coupon_part()
    touched = np.flatnonzero(stroke_log.removal > 0)
    assert stroke_log.sliding_m > 0 and touched.size
    # the wear sits on the stroke (along x at y = 0): faces on its line wear most
    y = np.abs(part.mesh.triangles_center[:, 1])
    w = stroke_log.removal
    assert (w * y).sum() / w.sum() < 0.015
    assert w[y < 0.01].mean() > 2 * w[y > 0.025].mean()


def test_same_seed_same_simulation():
    a, b = _stroke(), _stroke()
    assert np.array_equal(a.normal_force, b.normal_force)
    assert np.array_equal(a.removal, b.removal)


def test_setup_motion_moves_the_part_and_takes_time():
    cleaner, holder = cell_robots(CELL)
    part = coupon_part()
    T = base_T_part(np.array([[0.2, 0.1, 1.0]]), CELL.space)
    q = holder_ik(holder, T, CELL).q[0]
    with SimWorld(time_step=CELL.time_step) as world:
        cell = open_cell(world, cleaner, holder, part.mesh, HOLDER_SEED, params=CELL, pad_width=0.03)
        seconds = move_holder(cell, q)
        world.step(100)
        assert seconds > 0.5
        assert np.linalg.norm(world_T_part(cell)[:3, 3] - T[0, :3, 3]) < 0.02


def test_bad_inputs_name_the_parameter():
    n = 5
    R = np.repeat(np.eye(3)[None], n, 0)
    with pytest.raises(ValueError, match="contact"):
        Schedule(np.zeros((n, 3)), R, np.zeros((n, 3)), np.zeros(n, dtype=bool))
    with pytest.raises(ValueError, match="rotations"):
        Schedule(np.zeros((n, 3)), R[:2], np.zeros((n, 3)), np.ones(n, dtype=bool))
    with pytest.raises(ValueError, match="toolpath"):
        schedule_for_pass(PassPath(1, np.arange(3)), BOWL, ToolpathParams(), 0.002)
    cleaner, _ = cell_robots(CELL)
    with pytest.raises(ValueError, match="f_n"):
        check_force_limits(cleaner, cleaner.q_home, np.diag([1.0, -1.0, -1.0]), [0.0, 0.0, 5000.0], name="f_n")


def test_no_client_left_after_a_raise():
    before = _connected()
    cleaner, holder = cell_robots(CELL)
    with pytest.raises(RuntimeError, match="boom"):
        with SimWorld(time_step=CELL.time_step) as world:
            open_cell(world, cleaner, holder, coupon_part().mesh, HOLDER_SEED, params=CELL, pad_width=0.03)
            raise RuntimeError("boom")
    huge = lissajous_from_vector(np.array([[0.3, 10.0, 5000.0, 7.0, 3000.0]]))
    with pytest.raises(ValueError, match="lissajous"):
        with CouponCell(CELL) as coupon:
            sched = schedule_for_pass(coupon.stroke, huge, ToolpathParams(), coupon.world.time_step)
            approach(coupon.cell, sched, 0.02, huge)
    assert _connected() == before


def test_schedule_alternates_contact_and_repositioning():
    seg1 = np.column_stack([np.linspace(0, 0.05, 11), np.zeros(11), np.zeros(11)])
    seg2 = seg1 + [0.0, 0.05, 0.0]
    up = np.tile([0.0, 0.0, 1.0], (11, 1))
    move = np.array([seg1[-1], seg1[-1] + [0, 0, 0.02], seg2[0] + [0, 0, 0.02], seg2[0]])
    pp = PassPath(1, np.arange(2), [seg1, seg2], [up, up], [move])
    s = schedule_for_pass(pp, BOWL, ToolpathParams(), 0.002)
    changes = np.flatnonzero(np.diff(s.contact.astype(int)))
    assert len(changes) == 3 and not s.contact[0] and s.contact[-1]  # lands, scrubs, moves, scrubs
    assert np.allclose(s.forces[s.contact, 2], BOWL.f_n)
    assert np.all(s.forces[~s.contact] == 0)
    free = s.positions[~s.contact]
    assert free[:, 2].max() == pytest.approx(0.02)  # lifted by the tool path's lift height
    assert np.allclose(s.rotations[s.contact][:, :, 2], [0.0, 0.0, -1.0])  # pad axis into the surface


def test_run_part_parameters_are_one_checked_bundle():
    from mavac.scrubbing.run import PartRunParams

    with pytest.raises(TypeError, match="cell"):
        PartRunParams(BOWL, cell=ToolpathParams())
    with pytest.raises(TypeError, match="toolpath"):
        PartRunParams(BOWL, toolpath=CELL)
    with pytest.raises(TypeError, match="lissajous"):
        PartRunParams((0.3, 10.0, 5000.0, 7.0, 30.0))
    with pytest.raises(ValueError, match="max_setups"):
        PartRunParams(BOWL, max_setups=0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        PartRunParams(BOWL).max_setups = 2


def test_run_part_takes_any_part_with_its_own_plan_and_refuses_bad_input_before_simulating():
    import trimesh

    from mavac.geometry.stain_marking import mark_stain
    from mavac.scrubbing.run import PartRunParams, cell_plan, run_part

    part = mark_stain(trimesh.creation.icosphere(subdivisions=3, radius=0.06), cone=((0, 0, 1), 60))
    params = PartRunParams(paper_lissajous("hull"), cell=dataclasses.replace(CELL, max_rounds=0), max_setups=1)
    plan = cell_plan(part, params)
    with pytest.raises(TypeError, match="part"):
        run_part(part.mesh, plan, params=params)
    with pytest.raises(TypeError, match="plan"):
        run_part(part, plan.setups, params=params)
    with pytest.raises(TypeError, match="params"):
        run_part(part, plan, params=CELL)
    with pytest.raises(ValueError, match="seed"):
        run_part(part, plan, params=params, seed=-1)
    other = dataclasses.replace(plan, part_name="bowl")
    with pytest.raises(ValueError, match="plan is for part 'bowl'"):
        run_part(part, other, params=params)
    heavy = PartRunParams(BOWL, cell=BimanualCellParams(part_mass=7.5))
    with pytest.raises(ValueError, match=r"part_mass must be at most 7 kg, the holding arm's rated payload"):
        run_part(part, plan, params=heavy)
    run = run_part(part, plan, params=params, snapshots=False)
    assert run.plans[0] is plan and len(run.execution.setups) <= 1
    row = run.row()
    assert row["part"] == part.name and row["status"] == run.status and row["passes"] == len(run.execution.rows) > 0
    assert row["duty_min"] == min(r["duty"] for r in run.execution.rows)
    assert row["failed_passes"] == sum(r["failed"] for r in run.execution.rows)


def test_the_paper_parts_take_their_operating_parameters_from_the_paper():
    from mavac.experiments.kabir_bimanual import paper_operation

    assert paper_lissajous("hull").f_n == paper_operation("hull")[1]
    with pytest.raises(ValueError, match="part must be one of"):
        paper_operation("teapot")
    with pytest.raises(ValueError, match="part must be one of"):
        run_paper_part("teapot", fast=True)


def test_a_setup_the_holding_arm_cannot_reach_is_skipped_with_a_note(monkeypatch):
    import mavac.scrubbing.run as run_module
    from mavac.scrubbing.scene import SetupMotionError

    def unreachable(*args, label, **kwargs):
        raise SetupMotionError("no collision-free setup motion of the holding arm: test")

    monkeypatch.setattr(run_module, "execute_setup", unreachable)
    run = run_paper_part("hull", fast=True, snapshots=False)
    assert run.status == "no setup" and not run.execution.rows
    assert run.notes == ["round 0 setup 1 skipped: no collision-free setup motion of the holding arm: test"]
    assert run.stain_removed == 0.0 and run.to_dict()["setups"] == []


def test_cell_gains_and_limits_are_checked_parameters():
    for name, bad in (("brake_torque", 0.0), ("park_margin", -0.1), ("setup_rrt_iterations", 0),
                      ("damping_ratio", 0.0), ("force_integral_limit", 0.0), ("tracking_duty", 1.5),
                      ("tracking_force_error", 0.0)):
        with pytest.raises(ValueError, match=name):
            dataclasses.replace(CELL, **{name: bad})


def _log(force, touch, cmd, f_n=10.0):
    """A ScrubLog of given per-step forces, pad contacts and commanded contact (nothing else touching)."""
    from mavac.scrubbing.scrub import ScrubLog

    m = len(force)
    cmd = np.asarray(cmd, bool)
    return ScrubLog(np.arange(1, m + 1) * 0.002, np.asarray(force, float), np.asarray(touch, bool), cmd,
                    np.where(cmd, f_n, 0.0), np.zeros(m, bool), np.zeros((m, 3)), np.zeros((m, 3), int),
                    np.zeros(m), np.zeros((m, 3)), np.zeros(4), 0.0, 0.0)


def test_a_pass_where_the_pad_leaves_the_part_shows_it():
    # 10 commanded steps, the pad off the part on 4 of them (at 12 N on the others), then 2
    # repositioning steps where it brushes the part
    touch = [True] * 6 + [False] * 4 + [True, False]
    force = [12.0] * 6 + [0.0] * 4 + [3.0, 0.0]
    row = _log(force, touch, [True] * 10 + [False] * 2).row()
    assert row["commanded_steps"] == 10 and row["contact_steps"] == 6
    assert row["duty"] == pytest.approx(0.6)
    assert row["mean_force_all_n"] == pytest.approx(7.2)  # 0 N counted while off the part
    assert row["force_error_all"] == pytest.approx(-0.28)
    assert row["force_error_contact"] == pytest.approx(0.2)
    assert row["force_rms_all"] == pytest.approx(np.sqrt((6 * 4 + 4 * 100) / 10) / 10)
    assert row["pad_touch_outside_steps"] == 1
    assert row["contact_s"] == pytest.approx(6 * 0.002)
    assert not row["failed"]


def test_any_contact_but_the_pad_fails_the_pass():
    log = _log([10.0] * 4, [True] * 4, [True] * 4)
    log.other[2, 1], log.other_count[2, 1] = 40.0, 2  # the arms touched once
    row = log.row()
    assert row["failed"] and row["arm_arm_steps"] == 1 and row["arm_arm_peak_n"] == 40.0
    assert row["nonpad_part_steps"] == 0 and row["arm_floor_steps"] == 0


def test_force_integral_only_while_the_pad_is_on_the_part():
    from mavac.scrubbing.scrub import Gains, _scrub_torques, schedule_twists

    cleaner, _ = cell_robots(CELL)
    robot = cleaner.model
    q, dq = cleaner.q_home, np.zeros(7)
    data = robot.createData()
    import pinocchio as pin

    fid = robot.getFrameId(cleaner.tool_frame)
    pin.computeJointJacobians(robot, data, q)
    pin.updateFramePlacements(robot, data)
    J, T = pin.getFrameJacobian(robot, data, fid, pin.LOCAL_WORLD_ALIGNED), data.oMf[fid]
    n = 400
    sched = Schedule(np.tile(T.translation, (n, 1)), np.repeat(T.rotation[None], n, 0),
                     np.tile([0.0, 0.0, 10.0], (n, 1)), np.ones(n, bool))
    g = Gains.of(CELL, 5000.0)
    state = {"integral": 0.0, "touch": False, "saturated": False, "twists": schedule_twists(sched, 0.002),
             "mass_data": robot.createData()}
    for i in range(n):  # off the part, 0 N measured: nothing may wind up
        _scrub_torques(robot, q, dq, J, T, sched, i, g, state, 0.0, 0.002)
        assert state["integral"] == 0.0 and not state["saturated"]
    state["touch"] = True
    for i in range(n):  # on the part at 0 N: it integrates up to its clip, and says so
        _scrub_torques(robot, q, dq, J, T, sched, i, g, state, 0.0, 0.002)
    assert state["integral"] == pytest.approx(CELL.force_integral_limit * 10.0) and state["saturated"]
    state["touch"] = False  # contact lost: the integral restarts from 0
    _scrub_torques(robot, q, dq, J, T, sched, 0, g, state, 0.0, 0.002)
    assert state["integral"] == 0.0


def test_each_pass_lands_from_its_approach_point_and_the_oscillation_ramps_in():
    seg = np.column_stack([np.linspace(0, 0.05, 11), np.zeros(11), np.zeros(11)])
    pp = PassPath(1, np.arange(1), [seg], [np.tile([0.0, 0.0, 1.0], (11, 1))])
    s = schedule_for_pass(pp, BOWL, ToolpathParams(), 0.002, ramp_periods=1.0)
    assert not s.contact[0] and s.positions[0, 2] == pytest.approx(0.02)  # the approach point, lift above
    first = np.flatnonzero(s.contact)[0]
    assert np.allclose(s.positions[first], seg[0])
    lateral = np.linalg.norm(s.forces[s.contact, :2], axis=1)
    ramp = int(round(1.0 / BOWL.f_y / 0.002))
    assert lateral[:ramp // 10].max() < 0.15 * BOWL.A_x  # the overlay starts near 0 N ...
    assert lateral[ramp:].max() > 0.9 * BOWL.A_x  # ... and reaches its amplitude after the ramp


def test_an_oscillation_wider_than_the_pad_is_refused():
    from mavac.scrubbing.lissajous import excursion, vector_excursions

    # the coupon-learned hull parameters of the review: A = 60 N at kappa = 1017 N/m
    wide = lissajous_from_vector(np.array([[0.6, 14.66, 1017.0, 11.96, 60.0]]))
    assert excursion(wide) > ToolpathParams().tool_width_m
    assert vector_excursions(np.array([[0.6, 14.66, 1017.0, 11.96, 60.0]]))[0] == pytest.approx(excursion(wide))
    seg = np.column_stack([np.linspace(0, 0.05, 11), np.zeros(11), np.zeros(11)])
    pp = PassPath(1, np.arange(1), [seg], [np.tile([0.0, 0.0, 1.0], (11, 1))])
    with pytest.raises(ValueError, match="lissajous"):
        schedule_for_pass(pp, wide, ToolpathParams(), 0.002)
    schedule_for_pass(pp, BOWL, ToolpathParams(), 0.002)  # the paper's 8.5 mm is fine


def test_the_coupon_stroke_logs_only_the_pad(stroke_log):
    row = stroke_log.row()
    assert row["commanded_steps"] > 500 and 0.5 < row["duty"] <= 1.0
    assert row["nonpad_part_steps"] == 0 and row["arm_arm_steps"] == 0 and row["arm_floor_steps"] == 0
    assert not row["failed"]
    assert row["wear_depth_max_mm"] <= 1e3 * CELL.wear_depth


def test_the_pad_meets_the_exact_concave_part_while_it_is_fixed():
    """A channel (5 mm floor, 30 mm walls): a ball dropped into it settles on the floor of the
    fixed part's exact mesh, not on the held copy's convex hull 30 mm higher."""
    import trimesh

    from mavac.geometry.transforms import transform_points
    from mavac.scrubbing.scene import fix_part, release_part

    plate = trimesh.creation.box((0.08, 0.08, 0.005))
    plate.apply_translation((0.0, 0.0, 0.0025))
    walls = [trimesh.creation.box((0.005, 0.08, 0.035)) for _ in range(2)]
    walls[0].apply_translation((-0.0375, 0.0, 0.0175))
    walls[1].apply_translation((0.0375, 0.0, 0.0175))
    channel = trimesh.util.concatenate([plate, *walls])
    from mavac.scrubbing.coupon import COUPON_SETUP

    cleaner, holder = cell_robots(CELL)
    q = holder_ik(holder, base_T_part(np.array([COUPON_SETUP]), CELL.space), CELL).q[0]  # the part level
    with SimWorld(time_step=CELL.time_step) as world:
        cell = open_cell(world, cleaner, holder, channel, q, params=CELL, pad_width=0.03)
        world.step(100)
        fixed = fix_part(cell)
        assert cell.scrubbed == fixed != cell.part and fix_part(cell) == fixed
        T = world_T_part(cell)
        ball = trimesh.creation.icosphere(subdivisions=2, radius=0.008)
        start = np.eye(4)
        start[:3, 3] = transform_points(T, np.array([[0.0, 0.0, 0.06]]))[0]
        body = world.add_dynamic_mesh(ball.vertices, ball.faces, mass=0.02, world_T_mesh=start)
        world.ignore_contacts(body, cell.part)  # the held copy: its convex hull would catch the ball
        world.step(400)
        z = transform_points(np.linalg.inv(world_T_part(cell)), world.body_pose(body)[None, :3, 3])[0, 2]
        assert z == pytest.approx(0.005 + 0.008, abs=0.003)
        release_part(cell)
        assert cell.fixed_part is None and cell.scrubbed == cell.part


def test_snapshot_camera_faces_the_stain_from_its_side():
    import trimesh

    from mavac.scrubbing.run import SNAPSHOT_DISTANCE, snapshot_view

    box = trimesh.creation.box([0.1, 0.1, 0.1])
    side = np.flatnonzero(box.face_normals[:, 0] < -0.9)  # the stain on the -x side
    world_T_part = np.eye(4)
    world_T_part[:3, :3] = trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1])[:3, :3]  # -x -> -y
    world_T_part[:3, 3] = [0.5, 0.0, 0.4]
    T = snapshot_view(box, side, world_T_part)
    target = world_T_part[:3, :3] @ box.triangles_center[side].mean(axis=0) + world_T_part[:3, 3]
    eye, axis = T[:3, 3], T[:3, 2]  # OpenCV camera: z looks forward
    assert np.linalg.norm(eye - target) == pytest.approx(SNAPSHOT_DISTANCE)
    assert np.allclose(axis, (target - eye) / np.linalg.norm(target - eye))
    assert eye[1] < target[1] - 0.3 and eye[2] > target[2]  # from the stain's side (-y), a little above


def test_replanning_stops_when_a_round_makes_no_progress(monkeypatch):
    import trimesh

    import mavac.scrubbing.run as run_module
    from mavac.geometry.stain_marking import mark_stain

    rounds = []

    def nothing_removed(sim, part, patches, q, state, lissajous, toolpath, rng, out, *, label, **kwargs):
        rounds.append(label)
        out.rows.append(dict(setup=label))
        state.images.append(dict(residue_fraction=1.0, mask=np.ones_like(state.face_index, dtype=bool)))

    monkeypatch.setattr(run_module, "execute_setup", nothing_removed)
    part = mark_stain(trimesh.creation.icosphere(subdivisions=3, radius=0.06), cone=((0, 0, 1), 40))
    params = run_module.PartRunParams(paper_lissajous("hull"))
    run = run_module.run_part(part, run_module.cell_plan(part, params), params=params, snapshots=False)
    assert run.rounds == 0 and rounds and all(label.startswith("round 0") for label in rounds)
    assert "round 0: no progress" in run.notes[-1]


def test_a_setup_whose_pass_start_the_cleaning_arm_cannot_reach_is_noted_not_fatal(monkeypatch):
    import mavac.scrubbing.scrub as scrub_module
    def no_solution(model, points, axes, **kwargs):
        res = ik_axis(model, points, axes, **kwargs)
        res.success[:] = False
        return res

    monkeypatch.setattr(scrub_module, "ik_axis", no_solution)
    run = run_paper_part("hull", fast=True, snapshots=False)
    assert run.status == "residue left" and not run.execution.rows and run.stain_removed == 0.0
    assert len(run.notes) == 1 and run.notes[0].startswith("round 0 setup 1 presented but not scrubbed: the cleaning "
                                                           "arm cannot reach the start of the tool path at [")


def test_the_force_loop_measures_the_force_along_the_tool_axis():
    from types import SimpleNamespace

    from mavac.scrubbing.scrub import _StepLog
    from mavac.sim.world import ContactTable

    # two pad contacts of 10 N each, their normals 30 deg either side of the tool axis (a pad
    # across a crease): 17.3 N push the pad back along its axis, not their 20 N sum
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    pad = ContactTable(np.array([7, 7]), np.array([6, 6]), np.array([-1, -1]), np.array([10.0, 10.0]),
                       np.zeros((2, 3)), np.zeros((2, 3)), np.array([[s, 0.0, c], [-s, 0.0, c]]))
    none = ContactTable(*(np.zeros(0, int),) * 3, np.zeros(0), *(np.zeros((0, 3)),) * 3)
    world = SimpleNamespace(contacts_of=lambda body: pad if body == 1 else none)
    cell = SimpleNamespace(world=world, cleaner=SimpleNamespace(body=1), holder=SimpleNamespace(body=2), part=7,
                           scrubbed=7, pad_link=6, floor=0)
    down = np.diag([1.0, -1.0, -1.0])  # tool z into the part, along world -z
    sched = Schedule(np.zeros((1, 3)), down[None], np.array([[0.0, 0.0, 10.0]]), np.ones(1, bool))
    log = _StepLog(1)
    summed, points, normals = log.record(0, cell, False, np.zeros(3), sched)
    assert log.force[0] == pytest.approx(20 * c) and summed == pytest.approx(20.0) and log.touch[0]


def test_a_coupon_stroke_that_does_not_hold_contact_is_a_failed_experiment():
    x = np.array([BOWL.v, BOWL.f_n, BOWL.kappa_x, BOWL.f_x, BOWL.A_x])
    with CouponCell(CELL) as coupon:
        held = coupon(x)
        row = coupon.stroke_row(x)
        assert held > 0.1 and coupon.held_contact(row) and row["duty"] >= CELL.tracking_duty
        # the same stroke, off the pad for 10 % of it or 20 % short of f_n, would have failed
        assert not coupon.held_contact(dict(row, duty=0.9))
        assert not coupon.held_contact(dict(row, force_error_all=-0.2))
    strict = dataclasses.replace(CELL, tracking_force_error=1e-9)  # no stroke tracks f_n this well
    with CouponCell(strict) as coupon:
        assert coupon(x) == 0.0 and not coupon.held_contact(coupon.stroke_row(x))
        with pytest.raises(ValueError, match="x: no stroke was run"):
            coupon.stroke_row(x + 1.0)


def test_schedule_twists_are_the_nominal_frames_own_motion():
    from scipy.spatial.transform import Rotation

    from mavac.scrubbing.scrub import schedule_twists

    # 0.1 m/s along x while turning at 0.5 rad/s about z
    dt, m = 0.002, 50
    t = np.arange(m) * dt
    R = Rotation.from_rotvec(np.outer(0.5 * t, [0.0, 0.0, 1.0])).as_matrix()
    sched = Schedule(np.column_stack([0.1 * t, np.zeros(m), np.zeros(m)]), R, np.zeros((m, 3)), np.ones(m, bool))
    twists = schedule_twists(sched, dt)
    assert twists == pytest.approx(np.tile([0.1, 0.0, 0.0, 0.0, 0.0, 0.5], (m, 1)))


def test_a_bowl_stained_inside_is_scrubbed_where_the_pad_reaches():
    """A user's bowl standing upright with a stain on its concave inside: the pad meets the
    exact inner surface (not the held copy's convex hull over the rim) and removes most of it,
    with no link but the pad touching the part."""
    import trimesh

    from mavac.geometry.parts import load_part
    from mavac.geometry.stain_marking import mark_stain
    from mavac.experiments.kabir_bimanual import run_params
    from mavac.scrubbing.run import cell_plan, run_part

    mesh = load_part("bowl").mesh.copy()  # the paper's bowl stands upside down: turn it upright
    mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi, [1.0, 0.0, 0.0]))
    mesh.invert()  # its one sheet now faces into the bowl
    mesh.apply_translation((0.0, 0.0, -mesh.bounds[0, 2]))
    c, n = mesh.triangles_center, mesh.face_normals
    r = np.hypot(c[:, 0], c[:, 1])
    inside = np.flatnonzero((n[:, 2] > 0.3) & (r > 0.03) & (r < 0.05) & (c[:, 0] > 0.0) & (np.abs(c[:, 1]) < 0.02))
    assert len(inside) > 50 and c[inside, 2].max() < mesh.bounds[1, 2] - 0.03  # well below the rim
    part = mark_stain(mesh, faces=inside, passes=1, name="bowl inside")
    params = run_params(paper_lissajous("bowl"), fast=True)
    run = run_part(part, cell_plan(part, params), params=params, snapshots=False)
    rows = run.execution.rows
    assert rows and all(row["nonpad_part_steps"] == 0 and row["arm_arm_steps"] == 0 for row in rows)
    assert run.stain_removed > 0.5

"""The simulated two-arm cell (mavac.scrubbing.scene, .scrub, .coupon)."""

import numpy as np
import pybullet as p
import pytest

from mavac.params import BimanualCellParams, ToolpathParams
from mavac.scrubbing.cell import HOLDER_SEED, cell_robots, holder_ik
from mavac.scrubbing.coupon import CouponCell, coupon_part
from mavac.scrubbing.run import paper_lissajous
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
    assert len(changes) == 2 and s.contact[0] and s.contact[-1]
    assert np.allclose(s.forces[s.contact, 2], BOWL.f_n)
    assert np.all(s.forces[~s.contact] == 0)
    free = s.positions[~s.contact]
    assert free[:, 2].max() == pytest.approx(0.02)  # lifted by the tool path's lift height
    assert np.allclose(s.rotations[s.contact][:, :, 2], [0.0, 0.0, -1.0])  # pad axis into the surface


def test_run_part_validates_its_parameters_before_loading_anything():
    from mavac.scrubbing.run import run_part

    with pytest.raises(TypeError, match="cell"):
        run_part("bowl", fast=True, cell=ToolpathParams())
    with pytest.raises(TypeError, match="toolpath"):
        run_part("bowl", fast=True, toolpath=CELL)
    with pytest.raises(TypeError, match="lissajous"):
        run_part("bowl", fast=True, lissajous=(0.3, 10.0, 5000.0, 7.0, 30.0))
    with pytest.raises(ValueError, match="seed"):
        run_part("bowl", fast=True, seed=-1)


def test_cell_gains_limits_and_masses_are_parameters():
    import dataclasses

    from mavac.params import ScrubModel
    from mavac.scrubbing.scrub import Gains

    assert CELL.apparent_mass == ScrubModel().mass  # one home: the wear model's apparent mass
    g = Gains.of(dataclasses.replace(CELL, apparent_mass=4 * CELL.apparent_mass), 5000.0)
    assert g.d == pytest.approx(2 * Gains.of(CELL, 5000.0).d)
    for name, bad in (("brake_torque", 0.0), ("park_margin", -0.1), ("setup_rrt_iterations", 0),
                      ("wrist_inertia", -1.0), ("force_integral_limit", 0.0)):
        with pytest.raises(ValueError, match=name):
            dataclasses.replace(CELL, **{name: bad})

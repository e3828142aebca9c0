"""The iiwa model, its batched 7-DOF IK and the two-arm cell's kinematics (mavac.scrubbing.cell, mavac.scrubbing.holding)."""

import dataclasses
import warnings

import numpy as np
import pytest

from mavac.geometry.parts import load_part
from mavac.params import BimanualCellParams
from mavac.robots import kinematics as K
from mavac.robots.models import iiwa7, load_robot
from mavac.scrubbing.cell import cell_robots, flange_T_part, holder_flange_targets, holder_ik
from mavac.scrubbing import cell as C
from mavac.scrubbing.holding import HeldSetups
from mavac.setups.reach import FeasibleReach, base_T_part


@pytest.fixture(scope="module")
def arms():
    return cell_robots(BimanualCellParams())


def test_iiwa_axis_ik_round_trip(arms):
    cleaner, _ = arms
    rng = np.random.default_rng(3)
    T = K.fk(cleaner, rng.uniform(cleaner.q_lower, cleaner.q_upper, (300, 7)))
    res = K.ik_axis(cleaner, T[:, :3, 3], T[:, :3, 2], rng=np.random.default_rng(0))
    assert res.success.mean() > 0.97
    back = K.fk(cleaner, res.q[res.success])
    assert np.abs(back[:, :3, 3] - T[res.success, :3, 3]).max() < 1e-4
    cos = np.einsum("ni,ni->n", back[:, :3, 2], T[res.success, :3, 2])
    assert cos.min() > np.cos(1e-3)


def test_iiwa_pad_frame_and_registry():
    robot = load_robot("iiwa7", tool_length=0.12, pad_width=0.03)
    assert robot.nq == 7 and robot.tool_frame == "pad_face"
    T = K.fk(robot, np.zeros(7))
    # straight up: 0.36 + 0.42 + 0.40 + 0.126 (flange) + 0.12 tool, pybullet_data's iiwa URDF
    assert T[2, 3] == pytest.approx(0.1575 + 0.2025 + 0.2045 + 0.2155 + 0.1845 + 0.2155 + 0.081 + 0.045 + 0.12, abs=1e-6)
    assert iiwa7().tool_frame == "flange"
    with pytest.raises(ValueError, match="tool_length"):
        iiwa7(tool_length=-0.1)
    with pytest.raises(ValueError, match="pad_width"):
        iiwa7(tool_length=0.1, pad_width=0.0)


def test_pybullet_and_pinocchio_agree_on_the_pad(arms):
    from mavac.sim.world import SimWorld

    cleaner, _ = arms
    rng = np.random.default_rng(1)
    with SimWorld() as world:
        sim = world.add_robot(cleaner.urdf_path, joint_names=list(cleaner.model.names[1:]))
        for q in rng.uniform(cleaner.q_lower, cleaner.q_upper, (5, 7)):
            sim.reset_q(q)
            assert np.abs(sim.world_T_link("pad_face")[:3, 3] - K.fk(cleaner, q)[:3, 3]).max() < 1e-3


def test_holder_ik_puts_the_part_where_the_setup_says(arms):
    cleaner, holder = arms
    cell = BimanualCellParams()
    setups = np.array([[0.0, 0.0, 0.0], [0.15, 0.15, 1.0], [0.3, 0.3, 4.0]])
    T = base_T_part(setups, cell.space)
    res = holder_ik(holder, T, cell)
    assert res.success.all()
    flange = K.fk(holder, res.q, frame="flange")
    part = cell.world_T_holder @ flange @ flange_T_part(cell)
    assert np.abs(part - T).max() < 1e-4
    assert holder_flange_targets(T, cell).shape == (3, 4, 4)


def test_held_setups_drop_what_the_holder_cannot_present(arms):
    cleaner, holder = arms
    cell = BimanualCellParams()
    part = load_part("bowl")
    held = HeldSetups(cleaner, holder, part.mesh, cell)
    far = dataclasses.replace(cell, space=dataclasses.replace(cell.space, origin_x=3.0))
    assert not HeldSetups(cleaner, holder, part.mesh, far)(np.array([[0.1, 0.1, 0.0]])).any()
    assert held(np.array([[0.1, 0.1, 0.0]])).all()
    big = part.mesh.copy()
    big.apply_scale(6.0)  # a 1.3 m bowl cannot fit between the arms
    too_big = HeldSetups(cleaner, holder, big, cell)
    assert not too_big(np.array([[0.1, 0.1, 0.0]])).any()
    assert too_big.collides + too_big.unreachable == 1
    assert "too large" in too_big.summary()


def test_feasible_reach_counts_and_blanks():
    class Reach:
        n_patches = 2

        def __call__(self, s):
            return np.ones((len(s), 2), dtype=bool)

    fr = FeasibleReach(Reach(), lambda s: s[:, 0] < 0.5)
    out = fr(np.array([[0.1, 0, 0], [0.9, 0, 0]]))
    assert out.tolist() == [[True, True], [False, False]] and fr.dropped == 1
    bad = FeasibleReach(Reach(), lambda s: np.ones(3, dtype=bool))
    with pytest.raises(ValueError, match="feasible"):
        bad(np.zeros((2, 3)))


def test_cell_params_name_the_field():
    with pytest.raises(ValueError, match="time_step"):
        BimanualCellParams(time_step=0.5)
    with pytest.raises(TypeError, match="kp"):
        BimanualCellParams(kp="stiff")
    with pytest.raises(ValueError, match="max_rounds"):
        BimanualCellParams(max_rounds=-1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert BimanualCellParams().world_T_holder[0, 3] == pytest.approx(1.2)


def test_held_setups_build_the_part_checkers_once_and_agree_with_a_fresh_build(arms, count_checker_builds):
    cleaner, holder = arms
    cell = BimanualCellParams()
    part = load_part("bowl")
    built = count_checker_builds(C)
    held = HeldSetups(cleaner, holder, part.mesh, cell)
    setups = np.array([[0.1, 0.1, 0.0], [0.0, -0.1, 1.0], [-0.1, 0.05, 2.5]])
    first = held(setups)
    assert len(built) == 2  # the holding arm's links and the cleaning arm, against the part
    assert held(setups).tolist() == first.tolist() and held(setups[::-1]).tolist() == first[::-1].tolist()
    assert len(built) == 2
    q, ok = held.holder_q(setups)
    fresh = C.part_clear_of_arms(cleaner, holder, part.mesh, base_T_part(setups[ok], cell.space), q[ok], cell)
    assert first[ok].tolist() == fresh.tolist() and len(built) == 4

"""URDF from pinocchio: pybullet's forward kinematics equals pinocchio's."""

import numpy as np
import pytest

from mavac.geometry.transforms import se2_to_matrix
from mavac.robots.kinematics import fk
from mavac.robots.models import ur10_mobile
from mavac.sim.urdf import robot_urdf, urdf_from_pinocchio
from mavac.sim.world import SimWorld


def test_pybullet_tool_and_camera_fk_match_pinocchio_within_a_millimetre():
    robot = ur10_mobile()
    names = [robot.model.names[j] for j in range(1, robot.model.njoints)]
    world_T_base = se2_to_matrix(0.4, -0.3, 0.8)
    rng = np.random.default_rng(1)
    with SimWorld() as world:
        sim = world.add_robot(robot_urdf(robot), world_T_base=world_T_base, joint_names=names)
        for q in rng.uniform(robot.q_lower, robot.q_upper, size=(20, 6)):
            sim.reset_q(q)
            for frame in ("tool_tip", "camera", "tool0"):
                expected = world_T_base @ fk(robot, q, frame)
                got = sim.world_T_link(frame)
                assert np.linalg.norm(got[:3, 3] - expected[:3, 3]) < 1e-3
                assert np.abs(got[:3, :3] - expected[:3, :3]).max() < 1e-6


def test_urdf_has_resolved_mesh_paths_and_the_dynamics(tmp_path):
    robot = ur10_mobile()
    path = urdf_from_pinocchio(robot.model, robot.collision_model, tmp_path / "r.urdf")
    text = path.read_text()
    assert "package://" not in text and ".stl" in text
    assert text.count('type="revolute"') == 6
    assert '<link name="tool_tip">' in text and '<link name="camera">' in text
    assert not list(tmp_path.glob(".mavac_tmp/*"))  # atomic write left no temporary


def test_bad_models_are_refused(tmp_path):
    robot = ur10_mobile()
    with pytest.raises(ValueError, match="model"):
        urdf_from_pinocchio("robot", robot.collision_model, tmp_path / "r.urdf")
    with pytest.raises(ValueError, match="collision_model"):
        urdf_from_pinocchio(robot.model, None, tmp_path / "r.urdf")

"""Torque control in pybullet with pinocchio dynamics: gravity holds, impedance and trajectories track."""

import numpy as np
import pinocchio as pin
import pytest

from mavac.robots.models import ur10_mobile
from mavac.sim import control as C
from mavac.sim.urdf import robot_urdf
from mavac.sim.world import SimWorld


@pytest.fixture(scope="module")
def robot():
    return ur10_mobile()


def _sim(world, robot):
    names = [robot.model.names[j] for j in range(1, robot.model.njoints)]
    sim = world.add_robot(robot_urdf(robot), joint_names=names)
    sim.reset_q(robot.q_home)
    sim.enable_torque_control()
    return sim


def test_gravity_compensation_holds_the_pose_for_a_second(robot):
    with SimWorld() as world:
        sim = _sim(world, robot)
        start = sim.world_T_link("tool_tip")[:3, 3]
        for _ in range(240):
            sim.apply_torques(C.gravity_torques(robot.model, sim.q()))
            world.step()
        assert np.linalg.norm(sim.world_T_link("tool_tip")[:3, 3] - start) < 1e-3


def test_without_compensation_the_arm_falls(robot):
    with SimWorld() as world:
        sim = _sim(world, robot)
        start = sim.world_T_link("tool_tip")[:3, 3]
        for _ in range(240):
            sim.apply_torques(np.zeros(6))
            world.step()
        assert np.linalg.norm(sim.world_T_link("tool_tip")[:3, 3] - start) > 0.05


def test_cartesian_impedance_tracks_a_5cm_step(robot):
    model, data = robot.model, robot.model.createData()
    fid = model.getFrameId("tool_tip")
    with SimWorld() as world:
        sim = _sim(world, robot)
        target = sim.world_T_link("tool_tip")
        target[:3, 3] += [0.03, 0.0, -0.04]
        K, D = np.array([1000.0] * 3 + [30.0] * 3), np.array([60.0] * 3 + [1.0] * 3)
        for _ in range(480):
            sim.apply_torques(C.cartesian_impedance_torques(model, data, sim.q(), sim.dq(), fid, target,
                                                            stiffness=K, damping=D))
            world.step()
        assert np.linalg.norm(sim.world_T_link("tool_tip")[:3, 3] - target[:3, 3]) < 2e-3
        assert np.abs(sim.dq()).max() < 0.05


def test_impedance_at_its_target_is_pure_gravity_compensation(robot):
    model, data = robot.model, robot.model.createData()
    fid = model.getFrameId("tool_tip")
    pin.framesForwardKinematics(model, data, robot.q_home)
    tau = C.cartesian_impedance_torques(model, data, robot.q_home, np.zeros(6), fid, data.oMf[fid].homogeneous,
                                        stiffness=np.full(6, 500.0), damping=np.full(6, 10.0))
    np.testing.assert_allclose(tau, C.gravity_torques(model, robot.q_home), atol=1e-9)
    with pytest.raises(ValueError, match="stiffness"):
        C.cartesian_impedance_torques(model, data, robot.q_home, np.zeros(6), fid, np.eye(4),
                                      stiffness=np.full(5, 1.0), damping=np.zeros(6))


def test_follow_joint_trajectory_reaches_the_goal(robot):
    goal = robot.q_home + np.array([0.4, -0.2, 0.3, 0.2, -0.3, 0.5])
    with SimWorld() as world:
        sim = _sim(world, robot)
        log = C.follow_joint_trajectory(world, sim, robot.model, np.array([robot.q_home, goal]))
        assert np.abs(sim.q() - goal).max() < 2e-3
        assert log.max_error < 0.02
        assert log.duration > 0.5  # 0.5 rad at <= 1 rad/s


def test_time_parametrisation_respects_the_velocity_limit():
    q, dq, _ = C.time_parametrise(np.array([[0.0, 0.0], [1.0, 0.5]]), max_velocity=0.5, max_acceleration=1.0,
                                  dt=0.01)
    assert np.abs(dq).max() <= 0.5 + 1e-6
    np.testing.assert_allclose(q[-1], [1.0, 0.5], atol=1e-9)
    np.testing.assert_allclose(q[0], [0.0, 0.0], atol=1e-9)


def test_pd_torques_add_gravity(robot):
    q = robot.q_home
    tau = C.joint_pd_torques(robot.model, q, np.zeros(6), q + 0.1, np.zeros(6), kp=10.0, kd=1.0)
    np.testing.assert_allclose(tau - C.gravity_torques(robot.model, q), 1.0, atol=1e-9)


def test_impedance_step_places_the_frame_itself(robot):
    """One data through many random states: the law equals the one on fresh kinematics
    (forwardKinematics + updateFramePlacements first), bit for bit."""
    model, data, fresh = robot.model, robot.model.createData(), robot.model.createData()
    fid = model.getFrameId("tool_tip")
    rng = np.random.default_rng(5)
    K, D = np.array([800.0] * 3 + [40.0] * 3), np.array([50.0] * 3 + [2.0] * 3)
    for _ in range(50):
        q, dq = rng.uniform(-3.0, 3.0, model.nq), rng.normal(size=model.nv)
        target = np.eye(4)
        target[:3, :3] = pin.rpy.rpyToMatrix(*rng.uniform(-1.0, 1.0, 3))
        target[:3, 3] = rng.normal(size=3)
        pin.forwardKinematics(model, fresh, q)
        pin.updateFramePlacements(model, fresh)
        J = pin.computeFrameJacobian(model, fresh, q, fid, pin.LOCAL_WORLD_ALIGNED)
        M = fresh.oMf[fid]
        error = np.concatenate([target[:3, 3] - M.translation, pin.log3(target[:3, :3] @ M.rotation.T)])
        expected = J.T @ (K * error - D * (J @ dq)) + pin.computeGeneralizedGravity(model, fresh, q)
        np.testing.assert_array_equal(C.impedance_step(model, data, q, dq, fid, target, K, D), expected)


def test_cartesian_damping_gives_each_axis_its_ratio_for_the_arm_inertia_it_has():
    from mavac.params import BimanualCellParams, ToolpathParams
    from mavac.scrubbing.cell import cell_robots

    cleaner, _ = cell_robots(BimanualCellParams(), ToolpathParams())
    robot = cleaner.model
    data = robot.createData()
    q = cleaner.q_home + 0.3
    J = pin.computeFrameJacobian(robot, data, q, robot.getFrameId(cleaner.tool_frame), pin.LOCAL_WORLD_ALIGNED)
    Lambda = np.linalg.inv(J @ pin.computeMinverse(robot, robot.createData(), q) @ J.T)
    k, zeta = 5000.0, 0.7
    D = C.cartesian_damping(robot, robot.createData(), q, J, k, k, zeta)
    # one stiffness on every axis: D = 2 zeta sqrt(k Lambda), so D^2 = 4 zeta^2 k Lambda
    assert np.allclose(D, D.T) and np.allclose(D @ D, 4 * zeta**2 * k * Lambda, rtol=1e-6, atol=1e-6)
    # the iiwa's Cartesian inertia spans more than 10x: one scalar mass cannot damp every axis
    w = np.linalg.eigvalsh(Lambda)
    assert w[-1] > 10 * w[0]

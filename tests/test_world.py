"""SimWorld: the client is always disconnected, bodies, contacts, visual-only markers, SimRobot."""

import numpy as np
import pytest
import trimesh

from mavac.geometry.transforms import se2_to_matrix
from mavac.robots.models import ur10_mobile
from mavac.sim.urdf import robot_urdf
from mavac.sim.world import SimWorld


def _connected(client: int) -> bool:
    import pybullet as p

    return bool(p.isConnected(physicsClientId=client))


def test_client_is_disconnected_after_an_exception_inside_the_block():
    with pytest.raises(KeyError):
        with SimWorld() as world:
            client = world.client
            assert _connected(client)
            raise KeyError("boom")
    assert not _connected(client)
    assert not world.connected


def test_close_is_idempotent_and_a_closed_world_refuses_work():
    world = SimWorld()
    world.close()
    world.close()
    with pytest.raises(RuntimeError, match="closed"):
        world.add_floor()


def test_bad_parameters_are_refused_before_connecting():
    with pytest.raises(ValueError, match="time_step"):
        SimWorld(time_step=0.0)
    with pytest.raises(TypeError, match="gravity"):
        SimWorld(gravity="down")


def test_box_falls_on_a_static_concave_mesh_and_contact_force_is_its_weight():
    machine = trimesh.creation.box(bounds=[[-0.5, -0.5, 0.0], [0.5, 0.5, 0.3]])
    part = trimesh.creation.box(extents=[0.1, 0.1, 0.1])
    with SimWorld() as world:
        world.add_floor()
        table = world.add_static_mesh(machine.vertices, machine.faces)
        T = np.eye(4)
        T[:3, 3] = [0.0, 0.0, 0.5]
        box = world.add_dynamic_mesh(part.vertices, part.faces, mass=2.0, world_T_mesh=T)
        world.step(480)
        assert world.body_pose(box)[2, 3] == pytest.approx(0.35, abs=0.01)
        contact = world.contact_forces(box, table)
        assert contact.count >= 3
        assert contact.normal_force == pytest.approx(2.0 * 9.81, rel=0.05)
        assert contact.positions.shape == (contact.count, 3)


def test_visual_spheres_have_no_collision_and_keep_their_order():
    centres = np.array([[0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [2.0, 0.0, 0.1]])
    with SimWorld() as world:
        ids = world.add_visual_spheres(centres, 0.02, (0.0, 1.0, 0.0, 1.0))
        assert len(ids) == 3
        for i, c in zip(ids, centres):
            np.testing.assert_allclose(world.body_pose(i)[:3, 3], c, atol=1e-9)
        world.step(10)
        np.testing.assert_allclose(world.body_pose(ids[0])[:3, 3], centres[0], atol=1e-9)  # static, no gravity
        with pytest.raises(ValueError, match="rgba"):
            world.add_visual_spheres(centres, 0.02, (0, 2, 0, 1))


def test_robot_joints_follow_the_pinocchio_order_and_the_base_teleports():
    robot = ur10_mobile()
    names = [robot.model.names[j] for j in range(1, robot.model.njoints)]
    with SimWorld() as world:
        sim = world.add_robot(robot_urdf(robot), joint_names=names[::-1])
        assert sim.joint_names == names[::-1]
        sim.reset_q(np.arange(6) * 0.1)
        np.testing.assert_allclose(sim.q(), np.arange(6) * 0.1, atol=1e-12)
        np.testing.assert_allclose(sim.dq(), 0.0)
        T = se2_to_matrix(1.0, -2.0, 0.5)
        sim.set_base_pose(T)
        np.testing.assert_allclose(sim.world_T_link("mobile_base"), T, atol=1e-9)
        with pytest.raises(ValueError, match="link_name"):
            sim.link_index("no_such_link")
        with pytest.raises(ValueError, match="joint_names"):
            world.add_robot(robot_urdf(robot), joint_names=["nope"])


def test_weld_contacts_brakes_and_velocity():
    robot = ur10_mobile()
    names = list(robot.model.names[1:])
    with SimWorld(time_step=1 / 240) as world:
        world.add_floor()
        sim = world.add_robot(robot_urdf(robot), joint_names=names)
        sim.reset_q(robot.q_home)
        box = trimesh.creation.box((0.05, 0.05, 0.05))
        body = world.add_dynamic_mesh(box.vertices, box.faces, mass=0.2, world_T_mesh=sim.world_T_link("tool0"))
        link = sim.link_index("tool0")
        assert world.weld(sim.body, link, body) >= 0
        world.ignore_contacts(sim.body, body)
        world.set_contact(body, friction=0.5, stiffness=1e4, damping=100.0)
        sim.brake(robot.q_home, 300.0)
        world.step(120)
        lin, ang = world.body_velocity(body)
        assert lin.shape == (3,) and ang.shape == (3,)
        assert np.abs(sim.q() - robot.q_home).max() < 0.05  # the brakes hold the arm and its load
        with pytest.raises(ValueError, match="together"):
            world.set_contact(body, friction=0.5, stiffness=1e4)
        with pytest.raises(ValueError, match="parent_position"):
            world.weld(sim.body, link, body, parent_position=(0.0, 0.0))
        with pytest.raises(ValueError, match="max_torque"):
            sim.brake(robot.q_home, 0.0)


def test_contacts_of_lists_every_contact_and_ignoring_is_undone():
    with SimWorld(time_step=1 / 240) as world:
        floor = world.add_floor()
        box = trimesh.creation.box((0.05, 0.05, 0.05))
        T = np.eye(4)
        T[2, 3] = 0.024
        body = world.add_dynamic_mesh(box.vertices, box.faces, mass=0.2, world_T_mesh=T)
        world.step(20)
        table = world.contacts_of(body)
        assert len(table.body_b) >= 1 and np.all(table.body_b == floor) and np.all(table.link_a == -1)
        assert table.normal_force.sum() == pytest.approx(0.2 * 9.81, rel=0.05)
        assert table.positions_b[:, 2] == pytest.approx(np.zeros(len(table.body_b)), abs=2e-3)
        world.ignore_contacts(floor, body)
        world.step(1)
        assert len(world.contacts_of(body).body_b) == 0
        world.ignore_contacts(floor, body, collide=True)
        world.step(1)
        assert len(world.contacts_of(body).body_b) > 0

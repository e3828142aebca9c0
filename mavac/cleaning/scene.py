"""The simulated cell of an online trial: machine, floor, dust heaps and the mobile manipulator
in one :class:`mavac.sim.world.SimWorld`, plus the coal collision checker the planners use.

The base is moved kinematically (teleported to each spot); the arm is torque-controlled.
The robot plans in the frame it believes in (``world_T_base``, the checker, the link poses of
:meth:`Cell.world_T_link`); the simulator holds the truth, which differs only under a
:class:`mavac.params.PerturbationParams` (``truth_T_belief``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.machines import Machine
from ..params import OnlineParams
from ..robots.collision import CollisionChecker
from ..sim.control import follow_joint_trajectory
from ..sim.urdf import robot_urdf
from .heaps import DustField

#: machine colour in the images (grey: saturation 0, never green)
MACHINE_RGBA = (0.55, 0.55, 0.58, 1.0)


@dataclass
class Cell:
    """Everything a trial drives.

    Attributes
    ----------
    world : SimWorld
    robot : RobotModel
    sim : SimRobot
    model, data : pinocchio.Model, pinocchio.Data
    tool_frame : str
    tool_id : int
        pinocchio frame id of the tool centre.
    machine_body : int
    dust : DustField
    checker : CollisionChecker
        Machine + floor, with the approach clearance margin, at ``world_T_base``.
    world_T_base : (4, 4) float
        Where the robot believes its base is (the plan's frame).
    q_cmd : (nq,) float
        Last commanded configuration (planning starts here).
    truth_T_belief : (4, 4) float
        The simulator's frame from the robot's at the current spot (identity unless perturbed).
    transit_contacts : list of float, N
        Peak robot-machine normal force of every tracked joint path that touched the machine.
    """

    world: object
    robot: object
    sim: object
    model: object
    data: object
    tool_frame: str
    tool_id: int
    machine_body: int
    dust: DustField
    checker: CollisionChecker
    world_T_base: np.ndarray
    q_cmd: np.ndarray
    truth_T_belief: np.ndarray = field(default_factory=lambda: np.eye(4))
    transit_contacts: list = field(default_factory=list)

    def move_base(self, world_T_base, *, true_world_T_base=None) -> None:
        """Teleport the mobile base (kinematic drive) and move the checker with it.
        ``true_world_T_base``: where the base really lands (default: where it believes)."""
        self.world_T_base = np.array(world_T_base, dtype=float)
        truth = self.world_T_base if true_world_T_base is None else np.asarray(true_world_T_base, dtype=float)
        # exactly the identity when unperturbed, so that the robot's estimates are the simulator's
        same = np.array_equal(truth, self.world_T_base)
        self.truth_T_belief = np.eye(4) if same else truth @ np.linalg.inv(self.world_T_base)
        self.sim.set_base_pose(truth)
        self.checker.set_base(self.world_T_base)

    def track(self, path, params: OnlineParams) -> float:
        """Follow a joint path in torque control, watching the machine for contact; returns
        its simulated duration, s."""
        path = np.vstack([self.sim.q()[None], np.asarray(path, dtype=float)])
        log = follow_joint_trajectory(self.world, self.sim, self.model, path,
                                      max_velocity=params.approach.max_joint_velocity,
                                      max_acceleration=params.approach.max_joint_acceleration, log_every=10**9,
                                      contact_body=self.machine_body)
        if log.peak_contact_force > 0.0:
            self.transit_contacts.append(log.peak_contact_force)
        self.q_cmd = np.array(path[-1], dtype=float)
        return log.duration

    def world_T_link(self, link: str) -> np.ndarray:
        """(4, 4) a link's pose as the robot estimates it: its base pose belief and the
        measured joints (the simulator's pose mapped by ``inv(truth_T_belief)``)."""
        return np.linalg.solve(self.truth_T_belief, self.sim.world_T_link(link))

    def world_T_tool(self) -> np.ndarray:
        return self.world_T_link(self.tool_frame)


def build_cell(world, machine: Machine, robot, heaps, params: OnlineParams, world_T_base, *, decoys=None) -> Cell:
    """Floor, machine (static concave mesh) and the robot at ``world_T_base`` in ``q_home``; the
    heaps (:class:`mavac.cleaning.heaps.DustField`) enter the world only to be rendered.
    ``decoys`` : (k, 3) float, m: static spheres that look like heaps (green-ish machine parts)."""
    world.add_floor()
    machine_body = world.add_static_mesh(machine.mesh.vertices, machine.mesh.faces, rgba=MACHINE_RGBA)
    if decoys is not None and len(decoys):
        world.add_visual_spheres(decoys, params.dust.radius, params.dust.rgba)
    dust = DustField.of(heaps, params.dust)
    names = [robot.model.names[j] for j in range(1, robot.model.njoints)]
    sim = world.add_robot(robot_urdf(robot), world_T_base=world_T_base, joint_names=names)
    sim.reset_q(robot.q_home)
    sim.enable_torque_control()
    checker = CollisionChecker(robot, machine.mesh, world_T_base=world_T_base,
                               margin=params.approach.collision_margin, floor=True)
    model = robot.model
    return Cell(world, robot, sim, model, model.createData(), robot.tool_frame, model.getFrameId(robot.tool_frame),
                machine_body, dust, checker, np.array(world_T_base, dtype=float), np.array(robot.q_home, dtype=float))

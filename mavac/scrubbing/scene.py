"""Kabir et al.'s two-arm cleaning cell in pybullet (Sec. IX-C): load it, hold the part, move it.

* :func:`open_cell` loads both iiwa arms (the same URDFs as their pinocchio models) into a
  :class:`mavac.sim.world.SimWorld`, the part as a carried body (convex-hull collision, mass
  ``part_mass``) welded to the holding flange (the grasp); while a setup is scrubbed,
  :func:`fix_part` puts the part's exact concave mesh where the held part is, as a static body
  the pad meets (:func:`release_part` removes it);
* :func:`move_holder` plans a collision-free joint motion of the holding arm with the part
  (OMPL RRT-Connect, coal checks) and tracks it in torque mode (pinocchio computed torques
  with the part's inertia); its simulated duration is the setup time;
* :func:`stain_overlay` and :func:`snapshot` draw the stain on the part and photograph the cell.

An arm that is not being moved waits on its brakes (pybullet position motors at its
configuration), as the real iiwa does. The scrubbing itself is :mod:`mavac.scrubbing.scrub`;
the kinematics of the cell :mod:`mavac.scrubbing.cell`. This is the twin of
:mod:`mavac.cleaning.scene`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pinocchio as pin
import trimesh

from ..geometry.mesh import check_mesh
from ..geometry.transforms import check_transform, transform_points
from ..params import BimanualCellParams
from ..planning.rrt import plan_rrt_connect
from ..robots.collision import CollisionChecker, bvh_from_mesh
from ..sim.control import follow_joint_trajectory
from ..sim.world import SimWorld
from ..validate import check_instance
from .cell import CLEANER_PARK, flange_T_part

#: Steps between the joint-motion log samples kept for replays.
LOG_EVERY = 8


@dataclass
class TwoArmCell:
    """Handles of an open two-arm cell (see :func:`open_cell`)."""

    world: SimWorld
    cleaner: object
    holder: object
    cleaner_model: object
    holder_model: object
    holder_dynamics: pin.Model
    part: int
    part_mesh: trimesh.Trimesh
    params: BimanualCellParams
    pad_link: int
    pad_area: float
    log: dict = field(default_factory=dict)
    #: the holding arm's setup-motion checker (:func:`setup_motion_checker`), built on first use
    setup_checker: CollisionChecker | None = None
    #: the floor's body id
    floor: int = -1
    #: the part's exact concave mesh as a static body while it is scrubbed (:func:`fix_part`)
    fixed_part: int | None = None

    @property
    def scrubbed(self) -> int:
        """The body the pad scrubs: the static concave copy while fixed, else the held part."""
        return self.part if self.fixed_part is None else self.fixed_part


def holder_dynamics_model(holder_model, params: BimanualCellParams) -> pin.Model:
    """The holding arm's pinocchio model with the part's mass on the flange (its centre of mass
    at the part frame origin, as pybullet places a mesh body's inertial frame)."""
    model = pin.Model(holder_model.model)
    frame = model.frames[model.getFrameId("flange")]
    joint_T_part = frame.placement * pin.SE3(flange_T_part(params))
    r = params.part_inertia_radius
    inertia = pin.Inertia(params.part_mass, joint_T_part.translation, np.eye(3) * 0.4 * params.part_mass * r**2)
    model.appendBodyToJoint(frame.parentJoint, inertia, pin.SE3.Identity())
    return model


def open_cell(world: SimWorld, cleaner_model, holder_model, part_mesh: trimesh.Trimesh, q_holder, *,
              params: BimanualCellParams = BimanualCellParams(), pad_width: float) -> TwoArmCell:
    """Load both arms and the held part into ``world``.

    Parameters
    ----------
    world : SimWorld
    cleaner_model, holder_model : RobotModel
        From :func:`mavac.scrubbing.cell.cell_robots` (their ``urdf_path`` is loaded).
    part_mesh : trimesh.Trimesh
        Part frame, metres.
    q_holder : (7,) float
        Holding arm configuration to start from (the part is placed at its flange).
    params : BimanualCellParams
    pad_width : float, m
        Pad diameter (its area turns the measured force into pressure).
    """
    check_instance("params", params, BimanualCellParams)
    check_mesh("part_mesh", part_mesh)
    floor = world.add_floor()
    names = [n for n in cleaner_model.model.names[1:]]
    cleaner = world.add_robot(cleaner_model.urdf_path, world_T_base=params.world_T_cleaner, joint_names=names)
    holder = world.add_robot(holder_model.urdf_path, world_T_base=params.world_T_holder, joint_names=names)
    cleaner.reset_q(CLEANER_PARK)
    holder.reset_q(q_holder)
    world_T_part = holder.world_T_link("flange") @ flange_T_part(params)
    part = world.add_dynamic_mesh(part_mesh.vertices, part_mesh.faces, mass=params.part_mass,
                                  world_T_mesh=world_T_part, rgba=(0.85, 0.85, 0.8, 1))
    world.weld(holder.body, holder.link_index("flange"), part, parent_position=(0.0, 0.0, params.grasp_offset))
    world.ignore_contacts(holder.body, part)
    pad = cleaner.link_index("pad")
    world.set_contact(part, friction=params.friction)
    # the pad is foam: a compliant contact (pybullet's default is nearly rigid and chatters)
    world.set_contact(cleaner.body, pad, friction=params.friction, stiffness=params.pad_stiffness,
                      damping=params.pad_damping)
    cleaner.brake(CLEANER_PARK, params.brake_torque)
    holder.brake(q_holder, params.brake_torque)
    return TwoArmCell(world, cleaner, holder, cleaner_model, holder_model, holder_dynamics_model(holder_model, params),
                      part, part_mesh, params, pad, float(np.pi * (pad_width / 2) ** 2), floor=floor)


def world_T_part(cell: TwoArmCell) -> np.ndarray:
    """(4, 4) pose of the part in the simulation (its base frame is the part frame)."""
    return cell.world.body_pose(cell.scrubbed)


def fix_part(cell: TwoArmCell) -> int:
    """The part as the pad meets it: its exact concave mesh, a static body at the held part's
    pose (pybullet collides a movable mesh as its convex hull, which lets the pad ride over
    concave regions). The cleaning arm then touches only this copy; the held copy keeps the
    grasp. Undone by :func:`release_part`. Returns the static body's id."""
    if cell.fixed_part is not None:
        return cell.fixed_part
    world, mesh = cell.world, cell.part_mesh
    body = world.add_static_mesh(mesh.vertices, mesh.faces, world_T_mesh=world.body_pose(cell.part),
                                 rgba=(0.85, 0.85, 0.8, 1))
    world.ignore_contacts(cell.holder.body, body)
    world.ignore_contacts(body, cell.part)
    world.ignore_contacts(cell.cleaner.body, cell.part)
    world.set_contact(body, friction=cell.params.friction)
    cell.fixed_part = body
    return body


def release_part(cell: TwoArmCell) -> None:
    """Remove :func:`fix_part`'s static copy; the cleaning arm collides with the held part again."""
    if cell.fixed_part is None:
        return
    cell.world.remove_body(cell.fixed_part)
    cell.world.ignore_contacts(cell.cleaner.body, cell.part, collide=True)
    cell.fixed_part = None


# ---------------------------------------------------------------- holding arm motion


def parked_cleaner_box(cleaner_model, params: BimanualCellParams) -> trimesh.Trimesh:
    """Axis-aligned box around the parked cleaning arm's link origins, grown by
    ``params.park_margin`` m: the obstacle the holding arm and the part must avoid while setups
    change."""
    data = cleaner_model.model.createData()
    pin.framesForwardKinematics(cleaner_model.model, data, CLEANER_PARK)
    pts = np.array([data.oMf[i].translation for i in range(len(cleaner_model.model.frames))])
    pts = transform_points(params.world_T_cleaner, pts)
    lo, hi = pts.min(axis=0) - params.park_margin, pts.max(axis=0) + params.park_margin
    lo[2] = max(lo[2], 0.0)
    box = trimesh.creation.box(extents=hi - lo)
    box.apply_translation((lo + hi) / 2)
    return box


def _holder_with_part(holder_model, part_mesh, params):
    """Collision model of the holding arm carrying the part (part BVH on the flange's joint)."""
    model = holder_model.model
    frame = model.frames[model.getFrameId("flange")]
    gm = holder_model.collision_model.copy()
    placement = frame.placement * pin.SE3(flange_T_part(params))
    gm.addGeometryObject(pin.GeometryObject("held_part", frame.parentJoint, model.getFrameId("flange"), placement,
                                            bvh_from_mesh(part_mesh)))
    return replace(holder_model, collision_model=gm)


def setup_motion_checker(cell: TwoArmCell) -> CollisionChecker:
    """The holding arm carrying the part against the parked cleaning arm's box and the floor,
    self-collision included; built once per cell (the part, the arms and the box never change)."""
    if cell.setup_checker is None:
        params = cell.params
        robot = _holder_with_part(cell.holder_model, cell.part_mesh, params)
        checker = CollisionChecker(robot, parked_cleaner_box(cell.cleaner_model, params),
                                   world_T_base=params.world_T_holder, floor=True)
        # the part sits on the flange and link 7 by construction: those pairs are not collisions
        names = [g.name for g in robot.collision_model.geometryObjects]
        checker.ignore_pairs(("held_part", b) for b in names if b.startswith(("lbr_iiwa_link_7", "flange")))
        cell.setup_checker = checker
    return cell.setup_checker


class SetupMotionError(RuntimeError):
    """No collision-free motion of the holding arm to a setup (OMPL's reason in the message)."""


def check_held_start(cell: TwoArmCell, part_mesh) -> None:
    """ValueError when the part, held at the holding arm's start configuration, already hits
    the floor, the parked cleaning arm or the holding arm: too large for the cell."""
    if not setup_motion_checker(cell).is_free(cell.holder.q()):
        size = " x ".join(f"{e:.2f}" for e in part_mesh.extents)
        raise ValueError(f"part ({size} m) is too large for the cell: held at the holding arm's start pose it hits "
                         "the floor, the parked cleaning arm or the holding arm itself")


def setup_motion_path(cell: TwoArmCell, q_goal, *, seed: int = 0):
    """Collision-free joint path of the holding arm (with the part) to ``q_goal``: RRT-Connect
    against the parked cleaning arm's box and the floor, self-collision included, within
    ``cell.params.setup_rrt_iterations`` (OMPL seeded with ``seed``).

    Returns
    -------
    (k, 7) float path, or raises :class:`SetupMotionError` with OMPL's reason.
    """
    params = cell.params
    res = plan_rrt_connect(setup_motion_checker(cell).is_free, cell.holder.q(), np.asarray(q_goal, float),
                           cell.holder_model.q_lower, cell.holder_model.q_upper, seed=seed,
                           max_iterations=params.setup_rrt_iterations, time_limit=params.setup_rrt_time_limit)
    if not res.solved:
        raise SetupMotionError(f"no collision-free setup motion of the holding arm: {res.reason}")
    return res.path


def move_holder(cell: TwoArmCell, q_goal, *, seed: int = 0) -> float:
    """Move the part to a setup: plan (:func:`setup_motion_path`, OMPL seed ``seed``), track it
    in torque mode with the cleaning arm braked, brake the holding arm there. Returns the
    simulated duration of the motion (the setup time), s."""
    path = setup_motion_path(cell, q_goal, seed=seed)
    params = cell.params
    cell.cleaner.brake(cell.cleaner.q(), params.brake_torque)
    log = follow_joint_trajectory(cell.world, cell.holder, cell.holder_dynamics, path, max_velocity=params.joint_speed,
                                  max_acceleration=params.joint_acceleration, log_every=LOG_EVERY)
    cell.holder.brake(path[-1], params.brake_torque)
    cell.log.setdefault("holder", []).append(log)
    return float(log.duration)


def move_cleaner(cell: TwoArmCell, q_goal) -> float:
    """Joint motion of the cleaning arm to ``q_goal`` (torque mode, holding arm braked); s."""
    params = cell.params
    cell.holder.brake(cell.holder.q(), params.brake_torque)
    path = np.array([cell.cleaner.q(), np.asarray(q_goal, float)])
    log = follow_joint_trajectory(cell.world, cell.cleaner, cell.cleaner_model.model, path,
                                  max_velocity=params.joint_speed, max_acceleration=params.joint_acceleration,
                                  log_every=LOG_EVERY)
    cell.cleaner.brake(np.asarray(q_goal, float), params.brake_torque)
    cell.log.setdefault("cleaner", []).append(log)
    return float(log.duration)


def stain_overlay(cell: TwoArmCell, face_opacity, *, offset: float = 0.0015, levels: int = 3) -> list[int]:
    """Visual-only bodies showing the stain on the part in pybullet's camera: the faces with
    opacity > 0.15, in ``levels`` shades of brown, ``offset`` m off the surface along their
    normals, at the part's current pose. Remove them with ``world.remove_body``."""
    op = np.asarray(face_opacity, dtype=float)
    mesh = cell.part_mesh
    T = world_T_part(cell)
    ids = []
    edges = np.linspace(0.15, 1.0 + 1e-9, levels + 1)
    for k in range(levels):
        faces = np.flatnonzero((op > edges[k]) & (op <= edges[k + 1]))
        if faces.size == 0:
            continue
        sub = mesh.submesh([faces], append=True)
        sub.vertices = sub.vertices + offset * sub.vertex_normals
        shade = 0.75 - 0.45 * (k + 1) / levels
        ids.append(cell.world.add_static_mesh(sub.vertices, sub.faces, world_T_mesh=T, collision=False,
                                              rgba=(shade + 0.15, shade * 0.7, shade * 0.35, 1.0)))
    return ids


def snapshot(cell: TwoArmCell, world_T_camera, *, width: int = 480, height: int = 360, fov_y_deg: float = 40.0) -> np.ndarray:
    """RGB image (h, w, 3) uint8 of the cell from pybullet's camera (OpenCV convention pose)."""
    from ..sim.render import render_rgbd

    check_transform("world_T_camera", world_T_camera)
    rgb, _, _ = render_rgbd(cell.world.client, world_T_camera, width=width, height=height, fov_y_deg=fov_y_deg,
                            near=0.05, far=5.0)
    return rgb

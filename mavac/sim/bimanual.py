"""Kabir et al.'s two-arm cleaning cell in pybullet (Sec. IX-C): hold, move the part, scrub.

* :func:`open_cell` loads both iiwa arms (the same URDFs as their pinocchio models) into a
  :class:`mavac.sim.world.SimWorld`, the part as a carried body (convex-hull collision, mass
  ``part_mass``) fixed to the holding flange by a pybullet fixed constraint (the grasp);
* :func:`move_holder` plans a collision-free joint motion of the holding arm with the part
  (OMPL RRT-Connect, coal checks) and tracks it in torque mode (pinocchio computed torques
  with the part's inertia); its simulated duration is the setup time;
* :func:`run_schedule` makes the cleaning arm follow a time-sampled tool schedule in torque
  mode: Cartesian impedance with stiffness kappa in the tool plane, explicit force control
  (f_n plus an integral of the measured force error) along tool z, the Lissajous force as
  feed-forward, pinocchio gravity compensation. It logs the measured pad/part contact force
  and accumulates, per stain face, the Preston removal ``preston x pressure x sliding`` where
  the pad touches (pressure = measured normal force / pad area, sliding = measured relative
  pad/part velocity x dt). All of it is SIMULATED.

An arm that is not being moved waits on its brakes (pybullet position motors at its
configuration), as the real iiwa does.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
import trimesh
from scipy.spatial import cKDTree

from ..geometry.mesh import check_mesh
from ..geometry.transforms import check_transform, transform_points
from ..params import BimanualCellParams
from ..planning.rrt import plan_rrt_connect
from ..robots.collision import CollisionChecker, bvh_from_mesh
from ..validate import check_array, check_instance
from .cell import CLEANER_PARK, flange_T_part
from .control import follow_joint_trajectory, gravity_torques
from .world import SimWorld

#: Steps between the configurations kept for replays.
REPLAY_EVERY = 25
#: pybullet joint effort of the URDF (N m), the motor force of a braked arm.
BRAKE_TORQUE = 300.0


@dataclass
class Cell:
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


def holder_dynamics_model(holder_model, params: BimanualCellParams) -> pin.Model:
    """The holding arm's pinocchio model with the part's mass on the flange (its centre of mass
    at the part frame origin, as pybullet places a mesh body's inertial frame)."""
    model = pin.Model(holder_model.model)
    frame = model.frames[model.getFrameId("flange")]
    joint_T_part = frame.placement * pin.SE3(flange_T_part(params))
    r = 0.1  # ours: inertia of a 0.1 m radius sphere of the part's mass (rotations are slow)
    inertia = pin.Inertia(params.part_mass, joint_T_part.translation, np.eye(3) * 0.4 * params.part_mass * r**2)
    model.appendBodyToJoint(frame.parentJoint, inertia, pin.SE3.Identity())
    return model


def brake(robot, q) -> None:
    """Hold ``robot`` at ``q`` with pybullet's position motors (the arm's brakes)."""
    p = robot.world._p
    p.setJointMotorControlArray(robot.body, robot.joint_indices, p.POSITION_CONTROL,
                                targetPositions=list(map(float, q)), forces=[BRAKE_TORQUE] * len(q),
                                physicsClientId=robot.world.client)


def open_cell(world: SimWorld, cleaner_model, holder_model, part_mesh: trimesh.Trimesh, q_holder, *,
              params: BimanualCellParams = BimanualCellParams(), pad_width: float) -> Cell:
    """Load both arms and the held part into ``world``.

    Parameters
    ----------
    world : SimWorld
    cleaner_model, holder_model : RobotModel
        From :func:`mavac.sim.cell.cell_robots` (their ``urdf_path`` is loaded).
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
    p, c = world._p, world.client
    world.add_floor()
    names = [n for n in cleaner_model.model.names[1:]]
    cleaner = world.add_robot(cleaner_model.urdf_path, world_T_base=params.world_T_cleaner, joint_names=names)
    holder = world.add_robot(holder_model.urdf_path, world_T_base=params.world_T_holder, joint_names=names)
    cleaner.reset_q(CLEANER_PARK)
    holder.reset_q(q_holder)
    world_T_part = holder.world_T_link("flange") @ flange_T_part(params)
    part = world.add_dynamic_mesh(part_mesh.vertices, part_mesh.faces, mass=params.part_mass,
                                  world_T_mesh=world_T_part, rgba=(0.85, 0.85, 0.8, 1))
    p.createConstraint(holder.body, holder.link_index("flange"), part, -1, p.JOINT_FIXED, [0, 0, 0],
                       [0, 0, params.grasp_offset], [0, 0, 0], physicsClientId=c)
    for link in range(-1, p.getNumJoints(holder.body, physicsClientId=c)):
        p.setCollisionFilterPair(holder.body, part, link, -1, 0, physicsClientId=c)
    pad = cleaner.link_index("pad")
    p.changeDynamics(part, -1, lateralFriction=params.friction, physicsClientId=c)
    # the pad is foam: a compliant contact (pybullet's default is nearly rigid and chatters)
    p.changeDynamics(cleaner.body, pad, lateralFriction=params.friction, contactStiffness=params.pad_stiffness,
                     contactDamping=params.pad_damping, physicsClientId=c)
    brake(cleaner, CLEANER_PARK)
    brake(holder, q_holder)
    return Cell(world, cleaner, holder, cleaner_model, holder_model, holder_dynamics_model(holder_model, params),
                part, part_mesh, params, pad, float(np.pi * (pad_width / 2) ** 2))


def world_T_part(cell: Cell) -> np.ndarray:
    """(4, 4) pose of the part in the simulation (its base frame is the part frame)."""
    return cell.world.body_pose(cell.part)


# ---------------------------------------------------------------- holding arm motion


def parked_cleaner_box(cleaner_model, params: BimanualCellParams, margin: float = 0.08) -> trimesh.Trimesh:
    """Axis-aligned box around the parked cleaning arm's link origins, grown by ``margin`` m (ours):
    the obstacle the holding arm and the part must avoid while setups change."""
    data = cleaner_model.model.createData()
    pin.framesForwardKinematics(cleaner_model.model, data, CLEANER_PARK)
    pts = np.array([data.oMf[i].translation for i in range(len(cleaner_model.model.frames))])
    pts = transform_points(params.world_T_cleaner, pts)
    lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
    lo[2] = max(lo[2], 0.0)
    box = trimesh.creation.box(extents=hi - lo)
    box.apply_translation((lo + hi) / 2)
    return box


def _holder_with_part(holder_model, part_mesh, params):
    """Collision model of the holding arm carrying the part (part BVH on the flange's joint)."""
    from dataclasses import replace

    model = holder_model.model
    frame = model.frames[model.getFrameId("flange")]
    gm = holder_model.collision_model.copy()
    placement = frame.placement * pin.SE3(flange_T_part(params))
    gm.addGeometryObject(pin.GeometryObject("held_part", frame.parentJoint, model.getFrameId("flange"), placement,
                                            bvh_from_mesh(part_mesh)))
    return replace(holder_model, collision_model=gm)


def setup_motion_path(cell: Cell, q_goal, *, seed: int = 0, max_iterations: int = 5000):
    """Collision-free joint path of the holding arm (with the part) to ``q_goal``: RRT-Connect
    against the parked cleaning arm's box and the floor, self-collision included.

    Returns
    -------
    (k, 7) float path, or raises ``RuntimeError`` with OMPL's reason.
    """
    robot = _holder_with_part(cell.holder_model, cell.part_mesh, cell.params)
    checker = CollisionChecker(robot, parked_cleaner_box(cell.cleaner_model, cell.params),
                               world_T_base=cell.params.world_T_holder, floor=True)
    names = {g.name for g in robot.collision_model.geometryObjects}
    # the part sits on the flange and link 7 by construction: those pairs are not collisions
    for a in ("held_part",):
        for b in names:
            if b.startswith(("lbr_iiwa_link_7", "flange")):
                checker.geometry_model.removeCollisionPair(pin.CollisionPair(
                    checker.geometry_model.getGeometryId(a), checker.geometry_model.getGeometryId(b)))
    checker._gdata = pin.GeometryData(checker.geometry_model)
    res = plan_rrt_connect(lambda q: not checker.in_collision(q), cell.holder.q(), np.asarray(q_goal, float),
                           cell.holder_model.q_lower, cell.holder_model.q_upper, seed=seed,
                           max_iterations=max_iterations, time_limit=60.0)
    if not res.solved:
        raise RuntimeError(f"no collision-free setup motion of the holding arm: {res.reason}")
    return res.path


def move_holder(cell: Cell, q_goal, *, seed: int = 0) -> float:
    """Move the part to a setup: plan (:func:`setup_motion_path`), track it in torque mode
    with the cleaning arm braked, brake the holding arm there. Returns the simulated duration
    of the motion (the setup time), s."""
    path = setup_motion_path(cell, q_goal, seed=seed)
    brake(cell.cleaner, cell.cleaner.q())
    log = follow_joint_trajectory(cell.world, cell.holder, cell.holder_dynamics, path,
                                  max_velocity=cell.params.joint_speed, max_acceleration=1.0, log_every=8)
    brake(cell.holder, path[-1])
    cell.log.setdefault("holder", []).append(log)
    return float(log.duration)


def move_cleaner(cell: Cell, q_goal) -> float:
    """Joint motion of the cleaning arm to ``q_goal`` (torque mode, holding arm braked); s."""
    brake(cell.holder, cell.holder.q())
    path = np.array([cell.cleaner.q(), np.asarray(q_goal, float)])
    log = follow_joint_trajectory(cell.world, cell.cleaner, cell.cleaner_model.model, path,
                                  max_velocity=cell.params.joint_speed, max_acceleration=1.0, log_every=8)
    brake(cell.cleaner, np.asarray(q_goal, float))
    cell.log.setdefault("cleaner", []).append(log)
    return float(log.duration)


# ---------------------------------------------------------------- scrubbing under force control


@dataclass(frozen=True)
class Schedule:
    """A time-sampled tool schedule for the cleaning arm, one sample per physics step.

    Attributes
    ----------
    positions : (m, 3) float, m
        Nominal pad-face positions (world).
    rotations : (m, 3, 3) float
        Nominal tool frames (z into the surface, x along travel).
    forces : (m, 3) float, N
        Commanded force in the tool frame: Lissajous ``(F_x, F_y)`` and ``f_n`` along z.
    contact : (m,) bool
        True where the pad should be in contact (force control along z); False for
        repositioning (stiffness along z, no force).
    """

    positions: np.ndarray
    rotations: np.ndarray
    forces: np.ndarray
    contact: np.ndarray

    def __post_init__(self):
        m = len(check_array("positions", self.positions, float))
        for name, shape in (("rotations", (m, 3, 3)), ("forces", (m, 3)), ("contact", (m,))):
            if np.shape(getattr(self, name)) != shape:
                raise ValueError(f"{name} must have shape {shape}, got {np.shape(getattr(self, name))}")
        if m == 0:
            raise ValueError("positions must hold at least one sample")
        if not np.any(self.contact):
            raise ValueError("contact: the tool path has no contact sample (nothing would be cleaned)")


@dataclass
class ScrubLog:
    """What the simulation measured while a schedule ran (SIMULATED).

    Attributes
    ----------
    t : (m,) float, s
    normal_force : (m,) float, N
        Measured pad/part contact normal force.
    in_contact : (m,) bool
        The pad touched the part.
    commanded_contact : (m,) bool
    pad_positions : (m, 3) float
        Measured pad-face positions (world).
    removal : (F,) float
        Preston removal accumulated per face of the part (stain layers at unit hardness).
    sliding_m : float
        Total measured pad/part sliding distance in contact, m.
    q_samples : (k, 7) float
        Cleaning arm configuration every :data:`REPLAY_EVERY` steps (for replays).
    """

    t: np.ndarray
    normal_force: np.ndarray
    in_contact: np.ndarray
    commanded_contact: np.ndarray
    pad_positions: np.ndarray
    removal: np.ndarray
    sliding_m: float
    q_samples: np.ndarray = field(default_factory=lambda: np.zeros((0, 7)))

    @property
    def contact_s(self) -> float:
        """Time with the pad touching the part, s."""
        dt = float(self.t[1] - self.t[0]) if len(self.t) > 1 else 0.0
        return float(self.in_contact.sum()) * dt

    @property
    def mean_contact_force(self) -> float:
        """Mean measured normal force over the steps in contact, N (nan without contact)."""
        sel = self.in_contact & self.commanded_contact
        return float(self.normal_force[sel].mean()) if sel.any() else float("nan")


def check_force_limits(cleaner_model, q, rotation, force_max, *, name: str = "force") -> None:
    """Refuse a commanded tool force whose static joint torques ``J^T F + g`` exceed the URDF's
    effort limits at configuration ``q`` (ValueError naming ``name``)."""
    model = cleaner_model.model
    data = model.createData()
    fid = model.getFrameId(cleaner_model.tool_frame)
    J = pin.computeFrameJacobian(model, data, np.asarray(q, float), fid, pin.LOCAL_WORLD_ALIGNED)[:3]
    F = np.asarray(rotation, float) @ np.asarray(force_max, float)
    tau = np.abs(J.T @ F) + np.abs(gravity_torques(model, q))
    limit = np.asarray(model.effortLimit, dtype=float)
    if np.any(tau > limit):
        j = int(np.argmax(tau / limit))
        raise ValueError(f"{name}: the commanded force {np.round(force_max, 2).tolist()} N needs {tau[j]:.0f} N m on "
                         f"joint {j + 1}, above its limit {limit[j]:.0f} N m")


class _Wear:
    """Per-face Preston removal from measured contact (pad centroid, force, sliding)."""

    def __init__(self, part_mesh, pad_radius, preston):
        self.centres = np.asarray(part_mesh.triangles_center)
        self.tree = cKDTree(self.centres)
        self.radius = pad_radius
        self.preston = preston
        self.removal = np.zeros(len(self.centres))

    def add(self, part_T_world, contact_points, pressure, sliding):
        centre = transform_points(part_T_world, contact_points.mean(axis=0, keepdims=True))[0]
        faces = self.tree.query_ball_point(centre, self.radius)
        if faces:
            self.removal[faces] += self.preston * pressure * sliding


def run_schedule(cell: Cell, schedule: Schedule, *, stiffness: float) -> ScrubLog:
    """The cleaning arm follows ``schedule`` in torque mode (see the module docstring).

    Parameters
    ----------
    cell : Cell
    schedule : Schedule
    stiffness : float, N/m
        kappa_x = kappa_y in the tool plane (also along z while repositioning).

    Returns
    -------
    ScrubLog (SIMULATED)
    """
    check_instance("schedule", schedule, Schedule)
    c, p = cell.cleaner, cell.world._p
    robot = cell.cleaner_model.model
    data = robot.createData()
    fid = robot.getFrameId(cell.cleaner_model.tool_frame)
    dt = cell.world.time_step
    gains = _gains(cell.params, stiffness)
    wear = _Wear(cell.part_mesh, np.sqrt(cell.pad_area / np.pi), cell.params.preston)
    brake(cell.holder, cell.holder.q())
    c.enable_torque_control()
    m = len(schedule.positions)
    force, touch, pads = np.zeros(m), np.zeros(m, dtype=bool), np.zeros((m, 3))
    state = {"integral": 0.0, "sliding": 0.0}
    kept = []
    for i in range(m):
        q, dq = c.q(), c.dq()
        if i % REPLAY_EVERY == 0:
            kept.append(q)
        pin.computeJointJacobians(robot, data, q)
        pin.updateFramePlacements(robot, data)
        J = pin.getFrameJacobian(robot, data, fid, pin.LOCAL_WORLD_ALIGNED)
        T = data.oMf[fid]
        tau = _scrub_torques(robot, q, dq, J, T, schedule, i, gains, state, force[i - 1] if i else 0.0, dt)
        c.apply_torques(tau)
        cell.world.step()
        summary = cell.world.contact_forces(c.body, cell.part, link_a=cell.pad_link)
        force[i], touch[i], pads[i] = summary.normal_force, summary.count > 0, T.translation
        if touch[i]:
            _measure_wear(cell, wear, summary, J @ dq, state, dt)
    return ScrubLog(np.arange(1, m + 1) * dt, force, touch, np.asarray(schedule.contact, bool), pads,
                    wear.removal, state["sliding"], np.array(kept))


def _gains(params: BimanualCellParams, stiffness: float) -> dict:
    mass = 3.0  # ours: apparent mass of the iiwa at the pad, as ScrubModel.mass
    return {"k": float(stiffness), "d": 2 * params.damping_ratio * np.sqrt(stiffness * mass),
            "kr": params.rot_stiffness, "dr": 2 * params.damping_ratio * np.sqrt(params.rot_stiffness * 0.02),
            "dz": 2 * params.damping_ratio * np.sqrt(stiffness * mass), "ki": params.force_gain,
            "kn": 2.0, "dn": 0.1}


def _scrub_torques(robot, q, dq, J, T, schedule, i, g, state, f_measured, dt) -> np.ndarray:
    """Hybrid impedance/force law at sample ``i`` (tool-frame gains), plus gravity and a
    null-space pull towards the previous posture (the iiwa is redundant)."""
    R = schedule.rotations[i]
    e_t = R.T @ (schedule.positions[i] - T.translation)
    v = J @ dq
    v_t = R.T @ v[:3]
    f_cmd = schedule.forces[i]
    if schedule.contact[i]:
        state["integral"] = float(np.clip(state["integral"] + g["ki"] * (f_cmd[2] - f_measured) * dt,
                                          -2 * f_cmd[2], 2 * f_cmd[2]))
        fz = f_cmd[2] + state["integral"] - g["dz"] * v_t[2]
    else:
        state["integral"] = 0.0
        fz = g["k"] * e_t[2] - g["d"] * v_t[2]
    F_t = np.array([g["k"] * e_t[0] - g["d"] * v_t[0] + f_cmd[0], g["k"] * e_t[1] - g["d"] * v_t[1] + f_cmd[1], fz])
    moment = g["kr"] * pin.log3(R @ T.rotation.T) - g["dr"] * v[3:]
    # spin about the pad axis is free (a round pad): no stiffness or damping on link 7's tiny inertia
    moment -= R[:, 2] * (R[:, 2] @ moment)
    wrench = np.concatenate([R @ F_t, moment])
    J_pinv = np.linalg.pinv(J)
    null = np.eye(len(q)) - J.T @ J_pinv.T
    q_rest = state.setdefault("q_rest", q.copy())
    tau_null = null @ (g["kn"] * (q_rest - q) - g["dn"] * dq)
    return J.T @ wrench + tau_null + gravity_torques(robot, q)


def _measure_wear(cell, wear, summary, pad_twist, state, dt) -> None:
    """Preston increment of the faces under the pad from this step's measured contact."""
    p, client = cell.world._p, cell.world.client
    lin, ang = p.getBaseVelocity(cell.part, physicsClientId=client)
    world_T_p = cell.world.body_pose(cell.part)
    centre = summary.positions.mean(axis=0)
    v_part = np.asarray(lin) + np.cross(ang, centre - world_T_p[:3, 3])
    v_rel = pad_twist[:3] - v_part
    n = summary.normals.mean(axis=0)
    n = n / max(np.linalg.norm(n), 1e-12)
    sliding = float(np.linalg.norm(v_rel - (v_rel @ n) * n)) * dt
    state["sliding"] += sliding
    wear.add(np.linalg.inv(world_T_p), summary.positions, summary.normal_force / cell.pad_area, sliding)


# ---------------------------------------------------------------- pictures


def stain_overlay(cell: Cell, face_opacity, *, offset: float = 0.0015, levels: int = 3) -> list[int]:
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


def snapshot(cell: Cell, world_T_camera, *, width: int = 480, height: int = 360, fov_y_deg: float = 40.0) -> np.ndarray:
    """RGB image (h, w, 3) uint8 of the cell from pybullet's camera (OpenCV convention pose)."""
    from .camera import render_rgbd

    check_transform("world_T_camera", world_T_camera)
    rgb, _, _ = render_rgbd(cell.world.client, world_T_camera, width=width, height=height, fov_y_deg=fov_y_deg,
                            near=0.05, far=5.0)
    return rgb

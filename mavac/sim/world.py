"""A pybullet world with an explicit client: machines, floor, robots, visual markers, contacts.

:class:`SimWorld` connects in ``DIRECT`` mode (never a GUI, no server) and is a context
manager: leaving the ``with`` block disconnects the client, also when the block raised, so no
client is ever left connected. Every pybullet call names the world's ``client``, so several
worlds can live in one process. pybullet is imported inside the methods (``import mavac.sim``
stays light).

Meshes are handed to pybullet as Wavefront OBJ files written into a temporary folder that the
world deletes on :meth:`SimWorld.close` (pybullet's in-memory ``vertices=`` path caps the
vertex count).
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
import trimesh

from ..geometry.transforms import check_transform
from ..validate import check_array, check_int, check_points, check_positive, check_range, check_real

#: pybullet's ``createMultiBody(batchPositions=...)`` limit per call (bodies)
_BATCH = 1000


@dataclass(frozen=True)
class ContactSummary:
    """Contacts between two bodies at the last simulation step.

    Attributes
    ----------
    normal_force : float, N
        Sum of the contact normal forces.
    count : int
        Number of contact points.
    positions : (k, 3) float, metres
        Contact points on body A (world frame).
    normals : (k, 3) float
        Contact normals, from B towards A.
    """

    normal_force: float
    count: int
    positions: np.ndarray
    normals: np.ndarray


class ContactTable(NamedTuple):
    """Every contact point of one body at the last simulation step (:meth:`SimWorld.contacts_of`).

    Attributes
    ----------
    body_b, link_a, link_b : (k,) int
        The other body, this body's link (-1: base) and the other body's link.
    normal_force : (k,) float, N
    positions_a, positions_b : (k, 3) float, m
        Contact points on this body and on the other (world).
    normals : (k, 3) float
        Contact normals, from the other body towards this one.
    """

    body_b: np.ndarray
    link_a: np.ndarray
    link_b: np.ndarray
    normal_force: np.ndarray
    positions_a: np.ndarray
    positions_b: np.ndarray
    normals: np.ndarray


def _pose_from_matrix(world_T_x) -> tuple[list, list]:
    """(position, xyzw quaternion) of a (4, 4) rigid transform."""
    from scipy.spatial.transform import Rotation

    T = check_transform("world_T_x", world_T_x)
    return T[:3, 3].tolist(), Rotation.from_matrix(T[:3, :3]).as_quat().tolist()


def _matrix_from_pose(position, quaternion) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat(quaternion).as_matrix()
    T[:3, 3] = position
    return T


def transforms_from_poses(positions, quaternions) -> np.ndarray:
    """(n, 4, 4) rigid transforms of ``positions`` (n, 3) and xyzw ``quaternions`` (n, 4), as
    pybullet gives them (each equal to :meth:`SimWorld.body_pose`'s matrix of that pose)."""
    from scipy.spatial.transform import Rotation

    P = np.asarray(positions, dtype=float).reshape(-1, 3)
    T = np.tile(np.eye(4), (len(P), 1, 1))
    if len(P):
        T[:, :3, :3] = Rotation.from_quat(np.asarray(quaternions, dtype=float).reshape(-1, 4)).as_matrix()
    T[:, :3, 3] = P
    return T


def _check_rgba(rgba) -> list:
    a = check_array("rgba", rgba, float).reshape(-1)
    if a.shape != (4,) or np.any(a < 0) or np.any(a > 1):
        raise ValueError(f"rgba must be 4 values in [0, 1], got {rgba!r}")
    return a.tolist()


class SimWorld:
    """pybullet ``DIRECT`` world with an explicit client id. Context manager: ``__exit__``
    disconnects, also when the body raised. Never a GUI.

    Parameters
    ----------
    time_step : float, s
        Physics step (pybullet default 1/240 s).
    gravity : float, m/s^2
        Gravity along world z.
    seed : int, >= 0
        Kept for the caller's random draws (pybullet's own stepping is deterministic).
    """

    def __init__(self, *, time_step: float = 1 / 240, gravity: float = -9.81, seed: int = 0):
        check_range("time_step", time_step, 0.0, 0.1, lo_open=True)
        gravity = check_real("gravity", gravity)
        check_range("gravity", gravity, -100.0, 100.0)
        self.seed = check_int("seed", seed, 0)
        import pybullet as p

        self._p = p
        self.time_step = float(time_step)
        self.client = -1
        self._tmp = Path(tempfile.mkdtemp(prefix="mavac_sim_"))
        self.client = p.connect(p.DIRECT)
        if self.client < 0:
            shutil.rmtree(self._tmp, ignore_errors=True)
            raise RuntimeError("pybullet could not connect in DIRECT mode")
        p.setTimeStep(self.time_step, physicsClientId=self.client)
        p.setGravity(0.0, 0.0, gravity, physicsClientId=self.client)
        self._n_meshes = 0

    # ---- lifetime ----
    def __enter__(self) -> SimWorld:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        self.close()

    @property
    def connected(self) -> bool:
        return self.client >= 0 and bool(self._p.isConnected(physicsClientId=self.client))

    def close(self) -> None:
        """Disconnect the client and delete the world's temporary meshes (idempotent)."""
        if getattr(self, "client", -1) >= 0:
            if self._p.isConnected(physicsClientId=self.client):
                self._p.disconnect(physicsClientId=self.client)
            self.client = -1
        if getattr(self, "_tmp", None) is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    def _check_open(self) -> None:
        if not self.connected:
            raise RuntimeError("the SimWorld is closed")

    # ---- bodies ----
    def add_floor(self, *, z: float = 0.0) -> int:
        """A static plane at height ``z`` (m); returns its body id."""
        self._check_open()
        p = self._p
        shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=self.client)
        # pybullet has no visual plane: a thin 40 x 40 m slab whose top is the plane
        visual = p.createVisualShape(p.GEOM_BOX, halfExtents=[20.0, 20.0, 0.005], visualFramePosition=[0, 0, -0.005],
                                     rgbaColor=[0.85, 0.85, 0.85, 1], physicsClientId=self.client)
        return p.createMultiBody(0.0, shape, visual, [0.0, 0.0, float(check_real("z", z))],
                                 physicsClientId=self.client)

    def _mesh_file(self, vertices, faces) -> str:
        """The mesh as an OBJ in the world's temporary folder."""
        V = check_points("vertices", vertices)
        F = check_array("faces", faces)
        if F.ndim != 2 or F.shape[1] != 3 or F.size == 0 or F.dtype.kind not in "iu":
            raise ValueError(f"faces must be a non-empty (m, 3) integer array, got shape {F.shape}, {F.dtype}")
        if F.min() < 0 or F.max() >= len(V):
            raise ValueError(f"faces must index vertices in [0, {len(V) - 1}]")
        self._n_meshes += 1
        path = self._tmp / f"mesh_{self._n_meshes}.obj"
        trimesh.Trimesh(V, F, process=False).export(path)
        return str(path)

    def add_static_mesh(self, vertices, faces, *, world_T_mesh=None, rgba=(0.6, 0.6, 0.6, 1),
                        collision: bool = True) -> int:
        """Static concave body (``GEOM_FORCE_CONCAVE_TRIMESH``), visual from the same mesh.

        Parameters
        ----------
        vertices : (n, 3) float, metres
        faces : (m, 3) int
        world_T_mesh : (4, 4) float, optional
        rgba : 4 floats in [0, 1]
        collision : bool
            False: visual only.
        """
        self._check_open()
        p = self._p
        color = _check_rgba(rgba)
        path = self._mesh_file(vertices, faces)
        shape = (p.createCollisionShape(p.GEOM_MESH, fileName=path, flags=p.GEOM_FORCE_CONCAVE_TRIMESH,
                                        physicsClientId=self.client) if collision else -1)
        visual = p.createVisualShape(p.GEOM_MESH, fileName=path, rgbaColor=color, physicsClientId=self.client)
        pos, quat = _pose_from_matrix(np.eye(4) if world_T_mesh is None else world_T_mesh)
        return p.createMultiBody(0.0, shape, visual, pos, quat, physicsClientId=self.client)

    def add_dynamic_mesh(self, vertices, faces, *, mass: float, world_T_mesh=None,
                         rgba=(0.6, 0.6, 0.6, 1)) -> int:
        """A movable body: convex-hull collision of the mesh (pybullet's default for a
        non-concave ``GEOM_MESH``), visual from the mesh, ``mass`` in kg (> 0)."""
        self._check_open()
        check_positive("mass", mass)
        p = self._p
        color = _check_rgba(rgba)
        path = self._mesh_file(vertices, faces)
        shape = p.createCollisionShape(p.GEOM_MESH, fileName=path, physicsClientId=self.client)
        visual = p.createVisualShape(p.GEOM_MESH, fileName=path, rgbaColor=color, physicsClientId=self.client)
        pos, quat = _pose_from_matrix(np.eye(4) if world_T_mesh is None else world_T_mesh)
        return p.createMultiBody(float(mass), shape, visual, pos, quat, physicsClientId=self.client)

    def add_visual_spheres(self, centres, radius, rgba) -> list[int]:
        """Visual-only spheres (no collision), e.g. dust heaps; one body each, created in
        batches. Returns their body ids in the order of ``centres`` (k, 3)."""
        self._check_open()
        P = check_points("centres", centres) if len(np.atleast_2d(centres)) and np.size(centres) else np.zeros((0, 3))
        check_positive("radius", radius)
        color = _check_rgba(rgba)
        p = self._p
        visual = p.createVisualShape(p.GEOM_SPHERE, radius=float(radius), rgbaColor=color, physicsClientId=self.client)
        ids: list[int] = []
        for start in range(0, len(P), _BATCH):
            chunk = P[start:start + _BATCH].tolist()
            if len(chunk) == 1:
                ids.append(p.createMultiBody(0.0, -1, visual, chunk[0], physicsClientId=self.client))
                continue
            out = p.createMultiBody(0.0, -1, visual, [0, 0, 0], batchPositions=chunk, physicsClientId=self.client)
            ids += list(out) if isinstance(out, (list, tuple)) else list(range(out - len(chunk) + 1, out + 1))
        return [int(i) for i in ids]

    def remove_body(self, body: int) -> None:
        """Delete a body (e.g. a vacuumed dust heap)."""
        self._check_open()
        self._p.removeBody(int(body), physicsClientId=self.client)

    def add_robot(self, urdf_path, *, world_T_base=None, fixed_base=True, joint_names=None) -> SimRobot:
        """Load a URDF (e.g. from :func:`mavac.sim.urdf.urdf_from_pinocchio`).

        Parameters
        ----------
        urdf_path : str or Path
        world_T_base : (4, 4) float, optional
            Pose of the URDF root link.
        fixed_base : bool
        joint_names : list of str, optional
            Controlled joints in the caller's q order (default: every non-fixed joint in URDF
            order).
        """
        self._check_open()
        p = self._p
        path = Path(urdf_path)
        if not path.is_file():
            raise ValueError(f"urdf_path {path} does not exist")
        pos, quat = _pose_from_matrix(np.eye(4) if world_T_base is None else world_T_base)
        body = p.loadURDF(str(path), pos, quat, useFixedBase=bool(fixed_base),
                          flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=self.client)
        return SimRobot(self, body, joint_names)

    # ---- stepping and queries ----
    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps of ``time_step``."""
        self._check_open()
        for _ in range(check_int("n", n, 0)):
            self._p.stepSimulation(physicsClientId=self.client)

    def step_once(self) -> None:
        """One physics step, no checks (control loops)."""
        self._p.stepSimulation(physicsClientId=self.client)

    def contact_forces(self, body_a: int, body_b: int | None = None, *, link_a: int | None = None) -> ContactSummary:
        """Sum of normal forces (N), count, positions (k, 3), normals (k, 3) from
        ``getContactPoints`` of the last step (``body_b`` None: against every body)."""
        self._check_open()
        kwargs = {"bodyA": int(body_a), "physicsClientId": self.client}
        if body_b is not None:
            kwargs["bodyB"] = int(body_b)
        if link_a is not None:
            kwargs["linkIndexA"] = int(link_a)
        points = self._p.getContactPoints(**kwargs) or ()
        if not points:
            return ContactSummary(0.0, 0, np.zeros((0, 3)), np.zeros((0, 3)))
        forces = np.array([c[9] for c in points], dtype=float)
        return ContactSummary(float(forces.sum()), len(points), np.array([c[5] for c in points], dtype=float),
                              np.array([c[7] for c in points], dtype=float))

    def contacts_of(self, body_a: int) -> ContactTable:
        """Every contact point of ``body_a`` with any body at the last step, unchecked (control
        loops: one pybullet query gives what a loop classifies by body and link)."""
        points = self._p.getContactPoints(bodyA=body_a, physicsClientId=self.client) or ()
        if not points:
            z = np.zeros(0, dtype=int)
            return ContactTable(z, z, z, np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
        cols = list(zip(*points))
        return ContactTable(np.array(cols[2], dtype=int), np.array(cols[3], dtype=int), np.array(cols[4], dtype=int),
                            np.array(cols[9], dtype=float), np.array(cols[5], dtype=float),
                            np.array(cols[6], dtype=float), np.array(cols[7], dtype=float))

    def normal_force(self, body_a: int, body_b: int) -> float:
        """:attr:`ContactSummary.normal_force` of :meth:`contact_forces` (N), without the
        summary's arrays and the checks (control loops)."""
        points = self._p.getContactPoints(bodyA=body_a, bodyB=body_b, physicsClientId=self.client)
        return float(np.array([c[9] for c in points], dtype=float).sum()) if points else 0.0

    def body_pose(self, body: int) -> np.ndarray:
        """(4, 4) ``world_T_body`` of a body's base."""
        self._check_open()
        pos, quat = self._p.getBasePositionAndOrientation(int(body), physicsClientId=self.client)
        return _matrix_from_pose(pos, quat)

    def body_position(self, body: int) -> tuple[np.ndarray, np.ndarray]:
        """Position (3,) m and xyzw quaternion (4,) of a body's base, world frame (the pose of
        :meth:`body_pose` without the matrix: :func:`transforms_from_poses` makes many at once)."""
        pos, quat = self._p.getBasePositionAndOrientation(int(body), physicsClientId=self.client)
        return np.asarray(pos, dtype=float), np.asarray(quat, dtype=float)

    def body_velocity(self, body: int) -> tuple[np.ndarray, np.ndarray]:
        """Linear (3,) m/s and angular (3,) rad/s velocity of a body's base, world frame."""
        self._check_open()
        lin, ang = self._p.getBaseVelocity(int(body), physicsClientId=self.client)
        return np.asarray(lin, dtype=float), np.asarray(ang, dtype=float)

    # ---- constraints and contact properties ----
    def weld(self, parent: int, parent_link: int, child: int, *, parent_position=(0.0, 0.0, 0.0)) -> int:
        """Fix ``child``'s base to link ``parent_link`` of ``parent`` (a pybullet fixed
        constraint, e.g. a grasp), its origin at ``parent_position`` (3,) m in the link frame.
        Returns the constraint id."""
        self._check_open()
        offset = check_array("parent_position", parent_position, float)
        if offset.shape != (3,):
            raise ValueError(f"parent_position must have shape (3,), got {offset.shape}")
        p = self._p
        return p.createConstraint(int(parent), int(parent_link), int(child), -1, p.JOINT_FIXED, [0, 0, 0],
                                  offset.tolist(), [0, 0, 0], physicsClientId=self.client)

    def ignore_contacts(self, body_a: int, body_b: int, *, collide: bool = False) -> None:
        """No contact between any link of ``body_a`` and the base of ``body_b`` (a held body
        touches its gripper by construction); ``collide=True`` restores their contacts."""
        self._check_open()
        p, c = self._p, self.client
        for link in range(-1, p.getNumJoints(int(body_a), physicsClientId=c)):
            p.setCollisionFilterPair(int(body_a), int(body_b), link, -1, int(bool(collide)), physicsClientId=c)

    def set_contact(self, body: int, link: int = -1, *, friction: float, stiffness: float | None = None,
                    damping: float | None = None) -> None:
        """Contact properties of one link (``-1``: the base): Coulomb ``friction`` and,
        together, a compliant contact's ``stiffness`` (N/m) and ``damping`` (N s/m)."""
        self._check_open()
        kwargs = {"lateralFriction": float(check_positive("friction", friction))}
        if (stiffness is None) != (damping is None):
            raise ValueError("stiffness and damping must be given together (a compliant contact needs both)")
        if stiffness is not None:
            kwargs.update(contactStiffness=float(check_positive("stiffness", stiffness)),
                          contactDamping=float(check_positive("damping", damping)))
        self._p.changeDynamics(int(body), int(link), physicsClientId=self.client, **kwargs)


class SimRobot:
    """A robot loaded in a :class:`SimWorld`, addressed by the names of its pinocchio model.

    Attributes
    ----------
    body : int
    joint_names : list of str
        Controlled joints, in the pinocchio model's q order.
    joint_indices : list of int
        pybullet joint index of each name.
    """

    def __init__(self, world: SimWorld, body: int, joint_names=None):
        self.world = world
        self.body = int(body)
        p, c = world._p, world.client
        self._links: dict[str, int] = {}
        movable: dict[str, int] = {}
        for i in range(p.getNumJoints(self.body, physicsClientId=c)):
            info = p.getJointInfo(self.body, i, physicsClientId=c)
            self._links[info[12].decode()] = i
            if info[2] != p.JOINT_FIXED:
                movable[info[1].decode()] = i
        self._links[p.getBodyInfo(self.body, physicsClientId=c)[0].decode()] = -1
        names = list(movable) if joint_names is None else [str(n) for n in joint_names]
        missing = [n for n in names if n not in movable]
        if missing:
            raise ValueError(f"joint_names {missing} are not movable joints of the URDF (have {list(movable)})")
        self.joint_names = names
        self.joint_indices = [movable[n] for n in names]

    @property
    def _c(self) -> int:
        return self.world.client

    def q(self) -> np.ndarray:
        """(nq,) joint positions, rad."""
        states = self.world._p.getJointStates(self.body, self.joint_indices, physicsClientId=self._c)
        return np.array([s[0] for s in states], dtype=float)

    def dq(self) -> np.ndarray:
        """(nq,) joint velocities, rad/s."""
        states = self.world._p.getJointStates(self.body, self.joint_indices, physicsClientId=self._c)
        return np.array([s[1] for s in states], dtype=float)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """(q, dq) in one pybullet call."""
        states = self.world._p.getJointStates(self.body, self.joint_indices, physicsClientId=self._c)
        return np.array([s[0] for s in states], dtype=float), np.array([s[1] for s in states], dtype=float)

    def _check_q(self, name: str, q) -> np.ndarray:
        a = check_array(name, q, float).reshape(-1)
        if a.shape != (len(self.joint_indices),) or not np.all(np.isfinite(a)):
            raise ValueError(f"{name} must be {len(self.joint_indices)} finite values, got shape {np.shape(q)}")
        return a

    def reset_q(self, q) -> None:
        """Teleport the joints to ``q`` (rad) with zero velocity."""
        a = self._check_q("q", q)
        for i, v in zip(self.joint_indices, a):
            self.world._p.resetJointState(self.body, i, float(v), 0.0, physicsClientId=self._c)

    def enable_torque_control(self) -> None:
        """Disable pybullet's default velocity motors (force 0) so applied torques act alone."""
        p = self.world._p
        p.setJointMotorControlArray(self.body, self.joint_indices, p.VELOCITY_CONTROL,
                                    forces=[0.0] * len(self.joint_indices), physicsClientId=self._c)

    def brake(self, q, max_torque: float) -> None:
        """Hold the joints at ``q`` (nq,) rad with pybullet's position motors, each limited to
        ``max_torque`` N m (an arm waiting on its brakes)."""
        a = self._check_q("q", q)
        check_positive("max_torque", max_torque)
        p = self.world._p
        p.setJointMotorControlArray(self.body, self.joint_indices, p.POSITION_CONTROL, targetPositions=a.tolist(),
                                    forces=[float(max_torque)] * len(a), physicsClientId=self._c)

    def apply_torques(self, tau) -> None:
        """Joint torques (N m) for the next step (``TORQUE_CONTROL``)."""
        a = self._check_q("tau", tau)
        p = self.world._p
        p.setJointMotorControlArray(self.body, self.joint_indices, p.TORQUE_CONTROL, forces=a.tolist(),
                                    physicsClientId=self._c)

    def apply_torques_unchecked(self, tau) -> None:
        """:meth:`apply_torques` without input checks (control loops; tau (nq,) float)."""
        p = self.world._p
        p.setJointMotorControlArray(self.body, self.joint_indices, p.TORQUE_CONTROL, forces=tau.tolist(),
                                    physicsClientId=self._c)

    def link_position(self, link_name: str) -> np.ndarray:
        """(3,) world position of a link frame's origin (cheaper than :meth:`world_T_link`)."""
        i = self.link_index(link_name)
        if i < 0:
            return self.world_T_link(link_name)[:3, 3]
        state = self.world._p.getLinkState(self.body, i, computeForwardKinematics=True, physicsClientId=self._c)
        return np.array(state[4], dtype=float)

    def link_index(self, link_name: str) -> int:
        """pybullet link index of ``link_name`` (-1 for the root link)."""
        if link_name not in self._links:
            raise ValueError(f"link_name must be one of {sorted(self._links)}, got {link_name!r}")
        return self._links[link_name]

    def world_T_link(self, link_name: str) -> np.ndarray:
        """(4, 4) pose of a link frame (its URDF frame, not its centre of mass)."""
        i = self.link_index(link_name)
        p = self.world._p
        if i < 0:
            return self.world.body_pose(self.body) @ np.linalg.inv(self._root_inertial())
        state = p.getLinkState(self.body, i, computeForwardKinematics=True, physicsClientId=self._c)
        return _matrix_from_pose(state[4], state[5])

    def _root_inertial(self) -> np.ndarray:
        """root_link_T_inertial: pybullet's base pose is that of the root's inertial frame."""
        info = self.world._p.getDynamicsInfo(self.body, -1, physicsClientId=self._c)
        return _matrix_from_pose(info[3], info[4])

    def set_base_pose(self, world_T_base) -> None:
        """Teleport the root link to ``world_T_base`` (4, 4) (the mobile base drives)."""
        T = check_transform("world_T_base", world_T_base) @ self._root_inertial()
        pos, quat = _pose_from_matrix(T)
        self.world._p.resetBasePositionAndOrientation(self.body, pos, quat, physicsClientId=self._c)

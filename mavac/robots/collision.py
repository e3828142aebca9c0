"""Self- and obstacle-collision checking with pinocchio + coal.

The obstacle (a machine or a part, a trimesh in the world frame) becomes a coal BVH
(``BVHModelOBB``) attached to the robot's base (universe) joint at ``base_T_world``;
moving the base only moves that placement. Self-collision pairs are all pairs of robot
geometries except those on the same joint or on kinematically adjacent joints (parent/child),
which touch by construction.

Two speed-ups leave every answer unchanged: pairs whose both geometries are fixed to the base
(e.g. the platform box against the machine) do not depend on ``q``, so they are tested once per
:meth:`CollisionChecker.set_base` and their answer is cached; the other pairs are tested cheapest
first (see :func:`pair_cost_key`), so a colliding configuration usually stops at a cheap pair.
Every mesh is tested in an OBB hierarchy (pinocchio loads URDF meshes as OBBRSS): a bounding
volume only prunes triangle pairs, the triangles decide, and with a security margin the OBB
tests cost about half as much (same answer on each of the 278,484 checks of a test-bench trial).
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import trimesh

from ..geometry.mesh import check_mesh
from ..geometry.transforms import check_transform
from ..validate import check_nonnegative
from .kinematics import _check_q

_OBSTACLE = "obstacle"
_FLOOR = "floor"
# Floor slab: wide enough for any cell, thick enough that nothing tunnels through it.
_FLOOR_SIZE = (100.0, 100.0, 1.0)


def bvh_from_mesh(mesh: trimesh.Trimesh) -> coal.BVHModelOBB:
    """A coal bounding-volume hierarchy (OBB) of a triangle mesh (vertices in metres)."""
    return _obb_bvh(mesh.vertices, mesh.faces)


def _obb_bvh(vertices, faces) -> coal.BVHModelOBB:
    """OBB hierarchy of vertices (n, 3) float, metres, and triangles (m, 3) int."""
    bvh = coal.BVHModelOBB()
    bvh.beginModel(len(faces), len(vertices))
    bvh.addVertices(np.asarray(vertices, dtype=float))
    bvh.addTriangles(np.asarray(faces, dtype=np.int64))
    bvh.endModel()
    return bvh


def _robot_obb_geometries(robot) -> list:
    """Each of ``robot.collision_model``'s geometries, an OBBRSS mesh as the same triangles in an
    OBB hierarchy (others unchanged); cached on the robot while its collision model is the same
    object."""
    hit = robot._cache.get("obb_geometries")
    if hit is not None and hit[0] is robot.collision_model:
        return hit[1]
    out = []
    for g in robot.collision_model.geometryObjects:
        geo = g.geometry
        if isinstance(geo, coal.BVHModelOBBRSS):
            faces = [[t[0], t[1], t[2]] for t in (geo.tri_indices(i) for i in range(geo.num_tris))]
            geo = _obb_bvh(geo.vertices(), faces)
        out.append(geo)
    robot._cache["obb_geometries"] = (robot.collision_model, out)
    return out


def pair_cost_key(first: pin.GeometryObject, second: pin.GeometryObject) -> tuple[int, int]:
    """Sort key of a collision pair by its expected cost: (number of triangle meshes in the pair,
    their total triangle count). Primitive-only pairs come first, then a primitive against a
    mesh (smaller meshes first), then mesh against mesh. Only the order of the tests changes,
    never a pair's answer: ours, because a colliding state then often stops at a cheap pair
    (the links against the platform box or the floor are the most frequent hits of a trial)."""
    tris = [g.geometry.num_tris for g in (first, second) if isinstance(g.geometry, coal.BVHModelBase)]
    return len(tris), sum(tris)


class CollisionChecker:
    """Batched collision test of robot configurations (self-collision + one obstacle mesh).

    Parameters
    ----------
    robot : RobotModel
    obstacle : trimesh.Trimesh or None
        Obstacle in the world frame (metres). Only its surface is modelled: a link entirely
        inside a closed obstacle without touching its surface is not reported.
    world_T_base : (4, 4) float
        Pose of the robot base in the world.
    margin : float, metres, >= 0
        Security margin for robot-vs-obstacle (and floor) pairs: closer than ``margin`` counts
        as a collision. Self-collision pairs use no margin.
    floor : bool
        Also test the moving links against the floor half-space z < 0 (world).
    """

    def __init__(self, robot, obstacle: trimesh.Trimesh | None = None, *, world_T_base=np.eye(4),
                 margin: float = 0.0, floor: bool = False):
        if obstacle is not None:
            check_mesh("obstacle", obstacle)
        self.margin = float(check_nonnegative("margin", margin))
        self.robot = robot
        model = robot.model
        gm = robot.collision_model.copy()
        for g, geo in zip(gm.geometryObjects, _robot_obb_geometries(robot)):
            g.geometry = geo
        n_robot = len(gm.geometryObjects)
        parents = list(model.parents)
        pairs = [(a, b) for a in range(n_robot) for b in range(a + 1, n_robot)
                 if (ja := gm.geometryObjects[a].parentJoint) != (jb := gm.geometryObjects[b].parentJoint)
                 and parents[ja] != jb and parents[jb] != ja]
        self._world_ids = []
        if obstacle is not None:
            oid = gm.addGeometryObject(pin.GeometryObject(_OBSTACLE, 0, 0, pin.SE3.Identity(), bvh_from_mesh(obstacle)))
            self._world_ids.append((oid, np.eye(4)))
            pairs += [(a, oid) for a in range(n_robot)]
        if floor:
            world_T_floor = np.eye(4)
            world_T_floor[2, 3] = -_FLOOR_SIZE[2] / 2
            fid = gm.addGeometryObject(pin.GeometryObject(_FLOOR, 0, 0, pin.SE3.Identity(), coal.Box(*_FLOOR_SIZE)))
            self._world_ids.append((fid, world_T_floor))
            # the base itself rests on the floor
            pairs += [(a, fid) for a in range(n_robot) if gm.geometryObjects[a].parentJoint != 0]
        objs = gm.geometryObjects
        for a, b in sorted(pairs, key=lambda ab: pair_cost_key(objs[ab[0]], objs[ab[1]])):  # stable sort
            gm.addCollisionPair(pin.CollisionPair(a, b))
        self.geometry_model = gm
        self._data = model.createData()
        self._new_geometry_data()
        self.set_base(world_T_base)

    def _new_geometry_data(self) -> None:
        """Fresh coal data for the current pairs; the margin applies to robot-vs-world pairs.
        Pairs of two base-fixed geometries are deactivated here and tested in :meth:`set_base`."""
        gm = self.geometry_model
        self._gdata = pin.GeometryData(gm)
        world = {gid for gid, _ in self._world_ids}
        self._base_pairs = []
        for k, cp in enumerate(gm.collisionPairs):
            if cp.first in world or cp.second in world:
                self._gdata.collisionRequests[k].security_margin = self.margin
            if gm.geometryObjects[cp.first].parentJoint == 0 and gm.geometryObjects[cp.second].parentJoint == 0:
                self._base_pairs.append(k)
                self._gdata.deactivateCollisionPair(k)

    def reset(self) -> None:
        """Forget every earlier query: fresh pinocchio and coal data, as a newly built checker has.

        coal's solvers keep state from one query to the next (a warm start), which can flip a
        borderline contact; a caller that keeps one checker for many batches (its hierarchy of a
        large obstacle is the costly part) resets it per batch to answer as a new one would.
        The pairs, the margin and the base pose stay.
        """
        self._data = self.robot.model.createData()
        self._new_geometry_data()
        self.set_base(self.world_T_base)

    def ignore_pairs(self, pairs) -> None:
        """Stop testing the named geometry pairs, e.g. a held part and the flange it sits on.

        Parameters
        ----------
        pairs : iterable of (str, str)
            Geometry object names; a pair that is not tested is skipped, an unknown name is a
            ``ValueError``.
        """
        gm = self.geometry_model
        n = len(gm.geometryObjects)
        for a, b in pairs:
            ids = [gm.getGeometryId(str(name)) for name in (a, b)]
            for name, i in zip((a, b), ids):
                if i >= n:
                    raise ValueError(f"pairs: no geometry object named {name!r}")
            if gm.existCollisionPair(pin.CollisionPair(*ids)):
                gm.removeCollisionPair(pin.CollisionPair(*ids))
        self._new_geometry_data()
        self.set_base(self.world_T_base)

    @property
    def n_pairs(self) -> int:
        """Number of tested geometry pairs (self + world)."""
        return len(self.geometry_model.collisionPairs)

    def set_base(self, world_T_base) -> None:
        """Move the robot base to ``world_T_base`` (4, 4) (i.e. move the world under it) and test
        the pairs that do not depend on ``q`` (base-fixed geometries) once for this pose."""
        world_T_base = check_transform("world_T_base", world_T_base)
        self.world_T_base = world_T_base
        base_T_world = np.linalg.inv(world_T_base)
        gm = self.geometry_model
        for gid, world_T_obj in self._world_ids:
            gm.geometryObjects[gid].placement = pin.SE3(base_T_world @ world_T_obj)
        # base-fixed geometries sit on the universe joint, whose placement is always the identity
        pin.updateGeometryPlacements(self.robot.model, self._data, gm, self._gdata)
        self._base_hits = [k for k in self._base_pairs if pin.computeCollision(gm, self._gdata, k)]

    def in_collision(self, q):
        """Collision status of configurations.

        Parameters
        ----------
        q : (nq,) or (n, nq) float, rad

        Returns
        -------
        bool, or (n,) bool
        """
        qa, single = _check_q(self.robot, q)
        out = np.empty(qa.shape[0], dtype=bool)
        for i, qi in enumerate(qa):
            out[i] = not self.is_free(qi)
        return bool(out[0]) if single else out

    def is_free(self, q) -> bool:
        """Whether one configuration ``q`` (nq,) float ndarray, rad, is collision-free; no input
        checks (a planner's validity function: the checks of :meth:`in_collision` cost about a
        fifth of a paper-scale RRT-Connect query)."""
        return not self._base_hits and not pin.computeCollisions(
            self.robot.model, self._data, self.geometry_model, self._gdata, q, True)

    def colliding_pairs(self, q) -> list[tuple[str, str]]:
        """Names of the colliding geometry pairs at one configuration ``q`` (nq,) (diagnostics)."""
        qa, single = _check_q(self.robot, q)
        if not single:
            raise ValueError(f"q must have shape ({self.robot.nq},) for colliding_pairs, got {np.shape(q)}")
        gm = self.geometry_model
        pin.computeCollisions(self.robot.model, self._data, gm, self._gdata, qa[0], False)
        hits = set(self._base_hits) | {k for k, res in enumerate(self._gdata.collisionResults)
                                       if self._gdata.activeCollisionPairs[k] and res.isCollision()}
        objs = gm.geometryObjects
        return [(objs[cp.first].name, objs[cp.second].name)
                for k, cp in enumerate(gm.collisionPairs) if k in hits]

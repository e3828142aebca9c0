"""Which waypoints of a pass the cleaning arm can scrub with nothing but its pad touching (coal).

Kabir et al. (Sec. VI) keep the waypoints the robot reaches with the tool along the surface
normal. In the cell the pad sits on a holder wider than itself, 10 mm above its face, so on a
concave or tightly curved stretch the holder's rim meets the part while the pad still reaches
it. :class:`ToolClearance` is the reach test of the cell's tool paths
(:func:`mavac.scrubbing.toolpath.toolpath_for_setup`'s ``reachable``): a waypoint is kept only
where

* the cleaning arm reaches it with its pad along the axis (IK, as
  :func:`mavac.scrubbing.toolpath.reachable_from_robot`);
* the pad holder, widened by the Lissajous oscillation's swing (the pad slides up to
  :func:`mavac.scrubbing.lissajous.excursion` off its path), stays clear of the part;
* the arm's links at that IK configuration stay clear of the part and the floor.

A pass is thus split where it would touch the part with anything but the pad, before it runs.
The holding arm is not in the test (the log of every run counts arm-arm contact).
"""

from __future__ import annotations

from dataclasses import replace

import coal
import numpy as np
import trimesh

from ..geometry.mesh import check_mesh
from ..robots.collision import CollisionChecker, bvh_from_mesh
from ..robots.kinematics import ik_axis
from ..validate import check_nonnegative, check_points

#: Collision geometries of the cleaning arm's tool (:func:`mavac.robots.models.iiwa7`).
HOLDER, PAD = "tool_0", "pad_0"


class ToolClearance:
    """``reachable(positions (n, 3), axes (n, 3)) -> (n,) bool`` for the cleaning arm (world =
    its base frame), see the module docstring.

    Parameters
    ----------
    cleaner : RobotModel
        The cleaning arm with its pad tool (:func:`mavac.scrubbing.cell.cell_robots`).
    part_world : trimesh.Trimesh
        The part where it is held, cleaning arm's base frame, metres.
    sweep : float, m, >= 0
        How far the oscillation swings the pad off its path (the holder's widening).
    """

    def __init__(self, cleaner, part_world: trimesh.Trimesh, *, sweep: float):
        check_mesh("part_world", part_world)
        sweep = float(check_nonnegative("sweep", sweep))
        self.robot = cleaner
        gm = cleaner.collision_model
        holder = gm.geometryObjects[gm.getGeometryId(HOLDER)]
        model = cleaner.model
        pad_frame = model.frames[model.getFrameId(cleaner.tool_frame)]
        if pad_frame.parentJoint != holder.parentJoint:
            raise ValueError("cleaner: its pad frame and pad holder must hang on the same joint")
        # the holder in the pad frame: a cylinder about the pad axis, widened by the swing
        self.pad_T_holder = np.linalg.inv(pad_frame.placement.homogeneous) @ holder.placement.homogeneous
        self.holder = coal.Cylinder(holder.geometry.radius + sweep, 2 * holder.geometry.halfLength)
        self.part = bvh_from_mesh(part_world)
        arm = gm.copy()
        for name in (HOLDER, PAD):
            arm.removeGeometryObject(name)
        self.arm = CollisionChecker(replace(cleaner, collision_model=arm), part_world, floor=True)

    def __call__(self, positions, axes) -> np.ndarray:
        positions, axes = check_points("positions", positions), check_points("axes", axes)
        if len(positions) != len(axes):
            raise ValueError(f"axes must have one row per position ({len(positions)}), got {len(axes)}")
        if len(positions) == 0:
            return np.zeros(0, dtype=bool)
        ik = ik_axis(self.robot, positions, axes)
        ok = np.asarray(ik.success, dtype=bool).copy()
        for i in np.flatnonzero(ok):
            ok[i] = not self.holder_hits(positions[i], axes[i]) and not self.arm.in_collision(ik.q[i])
        return ok

    def holder_hits(self, position, axis) -> bool:
        """Whether the widened holder meets the part with the pad face at ``position`` (3,), m,
        its axis (into the surface) along ``axis`` (3,)."""
        world_T_pad = np.eye(4)
        world_T_pad[:3, :3] = _frame_with_z(np.asarray(axis, float))
        world_T_pad[:3, 3] = position
        world_T_holder = world_T_pad @ self.pad_T_holder
        request, result = coal.CollisionRequest(), coal.CollisionResult()
        tf = coal.Transform3s(world_T_holder[:3, :3], world_T_holder[:3, 3])
        return coal.collide(self.holder, tf, self.part, coal.Transform3s(), request, result) > 0


def _frame_with_z(z: np.ndarray) -> np.ndarray:
    """(3, 3) rotation whose z axis is ``z`` (normalised); x any perpendicular (the holder is round)."""
    z = z / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])

"""Kinematics of Kabir et al.'s two-arm cleaning cell (Sec. IX-C): who stands where, the fixed
grasp, the holding arm's IK for a part pose, and whether a part pose leaves room for both arms.

Two KUKA iiwa arms (:func:`mavac.robots.models.iiwa7`) face each other across the workspace
(:class:`mavac.params.BimanualCellParams`): the cleaning arm at the world origin carries the
abrasive pad, the holding arm at ``world_T_holder`` grips the part at a fixed grasp
``flange_T_part`` (part z = flange z, ``grasp_offset`` along it). Everything here is plain
kinematics (pinocchio, coal); the pybullet cell is :mod:`mavac.scrubbing.scene`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import trimesh

from ..geometry.mesh import check_mesh
from ..geometry.transforms import check_transforms
from ..params import BimanualCellParams, ToolpathParams
from ..robots.collision import CollisionChecker
from ..robots.kinematics import IKResult, ik
from ..robots.models import iiwa7
from ..validate import check_instance

#: Cleaning arm parked out of the workspace (leaning back, elbow folded; ours): where it waits
#: while the holding arm changes setups.
CLEANER_PARK = np.array([0.0, -0.5, 0.0, 1.6, 0.0, -0.9, 0.0])
#: Holding arm seed: flange pointing up ~0.6 m in front of its base at ~0.3 m height (ours).
HOLDER_SEED = np.array([0.0, 0.9, 0.0, -1.2, 0.0, -1.05, 0.0])


def cell_robots(params: BimanualCellParams = BimanualCellParams(),
                toolpath: ToolpathParams = ToolpathParams()):
    """The two arms: ``(cleaner, holder)`` RobotModels.

    The cleaner's tool frame is the pad face (``params.tool_length`` past the flange, pad
    diameter ``toolpath.tool_width_m``: the pad width sets the slicing spacing); the holder's
    is its flange.
    """
    check_instance("params", params, BimanualCellParams)
    check_instance("toolpath", toolpath, ToolpathParams)
    cleaner = iiwa7(tool_length=params.tool_length, pad_width=toolpath.tool_width_m)
    holder = iiwa7(tool_length=0.0)
    holder.q_home = HOLDER_SEED.copy()
    return cleaner, holder


def flange_T_part(params: BimanualCellParams = BimanualCellParams()) -> np.ndarray:
    """The fixed grasp: part frame ``grasp_offset`` m along the holding flange's z, (4, 4)."""
    T = np.eye(4)
    T[2, 3] = params.grasp_offset
    return T


def holder_flange_targets(world_T_parts, params: BimanualCellParams = BimanualCellParams()) -> np.ndarray:
    """Holding flange poses in the holding arm's base frame that put the part at ``world_T_parts``.

    Parameters
    ----------
    world_T_parts : (k, 4, 4) or (4, 4) float

    Returns
    -------
    (k, 4, 4) float: ``holder_T_world @ world_T_part @ part_T_flange``.
    """
    T = check_transforms("world_T_parts", world_T_parts)
    holder_T_world = np.linalg.inv(params.world_T_holder)
    return holder_T_world @ T @ np.linalg.inv(flange_T_part(params))


def holder_ik(holder, world_T_parts, params: BimanualCellParams = BimanualCellParams(), *, q0=None) -> IKResult:
    """Holding arm configurations presenting the part at ``world_T_parts`` (full-pose IK, batched).

    Parameters
    ----------
    holder : RobotModel
        From :func:`cell_robots`.
    world_T_parts : (k, 4, 4) float
    q0 : (7,) or (k, 7) float, optional
        Seed (default :data:`HOLDER_SEED`): the solution nearest a previous setup's
        configuration keeps the motion short.
    """
    targets = holder_flange_targets(world_T_parts, params)
    return ik(holder, targets, frame="flange", q0=HOLDER_SEED if q0 is None else q0)


class ArmClearance:
    """Whether the part, held at a pose, stays clear of the holding arm and of the cleaning arm
    parked at :data:`CLEANER_PARK` (coal, ``params.part_clearance`` margin).

    The two collision checkers (one BVH of the part, in the part frame; each pose moves the
    arms' bases around it) are built once here: building them costs ~50 ms, as much as a few
    hundred poses' tests, and a setup plan tests the same part hundreds of times.

    Parameters
    ----------
    cleaner, holder : RobotModel
        From :func:`cell_robots`.
    part_mesh : trimesh.Trimesh
        Part frame, metres.
    params : BimanualCellParams
    """

    def __init__(self, cleaner, holder, part_mesh: trimesh.Trimesh,
                 params: BimanualCellParams = BimanualCellParams()):
        check_mesh("part_mesh", part_mesh)
        self.holder, self.params = holder, check_instance("params", params, BimanualCellParams)
        # The part touches the holding flange's adapter by construction; the links up to the
        # wrist (joints 1-5) must stay clear of it.
        self.hold = CollisionChecker(_links_up_to(holder, 5), part_mesh, margin=params.part_clearance)
        self.clean = CollisionChecker(cleaner, part_mesh, margin=params.part_clearance)

    def __call__(self, world_T_parts, q_holder) -> np.ndarray:
        """(k,) bool for the part at ``world_T_parts`` (k, 4, 4) held at ``q_holder`` (k, 7), rad."""
        T = check_transforms("world_T_parts", world_T_parts)
        q_holder = np.asarray(q_holder, dtype=float).reshape(len(T), self.holder.nq)
        out = np.ones(len(T), dtype=bool)
        for j, (Tj, qj) in enumerate(zip(T, q_holder)):
            part_T_world = np.linalg.inv(Tj)
            self.hold.set_base(part_T_world @ self.params.world_T_holder)
            self.clean.set_base(part_T_world @ self.params.world_T_cleaner)
            out[j] = not self.hold.in_collision(qj) and not self.clean.in_collision(CLEANER_PARK)
        return out


def part_clear_of_arms(cleaner, holder, part_mesh: trimesh.Trimesh, world_T_parts, q_holder,
                       params: BimanualCellParams = BimanualCellParams()) -> np.ndarray:
    """Whether the part, held at each pose, stays clear of the holding arm (at ``q_holder``) and
    of the cleaning arm parked at :data:`CLEANER_PARK` (:class:`ArmClearance`, built for this
    one call).

    A part too large to fit between the arms at a pose fails here.

    Parameters
    ----------
    part_mesh : trimesh.Trimesh
        Part frame, metres.
    world_T_parts : (k, 4, 4) float
    q_holder : (k, 7) float

    Returns
    -------
    (k,) bool
    """
    return ArmClearance(cleaner, holder, part_mesh, params)(world_T_parts, q_holder)


def _links_up_to(robot, last_joint: int):
    """A copy of ``robot`` whose collision model keeps only the geometry of joints <= ``last_joint``."""
    drop = [g.name for g in robot.collision_model.geometryObjects if g.parentJoint > last_joint]
    gm = robot.collision_model.copy()
    for name in drop:
        gm.removeGeometryObject(name)
    return replace(robot, collision_model=gm)

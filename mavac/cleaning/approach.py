"""Approach points of an area (MAVAC, "Trajectory generation", eq. 5).

For a node ``d`` seen from a guard whose tool orientation is (roll_g, pitch_g, yaw_g):

    p_a = [d_x, d_y, d_z - delta, roll_g +- alpha, pitch_g +- alpha, yaw_g +- alpha]   (5)

Two readings of ``d_z - delta`` (see :class:`mavac.params.ApproachParams`): ``"tool"`` puts the
approach point ``delta`` back along the tool axis from the node (tool z points into the
surface), ``"world"`` puts it ``delta`` above the node. Orientations are sampled within
``+- alpha`` on roll, pitch and yaw (the first sample is the guard's own), each solved with IK,
kept if the approach configuration is collision-free and the node itself is reachable with that
orientation; the one nearest in joint space is planned to with RRT-Connect. "If the approach
point is not reachable, another dust heap from the area is used ... If no p_a of the area is
reachable, the area is considered as unreachable from this guard."
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..geometry.transforms import check_transform
from ..params import ApproachParams
from ..robots.kinematics import ik
from ..seeding import int_seed
from .motion import Motion, plan_arm_motion

#: Ours: IK restarts per sampled orientation (the first attempt starts at the current q).
IK_RESTARTS = 2


def approach_orientations(world_R_guard, alpha: float, n: int, rng) -> np.ndarray:
    """(n, 3, 3) tool orientations: the guard's, then ``n - 1`` with roll, pitch and yaw each
    offset uniformly in ``[-alpha, alpha]`` (eq. 5)."""
    rpy = np.asarray(pin.rpy.matrixToRpy(np.asarray(world_R_guard, dtype=float)))
    offsets = np.vstack([np.zeros(3), rng.uniform(-alpha, alpha, size=(n - 1, 3))])
    return np.array([pin.rpy.rpyToMatrix(*(rpy + o)) for o in offsets])


def approach_poses(node, orientations, delta: float, reading: str) -> np.ndarray:
    """(n, 4, 4) tool poses at the approach point of ``node`` (3,) for each orientation."""
    R = np.asarray(orientations, dtype=float)
    T = np.tile(np.eye(4), (len(R), 1, 1))
    T[:, :3, :3] = R
    back = -R[:, :, 2] if reading == "tool" else np.tile([0.0, 0.0, 1.0], (len(R), 1))
    T[:, :3, 3] = np.asarray(node, dtype=float) + delta * back
    return T


def node_poses(node, orientations) -> np.ndarray:
    """(n, 4, 4) tool poses with the tool centre on ``node``."""
    R = np.asarray(orientations, dtype=float)
    T = np.tile(np.eye(4), (len(R), 1, 1))
    T[:, :3, :3] = R
    T[:, :3, 3] = np.asarray(node, dtype=float)
    return T


@dataclass
class Approach:
    """Outcome of :func:`find_approach` for one area.

    Attributes
    ----------
    success : bool
    node : int
        Index (into the area) of the node whose approach worked, -1 if none.
    q : (nq,) float or None
        Approach configuration.
    world_T_approach : (4, 4) float or None
        Tool pose at p_a.
    motion : Motion or None
        Path from the current configuration to ``q``.
    reason : str
        ``"ok"``, ``"no approach found"`` (no node had a valid approach configuration) or
        ``"planner failed"`` (some had one, RRT-Connect found no path to any).
    planning_seconds : float
        Wall time of IK and RRT-Connect, s.
    attempts : list of (int, str, float)
        Per node tried: its index, outcome, RRT-Connect wall time (s, 0 when not planned).
    """

    success: bool
    node: int = -1
    q: np.ndarray | None = None
    world_T_approach: np.ndarray | None = None
    motion: Motion | None = None
    reason: str = "no approach found"
    planning_seconds: float = 0.0
    attempts: list = field(default_factory=list)


def _valid_approach_configs(robot, checker, world_T_base, node, orientations, params, q_now, rng):
    """Approach configurations (m, nq) that are collision-free and whose node pose is reachable,
    nearest to ``q_now`` first."""
    base_T_world = np.linalg.inv(world_T_base)
    A = base_T_world @ approach_poses(node, orientations, params.delta, params.approach_reading)
    sol = ik(robot, A, q0=np.tile(q_now, (len(A), 1)), rng=rng, n_restarts=IK_RESTARTS)
    ok = np.flatnonzero(sol.success)
    if not len(ok):
        return np.zeros((0, robot.nq)), ok
    ok = ok[~checker.in_collision(sol.q[ok])]
    if not len(ok):
        return np.zeros((0, robot.nq)), ok
    at_node = ik(robot, base_T_world @ node_poses(node, orientations[ok]), q0=sol.q[ok], rng=rng, n_restarts=0)
    ok = ok[at_node.success]
    order = np.argsort(np.linalg.norm(sol.q[ok] - q_now, axis=1), kind="stable")
    return sol.q[ok][order], ok[order]


def find_approach(robot, checker, world_T_base, area_nodes, world_T_guard_tool, q_now, params: ApproachParams, *,
                  rng, seed: int) -> Approach:
    """Approach point and path for an area, trying its nodes in order (MAVAC, eq. 5).

    Parameters
    ----------
    robot : RobotModel
    checker : CollisionChecker
        At the current base pose, with the approach clearance margin.
    world_T_base : (4, 4) float
    area_nodes : (m, 3) float, metres
    world_T_guard_tool : (4, 4) float
        Tool pose at the current guard (its orientation is eq. 5's roll_g, pitch_g, yaw_g).
    q_now : (nq,) float
        Current configuration (RRT-Connect start).
    params : ApproachParams
    rng : numpy.random.Generator
        Orientation samples and IK restarts.
    seed : int
        Seed of this area's RRT-Connect plans (node ``k`` plans with
        ``mavac.seeding.int_seed(seed, "approach node", k)``).

    Returns
    -------
    Approach
    """
    world_T_base = check_transform("world_T_base", world_T_base)
    R_guard = check_transform("world_T_guard_tool", world_T_guard_tool)[:3, :3]
    t0, planner_tried = time.perf_counter(), False
    attempts = []
    for k, node in enumerate(np.asarray(area_nodes, dtype=float).reshape(-1, 3)):
        orientations = approach_orientations(R_guard, params.alpha, params.n_orientations, rng)
        configs, rows = _valid_approach_configs(robot, checker, world_T_base, node, orientations, params, q_now, rng)
        if not len(configs):
            attempts.append((k, "no approach found", 0.0))
            continue
        planner_tried = True
        motion = plan_arm_motion(robot, checker, q_now, configs[0], params, seed=int_seed(seed, "approach node", k))
        attempts.append((k, "ok" if motion.solved else "planner failed", motion.seconds))
        if motion.solved:
            T = approach_poses(node, orientations[rows[:1]], params.delta, params.approach_reading)[0]
            return Approach(True, k, configs[0], T, motion, "ok", time.perf_counter() - t0, attempts)
    reason = "planner failed" if planner_tried else "no approach found"
    return Approach(False, reason=reason, planning_seconds=time.perf_counter() - t0, attempts=attempts)

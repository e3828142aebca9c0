"""Collision-free arm motions between configurations (MAVAC, "Trajectory generation": the
paper's planner is RRT-Connect from OMPL).

:func:`plan_arm_motion` runs :func:`mavac.planning.rrt.plan_rrt_connect` against the machine
(coal, :class:`mavac.robots.collision.CollisionChecker`, with a clearance margin) in a box of
joint space around the start and goal: the UR10's +-2 pi limits would make the motion-check
step (a fraction of the box diagonal) ~0.3 rad, ~40 cm at the tool.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..planning.rrt import plan_rrt_connect
from ..params import ApproachParams
from ..validate import check_int

#: Ours: the planning box extends this far (rad) beyond the start and goal on every joint.
BOX_MARGIN = np.pi / 2


@dataclass(frozen=True)
class Motion:
    """A planned arm motion.

    Attributes
    ----------
    path : (k, nq) float or None
    solved : bool
    reason : str
        ``"solved"``, ``"same configuration"``, or the planner's reason.
    seconds : float
        Planning wall time, s.
    """

    path: np.ndarray | None
    solved: bool
    reason: str
    seconds: float


def planning_box(robot, q_start, q_goal) -> tuple[np.ndarray, np.ndarray]:
    """Joint box ``[lower, upper]`` (nq,) around start and goal, inside the joint limits."""
    lo = np.maximum(robot.q_lower, np.minimum(q_start, q_goal) - BOX_MARGIN)
    hi = np.minimum(robot.q_upper, np.maximum(q_start, q_goal) + BOX_MARGIN)
    return lo, hi


def plan_arm_motion(robot, checker, q_start, q_goal, params: ApproachParams, *, seed: int,
                    budget_factor: int = 1) -> Motion:
    """RRT-Connect from ``q_start`` to ``q_goal`` avoiding ``checker``'s machine and floor.

    Parameters
    ----------
    robot : RobotModel
    checker : CollisionChecker
        Already placed at the current base pose.
    q_start, q_goal : (nq,) float, rad
    params : ApproachParams
        ``rrt_max_iterations``, ``rrt_time_limit`` (a safety net), ``rrt_resolution``.
    seed : int
        OMPL seed (e.g. :func:`mavac.seeding.int_seed`).
    budget_factor : int, >= 1
        Multiplies the iteration budget and the time cap (a re-plan with a larger budget).

    Returns
    -------
    Motion

    Raises
    ------
    mavac.planning.rrt.PlanningTimeout
        If the wall-time safety net fires (never a quiet failure).
    """
    budget_factor = check_int("budget_factor", budget_factor, 1)
    qs, qg = np.asarray(q_start, dtype=float), np.asarray(q_goal, dtype=float)
    if np.allclose(qs, qg, atol=1e-9):
        return Motion(np.vstack([qs, qg]), True, "same configuration", 0.0)
    lo, hi = planning_box(robot, qs, qg)
    result = plan_rrt_connect(checker.is_free, qs, qg, lo, hi,
                              time_limit=params.rrt_time_limit * budget_factor, seed=int(seed),
                              resolution=params.rrt_resolution,
                              max_iterations=params.rrt_max_iterations * budget_factor)
    return Motion(result.path, result.solved, result.reason, result.seconds)

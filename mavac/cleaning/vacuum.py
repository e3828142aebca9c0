"""Dust collection under Cartesian impedance control (MAVAC, "Dust collecting", Algorithm 1
lines 9-14).

From the approach point the tool moves linearly into each node of the area, then back to the
approach point, in pybullet torque control with

    tau = J^T (K (x_d - x) - D xdot) + g(q)            (pinocchio: J, g)

where ``x_d`` slides along the segment at the vacuuming speed. The stiffness lets the sphere
press on the machine instead of fighting it; pybullet reports the contact forces, logged with
the peak per move. While the vacuum runs, every present heap within the suction radius of the
tool sphere's centre is removed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..params import VacuumParams
from ..sim.control import impedance_step

#: Ours: after the ramp, a move has settled when every joint is slower than this (rad/s), e.g.
#: the sphere resting on the machine short of a node.
SETTLED_JOINT_SPEED = 0.02


@dataclass
class VacuumLog:
    """What the vacuuming of one area did.

    Attributes
    ----------
    peak_forces : list of float, N
        Largest machine contact normal force of each linear move.
    sucked : list of int
        Heaps removed, in order.
    seconds : float
        Simulated time, s.
    reached : list of float, metres
        Closest the tool centre came to each node target.
    """

    peak_forces: list = field(default_factory=list)
    sucked: list = field(default_factory=list)
    seconds: float = 0.0
    reached: list = field(default_factory=list)


def _gains(params: VacuumParams) -> tuple[np.ndarray, np.ndarray]:
    K = np.array([params.stiffness] * 3 + [params.rotational_stiffness] * 3)
    D = np.array([params.damping] * 3 + [params.rotational_damping] * 3)
    return K, D


def linear_move(cell, world_T_from, world_T_to, params: VacuumParams, log: VacuumLog) -> float:
    """One impedance move of the tool centre from ``world_T_from`` to ``world_T_to`` (same
    orientation), then settling; sucks heaps on the way. Returns the closest approach to the
    target position, m."""
    dt = cell.world.time_step
    start, goal = world_T_from[:3, 3], world_T_to[:3, 3]
    n_ramp = max(1, int(np.ceil(np.linalg.norm(goal - start) / params.speed / dt)))
    n_settle = int(np.ceil(params.max_settle_time / dt))
    K, D = _gains(params)
    base_T_world = np.linalg.inv(cell.world_T_base)
    target = np.array(world_T_to, dtype=float)
    peak, closest = 0.0, np.inf
    for k in range(n_ramp + n_settle):
        s = min(1.0, (k + 1) / n_ramp)
        target[:3, 3] = start + s * (goal - start)
        q, dq = cell.sim.state()
        cell.sim.apply_torques_unchecked(impedance_step(cell.model, cell.data, q, dq, cell.tool_id,
                                                        base_T_world @ target, K, D))
        cell.world.step_once()
        tip = cell.sim.link_position(cell.tool_frame)
        log.sucked += cell.dust.suck(cell.world, tip, params.suction_radius).tolist()
        peak = max(peak, cell.world.contact_forces(cell.sim.body, cell.machine_body).normal_force)
        gap = float(np.linalg.norm(tip - goal))
        closest = min(closest, gap)
        if k >= n_ramp and (gap <= params.settle_tol or np.abs(dq).max() < SETTLED_JOINT_SPEED):
            break
    log.peak_forces.append(peak)
    log.seconds += (k + 1) * dt
    return closest


def vacuum_area(cell, world_T_approach, nodes, params: VacuumParams) -> VacuumLog:
    """Algorithm 1, lines 9-14: impedance moves into every node of an area, then back to the
    approach point.

    Parameters
    ----------
    cell : mavac.cleaning.scene.Cell
        The simulated cell (robot at the approach configuration).
    world_T_approach : (4, 4) float
        Tool pose at the approach point p_a (its orientation is kept for every move).
    nodes : (m, 3) float, metres
        The area's nodes in visiting order.
    params : VacuumParams

    Returns
    -------
    VacuumLog
    """
    log = VacuumLog()
    cell.sim.enable_torque_control()
    current = np.array(world_T_approach, dtype=float)
    for node in np.asarray(nodes, dtype=float).reshape(-1, 3):
        target = current.copy()
        target[:3, 3] = node
        log.reached.append(linear_move(cell, current, target, params, log))
        current = target
    linear_move(cell, current, world_T_approach, params, log)
    return log

"""Dust collection under Cartesian impedance control (MAVAC, "Dust collecting", Algorithm 1
lines 9-14).

From the approach point the tool moves linearly into each node of the area, then back to the
approach point, in pybullet torque control with

    tau = J^T (K (x_d - x) - D xdot) + g(q)            (pinocchio: J, g)

where ``x_d`` slides along the segment at the vacuuming speed. The stiffness lets the sphere
press on the machine instead of fighting it; pybullet reports the contact forces, logged with
the peak per move. While the vacuum runs, every present heap within the suction radius of the
tool sphere's centre is removed.

The authors' code (will-44/cleaning, ``script/online.py``, ``__main__``) does the same under
the Doosan's task compliance control: the tip, 5 cm short of the first node along the tool
axis, is pushed compliantly onto it (a linear move, no force set-point: ``set_force`` is
commented out), then moved node to node. It then spirals at the area's last node
(``VacuumParams.pattern = "spiral"``, :func:`spiral_path`), a motion our reading of the paper's
text ("a linear movement") does not have.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..params import VacuumParams
from ..sim.control import impedance_step
from ..validate import check_int, check_positive

#: Ours: after the ramp, a move has settled when every joint is slower than this (rad/s), e.g.
#: the sphere resting on the machine short of a node.
SETTLED_JOINT_SPEED = 0.02
#: Ours: the arm is sampled for the trial's replay every this many simulated seconds while it
#: vacuums (10 keys a second, smooth enough for a viewer that interpolates between them)
REPLAY_SAMPLE_S = 0.1


@dataclass
class VacuumLog:
    """What the vacuuming of one area did.

    Attributes
    ----------
    peak_forces : list of float, N
        Largest machine contact normal force of each move (linear or spiral).
    sucked : list of int
        Heaps removed, in order.
    seconds : float
        Simulated time, s.
    reached : list of float, metres
        Closest the tool centre came to each node target.
    sucked_at : list of float, s
        When each heap of ``sucked`` was removed, from the area's start.
    samples : list of (float, (nq,) float)
        The arm's configuration every :data:`REPLAY_SAMPLE_S` s (time from the area's start, q).
    """

    peak_forces: list = field(default_factory=list)
    sucked: list = field(default_factory=list)
    seconds: float = 0.0
    reached: list = field(default_factory=list)
    sucked_at: list = field(default_factory=list)
    samples: list = field(default_factory=list)


def _gains(params: VacuumParams) -> tuple[np.ndarray, np.ndarray]:
    K = np.array([params.stiffness] * 3 + [params.rotational_stiffness] * 3)
    D = np.array([params.damping] * 3 + [params.rotational_damping] * 3)
    return K, D


def spiral_path(center, *, radius: float, turns: float, n: int, axis=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Archimedean spiral around ``center`` in the plane normal to ``axis``.

    The radius grows linearly with the angle, from 0 at ``center`` to ``radius`` after
    ``turns`` revolutions (the Doosan ``move_spiral`` of the authors' code, about the base Z
    axis: world z for our upright base).

    Parameters
    ----------
    center : (3,) float, metres
    radius : float, metres (> 0)
    turns : float, revolutions (> 0)
    n : int, >= 2
        Points, evenly spaced in angle.
    axis : (3,) float
        Spiral axis (normalised here).

    Returns
    -------
    (n, 3) float, metres
        ``[0]`` is ``center``, ``[-1]`` lies ``radius`` from it.
    """
    check_positive("radius", radius)
    check_positive("turns", turns)
    n = check_int("n", n, 2)
    a = np.asarray(axis, dtype=float).reshape(3)
    if not np.isfinite(a).all() or np.linalg.norm(a) < 1e-12:
        raise ValueError(f"axis must be a finite non-zero 3-vector, got {axis!r}")
    a = a / np.linalg.norm(a)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(a, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    s = np.linspace(0.0, 1.0, n)
    phi, r = 2.0 * np.pi * turns * s, radius * s
    offsets = r[:, None] * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)
    return np.asarray(center, dtype=float).reshape(3) + offsets


def _follow(cell, world_T_ref, waypoints, n_settle: int, params: VacuumParams, log: VacuumLog) -> float:
    """Impedance-track the tool centre through ``waypoints`` (m, 3), one per physics step, with
    the orientation of ``world_T_ref``, then hold the last one for up to ``n_settle`` steps;
    sucks heaps on the way. Returns the closest approach to the last waypoint, m."""
    sim, world, dust = cell.sim, cell.world, cell.dust
    K, D = _gains(params)
    base_T_world = np.linalg.inv(cell.world_T_base)
    target = np.array(world_T_ref, dtype=float)
    goal = waypoints[-1]
    peak, closest, n_move = 0.0, np.inf, len(waypoints)
    every = max(1, round(REPLAY_SAMPLE_S / world.time_step))
    for k in range(n_move + n_settle):
        if k < n_move:  # the settling steps hold the last target
            target[:3, 3] = waypoints[k]
            base_T_target = base_T_world @ target
        q, dq = sim.state()
        if k % every == 0:
            log.samples.append((log.seconds + k * world.time_step, q))
        sim.apply_torques_unchecked(impedance_step(cell.model, cell.data, q, dq, cell.tool_id, base_T_target, K, D))
        world.step_once()
        tip = sim.link_position(cell.tool_frame)
        hit = dust.suck(tip, params.suction_radius)
        if len(hit):
            log.sucked += hit.tolist()
            log.sucked_at += [log.seconds + (k + 1) * world.time_step] * len(hit)
        peak = max(peak, world.normal_force(sim.body, cell.machine_body))
        d = tip - goal
        gap = math.sqrt(d.dot(d))  # numpy's norm of a vector, without its overhead
        closest = min(closest, gap)
        if k >= n_move and (gap <= params.settle_tol or np.abs(dq).max() < SETTLED_JOINT_SPEED):
            break
    log.peak_forces.append(peak)
    log.seconds += (k + 1) * world.time_step
    return closest


def linear_move(cell, world_T_from, world_T_to, params: VacuumParams, log: VacuumLog) -> float:
    """One impedance move of the tool centre from ``world_T_from`` to ``world_T_to`` (same
    orientation) at ``params.speed``, then settling; sucks heaps on the way. Returns the
    closest approach to the target position, m."""
    dt = cell.world.time_step
    start, goal = world_T_from[:3, 3], world_T_to[:3, 3]
    n_ramp = max(1, int(np.ceil(np.linalg.norm(goal - start) / params.speed / dt)))
    s = np.arange(1, n_ramp + 1) / n_ramp
    waypoints = start + s[:, None] * (goal - start)
    return _follow(cell, world_T_to, waypoints, int(np.ceil(params.max_settle_time / dt)), params, log)


def path_move(cell, world_T_ref, points, params: VacuumParams, log: VacuumLog) -> float:
    """Impedance-track the tool centre along the polyline ``points`` (k, 3), m, from its first
    point, at ``params.speed`` with the orientation of ``world_T_ref``, then settle; sucks heaps
    on the way (the systematic baseline's raster lines). Returns the closest approach to the
    last point, m."""
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
    n = max(1, int(np.ceil(s[-1] / params.speed / cell.world.time_step)))
    t = np.arange(1, n + 1) * (s[-1] / n)
    waypoints = np.column_stack([np.interp(t, s, P[:, i]) for i in range(3)])
    return _follow(cell, world_T_ref, waypoints, int(np.ceil(params.max_settle_time / cell.world.time_step)), params,
                   log)


def spiral_move(cell, world_T_node, params: VacuumParams, log: VacuumLog) -> np.ndarray:
    """The authors' spiral around the node of ``world_T_node`` (:func:`spiral_path`, over
    ``params.spiral_time`` s) under impedance; returns the tool pose commanded at its end."""
    dt = cell.world.time_step
    n = max(2, int(np.ceil(params.spiral_time / dt)))
    waypoints = spiral_path(world_T_node[:3, 3], radius=params.spiral_radius, turns=params.spiral_turns, n=n)
    _follow(cell, world_T_node, waypoints, int(np.ceil(params.max_settle_time / dt)), params, log)
    end = np.array(world_T_node, dtype=float)
    end[:3, 3] = waypoints[-1]
    return end


def vacuum_area(cell, world_T_approach, nodes, params: VacuumParams) -> VacuumLog:
    """Algorithm 1, lines 9-14: impedance moves into every node of an area, then back to the
    approach point; with ``params.pattern == "spiral"``, a spiral at the last node (or at
    every node, ``spiral_nodes="every"``).

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
    N = np.asarray(nodes, dtype=float).reshape(-1, 3)
    for i, node in enumerate(N):
        target = current.copy()
        target[:3, 3] = node
        log.reached.append(linear_move(cell, current, target, params, log))
        current = target
        if params.pattern == "spiral" and (params.spiral_nodes == "every" or i == len(N) - 1):
            current = spiral_move(cell, target, params, log)
    linear_move(cell, current, world_T_approach, params, log)
    return log

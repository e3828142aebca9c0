"""Torque controllers for pybullet robots, every dynamics term from pinocchio.

* :func:`gravity_torques` -- ``g(q)`` (``pinocchio.computeGeneralizedGravity``);
* :func:`joint_pd_torques` -- joint PD plus gravity compensation, gains in N m/rad;
* :func:`computed_torques` -- inverse dynamics (``pinocchio.rnea``) of a PD-corrected
  acceleration, gains in 1/s^2 and 1/s, so one pair of gains suits heavy and light joints;
* :func:`cartesian_impedance_torques` -- ``tau = J^T (K (x_d - x) - D xdot + w_ff) + g(q)``;
* :func:`follow_joint_trajectory` -- time-parametrised tracking of a joint path in pybullet
  torque control, returning a :class:`JointLog`.

The pinocchio model must be the one the pybullet robot was built from
(:func:`mavac.sim.urdf.urdf_from_pinocchio`), with the robot base as its root: torques are
computed in the base frame, so the base pose (moved kinematically) does not enter, and gravity
is world -z as long as the base stays level.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..geometry.transforms import check_transform
from ..validate import check_array, check_nonnegative, check_positive, check_range


def _vec(name: str, value, n: int) -> np.ndarray:
    a = check_array(name, value, float).reshape(-1)
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be {n} finite values, got shape {np.shape(value)}")
    return a


def _gains(name: str, value, n: int) -> np.ndarray:
    """A scalar or (n,) non-negative gain vector."""
    a = check_array(name, value, float).reshape(-1)
    if a.size == 1:
        a = np.full(n, float(a[0]))
    if a.shape != (n,) or not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"{name} must be a non-negative scalar or {n} non-negative values, got {value!r}")
    return a


def gravity_torques(model, q) -> np.ndarray:
    """Gravity compensation ``g(q)`` (nv,), N m (``pinocchio.computeGeneralizedGravity``)."""
    q = _vec("q", q, model.nq)
    return np.array(pin.computeGeneralizedGravity(model, model.createData(), q))


def joint_pd_torques(model, q, dq, q_des, dq_des, *, kp, kd) -> np.ndarray:
    """``kp (q_des - q) + kd (dq_des - dq) + g(q)``; gains scalar or (nv,), N m/rad, N m s/rad."""
    n = model.nv
    q, dq = _vec("q", q, model.nq), _vec("dq", dq, n)
    q_des, dq_des = _vec("q_des", q_des, model.nq), _vec("dq_des", dq_des, n)
    return _gains("kp", kp, n) * (q_des - q) + _gains("kd", kd, n) * (dq_des - dq) + gravity_torques(model, q)


def computed_torques(model, q, dq, q_des, dq_des, ddq_des=None, *, kp, kd, data=None) -> np.ndarray:
    """Inverse dynamics ``rnea(q, dq, ddq_des + kp (q_des - q) + kd (dq_des - dq))`` (nv,), N m.

    ``kp`` (1/s^2) and ``kd`` (1/s) shape the error dynamics of every joint alike
    (``kp = w^2``, ``kd = 2 w`` is critically damped at ``w`` rad/s).
    """
    n = model.nv
    q, dq = _vec("q", q, model.nq), _vec("dq", dq, n)
    q_des, dq_des = _vec("q_des", q_des, model.nq), _vec("dq_des", dq_des, n)
    acc = np.zeros(n) if ddq_des is None else _vec("ddq_des", ddq_des, n)
    data = model.createData() if data is None else data
    return computed_torques_step(model, data, q, dq, q_des, dq_des, acc, _gains("kp", kp, n), _gains("kd", kd, n))


def computed_torques_step(model, data, q, dq, q_des, dq_des, ddq_des, kp, kd) -> np.ndarray:
    """:func:`computed_torques` without input checks, for control loops (arrays (nv,) float)."""
    return np.array(pin.rnea(model, data, q, dq, ddq_des + kp * (q_des - q) + kd * (dq_des - dq)))


def cartesian_impedance_torques(model, data, q, dq, frame_id, world_T_target, *, stiffness, damping,
                                wrench_ff=None) -> np.ndarray:
    """``tau = J^T (K (x_d - x) - D xdot + wrench_ff) + g(q)`` (nv,), N m.

    Parameters
    ----------
    model, data : pinocchio.Model, pinocchio.Data
    q, dq : (nq,), (nv,) float
    frame_id : int
        Controlled frame (e.g. ``model.getFrameId("tool_tip")``).
    world_T_target : (4, 4) float
        Target pose in the model's root frame (the robot base).
    stiffness, damping : (6,) float
        ``K`` (N/m x3, N m/rad x3) and ``D`` (N s/m x3, N m s/rad x3), diagonal, >= 0.
    wrench_ff : (6,) float, optional
        Feed-forward force (N) and torque (N m), root-frame axes.

    Notes
    -----
    ``J`` is the frame Jacobian in ``LOCAL_WORLD_ALIGNED`` (linear velocity of the frame
    origin, angular velocity, root axes); the rotation error is ``log3(R_d R^T)``.
    """
    n = model.nv
    q, dq = _vec("q", q, model.nq), _vec("dq", dq, n)
    K, D = _vec("stiffness", stiffness, 6), _vec("damping", damping, 6)
    if np.any(K < 0) or np.any(D < 0):
        raise ValueError("stiffness and damping must be >= 0")
    ff = np.zeros(6) if wrench_ff is None else _vec("wrench_ff", wrench_ff, 6)
    target = check_transform("world_T_target", world_T_target)
    return impedance_step(model, data, q, dq, int(frame_id), target, K, D, ff)


def cartesian_damping(model, data, q, J, k: float, k_r: float, zeta: float) -> np.ndarray:
    """(6, 6) damping of the Cartesian impedance by the factorization design (Albu-Schaeffer et
    al., ICRA 2003; the damping ratio of KUKA's Cartesian impedance mode): ``D = zeta (A K1 + K1 A)``
    with ``A^2 = Lambda(q)``, the arm's Cartesian inertia at the pad, and ``K1^2 = diag(k I3, k_r I3)``.
    Each axis gets damping ratio zeta for the inertia it really has (the wrist's light rotations
    and the arm's heavy ones alike), where one scalar mass under- or over-damps some of them.

    Parameters
    ----------
    model, data : pinocchio Model and a Data of it (scratch: its mass matrix is overwritten)
    q : (nq,) float, rad
    J : (6, nq) float
        Frame Jacobian at ``q``, LOCAL_WORLD_ALIGNED (the twist the damping acts on).
    k, k_r : float
        Translational (N/m) and rotational (N m/rad) stiffness.
    zeta : float
        Damping ratio.

    Returns
    -------
    (6, 6) float: N s/m, N s, N m s/rad blocks, acting on the twist ``J dq``.
    """
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    w, V = np.linalg.eigh(J @ np.linalg.solve(M, J.T))
    A = (V / np.sqrt(np.maximum(w, 1e-9))) @ V.T
    K1 = np.sqrt(np.array([k] * 3 + [k_r] * 3))
    return zeta * (A * K1 + K1[:, None] * A)


def impedance_step(model, data, q, dq, frame_id: int, world_T_target, K, D, wrench_ff=None) -> np.ndarray:
    """:func:`cartesian_impedance_torques` without input checks, for control loops (only
    ``data.oMf[frame_id]`` is updated among the frame placements)."""
    # computeFrameJacobian places the joints of the frame's chain and the frame itself, by the
    # same products as forwardKinematics + updateFramePlacements (bit for bit)
    J = pin.computeFrameJacobian(model, data, q, frame_id, pin.LOCAL_WORLD_ALIGNED)
    M = data.oMf[frame_id]
    error = np.concatenate([world_T_target[:3, 3] - M.translation, pin.log3(world_T_target[:3, :3] @ M.rotation.T)])
    wrench = K * error - D * (J @ dq)
    if wrench_ff is not None:
        wrench = wrench + wrench_ff
    return J.T @ wrench + np.array(pin.computeGeneralizedGravity(model, data, q))


@dataclass(frozen=True)
class JointLog:
    """Joint-space log of a tracked trajectory.

    Attributes
    ----------
    t : (k,) float, s
    q, q_des : (k, nq) float, rad
    tau : (k, nv) float, N m
    duration : float, s
        Simulated time of the motion (trajectory plus settling).
    peak_contact_force : float, N
        Largest summed normal force between the robot and ``contact_body`` over every step
        (0 when no body was watched).
    """

    t: np.ndarray
    q: np.ndarray
    q_des: np.ndarray
    tau: np.ndarray
    duration: float
    peak_contact_force: float = 0.0

    @property
    def max_error(self) -> float:
        """Largest joint tracking error, rad."""
        return float(np.max(np.abs(self.q - self.q_des))) if len(self.q) else 0.0


def time_parametrise(qs, *, max_velocity, max_acceleration, dt) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample a piecewise-linear joint path with a trapezoidal profile along its arc length.

    The path (k, nq) is followed at ``s(t)``; the joint velocity limit ``max_velocity``
    (rad/s, scalar or per joint) bounds ``ds/dt`` through the largest ratio |dq/ds| / limit,
    ``max_acceleration`` (rad/s^2, scalar) its rate.

    Returns
    -------
    q, dq, ddq : (m, nq) float
        Desired positions, velocities and accelerations every ``dt`` seconds (m >= 1).
    """
    Q = check_array("qs", qs, float)
    if Q.ndim != 2 or len(Q) == 0 or not np.all(np.isfinite(Q)):
        raise ValueError(f"qs must be a finite (k, nq) array with k >= 1, got shape {Q.shape}")
    vmax = _gains("max_velocity", max_velocity, Q.shape[1])
    if np.any(vmax <= 0):
        raise ValueError("max_velocity must be > 0")
    check_positive("max_acceleration", max_acceleration)
    check_positive("dt", dt)
    seg = np.linalg.norm(np.diff(Q, axis=0), axis=1)
    s_knots = np.concatenate([[0.0], np.cumsum(seg)])
    length = s_knots[-1]
    if length <= 0.0:
        return Q[:1].copy(), np.zeros_like(Q[:1]), np.zeros_like(Q[:1])
    # |dq_i/ds| <= 1 along a unit-arc-length path; the slowest joint limits ds/dt
    direction = np.abs(np.diff(Q, axis=0)) / np.maximum(seg[:, None], 1e-12)
    sdot_max = float(np.min(vmax / np.maximum(direction.max(axis=0), 1e-9)))
    a = float(max_acceleration)
    t_acc = sdot_max / a
    if a * t_acc**2 > length:  # triangular profile
        t_acc = np.sqrt(length / a)
        sdot_max = a * t_acc
    total = 2 * t_acc + (length - a * t_acc**2) / sdot_max
    t = np.arange(0.0, total + dt, dt)
    s = np.where(t < t_acc, 0.5 * a * t**2,
                 np.where(t < total - t_acc, 0.5 * a * t_acc**2 + sdot_max * (t - t_acc),
                          length - 0.5 * a * np.clip(total - t, 0, None) ** 2))
    s = np.clip(s, 0.0, length)
    q = np.column_stack([np.interp(s, s_knots, Q[:, j]) for j in range(Q.shape[1])])
    dq = np.gradient(q, dt, axis=0) if len(q) > 1 else np.zeros_like(q)
    ddq = np.gradient(dq, dt, axis=0) if len(q) > 1 else np.zeros_like(q)
    return q, dq, ddq


def follow_joint_trajectory(world, robot, model, qs, *, dt=None, kp=400.0, kd=40.0, max_velocity=1.0,
                            max_acceleration=2.0, settle_tol: float = 1e-3, max_settle_steps: int = 240,
                            log_every: int = 1, contact_body: int | None = None) -> JointLog:
    """Torque-controlled tracking of a joint path in pybullet (computed torque from pinocchio).

    Parameters
    ----------
    world : mavac.sim.world.SimWorld
    robot : mavac.sim.world.SimRobot
        Its ``joint_names`` in ``model``'s q order; torque control is enabled here.
    model : pinocchio.Model
    qs : (k, nq) float
        Waypoints (e.g. an RRT-Connect path), the first one near the robot's current q.
    dt : float, optional
        Control period; default (and only supported value) ``world.time_step``: one torque
        per physics step.
    kp, kd : float or (nv,)
        Computed-torque gains, 1/s^2 and 1/s (default w = 20 rad/s, critically damped).
    max_velocity : float or (nv,), rad/s
    max_acceleration : float, rad/s^2
    settle_tol : float, rad
        After the path, hold the last waypoint until every joint is within this of it (or
        ``max_settle_steps`` steps).
    log_every : int
        Keep every n-th step in the log.
    contact_body : int, optional
        A body whose contacts with the robot are watched at every step (not only the logged
        ones): :attr:`JointLog.peak_contact_force`.

    Returns
    -------
    JointLog
    """
    dt = world.time_step if dt is None else float(dt)
    if abs(dt - world.time_step) > 1e-12:
        raise ValueError(f"dt must equal world.time_step ({world.time_step}), got {dt}")
    check_nonnegative("settle_tol", settle_tol)
    check_range("max_settle_steps", max_settle_steps, 0, 10**7)
    q_des, dq_des, ddq_des = time_parametrise(qs, max_velocity=max_velocity, max_acceleration=max_acceleration, dt=dt)
    data = model.createData()
    kp, kd = _gains("kp", kp, model.nv), _gains("kd", kd, model.nv)
    robot.enable_torque_control()
    rows: list = []
    n_total, zero = len(q_des), np.zeros(model.nv)
    peak = 0.0
    for k in range(n_total + int(max_settle_steps)):
        i = min(k, n_total - 1)
        q, dq = robot.state()
        if k >= n_total and np.max(np.abs(q - q_des[-1])) <= settle_tol and np.max(np.abs(dq)) < 10 * settle_tol:
            break
        ref_v, ref_a = (dq_des[i], ddq_des[i]) if k < n_total else (zero, zero)
        tau = computed_torques_step(model, data, q, dq, q_des[i], ref_v, ref_a, kp, kd)
        robot.apply_torques_unchecked(tau)
        world.step_once()
        if contact_body is not None:
            peak = max(peak, world.normal_force(robot.body, contact_body))
        if k % max(1, int(log_every)) == 0:
            rows.append((k * dt, q, q_des[i], tau))
    steps = k + 1
    t, q_log, qd_log, tau_log = (np.array(c) for c in zip(*rows)) if rows else (np.zeros(0),) * 4
    return JointLog(t, q_log, qd_log, tau_log, steps * dt, peak)

"""Batched kinematics of serial revolute arms: FK, Jacobian, IK, maneuverability index.

Everything is vectorised over many configurations / targets at once: the joint placements and
axes are read from the pinocchio model once per frame and composed with numpy (pinocchio is
the reference the tests compare against). Inverse kinematics:

* ``ik`` (full pose) and ``ik_axis`` (position + tool axis, free spin about it): one batched
  damped-least-squares Newton iteration over all targets at once (batched 6x6 solves),
  joint-limit clipping, seeded random restarts for the targets that did not converge;
* ``ik_axis`` on a model built from a Puma-type DH table (spherical wrist) dispatches to a
  closed-form, pure-numpy solver (8 branches: shoulder, elbow, wrist flip), the workhorse of
  Kabir et al.'s reach test.

All poses are in the robot base frame (``base_T_frame``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..validate import check_int, check_positive

_AXES = {"RX": (1.0, 0.0, 0.0), "RY": (0.0, 1.0, 0.0), "RZ": (0.0, 0.0, 1.0)}
_TWO_PI = 2.0 * np.pi


@dataclass
class IKResult:
    """Batched inverse-kinematics answer.

    Attributes
    ----------
    q : (n, nq) float, rad
        Best configuration found per target (within joint limits; meaningful only where
        ``success``).
    success : (n,) bool
        Converged within the tolerances and within joint limits.
    position_error : (n,) float, metres
    rotation_error : (n,) float, rad
        Full-pose: angle of ``R_target R^T``; axis IK: angle between tool z and the target axis.
    """

    q: np.ndarray
    success: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray


# ---------------------------------------------------------------------------------------------
# input checks


def _check_q(robot, q, name: str = "q") -> tuple[np.ndarray, bool]:
    """``q`` as (n, nq) plus whether a single (nq,) configuration was given."""
    a = np.asarray(q, dtype=float)
    single = a.ndim == 1
    if single:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != robot.nq:
        raise ValueError(f"{name} must have shape ({robot.nq},) or (n, {robot.nq}), got {np.shape(q)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a, single


def _check_frame(robot, frame) -> str:
    frame = robot.tool_frame if frame is None else frame
    if not isinstance(frame, str) or not robot.model.existFrame(frame):
        names = [f.name for f in robot.model.frames]
        raise ValueError(f"frame must be a frame of {robot.name} (one of {names}), got {frame!r}")
    return frame


def _check_vectors(name, v) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.ndim == 1 and a.shape[0] == 3:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {np.shape(v)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def _check_q0(robot, q0, n) -> np.ndarray:
    if q0 is None:
        return np.broadcast_to(robot.q_home, (n, robot.nq)).copy()
    a, _ = _check_q(robot, q0, "q0")
    if a.shape[0] not in (1, n):
        raise ValueError(f"q0 must have shape ({robot.nq},) or ({n}, {robot.nq}), got {np.shape(q0)}")
    return np.clip(np.broadcast_to(a, (n, robot.nq)), robot.q_lower, robot.q_upper)


# ---------------------------------------------------------------------------------------------
# forward kinematics and Jacobian


def _chain(robot, frame: str) -> dict:
    """Joint placements, axes and q indices from the root to ``frame`` (cached on the robot)."""
    key = ("chain", frame)
    if key in robot._cache:
        return robot._cache[key]
    m = robot.model
    f = m.frames[m.getFrameId(frame)]
    joint_ids = list(m.supports[f.parentJoint])[1:]
    R_M, p_M, K, K2, idx = [], [], [], [], []
    for j in joint_ids:
        jm = m.joints[j]
        short = jm.shortname().replace("JointModel", "")
        if short in _AXES:
            axis = np.array(_AXES[short])
        elif short == "RevoluteUnaligned":
            axis = np.asarray(jm.extract().axis, dtype=float)
        else:
            raise ValueError(f"robot {robot.name}: joint {m.names[j]} ({short}) is not revolute")
        Kj = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
        R_M.append(m.jointPlacements[j].rotation.copy())
        p_M.append(m.jointPlacements[j].translation.copy())
        K.append(Kj)
        K2.append(Kj @ Kj)
        idx.append(jm.idx_q)
    chain = {
        "R_M": np.array(R_M), "p_M": np.array(p_M), "K": np.array(K), "K2": np.array(K2),
        "axis": np.array([[Kj[2, 1], Kj[0, 2], Kj[1, 0]] for Kj in K]), "idx": np.array(idx, dtype=int),
        "R_f": f.placement.rotation.copy(), "p_f": f.placement.translation.copy(),
    }
    robot._cache[key] = chain
    return chain


def _rmul(R: np.ndarray, M: np.ndarray) -> np.ndarray:
    """``R @ M`` for a stack R (n,3,3) and one matrix M (3,3) (or vector (3,)), as one GEMM."""
    out = R.reshape(-1, 3) @ M
    return out.reshape(R.shape[0], 3, 3) if M.ndim == 2 else out.reshape(R.shape[0], 3)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (..., 3) arrays (cheaper than np.cross for small rows)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _forward(chain: dict, q: np.ndarray, with_joints: bool = False):
    """Batched FK. Returns ``R (n,3,3)``, ``p (n,3)`` of the frame and, if asked, the joint
    origins ``(n,k,3)`` and world joint axes ``(n,k,3)``.

    Each joint: ``T <- T * placement * exp(theta [axis])`` with Rodrigues'
    ``exp = I + sin(theta) K + (1 - cos(theta)) K^2``; products with constant matrices are
    single GEMMs over the stacked rows.
    """
    n = q.shape[0]
    R = np.tile(np.eye(3), (n, 1, 1))
    p = np.zeros((n, 3))
    origins, axes = [], []
    for i in range(len(chain["idx"])):
        p = p + _rmul(R, chain["p_M"][i])
        R = _rmul(R, chain["R_M"][i])
        th = q[:, chain["idx"][i]]
        if with_joints:
            origins.append(p)
            axes.append(_rmul(R, chain["axis"][i]))
        s = np.sin(th)[:, None, None]
        c1 = (1.0 - np.cos(th))[:, None, None]
        R = R + s * _rmul(R, chain["K"][i]) + c1 * _rmul(R, chain["K2"][i])
    p = p + _rmul(R, chain["p_f"])
    R = _rmul(R, chain["R_f"])
    if with_joints:
        return R, p, np.stack(origins, axis=1), np.stack(axes, axis=1)
    return R, p


def _jacobian_from(chain, nq, p, origins, axes) -> np.ndarray:
    """LOCAL_WORLD_ALIGNED Jacobian (n, 6, nq) from joint origins/axes and the frame point."""
    n = p.shape[0]
    J = np.zeros((n, 6, nq))
    J[:, :3, chain["idx"]] = _cross(axes, p[:, None, :] - origins).transpose(0, 2, 1)
    J[:, 3:, chain["idx"]] = axes.transpose(0, 2, 1)
    return J


def fk(robot, q, frame: str | None = None) -> np.ndarray:
    """Forward kinematics ``base_T_frame``.

    Parameters
    ----------
    robot : RobotModel
    q : (nq,) or (n, nq) float, rad
    frame : str, default ``robot.tool_frame``

    Returns
    -------
    (4, 4) or (n, 4, 4) float
    """
    qa, single = _check_q(robot, q)
    R, p = _forward(_chain(robot, _check_frame(robot, frame)), qa)
    T = np.zeros((qa.shape[0], 4, 4))
    T[:, :3, :3] = R
    T[:, :3, 3] = p
    T[:, 3, 3] = 1.0
    return T[0] if single else T


def jacobian(robot, q, frame: str | None = None) -> np.ndarray:
    """Frame Jacobian, LOCAL_WORLD_ALIGNED (linear rows first), in the base frame.

    Parameters
    ----------
    q : (nq,) or (n, nq) float, rad

    Returns
    -------
    (6, nq) or (n, 6, nq) float
    """
    qa, single = _check_q(robot, q)
    chain = _chain(robot, _check_frame(robot, frame))
    _, p, origins, axes = _forward(chain, qa, with_joints=True)
    J = _jacobian_from(chain, robot.nq, p, origins, axes)
    return J[0] if single else J


# ---------------------------------------------------------------------------------------------
# numerical IK (batched damped least squares)


def _axis_residual(R, z_target):
    """Rotation-vector residual turning the current z axis onto ``z_target`` (n,3) and its angle."""
    z = R[:, :, 2]
    c = _cross(z, z_target)
    s = np.sqrt(np.einsum("ij,ij->i", c, c))
    ang = np.arctan2(s, np.einsum("ij,ij->i", z, z_target))
    axis = np.where(s[:, None] > 1e-12, c / np.maximum(s, 1e-300)[:, None], R[:, :, 0])
    return axis * ang[:, None], ang


def _pose_residual(R, R_target):
    """Rotation vector of ``R_target R^T`` (world frame) and its angle, (n,3) and (n,)."""
    E = R_target @ R.transpose(0, 2, 1)
    cos = np.clip((E[:, 0, 0] + E[:, 1, 1] + E[:, 2, 2] - 1.0) / 2.0, -1.0, 1.0)
    w = np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], axis=1)
    sin = 0.5 * np.sqrt(np.einsum("ij,ij->i", w, w))
    ang = np.arctan2(sin, cos)
    # theta / (2 sin theta), with its series near 0
    rv = w * np.where(sin > 1e-8, ang / np.maximum(2.0 * sin, 1e-300), 0.5 + ang * ang / 12.0)[:, None]
    near_pi = cos < -0.99  # axis from the skew part is ill-conditioned there
    if near_pi.any():
        rv[near_pi] = Rotation.from_matrix(E[near_pi]).as_rotvec()
    return rv, ang


def _random_q(robot, rng, n) -> np.ndarray:
    # +-2 pi limits sample one turn only: configurations repeat with period 2 pi.
    lo = np.maximum(robot.q_lower, -np.pi)
    hi = np.minimum(robot.q_upper, np.pi)
    return rng.uniform(lo, hi, size=(n, robot.nq))


_STALL_ITERS = 12  # a row whose residual has not dropped by 1 % in this many iterations is stuck


def _dls(robot, chain, q, p_t, rot_t, mode, max_iter, pos_tol, rot_tol, damping, max_step):
    """Newton DLS iterations on all rows of ``q`` at once.

    Converged rows are frozen; rows stuck in a local minimum or against a joint limit (no 1 %
    progress in ``_STALL_ITERS`` iterations) are dropped early and left to the restarts.
    Returns the final ``q`` and the errors at it.
    """
    lo, hi = robot.q_lower, robot.q_upper
    n = q.shape[0]
    pos_err = np.full(n, np.inf)
    rot_err = np.full(n, np.inf)
    best = np.full(n, np.inf)
    since = np.zeros(n, dtype=int)
    active = np.arange(n)
    eye6 = np.eye(6) * damping
    for it in range(max_iter + 1):
        qa = q[active]
        R, p, origins, axes = _forward(chain, qa, with_joints=True)
        e_p = p_t[active] - p
        if mode == "axis":
            e_r, ang = _axis_residual(R, rot_t[active])
        else:
            e_r, ang = _pose_residual(R, rot_t[active])
        pe = np.sqrt(np.einsum("ij,ij->i", e_p, e_p))
        pos_err[active], rot_err[active] = pe, ang
        metric = pe + 0.1 * ang
        improved = metric < 0.99 * best[active]
        best[active] = np.where(improved, metric, best[active])
        since[active] = np.where(improved, 0, since[active] + 1)
        keep = ((pe >= pos_tol) | (ang >= rot_tol)) & (since[active] < _STALL_ITERS)
        if it == max_iter or not keep.any():
            break
        active, qa, R, p, origins, axes = active[keep], qa[keep], R[keep], p[keep], origins[keep], axes[keep]
        e = np.concatenate([e_p[keep], e_r[keep]], axis=1)
        J = _jacobian_from(chain, robot.nq, p, origins, axes)
        if mode == "axis":
            # The spin about the tool axis is free: project it out of the angular rows.
            z = R[:, :, 2]
            P = np.eye(3) - z[:, :, None] * z[:, None, :]
            J[:, 3:, :] = P @ J[:, 3:, :]
        JJt = J @ J.transpose(0, 2, 1) + eye6
        dq = (J.transpose(0, 2, 1) @ np.linalg.solve(JJt, e[:, :, None]))[:, :, 0]
        step = np.max(np.abs(dq), axis=1)
        dq *= np.minimum(1.0, max_step / np.maximum(step, 1e-300))[:, None]
        q[active] = np.clip(qa + dq, lo, hi)
    return q, pos_err, rot_err


def _solve_batched(robot, frame, p_t, rot_t, mode, q0, rng, max_iter, n_restarts, pos_tol, rot_tol, damping, max_step):
    """First attempt from ``q0``, then restart rounds of 1, 2, 4, ... random seeds per
    unsolved target, all seeds of a round solved in one batch (fewer, larger batches)."""
    check_int("max_iter", max_iter, 1)
    check_int("n_restarts", n_restarts, 0)
    check_positive("pos_tol", pos_tol)
    check_positive("rot_tol", rot_tol)
    check_positive("damping", damping)
    check_positive("max_step", max_step)
    rng = np.random.default_rng(0) if rng is None else rng
    chain = _chain(robot, frame)
    n = p_t.shape[0]
    q, pe, re = _dls(robot, chain, _check_q0(robot, q0, n), p_t, rot_t, mode, max_iter, pos_tol, rot_tol, damping, max_step)
    ok = (pe < pos_tol) & (re < rot_tol)
    used, per_target = 0, 1
    while used < n_restarts and not ok.all():
        k = min(per_target, n_restarts - used)
        todo = np.repeat(np.flatnonzero(~ok), k)
        q_try, pe_try, re_try = _dls(
            robot, chain, _random_q(robot, rng, todo.size), p_t[todo], rot_t[todo], mode,
            max_iter, pos_tol, rot_tol, damping, max_step,
        )
        # per target keep the attempt with the smallest scaled residual (in seed order)
        score = pe_try + 0.1 * re_try
        for j in range(k):
            rows = slice(j, None, k)
            tgt = todo[rows]
            better = score[rows] < pe[tgt] + 0.1 * re[tgt]
            sel = tgt[better]
            q[sel], pe[sel], re[sel] = q_try[rows][better], pe_try[rows][better], re_try[rows][better]
        ok = (pe < pos_tol) & (re < rot_tol)
        used += k
        per_target *= 2
    return IKResult(q=q, success=ok, position_error=pe, rotation_error=re)


def ik(
    robot, base_T_target, frame: str | None = None, q0=None, rng: np.random.Generator | None = None,
    max_iter: int = 50, n_restarts: int = 8, pos_tol: float = 1e-5, rot_tol: float = 1e-4,
    damping: float = 1e-6, max_step: float = 1.0,
) -> IKResult:
    """Full-pose inverse kinematics, batched damped least squares with random restarts.

    Parameters
    ----------
    robot : RobotModel
    base_T_target : (n, 4, 4) or (4, 4) float
        Target poses of ``frame`` in the base frame (metres).
    frame : str, default ``robot.tool_frame``
    q0 : (nq,) or (n, nq) float, rad, optional
        First seed (default ``robot.q_home``); restarts draw uniform seeds within the limits.
    rng : numpy.random.Generator, optional
        For the restart seeds (default ``default_rng(0)``).
    max_iter : int
        Newton iterations per attempt.
    n_restarts : int
        Extra random attempts for the targets not converged yet.
    pos_tol, rot_tol : float (m, rad)
        Convergence tolerances.
    damping : float
        DLS damping lambda^2 added to ``J J^T``.
    max_step : float, rad
        Largest joint change per iteration.

    Returns
    -------
    IKResult
    """
    T = np.asarray(base_T_target, dtype=float)
    if T.ndim == 2:
        T = T[None]
    if T.ndim != 3 or T.shape[1:] != (4, 4):
        raise ValueError(f"base_T_target must have shape (n, 4, 4), got {np.shape(base_T_target)}")
    if not np.all(np.isfinite(T)):
        raise ValueError("base_T_target contains NaN or infinite values")
    R = T[:, :3, :3]
    if np.max(np.abs(R @ R.transpose(0, 2, 1) - np.eye(3)), initial=0.0) > 1e-6:
        raise ValueError("base_T_target rotations must be orthonormal")
    frame = _check_frame(robot, frame)
    return _solve_batched(robot, frame, T[:, :3, 3].copy(), R.copy(), "pose", q0, rng,
                          max_iter, n_restarts, pos_tol, rot_tol, damping, max_step)


def ik_axis(
    robot, positions, axes, frame: str | None = None, q0=None, rng: np.random.Generator | None = None,
    method: str = "auto", max_iter: int = 50, n_restarts: int = 8, pos_tol: float = 1e-5,
    rot_tol: float = 1e-4, damping: float = 1e-6, max_step: float = 1.0,
) -> IKResult:
    """Inverse kinematics for a position and a tool axis (free rotation about the axis).

    Parameters
    ----------
    robot : RobotModel
    positions : (n, 3) float, metres
        Targets for the origin of ``frame`` in the base frame.
    axes : (n, 3) float
        Target directions of the frame's z axis (normalised here).
    frame : str, default ``robot.tool_frame``
    q0 : (nq,) or (n, nq) float, optional
        Seed for DLS; for the closed form, the branch nearest to ``q0`` is returned.
    method : {"auto", "closed_form", "dls"}
        ``"auto"`` uses the closed form when the model has a Puma-type DH table and ``frame``
        lies on the flange axis, DLS otherwise.
    max_iter, n_restarts, pos_tol, rot_tol, damping, max_step, rng
        As in :func:`ik` (DLS only; ``pos_tol``/``rot_tol`` also decide closed-form success).

    Returns
    -------
    IKResult
    """
    p = _check_vectors("positions", positions)
    a = _check_vectors("axes", axes)
    if p.shape[0] != a.shape[0]:
        raise ValueError(f"positions and axes must have the same length, got {p.shape[0]} and {a.shape[0]}")
    norm = np.linalg.norm(a, axis=1)
    if np.any(norm < 1e-12):
        raise ValueError("axes must be non-zero vectors")
    a = a / norm[:, None]
    frame = _check_frame(robot, frame)
    if method not in ("auto", "closed_form", "dls"):
        raise ValueError(f"method must be 'auto', 'closed_form' or 'dls', got {method!r}")
    closed = _closed_form_params(robot, frame)
    if method == "closed_form" and closed is None:
        raise ValueError(f"method='closed_form' needs a Puma-type DH robot and a flange-axis frame, got {robot.name}/{frame}")
    if method != "dls" and closed is not None:
        q0a = None if q0 is None else _check_q0(robot, q0, p.shape[0])
        return _puma_ik_axis(closed, robot.q_lower, robot.q_upper, p, a, q0a, pos_tol, rot_tol)
    return _solve_batched(robot, frame, p, a, "axis", q0, rng, max_iter, n_restarts, pos_tol, rot_tol, damping, max_step)


# ---------------------------------------------------------------------------------------------
# closed-form axis IK for Puma-type arms (standard DH, spherical wrist)

# alpha pattern of the Puma 560 in standard DH (Corke, mdl_puma560)
_PUMA_ALPHA = np.array([np.pi / 2, 0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, 0.0])


def _closed_form_params(robot, frame):
    """DH constants for the closed form, or None when it does not apply."""
    dh = getattr(robot, "dh", None)
    if dh is None or dh.shape != (6, 3) or not np.allclose(dh[:, 2], _PUMA_ALPHA):
        return None
    a, d = dh[:, 0], dh[:, 1]
    if not (a[0] == 0 and a[3] == 0 and a[4] == 0 and a[5] == 0 and d[4] == 0):
        return None
    chain = _chain(robot, frame)
    if len(chain["idx"]) != 6 or not np.allclose(chain["p_f"][:2], 0.0):
        return None
    # The frame must keep z6 as its z axis (any spin about it is fine).
    if not np.allclose(chain["R_f"][:, 2], [0.0, 0.0, 1.0]):
        return None
    return {
        "d1": d[0], "a2": a[1], "d_off": d[1] + d[2], "a3": a[2], "d4": d[3],
        "reach": d[5] + chain["p_f"][2],
    }


def _puma_tool(c, q):
    """Analytic position and z axis of the tool for (..., 6) joint angles (closed-form FK)."""
    q1, q2, q3, q4, q5 = (q[..., i] for i in range(5))
    c1, s1 = np.cos(q1), np.sin(q1)
    c2, s2 = np.cos(q2), np.sin(q2)
    c23, s23 = np.cos(q2 + q3), np.sin(q2 + q3)
    x1 = c["a2"] * c2 + c["a3"] * c23 - c["d4"] * s23
    y1 = c["a2"] * s2 + c["a3"] * s23 + c["d4"] * c23
    w = np.stack([c1 * x1 + s1 * c["d_off"], s1 * x1 - c1 * c["d_off"], y1 + c["d1"]], axis=-1)
    # z6 in frame 3 is (-c4 s5, -s4 s5, c5); R03 = Rz(q1) Rx(pi/2) Rz(q23) Rx(-pi/2)
    # = Rz(q1) Ry(-q23).
    s5 = np.sin(q5)
    v0, v1, v2 = -np.cos(q4) * s5, -np.sin(q4) * s5, np.cos(q5)
    u0 = c23 * v0 - s23 * v2
    u2 = s23 * v0 + c23 * v2
    z = np.stack([c1 * u0 - s1 * v1, s1 * u0 + c1 * v1, u2], axis=-1)
    return w + c["reach"] * z, z


def _wrap_into(theta, lo: float, hi: float):
    """Equivalent of ``theta`` (mod 2 pi) with the largest normalised joint-limit margin.

    Returns the angle and its margin ``min(t - lo, hi - t) / (hi - lo)`` (< 0 when no
    equivalent angle lies within [lo, hi]).
    """
    t = theta - _TWO_PI * np.round(theta / _TWO_PI)
    span = hi - lo
    m = np.minimum(t - lo, hi - t) / span
    if lo < -np.pi or hi > np.pi:  # a second turn can fall inside the limits
        alt = t - np.copysign(_TWO_PI, t)
        m_alt = np.minimum(alt - lo, hi - alt) / span
        use = m_alt > m
        t = np.where(use, alt, t)
        m = np.where(use, m_alt, m)
    return t, m


_CHUNK = 16384  # rows per closed-form block: keeps the temporaries in cache


def _puma_ik_axis(c, lo, hi, p, a, q0, pos_tol, rot_tol):
    """Closed-form axis IK, 8 branches (shoulder x elbow x wrist flip), vectorised by blocks.

    Branch arrays are kept at their natural shapes ``(n, shoulder, elbow, wrist)`` and only
    broadcast when scored, so each angle is computed and wrapped once.
    """
    n = p.shape[0]
    if n > _CHUNK:
        parts = [
            _puma_ik_axis(c, lo, hi, p[i : i + _CHUNK], a[i : i + _CHUNK],
                          None if q0 is None else q0[i : i + _CHUNK], pos_tol, rot_tol)
            for i in range(0, n, _CHUNK)
        ]
        return IKResult(*(np.concatenate([getattr(r, f) for r in parts]) for f in
                          ("q", "success", "position_error", "rotation_error")))
    w = p - c["reach"] * a
    wx, wy, wz = w[:, 0], w[:, 1], w[:, 2] - c["d1"]
    r2 = wx * wx + wy * wy
    r = np.sqrt(r2)
    phi = np.arctan2(wy, wx)
    # q1: r sin(q1 - phi) = d_off (shoulder offset) -> two solutions (right/left arm).
    ratio = c["d_off"] / np.maximum(r, 1e-12)
    reach_ok = np.abs(ratio) <= 1.0
    gam = np.arcsin(np.clip(ratio, -1.0, 1.0))
    xr = np.sqrt(np.maximum(r2 - c["d_off"] ** 2, 0.0))
    q1 = np.stack([phi + gam, phi + np.pi - gam], axis=1)  # (n, 2) shoulder
    x1 = np.stack([xr, -xr], axis=1)  # in-plane horizontal reach of the wrist centre
    # planar 2R: upper arm a2, forearm L3 = |(a3, d4)| at angle beta.
    L3 = np.hypot(c["a3"], c["d4"])
    beta = np.arctan2(c["d4"], c["a3"])
    D = (r2 - c["d_off"] ** 2 + wz * wz - c["a2"] ** 2 - L3 * L3) / (2.0 * c["a2"] * L3)
    reach_ok &= np.abs(D) <= 1.0
    t3 = np.arccos(np.clip(D, -1.0, 1.0))
    t3 = np.stack([t3, -t3], axis=1)  # (n, 2) elbow
    q3 = t3 - beta
    q2 = np.arctan2(wz[:, None], x1)[:, :, None] - np.arctan2(L3 * np.sin(t3), c["a2"] + L3 * np.cos(t3))[:, None, :]
    # tool axis in frame 3 -> (q4, q5) for each (shoulder, elbow): (n, 2, 2)
    c1, s1 = np.cos(q1)[:, :, None], np.sin(q1)[:, :, None]
    q23 = q2 + q3[:, None, :]
    c23, s23 = np.cos(q23), np.sin(q23)
    ax, ay, az = (a[:, i, None, None] for i in range(3))
    u0 = c1 * ax + s1 * ay
    u1 = -s1 * ax + c1 * ay
    b0 = c23 * u0 + s23 * az
    b2 = -s23 * u0 + c23 * az
    q5 = np.arctan2(np.hypot(b0, u1), b2)
    q4 = np.arctan2(-u1, -b0)
    q4 = np.stack([q4, q4 + np.pi], axis=3)  # (n, 2, 2, 2) wrist flip
    q5 = np.stack([q5, -q5], axis=3)
    q6 = min(max(0.0, lo[5]), hi[5])  # free spin about the tool axis: closest to 0
    # wrap each joint once at its own shape, then score the 8 branches by broadcasting
    q1, m1 = _wrap_into(q1, lo[0], hi[0])
    q2, m2 = _wrap_into(q2, lo[1], hi[1])
    q3, m3 = _wrap_into(q3, lo[2], hi[2])
    q4, m4 = _wrap_into(q4, lo[3], hi[3])
    q5, m5 = _wrap_into(q5, lo[4], hi[4])
    m6 = min(q6 - lo[5], hi[5] - q6) / (hi[5] - lo[5])
    margin = np.minimum(np.minimum(np.minimum(m1[:, :, None, None], m2[:, :, :, None]), m3[:, None, :, None]),
                        np.minimum(np.minimum(m4, m5), m6)).reshape(n, 8)
    valid = (margin >= 0.0) & reach_ok[:, None]
    if q0 is None:
        # branch with the largest normalised distance to the joint limits (valid ones first)
        score = np.where(valid, margin, margin - 10.0)
    else:
        shape = (n, 2, 2, 2)
        Q = (q1[:, :, None, None], q2[:, :, :, None], q3[:, None, :, None], q4, q5)
        dist = sum((np.broadcast_to(Qj, shape) - q0[:, j, None, None, None]) ** 2 for j, Qj in enumerate(Q))
        dist = dist.reshape(n, 8) + (q6 - q0[:, 5, None]) ** 2
        score = np.where(valid, -dist, -dist - 1e6)
    best = np.argmax(score, axis=1)
    rows = np.arange(n)
    i, j, k = best // 4, (best // 2) % 2, best % 2  # shoulder, elbow, wrist of the branch
    q = np.column_stack([q1[rows, i], q2[rows, i, j], q3[rows, j], q4[rows, i, j, k], q5[rows, i, j, k],
                         np.full(n, q6)])
    q = np.clip(q, lo, hi)
    p_fk, z_fk = _puma_tool(c, q)
    pe = np.linalg.norm(p_fk - p, axis=1)
    re = np.arctan2(np.linalg.norm(np.cross(z_fk, a), axis=1), np.einsum("ij,ij->i", z_fk, a))
    ok = valid[rows, best] & (pe < pos_tol) & (re < rot_tol)
    return IKResult(q=q, success=ok, position_error=pe, rotation_error=re)


# ---------------------------------------------------------------------------------------------
# maneuverability index (MAVAC eq. 3-4)


def _manipulability(robot, q) -> np.ndarray:
    """Yoshikawa manipulability sqrt(det(J J^T)) at the tool frame, (n,)."""
    J = jacobian(robot, q, robot.tool_frame)
    if J.ndim == 2:
        J = J[None]
    return np.sqrt(np.clip(np.linalg.det(J @ J.transpose(0, 2, 1)), 0.0, None))


def estimate_manipulability_max(robot, n_samples: int = 20000, seed: int = 0) -> float:
    """Maximum of sqrt(det(J J^T)) over the joint box, by sampling plus a local random search.

    Sampling ``n_samples`` uniform configurations (seeded), then refining the 16 best by a
    shrinking Gaussian random search; deterministic for a given seed.
    """
    rng = np.random.default_rng(seed)
    lo, hi = robot.q_lower, robot.q_upper
    q = _random_q(robot, rng, n_samples)
    w = _manipulability(robot, q)
    top = np.argsort(w)[-16:]
    q, w = q[top], w[top]
    span = np.minimum(hi - lo, _TWO_PI)
    for sigma in np.geomspace(0.2, 0.002, 60):
        cand = np.clip(q + rng.normal(scale=sigma, size=q.shape) * span, lo, hi)
        wc = _manipulability(robot, cand)
        up = wc > w
        q[up], w[up] = cand[up], wc[up]
    return float(w.max())


def maneuverability(robot, q, k: float | None = None) -> np.ndarray:
    """Maneuverability index ``I_m`` in [0, 1] (MAVAC eq. 3-4, after Vahrenkamp et al. 2012).

    ``I_m = (w / w_max) * J_l`` with ``w = sqrt(det(J J^T))`` the manipulability at the tool
    frame, ``w_max = robot.manipulability_max`` (estimated once per model by
    :func:`estimate_manipulability_max`; the ratio is clipped to 1) and the joint-limit
    penalty (MAVAC eq. 4)
    ``J_l = 1 - exp(-k prod_j (q_j - l_j^-)(l_j^+ - q_j) / (l_j^+ - l_j^-)^2)``.

    Parameters
    ----------
    robot : RobotModel
    q : (nq,) or (n, nq) float, rad
    k : float, optional
        Scale of eq. 4. Each factor of the product is at most 1/4 (joint at mid-range), so the
        product scales as 4^-nq; the default ``k = 3 * 4**nq`` gives ``J_l = 1 - e^-3 = 0.95``
        with every joint at mid-range, independently of nq. (Vahrenkamp's Simox uses k = 50,
        which for 6 joints caps J_l at 0.012 and leaves I_m uninformative.)

    Returns
    -------
    (n,) float in [0, 1] (a float for a single configuration)
    """
    qa, single = _check_q(robot, q)
    k = 3.0 * 4.0 ** robot.nq if k is None else check_positive("k", k)
    lo, hi = robot.q_lower, robot.q_upper
    prod = np.prod(np.clip((qa - lo) * (hi - qa), 0.0, None) / (hi - lo) ** 2, axis=1)
    jl = 1.0 - np.exp(-k * prod)
    w_max = robot.manipulability_max or estimate_manipulability_max(robot)
    im = np.clip(_manipulability(robot, qa) / w_max, 0.0, 1.0) * jl
    return float(im[0]) if single else im

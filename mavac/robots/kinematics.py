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

from ..geometry.transforms import check_transforms
from ..tolerances import IK_POSITION_TOL, IK_ROTATION_TOL
from ..validate import ParameterTypeError, check_array, check_int, check_points, check_positive

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
        Full-pose: angle of ``R_target R^T``; axis IK: angle between the frame axis and the target.
    """

    q: np.ndarray
    success: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray


# ---------------------------------------------------------------------------------------------
# input checks


def _check_robot(robot) -> None:
    # duck-typed: models.py imports this module, so RobotModel cannot be imported here
    if not (hasattr(robot, "model") and hasattr(robot, "tool_frame")):
        raise ParameterTypeError(f"robot must be a mavac RobotModel (mavac.robots.models.load_robot), "
                                 f"got {type(robot).__name__}")


def _check_q(robot, q, name: str = "q") -> tuple[np.ndarray, bool]:
    """``q`` as (n, nq) plus whether a single (nq,) configuration was given."""
    _check_robot(robot)
    a = check_array(name, q, float)
    single = a.ndim == 1
    if single:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != robot.nq:
        raise ValueError(f"{name} must have shape ({robot.nq},) or (n, {robot.nq}), got {np.shape(q)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a, single


def _check_frame(robot, frame) -> str:
    _check_robot(robot)
    frame = robot.tool_frame if frame is None else frame
    if not isinstance(frame, str) or not robot.model.existFrame(frame):
        names = [f.name for f in robot.model.frames]
        raise ValueError(f"frame must be a frame of {robot.name} (one of {names}), got {frame!r}")
    return frame


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
    """Joint placements, axes and q indices from the root to ``frame`` (cached on the robot,
    valid while ``robot.model`` is the same object)."""
    key = ("chain", frame)
    hit = robot._cache.get(key)
    if hit is not None and hit[0] is robot.model:
        return hit[1]
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
    axes = np.array([[Kj[2, 1], Kj[0, 2], Kj[1, 0]] for Kj in K])
    chain = {
        "R_M": np.array(R_M), "p_M": np.array(p_M), "K": np.array(K), "K2": np.array(K2),
        "axis": axes, "idx": np.array(idx, dtype=int),
        # +x/+y/+z axes get closed-form column updates; -1 = general Rodrigues
        "aligned": [int(np.argmax(ax)) if np.isclose(ax.max(), 1.0) else -1 for ax in axes],
        "R_M_is_I": [bool(np.allclose(Rm, np.eye(3), atol=0.0, rtol=0.0)) for Rm in R_M],
        "R_f": f.placement.rotation.copy(), "p_f": f.placement.translation.copy(),
    }
    robot._cache[key] = (m, chain)
    return chain


# Numeric core in structure-of-arrays layout, the batch index last: a rotation is ``C (3, 3, n)``
# with ``C[j]`` its column j as a (3, n) array, a point ``(3, n)``, a Jacobian ``(6, nq, n)``.
# Elementwise work then runs over long contiguous rows and constant products are single GEMMs.


def _cmul(M: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``R @ M`` for stacked rotations ``C`` (3, 3, n) and one matrix M (3, 3) -> (3, 3, n),
    or ``R @ v`` for one vector v (3,) -> (3, n)."""
    flat = C.reshape(3, -1)
    if M.ndim == 2:
        return (M.T @ flat).reshape(C.shape)
    return (M @ flat).reshape(3, C.shape[2])


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product along axis 0 of (3, ...) arrays."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _forward(chain: dict, q: np.ndarray, with_joints: bool = False):
    """Batched FK in SoA layout for ``q`` (n, nq).

    Returns ``C (3, 3, n)`` and ``p (3, n)`` of the frame and, if asked, the joint origins and
    world joint axes ``(k, 3, n)``. Each joint: ``T <- T * placement * exp(theta [axis])``,
    axis-aligned joints by their 2-column update, others by Rodrigues'
    ``exp = I + sin(theta) K + (1 - cos(theta)) K^2``.
    """
    n = q.shape[0]
    qT = q.T[chain["idx"]]
    cos_q, sin_q = np.cos(qT), np.sin(qT)
    C = np.zeros((3, 3, n))
    C[0, 0] = C[1, 1] = C[2, 2] = 1.0
    p = np.zeros((3, n))
    origins, axes = [], []
    for i in range(len(chain["idx"])):
        p = p + _cmul(chain["p_M"][i], C)
        if not chain["R_M_is_I"][i]:
            C = _cmul(chain["R_M"][i], C)
        c, s = cos_q[i], sin_q[i]
        k = chain["aligned"][i]
        if with_joints:
            origins.append(p)
            axes.append(C[k].copy() if k >= 0 else _cmul(chain["axis"][i], C))
        if k >= 0:  # rotation about column k mixes the two others (in place: C is owned here)
            u, v = (k + 1) % 3, (k + 2) % 3
            new_u = c * C[u] + s * C[v]
            C[v] = c * C[v] - s * C[u]
            C[u] = new_u
        else:
            C = C + s * _cmul(chain["K"][i], C) + (1.0 - c) * _cmul(chain["K2"][i], C)
    p = p + _cmul(chain["p_f"], C)
    C = _cmul(chain["R_f"], C)
    if with_joints:
        if not origins:  # frame on the root: no joint moves it
            return C, p, np.zeros((0, 3, n)), np.zeros((0, 3, n))
        return C, p, np.stack(origins), np.stack(axes)
    return C, p


def _jacobian_from(chain, nq, p, origins, axes) -> np.ndarray:
    """LOCAL_WORLD_ALIGNED Jacobian (6, nq, n) from joint origins/axes (k, 3, n) and the
    frame point p (3, n)."""
    J = np.zeros((6, nq, p.shape[1]))
    J[:3, chain["idx"]] = _cross(axes.transpose(1, 0, 2), p[:, None, :] - origins.transpose(1, 0, 2))
    J[3:, chain["idx"]] = axes.transpose(1, 0, 2)
    return J


def _dls_step(J: np.ndarray, e: np.ndarray, damping: float) -> np.ndarray:
    """Damped least squares ``J^T (J J^T + damping I)^-1 e`` for J (6, nq, n), e (6, n).

    The 6x6 SPD system is solved by a Cholesky factorisation written over the batch axis
    (one numpy operation per matrix entry, each over all n rows).
    """
    m = J.shape[0]
    A = np.empty((m, m, J.shape[2]))
    for a in range(m):
        for b in range(a + 1):
            A[a, b] = np.einsum("kn,kn->n", J[a], J[b])
        A[a, a] += damping
    L = np.zeros_like(A)
    for j in range(m):
        d = A[j, j] - np.einsum("kn,kn->n", L[j, :j], L[j, :j])
        L[j, j] = np.sqrt(np.maximum(d, 1e-300))
        for i in range(j + 1, m):
            L[i, j] = (A[i, j] - np.einsum("kn,kn->n", L[i, :j], L[j, :j])) / L[j, j]
    y = np.empty_like(e)
    for i in range(m):
        y[i] = (e[i] - np.einsum("kn,kn->n", L[i, :i], y[:i])) / L[i, i]
    x = np.empty_like(e)
    for i in range(m - 1, -1, -1):
        x[i] = (y[i] - np.einsum("kn,kn->n", L[i + 1 :, i], x[i + 1 :])) / L[i, i]
    return np.einsum("akn,an->kn", J, x)


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
    C, p = _forward(_chain(robot, _check_frame(robot, frame)), qa)
    T = np.zeros((qa.shape[0], 4, 4))
    T[:, :3, :3] = C.transpose(2, 1, 0)
    T[:, :3, 3] = p.T
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
    J = _jacobian_from(chain, robot.nq, p, origins, axes).transpose(2, 0, 1)
    return J[0] if single else J


# ---------------------------------------------------------------------------------------------
# numerical IK (batched damped least squares)


def _axis_residual(C, z_target, k: int = 2):
    """Rotation vector (3, n) turning the frame's axis ``k`` (z by default) onto ``z_target``
    (3, n), and its angle."""
    z = C[k]
    c = _cross(z, z_target)
    s = np.sqrt(np.einsum("in,in->n", c, c))
    ang = np.arctan2(s, np.einsum("in,in->n", z, z_target))
    axis = np.where(s > 1e-12, c / np.maximum(s, 1e-300), C[(k + 1) % 3])  # antiparallel: any normal
    return axis * ang, ang


def _pose_residual(C, C_target):
    """Rotation vector (3, n) of ``R_target R^T`` (base frame) and its angle (n,)."""
    cos = np.clip((np.einsum("jin,jin->n", C_target, C) - 1.0) / 2.0, -1.0, 1.0)
    # vee(E - E^T) = sum_j R[:, j] x R_target[:, j] = 2 sin(theta) axis
    w = _cross(C.transpose(1, 0, 2), C_target.transpose(1, 0, 2)).sum(axis=1)
    sin = 0.5 * np.sqrt(np.einsum("in,in->n", w, w))
    ang = np.arctan2(sin, cos)
    # theta / (2 sin theta), with its series near 0
    rv = w * np.where(sin > 1e-8, ang / np.maximum(2.0 * sin, 1e-300), 0.5 + ang * ang / 12.0)
    near_pi = cos < -0.99  # the skew part is ill-conditioned there: axis from the symmetric part
    if near_pi.any():
        # (E + E^T) / 2 - cos I = (1 - cos) a a^T; take its largest-diagonal column
        E = np.einsum("jkn,jln->nkl", C_target[:, :, near_pi], C[:, :, near_pi])
        c_pi = cos[near_pi]
        S = 0.5 * (E + E.transpose(0, 2, 1)) - c_pi[:, None, None] * np.eye(3)
        k = np.argmax(np.diagonal(S, axis1=1, axis2=2), axis=1)
        rows = np.arange(k.size)
        a = S[rows, :, k] / np.sqrt(np.maximum(S[rows, k, k] * (1.0 - c_pi), 1e-300))[:, None]
        a *= np.where(np.einsum("ni,in->n", a, w[:, near_pi]) < 0.0, -1.0, 1.0)[:, None]
        rv[:, near_pi] = (a * ang[near_pi, None]).T
    return rv, ang


def _seed_box(robot) -> tuple[np.ndarray, np.ndarray]:
    """Box for random seeds: the joint limits, one turn at most (configurations repeat with
    period 2 pi, so +-2 pi limits need no wider seeds)."""
    return np.maximum(robot.q_lower, -np.pi), np.minimum(robot.q_upper, np.pi)


def _random_q(robot, rng, n) -> np.ndarray:
    lo, hi = _seed_box(robot)
    return rng.uniform(lo, hi, size=(n, robot.nq))


_STALL_ITERS = 12  # an attempt whose residual has not dropped by 1 % in this many iterations is stuck
_WIDE_BELOW = 512  # fewer rows than this: the loop is overhead-bound, run restarts side by side


def _check_solver_options(max_iter, n_restarts, pos_tol, rot_tol, damping, max_step) -> None:
    check_int("max_iter", max_iter, 1)
    check_int("n_restarts", n_restarts, 0)
    check_positive("pos_tol", pos_tol)
    check_positive("rot_tol", rot_tol)
    check_positive("damping", damping)
    check_positive("max_step", max_step)


def _limited_step(dq: np.ndarray, max_step: float) -> np.ndarray:
    """``dq`` (n, nq) scaled row by row so no joint moves more than ``max_step`` (in place)."""
    big = np.max(np.abs(dq), axis=1)
    dq *= np.minimum(1.0, max_step / np.maximum(big, 1e-300))[:, None]
    return dq


def _restarts(rt, ended, step, solved, left, wide):
    """Targets of the fresh rows of the next iteration, and whether rows now run side by side.

    Ended rows take a restart of their target while it has some left (in row order); when few
    rows remain, waiting targets start their remaining restarts side by side (``left`` is
    decremented in place).
    """
    e_rows = np.flatnonzero(ended)
    e_sorted = e_rows[np.argsort(rt[e_rows], kind="stable")]
    e_t = rt[e_sorted]
    t_u, t_first, t_count = np.unique(e_t, return_index=True, return_counts=True)
    rank = np.arange(e_t.size) - np.repeat(t_first, t_count)
    reseed_rows = e_sorted[rank < left[e_t]]
    left[t_u] -= np.minimum(t_count, left[t_u])
    new_t = [rt[reseed_rows]]
    n_next = int(step.sum()) + reseed_rows.size
    waiting = np.flatnonzero(~solved & (left > 0))
    if 0 < n_next < _WIDE_BELOW and waiting.size:
        extra = np.minimum(left[waiting], (_WIDE_BELOW - n_next) // waiting.size)
        new_t.append(np.repeat(waiting, extra))
        left[waiting] -= extra
        wide = True
    return np.concatenate(new_t), wide


def _residuals(C, p, p_tT, rot_tT, rows, mode: str, frame_axis: int):
    """Position error (3, n), rotation vector (3, n) and angle (n,) of each row against its target."""
    e_p = np.take(p_tT, rows, axis=1) - p
    if mode == "axis":
        e_r, ang = _axis_residual(C, np.take(rot_tT, rows, axis=1), frame_axis)
    else:
        e_r, ang = _pose_residual(C, np.take(rot_tT, rows, axis=2))
    return e_p, e_r, ang


def _solve_batched(robot, frame, p_t, rot_t, mode, q0, rng, max_iter, n_restarts, pos_tol, rot_tol, damping, max_step,
                   frame_axis: int = 2):
    """Batched damped-least-squares Newton iterations with in-loop random restarts.

    Rows (attempts) are iterated together, each row working for one target. Every target starts
    with one row at ``q0``. An attempt ends when it converges, after ``max_iter`` iterations, or
    when stuck (no 1 % progress of ``|e_p| + 0.1 |e_r|`` in ``_STALL_ITERS`` iterations: local
    minimum or joint limit); its target then gets a fresh uniform seed while it has restarts
    left (``n_restarts`` per target). When fewer than ``_WIDE_BELOW`` rows remain, a target's
    remaining restarts are started side by side instead of one after the other, which costs
    almost nothing in that overhead-bound regime and shortens the tail. A target is solved by
    its first converged row; per target the best attempt is kept.
    """
    _check_solver_options(max_iter, n_restarts, pos_tol, rot_tol, damping, max_step)
    rng = np.random.default_rng(0) if rng is None else rng
    chain = _chain(robot, frame)
    lo, hi = robot.q_lower, robot.q_upper
    seed_lo, seed_hi = _seed_box(robot)
    n = p_t.shape[0]
    p_tT = np.ascontiguousarray(p_t.T)
    rot_tT = np.ascontiguousarray(rot_t.transpose(2, 1, 0) if mode == "pose" else rot_t.T)
    # per target
    q_best = _check_q0(robot, q0, n)
    pe_best = np.full(n, np.inf)
    re_best = np.full(n, np.inf)
    best_metric = np.full(n, np.inf)
    left = np.full(n, n_restarts)
    solved = np.zeros(n, dtype=bool)
    # per row
    rq = q_best.copy()
    rt = np.arange(n)
    r_iters = np.zeros(n, dtype=int)
    r_since = np.zeros(n, dtype=int)
    r_best = np.full(n, np.inf)
    wide = False  # True once a target may have several rows
    while rt.size:
        C, p, origins, axes = _forward(chain, rq, with_joints=True)
        e_p, e_r, ang = _residuals(C, p, p_tT, rot_tT, rt, mode, frame_axis)
        pe = np.sqrt(np.einsum("in,in->n", e_p, e_p))
        metric = pe + 0.1 * ang
        converged = (pe < pos_tol) & (ang < rot_tol)
        progress = metric < 0.99 * r_best
        r_best = np.where(progress, metric, r_best)
        r_since = np.where(progress, 0, r_since + 1)
        ended = ~converged & ((r_since >= _STALL_ITERS) | (r_iters >= max_iter))
        # a finished attempt (converged or ended) is recorded if it beats its target's best
        fin = np.flatnonzero(converged | ended)
        if fin.size:
            if wide:  # several rows per target: the best finished row of each
                fin = fin[np.lexsort((metric[fin], rt[fin]))]
                fin = fin[np.unique(rt[fin], return_index=True)[1]]
            t_f = rt[fin]
            up = metric[fin] < best_metric[t_f]
            t_up, r_up = t_f[up], fin[up]
            q_best[t_up], pe_best[t_up], re_best[t_up], best_metric[t_up] = rq[r_up], pe[r_up], ang[r_up], metric[r_up]
            solved[rt[converged]] = True
        alive = ~solved[rt]  # drops the sibling rows of solved targets
        ended &= alive
        step = alive & ~ended & ~converged
        new_t, wide = _restarts(rt, ended, step, solved, left, wide)
        q_step = rq[step]
        if step.any():
            J = _jacobian_from(chain, robot.nq, p[:, step], origins[:, :, step], axes[:, :, step])
            if mode == "axis":
                # The spin about the aligned axis is free: project it out of the angular rows.
                z = C[frame_axis][:, step]
                J[3:] -= z[:, None, :] * np.einsum("in,ikn->kn", z, J[3:])[None]
            e = np.concatenate([e_p[:, step], e_r[:, step]], axis=0)
            q_step = np.clip(q_step + _limited_step(_dls_step(J, e, damping).T, max_step), lo, hi)
        m_new = new_t.size
        rq = np.concatenate([q_step, rng.uniform(seed_lo, seed_hi, size=(m_new, robot.nq))])
        rt = np.concatenate([rt[step], new_t])
        r_iters = np.concatenate([r_iters[step] + 1, np.zeros(m_new, dtype=int)])
        r_since = np.concatenate([r_since[step], np.zeros(m_new, dtype=int)])
        r_best = np.concatenate([r_best[step], np.full(m_new, np.inf)])
    ok = (pe_best < pos_tol) & (re_best < rot_tol)
    return IKResult(q=q_best, success=ok, position_error=pe_best, rotation_error=re_best)


def ik(
    robot, base_T_target, *, frame: str | None = None, q0=None, rng: np.random.Generator | None = None,
    max_iter: int = 50, n_restarts: int = 12, pos_tol: float = IK_POSITION_TOL, rot_tol: float = IK_ROTATION_TOL,
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
        Extra random attempts per target (an attempt ends converged, after ``max_iter``
        iterations, or stalled: no 1 % progress in 12 iterations).
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
    T = check_transforms("base_T_target", base_T_target)
    R = T[:, :3, :3]
    frame = _check_frame(robot, frame)
    return _solve_batched(robot, frame, T[:, :3, 3].copy(), R.copy(), "pose", q0, rng,
                          max_iter, n_restarts, pos_tol, rot_tol, damping, max_step)


def ik_axis(
    robot, positions, axes, *, frame: str | None = None, q0=None, rng: np.random.Generator | None = None,
    method: str = "auto", max_iter: int = 50, n_restarts: int = 12, pos_tol: float = IK_POSITION_TOL,
    rot_tol: float = IK_ROTATION_TOL, damping: float = 1e-6, max_step: float = 1.0, frame_axis: int = 2,
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
        Seed for DLS; for the closed form, the valid branch nearest to ``q0`` is returned
        (without ``q0``: the valid branch farthest from the joint limits).
    method : {"auto", "closed_form", "dls"}
        ``"auto"`` uses the closed form when the model has a Puma-type DH table and ``frame``
        lies on the flange axis, DLS otherwise. The closed form enumerates all 8 branches
        (shoulder, elbow, wrist flip) and sets the free joint 6 to 0.
    max_iter, n_restarts, pos_tol, rot_tol, damping, max_step, rng
        As in :func:`ik` (DLS only; ``pos_tol``/``rot_tol`` also decide closed-form success).
    frame_axis : {0, 1, 2}
        Which axis of ``frame`` goes along ``axes`` (default 2 = z, the tool axis). E.g.
        ``frame="camera", frame_axis=0`` points the MAVAC camera's optical (x) axis. The
        closed form needs 2.

    Returns
    -------
    IKResult
    """
    p = check_points("positions", positions)
    a = check_points("axes", axes)
    if p.shape[0] != a.shape[0]:
        raise ValueError(f"positions and axes must have the same length, got {p.shape[0]} and {a.shape[0]}")
    norm = np.linalg.norm(a, axis=1)
    if np.any(norm < 1e-12):
        raise ValueError("axes must be non-zero vectors")
    a = a / norm[:, None]
    frame = _check_frame(robot, frame)
    check_positive("pos_tol", pos_tol)
    check_positive("rot_tol", rot_tol)
    if method not in ("auto", "closed_form", "dls"):
        raise ValueError(f"method must be 'auto', 'closed_form' or 'dls', got {method!r}")
    frame_axis = check_int("frame_axis", frame_axis, 0, 2)
    closed = puma_dh_constants(robot, frame) if frame_axis == 2 else None
    if method == "closed_form" and closed is None:
        raise ValueError(
            f"method='closed_form' needs a Puma-type DH robot and a flange-axis frame, got {robot.name}/{frame}"
        )
    if method != "dls" and closed is not None:
        q0a = None if q0 is None else _check_q0(robot, q0, p.shape[0])
        return _puma_ik_axis(closed, robot.q_lower, robot.q_upper, p, a, q0a, pos_tol, rot_tol)
    return _solve_batched(robot, frame, p, a, "axis", q0, rng,
                          max_iter, n_restarts, pos_tol, rot_tol, damping, max_step, frame_axis)


# ---------------------------------------------------------------------------------------------
# closed-form axis IK for Puma-type arms (standard DH, spherical wrist)

# alpha pattern of the Puma 560 in standard DH (Corke, mdl_puma560)
_PUMA_ALPHA = np.array([np.pi / 2, 0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, 0.0])


def is_puma_dh(dh) -> bool:
    """Whether a standard DH table ``(a, d, alpha)`` (6, 3) is Puma-type: the Puma 560's alpha
    pattern, a spherical wrist (``a4 = a5 = a6 = d5 = 0``) and ``a1 = 0``."""
    if dh is None or np.shape(dh) != (6, 3) or not np.allclose(dh[:, 2], _PUMA_ALPHA):
        return False
    a, d = dh[:, 0], dh[:, 1]
    return bool(a[0] == 0 and a[3] == 0 and a[4] == 0 and a[5] == 0 and d[4] == 0)


def puma_dh_constants(robot, frame: str) -> dict | None:
    """Constants of the closed-form axis IK for ``frame``, or None when it does not apply.

    Applies when ``robot.dh`` :func:`is_puma_dh` and ``frame`` sits on the flange axis (z6)
    with its z along it. Keys (m): ``d1, a2, d_off (= d2 + d3), a3, d4`` and ``reach``, the
    distance from the wrist centre to the frame origin along z6.
    """
    dh = getattr(robot, "dh", None)
    if not is_puma_dh(dh):
        return None
    a, d = dh[:, 0], dh[:, 1]
    chain = _chain(robot, frame)
    if len(chain["idx"]) != 6 or not np.allclose(chain["p_f"][:2], 0.0):
        return None
    # The frame must keep z6 as its z axis (any spin about it is fine).
    if not np.allclose(chain["R_f"][:, 2], [0.0, 0.0, 1.0]):
        return None
    # "reach": wrist centre (joint 6 origin) to the frame origin along z6 (d6 + tool length,
    # both in the frame placement on joint 6)
    return {"d1": d[0], "a2": a[1], "d_off": d[1] + d[2], "a3": a[2], "d4": d[3], "reach": chain["p_f"][2]}


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


def _wrap_into(theta, lo: float, hi: float, principal: bool = False):
    """Equivalent of ``theta`` (mod 2 pi) with the largest normalised joint-limit margin.

    Returns the angle and its margin ``min(t - lo, hi - t) / (hi - lo)`` (< 0 when no
    equivalent angle lies within [lo, hi]). ``principal``: theta is already in [-pi, pi].
    """
    t = theta if principal else theta - _TWO_PI * np.round(theta / _TWO_PI)
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


def _concatenate_results(parts) -> IKResult:
    """One IKResult from the results of consecutive blocks of targets."""
    return IKResult(*(np.concatenate([getattr(r, f) for r in parts]) for f in
                      ("q", "success", "position_error", "rotation_error")))


def _puma_ik_axis(c, lo, hi, p, a, q0, pos_tol, rot_tol):
    """Closed-form axis IK, 8 branches (shoulder x elbow x wrist flip), vectorised by blocks.

    Branch arrays are kept at their natural shapes ``(n, shoulder, elbow, wrist)`` and only
    broadcast when scored, so each angle is computed and wrapped once.
    """
    n = p.shape[0]
    if n > _CHUNK:
        return _concatenate_results([_puma_ik_axis(c, lo, hi, p[i : i + _CHUNK], a[i : i + _CHUNK],
                                                   None if q0 is None else q0[i : i + _CHUNK], pos_tol, rot_tol)
                                     for i in range(0, n, _CHUNK)])
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
    # (n, 2, 2, 2) with the wrist flip (q4 + pi, -q5); all in [-pi, pi]
    q4 = np.stack([q4, np.where(q4 > 0.0, q4 - np.pi, q4 + np.pi)], axis=3)
    q5 = np.stack([q5, -q5], axis=3)
    q6 = min(max(0.0, lo[5]), hi[5])  # free spin about the tool axis: closest to 0
    # wrap each joint once at its own shape, then score the 8 branches by broadcasting
    q1, m1 = _wrap_into(q1, lo[0], hi[0])
    q2, m2 = _wrap_into(q2, lo[1], hi[1])
    q3, m3 = _wrap_into(q3, lo[2], hi[2])
    q4, m4 = _wrap_into(q4, lo[3], hi[3], principal=True)
    q5, m5 = _wrap_into(q5, lo[4], hi[4], principal=True)
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


def estimate_manipulability_max(robot, *, n_samples: int = 20000, seed: int = 0) -> float:
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


#: Scale ``k`` of MAVAC eq. 4. The MAVAC paper gives no value; eq. 4 is the joint-limit
#: penalization of Vahrenkamp et al. 2012 ("Manipulability analysis", MAVAC's ref. 26, after
#: Tsai 1999), and 50 is the default of Simox, Vahrenkamp's open-source library that implements
#: it (``PoseQualityManipulability::penalizeJointLimits(bool enable, float k = 50.0f)``). Each
#: factor of the product is at most 1/4 (joint at mid-range), so for 6 joints ``J_l`` stays
#: below ``1 - exp(-50 / 4**6) = 0.012`` and is nearly proportional to the product; eq. 3's
#: greedy threshold is relative (P_g x the first maximum), so that scale does not change any
#: selection, only the spread between configurations does.
JOINT_LIMIT_K = 50.0


def _manipulability_max(robot) -> float:
    w_max = robot.manipulability_max
    if w_max is None:  # hand-made model: estimate once and keep it with the model's caches
        hit = robot._cache.get("manipulability_max")
        if hit is None or hit[0] is not robot.model:
            hit = robot._cache["manipulability_max"] = (robot.model, estimate_manipulability_max(robot))
        w_max = hit[1]
    return w_max


def manipulability_ratio(robot, q) -> np.ndarray:
    """Distance from singular configurations: ``w / w_max`` in [0, 1], the first factor of I_m.

    ``w = sqrt(det(J J^T))`` is Yoshikawa's manipulability at the tool frame and ``w_max =
    robot.manipulability_max`` (estimated once per model by :func:`estimate_manipulability_max`);
    the ratio is clipped to 1.

    Parameters
    ----------
    robot : RobotModel
    q : (nq,) or (n, nq) float, rad

    Returns
    -------
    (n,) float in [0, 1] (a float for a single configuration)
    """
    qa, single = _check_q(robot, q)
    ratio = np.clip(_manipulability(robot, qa) / _manipulability_max(robot), 0.0, 1.0)
    return float(ratio[0]) if single else ratio


def joint_limit_penalty(robot, q, *, k: float = JOINT_LIMIT_K) -> np.ndarray:
    """Distance to the joint limits, MAVAC eq. 4:
    ``J_l = 1 - exp(-k prod_j (q_j - l_j^-)(l_j^+ - q_j) / (l_j^+ - l_j^-)^2)``.

    Parameters
    ----------
    robot : RobotModel
    q : (nq,) or (n, nq) float, rad
    k : float, > 0
        Scale factor; default :data:`JOINT_LIMIT_K` (Simox's 50, see there).

    Returns
    -------
    (n,) float in [0, 1 - exp(-k / 4**nq)] (a float for a single configuration)
    """
    qa, single = _check_q(robot, q)
    check_positive("k", k)
    lo, hi = robot.q_lower, robot.q_upper
    prod = np.prod(np.clip((qa - lo) * (hi - qa), 0.0, None) / (hi - lo) ** 2, axis=1)
    jl = 1.0 - np.exp(-float(k) * prod)
    return float(jl[0]) if single else jl


def maneuverability(robot, q, k: float = JOINT_LIMIT_K) -> np.ndarray:
    """Maneuverability index ``I_m`` (MAVAC eq. 3-4, after Vahrenkamp et al. 2012): the product
    of the distance from singular configurations and the distance to the joint limits,
    ``I_m = manipulability_ratio(q) * joint_limit_penalty(q, k)``.

    Parameters
    ----------
    robot : RobotModel
    q : (nq,) or (n, nq) float, rad
    k : float, > 0
        Scale of eq. 4; default :data:`JOINT_LIMIT_K` = 50 (Simox, Vahrenkamp's implementation).
        ``k`` scales I_m down for many joints (6 joints: I_m <= 0.012), which leaves eq. 3's
        relative threshold unchanged; a large ``k`` (e.g. ``3 * 4**nq``, J_l = 0.95 with every
        joint at mid-range) saturates J_l instead, so it ranks configurations almost by the
        manipulability ratio alone.

    Returns
    -------
    (n,) float in [0, 1] (a float for a single configuration); 0 at a singularity or a limit
    """
    qa, single = _check_q(robot, q)
    im = manipulability_ratio(robot, qa) * joint_limit_penalty(robot, qa, k=k)
    return float(im[0]) if single else im

"""Batched IK (mavac.robots.kinematics) vs one-target-at-a-time pinocchio DLS, side by side.

Both solve the same full-pose targets of the UR10 tool tip (FK of random configurations) with
the same algorithm and settings: damped least squares (lambda^2 = 1e-6), steps capped at
1 rad, joint-limit clipping, an attempt abandoned after 50 iterations or 12 iterations without
1 % progress, first seed ``q_home`` then up to 8 random restarts, tolerances 1e-5 m / 1e-4 rad.
The reference is the classic pinocchio loop (``framesForwardKinematics`` +
``computeFrameJacobian`` + a 6x6 solve per iteration, per target). Also prints the throughput
of the closed-form Puma 560 axis IK.

Rates are targets per second of CPU time of this process (``time.process_time``), best of
``REPEATS`` identical runs (as ``timeit`` does): the machine is shared, and wall-clock rates of
two runs taken at different moments are not comparable. Wall-clock times of the best runs are
printed alongside. Prints ``RATIO batched_ik_vs_pinocchio_dls <x>`` last.

Run: ``.venv/bin/python benchmarks/bench_ik.py [n_targets] [n_reference]``
"""

from __future__ import annotations

import sys
import time

import numpy as np
import pinocchio as pin

from mavac.robots import kinematics as K
from mavac.robots.models import puma560, ur10_mobile

MAX_ITER, N_RESTARTS, POS_TOL, ROT_TOL, DAMPING, MAX_STEP = 50, 8, 1e-5, 1e-4, 1e-6, 1.0
REPEATS = 3


def pinocchio_dls(robot, oMdes: pin.SE3, q0: np.ndarray, rng: np.random.Generator):
    """One target: pinocchio FK + Jacobian per iteration, same DLS as the batched solver."""
    model, data = robot.model, robot.model.createData()
    fid = model.getFrameId(robot.tool_frame)
    lo, hi = robot.q_lower, robot.q_upper
    seeds = [q0] + [rng.uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi)) for _ in range(N_RESTARTS)]
    for q in seeds:
        q = q.copy()
        best, since = np.inf, 0
        for _ in range(MAX_ITER + 1):
            pin.framesForwardKinematics(model, data, q)
            oMf = data.oMf[fid]
            e_p = oMdes.translation - oMf.translation
            e_r = pin.log3(oMdes.rotation @ oMf.rotation.T)
            pe, re = np.linalg.norm(e_p), np.linalg.norm(e_r)
            if pe < POS_TOL and re < ROT_TOL:
                return q, True
            since = 0 if pe + 0.1 * re < 0.99 * best else since + 1
            best = min(best, pe + 0.1 * re)
            if since >= K._STALL_ITERS:
                break
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
            dq = J.T @ np.linalg.solve(J @ J.T + DAMPING * np.eye(6), np.concatenate([e_p, e_r]))
            dq *= min(1.0, MAX_STEP / max(np.abs(dq).max(), 1e-300))
            q = np.clip(q + dq, lo, hi)
    return q, False


def _reference(robot, targets):
    rng = np.random.default_rng(1)
    return [pinocchio_dls(robot, pin.SE3(T), robot.q_home, rng)[1] for T in targets]


def timed(fn):
    """``(result, cpu_s, wall_s)`` of the fastest (CPU) of ``REPEATS`` runs of ``fn``."""
    best = None
    for _ in range(REPEATS):
        c0, w0 = time.process_time(), time.perf_counter()
        out = fn()
        run = (out, time.process_time() - c0, time.perf_counter() - w0)
        best = run if best is None or run[1] < best[1] else best
    return best


def main(n_targets: int = 10000, n_reference: int = 1000) -> float:
    robot = ur10_mobile()
    rng = np.random.default_rng(0)
    targets = K.fk(robot, rng.uniform(-np.pi, np.pi, (n_targets, robot.nq)))

    res, cpu_b, wall_b = timed(lambda: K.ik(
        robot, targets, rng=np.random.default_rng(1), max_iter=MAX_ITER, n_restarts=N_RESTARTS,
        pos_tol=POS_TOL, rot_tol=ROT_TOL, damping=DAMPING, max_step=MAX_STEP))
    ok_ref, cpu_r, wall_r = timed(lambda: _reference(robot, targets[:n_reference]))

    puma = puma560(tool_length=0.1)
    qp = rng.uniform(puma.q_lower, puma.q_upper, (1_000_000, 6))
    Tp = K.fk(puma, qp)
    pos, ax = Tp[:, :3, 3] + rng.normal(scale=0.2, size=(len(qp), 3)), Tp[:, :3, 2]
    cf, cpu_c, wall_c = timed(lambda: K.ik_axis(puma, pos, ax))

    rate_b, rate_r = n_targets / cpu_b, n_reference / cpu_r
    print(f"UR10 full-pose IK, batched, {n_targets} targets: {rate_b:,.0f} targets/s CPU "
          f"({cpu_b:.2f} s CPU, {wall_b:.2f} s wall), success {res.success.mean():.4f}")
    print(f"UR10 full-pose IK, pinocchio DLS one at a time, first {n_reference} of the same targets: "
          f"{rate_r:,.0f} targets/s CPU ({cpu_r:.2f} s CPU, {wall_r:.2f} s wall), success {np.mean(ok_ref):.4f}")
    print(f"Puma 560 closed-form axis IK: {len(qp) / cpu_c:,.0f} queries/s CPU ({len(qp)} queries, "
          f"{cpu_c:.2f} s CPU, {wall_c:.2f} s wall), reachable {cf.success.mean():.3f}")
    ratio = rate_b / rate_r
    print(f"RATIO batched_ik_vs_pinocchio_dls {ratio:.1f}")
    return ratio


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))

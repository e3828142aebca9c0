"""Kabir's two-arm cell: wall time of the whole simulated bowl run, and the 7-DOF reach-test IK.

1. ``SECONDS bimanual_bowl <x>``: wall time of :func:`mavac.scrubbing.run.run_part`
   on the bowl at paper scale (plan, hold, scrub, look, re-plan) with the paper's operating
   parameters (the learner is not part of it), on this machine.
2. ``RATIO iiwa_batched_ik_vs_per_point <x>``: the reach test's position + axis IK of the iiwa
   pad (spin about the axis free), batched (:func:`mavac.robots.kinematics.ik_axis`, DLS) vs
   one target at a time with pinocchio (``framesForwardKinematics`` + ``computeFrameJacobian``
   + a 6x6 solve per iteration), the same algorithm and settings: damped least squares
   (lambda^2 = 1e-6), steps capped at 1 rad, joint-limit clipping, an attempt abandoned after 50
   iterations or 12 without 1 % progress, seed ``q_home`` then up to 8 random restarts,
   tolerances 1e-5 m / 1e-4 rad. Targets: pad poses of random configurations. Rates are targets
   per CPU second, best of 3 runs (the machine is shared).

Run: ``.venv/bin/python benchmarks/bench_bimanual.py [--ik-only]``. Prints the RATIO line last.
"""

from __future__ import annotations

import sys
import time

import numpy as np
import pinocchio as pin

from mavac.params import BimanualCellParams
from mavac.robots import kinematics as K
from mavac.scrubbing.cell import cell_robots

from bench_ik import timed  # benchmarks run as scripts: their folder is on sys.path

MAX_ITER, N_RESTARTS, POS_TOL, ROT_TOL, DAMPING, MAX_STEP = 50, 8, 1e-5, 1e-4, 1e-6, 1.0


def pinocchio_axis_dls(robot, p_t, z_t, q0, rng):
    """One position + axis target with pinocchio, the batched solver's algorithm."""
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
            z = oMf.rotation[:, 2]
            e_p = p_t - oMf.translation
            c = np.cross(z, z_t)
            s = np.linalg.norm(c)
            ang = np.arctan2(s, z @ z_t)
            e_r = c / s * ang if s > 1e-12 else oMf.rotation[:, 0] * ang
            pe = np.linalg.norm(e_p)
            if pe < POS_TOL and ang < ROT_TOL:
                return q, True
            since = 0 if pe + 0.1 * ang < 0.99 * best else since + 1
            best = min(best, pe + 0.1 * ang)
            if since >= K._STALL_ITERS:
                break
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED).copy()
            J[3:] -= np.outer(z, z @ J[3:])  # spin about the tool axis is free
            dq = J.T @ np.linalg.solve(J @ J.T + DAMPING * np.eye(6), np.concatenate([e_p, e_r]))
            dq *= min(1.0, MAX_STEP / max(np.abs(dq).max(), 1e-300))
            q = np.clip(q + dq, lo, hi)
    return q, False


def ik_ratio(n_targets: int = 5000, n_reference: int = 300) -> float:
    """Batched vs per-point axis IK of the iiwa pad; prints both rates, returns the ratio."""
    cleaner, _ = cell_robots(BimanualCellParams())
    rng = np.random.default_rng(0)
    T = K.fk(cleaner, rng.uniform(cleaner.q_lower, cleaner.q_upper, (n_targets, cleaner.nq)))
    p, a = T[:, :3, 3], T[:, :3, 2]
    res, cpu_b, wall_b = timed(lambda: K.ik_axis(
        cleaner, p, a, method="dls", rng=np.random.default_rng(1), max_iter=MAX_ITER, n_restarts=N_RESTARTS,
        pos_tol=POS_TOL, rot_tol=ROT_TOL, damping=DAMPING, max_step=MAX_STEP))

    def reference():
        r = np.random.default_rng(1)
        return [pinocchio_axis_dls(cleaner, p[i], a[i], cleaner.q_home, r)[1] for i in range(n_reference)]

    ok_ref, cpu_r, wall_r = timed(reference)
    rate_b, rate_r = n_targets / cpu_b, n_reference / cpu_r
    print(f"iiwa pad axis IK, batched, {n_targets} targets: {rate_b:,.0f} targets/s CPU "
          f"({cpu_b:.2f} s CPU, {wall_b:.2f} s wall), success {res.success.mean():.4f}")
    print(f"iiwa pad axis IK, pinocchio DLS one at a time, first {n_reference} targets: {rate_r:,.0f} targets/s CPU "
          f"({cpu_r:.2f} s CPU, {wall_r:.2f} s wall), success {np.mean(ok_ref):.4f}")
    return rate_b / rate_r


def bowl_seconds() -> float:
    """Wall time of the whole simulated bowl run at paper scale."""
    from mavac.scrubbing.run import run_part

    t0 = time.perf_counter()
    run_part("bowl", fast=False)
    return time.perf_counter() - t0


def main(ik_only: bool = False) -> float:
    if not ik_only:
        print(f"SECONDS bimanual_bowl {bowl_seconds():.1f}")
    ratio = ik_ratio()
    print(f"RATIO iiwa_batched_ik_vs_per_point {ratio:.1f}")
    return ratio


if __name__ == "__main__":
    main(ik_only="--ik-only" in sys.argv[1:])

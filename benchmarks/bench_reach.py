"""Kabir reach test: batched closed-form reach test vs per-point pinocchio DLS, same targets.

Prints vertex-IK queries per second of both, ending with

    RATIO reach_test_vs_per_point_dls <x>
    SECONDS baseline_sweep <t>

Queries: one (setup, vertex target) pair is one query, as in the paper's count (every vertex
of every patch for every setup). The batched reach test answers all k x t pairs of k setups;
its rate is k x t over its wall time (it rejects far targets by an exact reach sphere and skips
the other vertices of a patch once one fails, which is part of what is measured). The baseline
solves each pair alone with pinocchio: damped least squares on position + tool axis, 100
iterations from the robot's home pose and up to 2 random restarts (tolerances 1e-5 m, 1e-4
rad, as ``mavac.robots.kinematics.ik_axis``), on a random sample of the same pairs.
The sweep is the full 16,317-setup uniform grid for the concave bowl on ``--jobs`` workers
(default 2), without the disk cache.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pinocchio as pin

from mavac.geometry.parts import load_part
from mavac.params import ReachParams, SetupSpaceParams
from mavac.robots.models import puma560
from mavac.setups.reach import PartReach, base_T_part, patch_reach, reach_sweep, reach_targets_from_part
from mavac.setups.sampling import uniform_setups


def dls_axis(model, data, frame_id, p_t, z_t, q0, lower, upper, max_iter=100, damping=1e-6,
             pos_tol=1e-5, rot_tol=1e-4, max_step=0.5):
    """One target: position + tool-axis IK by damped least squares (pinocchio FK/Jacobian)."""
    q = q0.copy()
    for _ in range(max_iter):
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacement(model, data, frame_id)
        M = data.oMf[frame_id]
        e_p = p_t - M.translation
        z = M.rotation[:, 2]
        e_r = np.cross(z, z_t)
        if np.linalg.norm(e_p) < pos_tol and np.arccos(np.clip(z @ z_t, -1, 1)) < rot_tol:
            return True
        J = pin.computeFrameJacobian(model, data, q, frame_id, pin.LOCAL_WORLD_ALIGNED)
        e = np.concatenate([e_p, e_r])
        dq = J.T @ np.linalg.solve(J @ J.T + damping * np.eye(6), e)
        n = np.linalg.norm(dq)
        if n > max_step:
            dq *= max_step / n
        q = np.clip(q + dq, lower, upper)
    return False


def per_point_dls(robot, pos, ax, rng, restarts=2):
    model, data = robot.model, robot.model.createData()
    fid = model.getFrameId(robot.tool_frame)
    ok = np.zeros(len(pos), dtype=bool)
    for i in range(len(pos)):
        seeds = [robot.q_home] + [rng.uniform(robot.q_lower, robot.q_upper) for _ in range(restarts)]
        ok[i] = any(dls_axis(model, data, fid, pos[i], ax[i], s, robot.q_lower, robot.q_upper) for s in seeds)
    return ok


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--setups", type=int, default=64, help="setups for the rate comparison")
    ap.add_argument("--dls-points", type=int, default=300, help="pairs solved by per-point DLS")
    ap.add_argument("--jobs", type=int, default=2, help="workers of the baseline sweep")
    ap.add_argument("--no-sweep", action="store_true", help="skip the 16,317-setup sweep")
    args = ap.parse_args()

    space, params = SetupSpaceParams(), ReachParams()
    robot = puma560(tool_length=params.tool_length)
    part = load_part("concave_bowl")
    targets = reach_targets_from_part(part)
    grid = uniform_setups(space)
    rng = np.random.default_rng(0)
    setups = grid[rng.choice(len(grid), args.setups, replace=False)]
    queries = len(setups) * targets.n_targets
    print(f"concave bowl: {targets.n_patches} patches, {targets.n_targets} (vertex, normal) targets, "
          f"{len(setups)} setups -> {queries} vertex queries")

    patch_reach(robot, targets, setups[:2], space, params=params)  # warm-up
    t0 = time.perf_counter()
    cover = patch_reach(robot, targets, setups, space, params=params)
    batched = time.perf_counter() - t0
    rate_batched = queries / batched
    print(f"batched reach test: {batched:.3f} s, {rate_batched:,.0f} vertex queries/s, "
          f"{cover.mean():.3f} of patch-setup pairs reachable")

    T = base_T_part(setups, space)
    pos = np.einsum("kij,tj->kti", T[:, :3, :3], targets.positions) + T[:, None, :3, 3]
    ax = np.einsum("kij,tj->kti", T[:, :3, :3], targets.axes)
    pick = rng.choice(queries, args.dls_points, replace=False)
    p_s, a_s = pos.reshape(-1, 3)[pick], ax.reshape(-1, 3)[pick]
    t0 = time.perf_counter()
    ok = per_point_dls(robot, p_s, a_s, np.random.default_rng(1))
    dls = time.perf_counter() - t0
    rate_dls = len(pick) / dls
    from mavac.robots.kinematics import ik_axis

    closed = ik_axis(robot, p_s, a_s).success
    print(f"per-point pinocchio DLS: {dls:.3f} s for {len(pick)} queries, {rate_dls:,.0f} queries/s; "
          f"agreement with the closed form {np.mean(ok == closed):.3f} "
          f"(DLS-only successes {int(np.sum(ok & ~closed))})")
    print(f"RATIO reach_test_vs_per_point_dls {rate_batched / rate_dls:.1f}")

    if not args.no_sweep:
        reach = PartReach(robot, targets, space, params=params)
        t0 = time.perf_counter()
        full = reach_sweep(reach, grid, n_jobs=args.jobs)
        sweep = time.perf_counter() - t0
        print(f"baseline sweep: {len(grid)} setups x {targets.n_targets} targets on {args.jobs} workers, "
              f"{full.any(axis=0).sum()} of {targets.n_patches} patches coverable")
        print(f"SECONDS baseline_sweep {sweep:.1f}")


if __name__ == "__main__":
    main()

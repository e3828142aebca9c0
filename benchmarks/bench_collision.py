"""The arm's collision checker on the calls of a real trial: every ``is_free`` call of one
paper-scale online trial (``bench_online.py``'s: test bench, paper reading, HPR offline, seed
1) is recorded (base pose, q, answer), then replayed, side by side in one process, through

* ``reference``: the checker as it was before its speed-ups: every pair (base-fixed pairs
  included) in construction order, the meshes as pinocchio loads them (OBBRSS hierarchies);
* ``checker``: :class:`mavac.robots.collision.CollisionChecker` as it is (base-fixed pairs
  cached per base pose, cheapest pairs first, OBB hierarchies);
* ``convex_hull``: the same checker with every link mesh replaced by its convex hull (coal
  ``buildConvexHull``), a modelling option (MoveIt plans against simplified shapes too) that
  changes answers: it is measured here, not used.

For each it prints the CPU microseconds per call (best of ``REPEATS`` replays) and how many
answers differ from the trial's. Prints ``RATIO collision_checker_vs_reference <x>`` last.

Run: ``.venv/bin/python benchmarks/bench_collision.py [n_calls]`` (default: every call, about
280,000; a smaller ``n_calls`` replays an evenly spaced subset).
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace

import coal
import numpy as np
import pinocchio as pin

from mavac.cleaning.trial import run_trial
from mavac.experiments.mavac_online import offline_plan, online_params
from mavac.geometry.machines import load_machine
from mavac.robots.collision import CollisionChecker

SCENE, READING, OFFLINE, SEED = "test_bench", "paper", "hpr", 1
REPEATS = 2


def record_calls():
    """Run the trial, logging every ``CollisionChecker.is_free`` call; returns the checker the
    trial built and the calls as (bases (n, 4, 4), qs (n, nq), free (n,) bool)."""
    bases, qs, answers, made = [], [], [], []
    is_free = CollisionChecker.is_free

    def logged(self, q):
        free = is_free(self, q)
        if not made or made[-1] is not self:
            made.append(self)
        bases.append(self.world_T_base)
        qs.append(np.array(q))
        answers.append(free)
        return free

    CollisionChecker.is_free = logged
    try:
        plan = offline_plan(SCENE, READING, offline=OFFLINE)
        run_trial(load_machine(SCENE), plan, params=online_params(READING), seed=SEED)
    finally:
        CollisionChecker.is_free = is_free
    if len(set(map(id, made))) != 1:
        raise RuntimeError(f"expected the trial's one arm checker, got {len(set(map(id, made)))}")
    return made[0], np.array(bases), np.array(qs), np.array(answers)


def reference(checker, obstacle):
    """``(set_base, is_free)`` of the checker's pairs as before: all of them, construction
    order (self pairs, then against the obstacle, then the floor), OBBRSS meshes, no cache."""
    gm = checker.geometry_model.copy()
    for g, original in zip(gm.geometryObjects, checker.robot.collision_model.geometryObjects):
        g.geometry = original.geometry
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(len(obstacle.faces), len(obstacle.vertices))
    bvh.addVertices(np.asarray(obstacle.vertices, dtype=float))
    bvh.addTriangles(np.asarray(obstacle.faces, dtype=np.int64))
    bvh.endModel()
    oid = gm.getGeometryId("obstacle")
    gm.geometryObjects[oid].geometry = bvh
    n_robot = len(checker.robot.collision_model.geometryObjects)
    pairs = sorted(((cp.first, cp.second) for cp in gm.collisionPairs),
                   key=lambda ab: (ab[1] >= n_robot, ab[1] if ab[1] >= n_robot else 0, ab))
    gm.removeAllCollisionPairs()
    for a, b in pairs:
        gm.addCollisionPair(pin.CollisionPair(a, b))
    gdata = pin.GeometryData(gm)
    for k, (a, b) in enumerate(pairs):  # the margin applies against the obstacle and the floor
        gdata.collisionRequests[k].security_margin = checker.margin if b >= n_robot else 0.0
    world = [(g, gm.geometryObjects[g].placement) for g in range(n_robot, len(gm.geometryObjects))]
    model, data = checker.robot.model, checker.robot.model.createData()

    def set_base(world_T_base):
        base_T_world = pin.SE3(np.linalg.inv(world_T_base))
        for g, placement_at_origin in world:  # the checker was left at the identity base
            gm.geometryObjects[g].placement = base_T_world * placement_at_origin

    def is_free(q):
        return not pin.computeCollisions(model, data, gm, gdata, q, True)

    return set_base, is_free


def convex_hull_checker(checker, obstacle):
    """The checker's robot, obstacle, margin and floor, each link mesh replaced by its convex
    hull."""
    gm = checker.robot.collision_model.copy()
    for g in gm.geometryObjects:
        if isinstance(g.geometry, coal.BVHModelBase):
            bvh = g.geometry.clone()
            bvh.buildConvexHull(True, "Qt")
            g.geometry = bvh.convex
    return CollisionChecker(replace(checker.robot, collision_model=gm), obstacle, margin=checker.margin, floor=True)


def replay(set_base, is_free, bases, qs) -> tuple[float, np.ndarray]:
    """Best CPU seconds of ``REPEATS`` replays, and the answers."""
    best = np.inf
    for _ in range(REPEATS):
        out = np.empty(len(qs), dtype=bool)
        last = None
        c0 = time.process_time()
        for i, (T, q) in enumerate(zip(bases, qs)):
            if last is None or not np.array_equal(T, last):
                set_base(T)
                last = T
            out[i] = is_free(q)
        best = min(best, time.process_time() - c0)
    return best, out


def main(n_calls: int | None) -> None:
    checker, bases, qs, free = record_calls()
    print(f"{len(qs)} is_free calls recorded in one trial ({(~free).mean() * 100:.1f} % in collision), "
          f"{len({T.tobytes() for T in bases})} base poses")
    if n_calls is not None and n_calls < len(qs):
        pick = np.linspace(0, len(qs) - 1, n_calls).round().astype(int)
        bases, qs, free = bases[pick], qs[pick], free[pick]
    machine = load_machine(SCENE)
    checker.set_base(np.eye(4))
    hull = convex_hull_checker(checker, machine.mesh)
    seconds = {}
    for name, (set_base, is_free) in {"reference": reference(checker, machine.mesh),
                                      "checker": (checker.set_base, checker.is_free),
                                      "convex_hull": (hull.set_base, hull.is_free)}.items():
        seconds[name], out = replay(set_base, is_free, bases, qs)
        changed = out != free
        print(f"{name:12s} {seconds[name] / len(qs) * 1e6:6.1f} CPU us a call, {changed.sum()} of {len(qs)} "
              f"answers differ from the trial's ({changed.mean() * 100:.2f} %: {np.sum(free & ~out)} free -> "
              f"collision, {np.sum(~free & out)} collision -> free)")
    print(f"RATIO collision_checker_vs_reference {seconds['reference'] / seconds['checker']:.2f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else None)

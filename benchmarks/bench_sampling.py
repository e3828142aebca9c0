"""Kabir Table IV random sampling: seed-by-seed gradient descent vs the end-point map.

One random-sampling run on a seeded synthetic grid (a disc-shaped workspace over random patch
points, as the toy reach of the tests, plus one patch that only the setups of one corner reach)
is timed twice, side by side:

* reference: :func:`mavac.setups.sampling.random_sampling` on a grid lookup, a
  :func:`gradient_descent` from every seed drawn (what ``random_runs`` did before);
* fast: :func:`endpoint_maps` for the variant (every seed's descent at once, built once per
  object and variant, shared by all repetitions), then
  :func:`random_sampling_on_map`.

The absolute round of a "CA" variant walks away from the corner patch, so the run draws every
setup of the grid (the expensive case of Fig. 7). Both runs must give the same result. Wall and
CPU seconds (``resource.getrusage``) are printed for each, and the fast run's cost per
repetition when the map serves ``--repetitions`` runs. The last line is

    RATIO gd_endpoint_map <x>

with x = reference CPU seconds / fast CPU seconds of the one run, map build included.

Run: ``.venv/bin/python benchmarks/bench_sampling.py [--res-mm 50] [--patches 1000]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import resource
import time

import numpy as np

from mavac.params import SamplingParams, SetupSpaceParams
from mavac.setups.sampling import (endpoint_maps, lookup_reach, random_sampling, random_sampling_on_map,
                                   uniform_setups)


def synthetic_cover(grid: np.ndarray, patches: int, seed: int) -> np.ndarray:
    """(m, patches) bool: patch points on a 1 m x 0.6 m part reachable inside a 0.45 m disc
    around (0.5 m, 0.5 m) once the part is placed at (x, y, alpha); patch 0 only from the
    corner x = y = 0."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-0.5, 0.5, (patches, 2)) * np.array([1.0, 0.6])
    ca, sa = np.cos(grid[:, 2:]), np.sin(grid[:, 2:])
    wx = grid[:, :1] + ca * pts[:, 0] - sa * pts[:, 1]
    wy = grid[:, 1:2] + sa * pts[:, 0] + ca * pts[:, 1]
    cover = (wx - 0.5) ** 2 + (wy - 0.5) ** 2 < 0.45**2
    cover[:, 0] = (grid[:, 0] < 1e-9) & (grid[:, 1] < 1e-9)
    return cover


def cpu_seconds() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def timed(fn):
    wall, cpu = time.perf_counter(), cpu_seconds()
    out = fn()
    return out, time.perf_counter() - wall, cpu_seconds() - cpu


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--res-mm", type=float, default=50.0, help="x and y resolution of the grid [mm]")
    ap.add_argument("--res-deg", type=float, default=10.0, help="alpha resolution of the grid [deg]")
    ap.add_argument("--patches", type=int, default=1000)
    ap.add_argument("--variant", default="CA_XY")
    ap.add_argument("--seed", type=int, default=0, help="seed of the run (the grid's cover is seeded 0)")
    ap.add_argument("--repetitions", type=int, default=100, help="runs one map serves")
    args = ap.parse_args()

    res = (args.res_mm / 1000.0, args.res_mm / 1000.0, math.radians(args.res_deg))
    space = dataclasses.replace(SetupSpaceParams(), res_x=res[0], res_y=res[1], res_alpha=res[2])
    sampling = dataclasses.replace(SamplingParams(), gd_step_x=res[0], gd_step_y=res[1], gd_step_alpha=res[2])
    grid = uniform_setups(space)
    cover = synthetic_cover(grid, args.patches, 0)
    target = cover.any(axis=0)
    print(f"grid {len(grid)} setups x {args.patches} patches, variant {args.variant}, run seed {args.seed}")

    ref, ref_wall, ref_cpu = timed(lambda: random_sampling(lookup_reach(grid, cover), space, sampling,
                                                           variant=args.variant, seed=args.seed, target=target))
    maps, map_wall, map_cpu = timed(lambda: endpoint_maps(grid, cover, space, sampling, (args.variant,)))
    fast, run_wall, run_cpu = timed(lambda: random_sampling_on_map(maps[args.variant], seed=args.seed, target=target))
    for name in ("setups", "cover", "nondominated", "seeds"):
        assert np.array_equal(getattr(ref, name), getattr(fast, name)), name
    assert (ref.n_rfc, ref.samples, ref.covers_target) == (fast.n_rfc, fast.samples, fast.covers_target)

    print(f"run: samples {ref.samples}, n_rfc {ref.n_rfc}, candidates {len(ref.setups)}, "
          f"covers target {ref.covers_target} (identical both ways)")
    print(f"reference (gradient descent per seed)  wall {ref_wall:8.3f} s  cpu {ref_cpu:8.3f} s")
    print(f"fast: end-point map build              wall {map_wall:8.3f} s  cpu {map_cpu:8.3f} s")
    print(f"fast: run read from the map            wall {run_wall:8.3f} s  cpu {run_cpu:8.3f} s")
    per_run = (map_cpu + args.repetitions * run_cpu) / args.repetitions
    print(f"fast per run over {args.repetitions} repetitions (one build)  cpu {per_run:8.3f} s"
          f"  (reference / this: {ref_cpu / per_run:.1f})")
    print(f"RATIO gd_endpoint_map {ref_cpu / (map_cpu + run_cpu):.1f}")


if __name__ == "__main__":
    main()

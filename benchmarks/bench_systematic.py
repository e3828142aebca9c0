"""Systematic-baseline benchmark: one paper-scale run of ``run_systematic`` (the raster over every
surface dust can rest on, from the spots of the paper's HPR plan), by default on the test bench,
seed 1.

    python benchmarks/bench_systematic.py [--scene S] [--seed N]

The offline plan comes from the disk cache (computed on the first run, not timed). Prints the
run's row and compares its cleaned heaps, simulated time and motion with the committed row of
the same scene and seed at full density in ``data/results/beyond_adaptive_vs_systematic_runs.csv``
(nothing in a run depends on the wall clock, so they must be equal), then the CPU seconds of the
reach test alone and of the whole run, and on the last line ``SECONDS systematic_<scene> <x>``
(wall time of the whole run).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from mavac.cleaning import systematic as S
from mavac.config import DATA_DIR
from mavac.experiments.beyond_online import comparison_rows, systematic_unit, unit_run
from mavac.experiments.mavac_online import offline_plan, online_params
from mavac.geometry.machines import load_machine
from mavac.params import SystematicParams
from mavac.robots.collision import CollisionChecker
from mavac.robots.models import ur10_mobile
from mavac.seeding import rng_for

COMPARED = ("heaps", "cleaned", "sim_time_s", "tool_path_m", "joint_travel_rad")


def reach_seconds(scene: str, seed: int) -> float:
    """CPU seconds of the reach test (every spot and tool axis against every raster waypoint)."""
    machine, plan, params = load_machine(scene), offline_plan(scene, "paper"), online_params("paper")
    robot = ur10_mobile()
    lines = S.raster_lines(machine, S.line_spacing(SystematicParams(), params), SystematicParams().waypoint_spacing)
    checker = CollisionChecker(robot, machine.mesh, margin=params.approach.collision_margin, floor=True)
    axes = S.tool_axes(params.approach.alpha, params.approach.n_orientations)
    t0 = time.process_time()
    S.reach_matrix(robot, checker, S.spots_of_poses(plan), np.vstack(lines), axes, params.approach.delta,
                   rng=rng_for(seed, "raster reach"))
    return time.process_time() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="test_bench")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    offline_plan(args.scene, "paper")  # fill the cache before the clock starts
    reach_cpu = reach_seconds(args.scene, args.seed)
    t0, c0 = time.perf_counter(), time.process_time()
    unit = systematic_unit(args.scene, (1.0,), args.seed)
    (row,) = comparison_rows(unit, unit_run(unit))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(row)
    path = DATA_DIR / "results" / "beyond_adaptive_vs_systematic_runs.csv"
    table = pd.read_csv(path) if path.is_file() else pd.DataFrame(columns=["method"])
    hit = table[(table.method == "systematic") & (table.scene == args.scene) & (table.density == 1.0)
                & (table.seed == args.seed)]
    if len(hit) != 1:
        print(f"no committed row for {args.scene}, seed {args.seed}")
    else:
        differ = [f"{c}: ours {row[c]} != committed {hit[c].iloc[0]}" for c in COMPARED if row[c] != hit[c].iloc[0]]
        print("committed row: " + ("equal" if not differ else "DIFFERS, " + "; ".join(differ)))
    print(f"reach test {reach_cpu:.1f} CPU s; whole run {cpu:.1f} CPU s")
    print(f"SECONDS systematic_{args.scene} {wall:.2f}")


if __name__ == "__main__":
    main()

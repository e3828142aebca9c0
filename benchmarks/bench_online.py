"""MAVAC online benchmark: one paper-scale trial (Algorithm 1 in pybullet), by default on the
test bench, the paper's reading with HPR offline, seed 1.

    python benchmarks/bench_online.py [--scene S] [--reading R] [--offline O] [--seed N]

The offline plan comes from the disk cache (computed on the first run, not timed); Open3D is
imported and the UR10's description parsed before the clock starts (a notebook's trial worker
does both once for all its trials). Prints the
trial's result and compares its whole row with the committed rows of the same scene, reading,
offline method and seed in ``data/results/mavac_table2_trials.csv`` and
``mavac_online_times.csv`` (every column but the wall-clock ``planning_wall_s``; no wall clock
decides anything in a trial, so they must be equal), naming each column that differs; then
the trial's CPU seconds (steadier than wall time on a shared machine) and, on the last two
lines, ``SECONDS rrt_approach_median <x>`` (median RRT-Connect wall time per approach plan; the
paper needed "several seconds") and ``SECONDS online_trial_<scene> <x>`` (wall time).
"""

from __future__ import annotations

import argparse
import io
import math
import time

import numpy as np
import pandas as pd

from mavac.cleaning.regions import heap_regions
from mavac.cleaning.trial import run_trial
from mavac.config import DATA_DIR
from mavac.experiments.mavac_online import offline_plan, online_params, times_table, trials_table, unseen_heaps
from mavac.geometry.machines import load_machine
from mavac.robots.models import ur10_mobile

#: committed result files and the columns of each that are not compared (wall clock)
COMMITTED = {"mavac_table2_trials.csv": (), "mavac_online_times.csv": ("planning_wall_s",)}


def _same(a, b) -> bool:
    """Equal as numbers (NaN equal to NaN) or, failing that, as text."""
    try:
        x, y = float(a), float(b)
    except (TypeError, ValueError):
        return str(a) == str(b)
    return x == y or (math.isnan(x) and math.isnan(y))


def committed_differences(run: dict) -> list[str] | None:
    """Columns (``file:column ours != committed``) where the trial's rows differ from the
    committed ones of its scene, reading, offline method and trial; None if none is committed."""
    ours = {"mavac_table2_trials.csv": trials_table([run]), "mavac_online_times.csv": times_table([run])}
    out = []
    for name, wall_clock in COMMITTED.items():
        path = DATA_DIR / "results" / name
        if not path.is_file():
            return None
        table = pd.read_csv(path)
        hit = table[(table.scene == run["scene"]) & (table.reading == run["reading"])
                    & (table.offline == run["offline"]) & (table.trial == run["trial"])]
        if len(hit) != 1:
            return None
        # through CSV text, as the notebook writes it, so floats compare as committed
        mine = pd.read_csv(io.StringIO(ours[name].to_csv(index=False))).iloc[0]
        for col in hit.columns:
            if col not in wall_clock and not _same(mine.get(col), hit.iloc[0][col]):
                out.append(f"{name}:{col} {mine.get(col)} != {hit.iloc[0][col]}")
    return out


def main(scene: str, reading: str, offline: str, seed: int) -> None:
    import open3d  # noqa: F401  its first import (about 1.7 CPU s) is no part of a trial's cost

    ur10_mobile()  # parses the UR10's description (0.4 CPU s), once per process as in a trial worker

    plan = offline_plan(scene, reading, offline=offline)
    machine = load_machine(scene)
    t0, c0 = time.perf_counter(), time.process_time()
    result = run_trial(machine, plan, params=online_params(reading), seed=seed)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(f"{scene}, {reading} reading, {offline} offline, seed {seed}: {result.n_heaps} heaps, {result.n_cleaned} "
          f"cleaned ({result.cleaning_pct:.1f} %, simulated), simulated time {result.times.sim_time_s:.3f} s, "
          f"{len(result.rrt_approach_seconds)} approach plans")
    run = dict(scene=scene, reading=reading, offline=offline, trial=seed, result=result,
               regions=heap_regions(machine, result.heaps), unseen=unseen_heaps(plan, result.heaps))
    diff = committed_differences(run)
    if diff is None:
        print("no committed row to compare with (run notebook 05 at paper scale)")
    else:
        print("committed rows (trials and times, every column but planning_wall_s): "
              + ("equal" if not diff else "DIFFERENT: " + "; ".join(diff)))
    print(f"CPU seconds of the trial: {cpu:.1f}")
    rrt = float(np.median(result.rrt_approach_seconds)) if result.rrt_approach_seconds else float("nan")
    print(f"SECONDS rrt_approach_median {rrt:.4f}")
    print(f"SECONDS online_trial_{scene} {wall:.1f}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="test_bench")
    ap.add_argument("--reading", default="paper")
    ap.add_argument("--offline", default="hpr")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    main(args.scene, args.reading, args.offline, args.seed)

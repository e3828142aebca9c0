"""MAVAC online benchmark: one paper-scale trial on the test bench (Algorithm 1 in pybullet),
the paper's reading with HPR offline, seed 1.

The offline plan comes from the disk cache (computed on the first run, not timed). Prints the
trial's result and whether it equals the committed ``data/results/mavac_table2_trials.csv`` row
of the same scene, reading and seed (no wall clock decides anything in a trial, so it must),
then the trial's CPU seconds (steadier than wall time on a shared machine) and, on the last two
lines, ``SECONDS rrt_approach_median <x>`` (median RRT-Connect wall time per approach plan; the
paper needed "several seconds") and ``SECONDS online_trial_test_bench <x>`` (wall time).
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from mavac.cleaning.trial import run_trial
from mavac.config import DATA_DIR
from mavac.experiments.mavac_online import offline_plan, online_params
from mavac.geometry.machines import load_machine

SCENE, READING, OFFLINE, SEED = "test_bench", "paper", "hpr", 1


def committed_row() -> dict | None:
    """The committed trial row of this scene, reading and seed, or None if there is none."""
    path = DATA_DIR / "results" / "mavac_table2_trials.csv"
    if not path.is_file():
        return None
    table = pd.read_csv(path)
    hit = table[(table.scene == SCENE) & (table.reading == READING) & (table.seed == SEED)]
    if "offline" in table.columns:
        hit = hit[hit.offline == OFFLINE]
    return hit.iloc[0].to_dict() if len(hit) else None


def main() -> None:
    plan = offline_plan(SCENE, READING, offline=OFFLINE)
    machine = load_machine(SCENE)
    t0, c0 = time.perf_counter(), time.process_time()
    result = run_trial(machine, plan, params=online_params(READING), seed=SEED)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(f"{SCENE}, {READING} reading, {OFFLINE} offline, seed {SEED}: {result.n_heaps} heaps, {result.n_cleaned} cleaned "
          f"({result.cleaning_pct:.1f} %, simulated), simulated time {result.times.sim_time_s:.0f} s, "
          f"{len(result.rrt_approach_seconds)} approach plans")
    row = committed_row()
    if row is None:
        print("no committed row to compare with (run notebook 05 at paper scale)")
    else:
        same = (row["heaps"], row["cleaned"]) == (result.n_heaps, result.n_cleaned)
        print(f"committed row: {row['heaps']} heaps, {row['cleaned']} cleaned -> {'equal' if same else 'DIFFERENT'}")
    print(f"CPU seconds of the trial: {cpu:.1f}")
    rrt = float(np.median(result.rrt_approach_seconds)) if result.rrt_approach_seconds else float("nan")
    print(f"SECONDS rrt_approach_median {rrt:.4f}")
    print(f"SECONDS online_trial_test_bench {wall:.1f}")


if __name__ == "__main__":
    main()

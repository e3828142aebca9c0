"""MAVAC online benchmark: one paper-scale trial on the test bench (Algorithm 1 in pybullet).

The offline plan comes from the disk cache (computed on the first run, not timed). Prints the
trial's wall time, the simulated time, the cleaning result and, on the last two lines,
``SECONDS rrt_approach_median <x>`` (median RRT-Connect wall time per approach plan; the paper
needed "several seconds") and ``SECONDS online_trial_test_bench <x>``.
"""

from __future__ import annotations

import time

import numpy as np

from mavac.cleaning.trial import run_trial
from mavac.experiments.mavac_online import offline_plan, online_params
from mavac.geometry.machines import load_machine


def main() -> None:
    plan = offline_plan("test_bench")
    machine = load_machine("test_bench")
    t0 = time.perf_counter()
    result = run_trial(machine, plan, params=online_params(), seed=1)
    wall = time.perf_counter() - t0
    print(f"test bench, seed 1: {result.n_heaps} heaps, {result.cleaning_pct:.1f} % cleaned (simulated), "
          f"simulated time {result.times.sim_time_s:.0f} s, {len(result.rrt_approach_seconds)} approach plans")
    rrt = float(np.median(result.rrt_approach_seconds)) if result.rrt_approach_seconds else float("nan")
    print(f"SECONDS rrt_approach_median {rrt:.4f}")
    print(f"SECONDS online_trial_test_bench {wall:.1f}")


if __name__ == "__main__":
    main()

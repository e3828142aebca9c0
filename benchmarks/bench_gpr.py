"""How many simulated scrubbing experiments GPR parameter learning (Kabir, Sec. VIII) saves
against random search.

For the paper's bowl and hull settings (C_p^th, P_th from data/paper_values.csv) and several
seeds, both methods run on the SIMULATED scrub (mavac.scrubbing.wear); we count the experiments
until the first point that is feasible (noise-free C_p >= C_p^th - 0.02) and within 0.05 of
the objective of the dense-search optimum (``experiments_to_reach``). A run that never gets
there counts as its budget + 1 (a lower bound for random search, a penalty for GPR).

Per setting: ratio = median(random) / median(GPR), printed with cp_tol 0.02 and 0 (noise-free
C_p >= C_p^th itself). The last line reports the smaller of the two settings' ratios at 0.02:

    RATIO gpr_vs_random_experiments <x>

Usage: .venv/bin/python benchmarks/bench_gpr.py [n_seeds, default 12]   (MAVAC_JOBS=k for k workers)
"""

from __future__ import annotations

import sys
import time

from mavac.experiments.kabir_gpr import dense_optima, gpr_vs_random, speedup

GPR_BUDGET = 100
RANDOM_BUDGET = {"bowl": 1000, "hull": 2500}


def main(n_seeds: int = 12) -> float:
    start = time.perf_counter()
    print(dense_optima().round(4).to_string(index=False))
    ratios = []
    for part, random_budget in RANDOM_BUDGET.items():
        summary, _ = gpr_vs_random(parts=(part,), seeds=range(n_seeds), gpr_budget=GPR_BUDGET,
                                   random_budget=random_budget)
        for method in ("gpr", "random"):
            r = summary.loc[summary["method"] == method, "experiments_to_reach"].to_numpy(float)
            print(f"{part:5s} {method:6s} experiments to reach: {r.tolist()} (nan: never)")
        table = speedup(summary)
        print(table.round(2).to_string(index=False))
        ratios.append(float(table.loc[table["cp_tol"] == 0.02, "ratio"].iloc[0]))
    print(f"wall time {time.perf_counter() - start:.0f} s")
    print(f"RATIO gpr_vs_random_experiments {min(ratios):.2f}")
    return min(ratios)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 12)

"""Setup planner benchmark: MILP certificate (HiGHS) vs the paper's Algorithm 2 (Kabir Sec. V).

Instance: the concave-bowl candidate setups from ``<cache_dir>/kabir_cover_concave_bowl.npz``
(arrays ``cover`` (m, n) bool, ``costs`` (m,) s, optional ``patch_area`` (n,) m^2) when that
file exists; otherwise a seeded synthetic instance resembling the paper's concave bowl of
Table V (13 non-dominated setups over ~5000 stain patches, setup time 60 s as in Table VI).
Both solvers run on the same instance in the same process; Algorithm 2 (bound eq. 2, both
heuristics on) is capped at T_max (no node limit: this is a timing benchmark), and every run
prints its ``timed_out`` / ``node_limited`` flags. The last line is ``RATIO certified_vs_alg2 <x>`` with
``x = Algorithm 2 seconds / MILP seconds``.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from mavac.config import cache_dir, fast_or_full
from mavac.params import SetupPlannerParams
from mavac.setups.dominance import nondominated
from mavac.planning.setcover import (
    dfbnb_setup_cover,
    execution_time_area_passes,
    milp_setup_cover,
    setup_costs_from_times,
)

CACHE_NAME = "kabir_cover_concave_bowl.npz"


def synthetic_bowl_instance(seed: int = 4, n: int = 5000, m: int = 13, setup_time: float = 60.0):
    """Seeded stand-in for the concave bowl's candidate setups.

    Stain patches lie on the bowl wall at polar coordinates ``(phi, rho)``; a setup (a rotation
    of the bowl about z plus a shift) lets the arm reach an angular sector around ``alpha_j``
    that narrows towards the rim, above a radius ``rho >= lo_j``. Execution time is
    area x passes / rate (:func:`execution_time_area_passes`), 1-3 passes per patch.

    Returns
    -------
    cover : (m', n) bool
        Non-dominated setups only.
    costs : (m',) float, s
    patch_area : (n,) float, m^2
    """
    rng = np.random.default_rng(seed)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    rho = np.sqrt(rng.uniform(0.04, 1.0, n))
    alpha = (np.arange(m) + rng.uniform(-0.4, 0.4, m)) * 2.0 * np.pi / m
    half_width = rng.uniform(0.75, 1.25, m)
    lo = rng.uniform(0.0, 0.3, m)
    dphi = np.abs((phi[None] - alpha[:, None] + np.pi) % (2.0 * np.pi) - np.pi)
    cover = (dphi < half_width[:, None] * (1.2 - 0.5 * rho[None])) & (rho[None] >= lo[:, None])
    area = rng.uniform(0.5e-4, 1.5e-4, n)  # triangles below 1.5 cm^2 (Kabir Sec. IX-A)
    passes = rng.integers(1, 4, n)  # at most three passes (Sec. IX-A)
    t_e = execution_time_area_passes(cover, area, passes, rate=0.002)
    keep = nondominated(cover)
    return cover[keep], setup_costs_from_times(t_e, setup_time)[keep], area


def load_instance():
    path = cache_dir() / CACHE_NAME
    if path.exists():
        data = np.load(path)
        cover = np.asarray(data["cover"], bool)
        area = np.asarray(data["patch_area"], float) if "patch_area" in data else None
        keep = nondominated(cover)
        return f"cached {path}", cover[keep], np.asarray(data["costs"], float)[keep], area
    cover, costs, area = synthetic_bowl_instance()
    return "synthetic concave-bowl-like (seed 4)", cover, costs, area


def table_vi_sweep(t_max: float):
    """Table VI's setup times on the synthetic instance: nodes of Algorithm 2 (eq. 2) and of
    Algorithm 4 (eq. 7) against the MILP optimum."""
    print("Table VI-style sweep (synthetic): t_s | MILP size, s | Alg.2 eq.2 nodes, size, s, gap"
          " | Alg.4 eq.7 nodes, size, s, gap")
    for t_s in (0.0, 60.0, 3000.0):
        cover, costs, area = synthetic_bowl_instance(setup_time=t_s)
        ref = milp_setup_cover(cover, costs)
        row = [f"{t_s:6.0f}", f"{len(ref.setups)}, {ref.seconds:.3f}"]
        for algorithm, bound in ((2, "lb"), (4, "b")):
            params = dataclasses.replace(SetupPlannerParams(), algorithm=algorithm, bound=bound,
                                         t_max=t_max, max_nodes=None)
            res = dfbnb_setup_cover(cover, costs, patch_area=area, params=params)
            flag = f" (timed_out={res.timed_out}, node_limited={res.node_limited})"
            row.append(f"{res.node_expansions}, {len(res.setups)}, {res.seconds:.2f}{flag}, "
                       f"{(res.cost - ref.cost) / ref.cost:.1e}")
        print("  " + " | ".join(row))


def main():
    source, cover, costs, area = load_instance()
    m, n = cover.shape
    t_max = fast_or_full(10.0, 120.0)
    print(f"instance: {source}: m = {m} non-dominated setups, n = {n} patches, "
          f"costs {costs.min():.1f}-{costs.max():.1f} s")

    # Warm up scipy/HiGHS so the timing below is the solve, not the import.
    milp_setup_cover(np.eye(2, dtype=bool), np.ones(2))
    runs = [milp_setup_cover(cover, costs) for _ in range(3)]
    milp = runs[0]
    milp_seconds = float(np.median([r.seconds for r in runs]))
    print(f"MILP (HiGHS, gap 0): status {milp.status}, cost {milp.cost:.3f} s, "
          f"{len(milp.setups)} setups {milp.setups.tolist()}, {milp_seconds:.4f} s (median of 3)")

    params = dataclasses.replace(SetupPlannerParams(), algorithm=2, bound="lb", guiding=True,
                                 pruning=True, t_max=t_max, max_nodes=None)
    alg2 = dfbnb_setup_cover(cover, costs, patch_area=area, params=params)
    finished = alg2.finished
    gap = (alg2.cost - milp.cost) / milp.cost if milp.cost > 0 else 0.0
    print(f"Algorithm 2 (eq. 2, guiding + pruning), T_max = {t_max:.0f} s: "
          f"{'finished' if finished else 'aborted at T_max'} (timed_out={alg2.timed_out}, "
          f"node_limited={alg2.node_limited}), cost {alg2.cost:.3f} s, "
          f"{len(alg2.setups)} setups, {alg2.node_expansions} nodes, {alg2.seconds:.3f} s, "
          f"gap to certificate {gap:.2e}")

    t0 = time.perf_counter()
    alg4 = dfbnb_setup_cover(cover, costs, patch_area=area, params=dataclasses.replace(params, algorithm=4, bound="b"))
    gap4 = (alg4.cost - milp.cost) / milp.cost if milp.cost > 0 else 0.0
    print(f"Algorithm 4 (eq. 7, IESS {alg4.iess}, N_repeat {alg4.n_repeat}): "
          f"{'finished' if alg4.finished else 'aborted at T_max'} (timed_out={alg4.timed_out}), cost {alg4.cost:.3f} s, "
          f"{alg4.node_expansions} nodes, {time.perf_counter() - t0:.3f} s, gap {gap4:.2e}")

    if source.startswith("synthetic"):
        table_vi_sweep(t_max)
    print(f"RATIO certified_vs_alg2 {alg2.seconds / milp_seconds:.2f}")


if __name__ == "__main__":
    main()

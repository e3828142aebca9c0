"""Setup planner benchmark: the proven optimum against the paper's Algorithm 2 (Kabir Sec. V).

Instances: Kabir Table II's, one per object (the non-dominated setups of the uniform grid over
the package's own setup space, eq. 1 costs with t_s = 60 s), as notebook 06 writes them to
``data/instances/kabir_table2_<object>.npz``; and OR-Library scp41-48 (``data/orlib``). Never
the cache: the time does not depend on what ran before.

Per instance it prints the sizes before and after :func:`mavac.planning.reduction.reduce_instance`,
then the CPU seconds and the result of

* ``certified``: :func:`mavac.planning.certified.certified_cover` (reduction, size bound,
  enumeration, else the LP bound by column generation, reduced-cost fixing and the integer
  program);
* ``alg2`` (Table II instances): Algorithm 2 (eq. 2, guiding and pruning on) on the reduced
  instance, stopped at the same node budget as the enumeration of ``certified``;
* ``highs`` (OR-Library): HiGHS alone on the reduced instance (:func:`milp_setup_cover`). On
  the Table II instances its root relaxation alone runs for minutes, so it is left out there.

Every solver is bounded by nodes, never seconds. The last line is ``RATIO certified_vs_alg2 x``
with x = Algorithm 2's CPU seconds / certified's, summed over the Table II instances.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

from mavac.config import fast_or_full
from mavac.params import CertifyParams, SetupPlannerParams
from mavac.planning.certified import certified_cover
from mavac.planning.instances import read_instance, read_scp
from mavac.planning.reduction import reduce_instance
from mavac.planning.setcover import dfbnb_setup_cover, milp_setup_cover

ROOT = Path(__file__).resolve().parent.parent
OBJECTS = ("concave_bowl", "schwefel", "hyperboloid", "sine")  # the sine, the slowest, last
ORLIB = tuple(f"scp4{k}" for k in range(1, 9))


def cpu(fn, *args, **kwargs):
    """``(result, CPU seconds)`` of one call."""
    t0 = time.process_time()
    out = fn(*args, **kwargs)
    return out, time.process_time() - t0


def table2_instance(name: str):
    path = ROOT / "data" / "instances" / f"kabir_table2_{name}.npz"
    if not path.is_file():
        raise SystemExit(f"{path} is missing: run notebook 06 at paper scale (make reproduce) to write it")
    data = read_instance(path)
    return data["cover"], data["costs"], data["patch_area"]


def row(name, cover, costs, certify: CertifyParams, alg2_nodes: int | None):
    """One instance: reduction, certified_cover, then Algorithm 2 (Table II instances) or HiGHS
    alone (OR-Library; on a Table II instance its root relaxation alone runs for minutes).

    Returns ``(certified CPU s, Algorithm 2 CPU s or None)``.
    """
    red, t_red = cpu(reduce_instance, cover, costs)
    cert, t_cert = cpu(certified_cover, cover, costs, params=certify)
    print(f"{name}: {red.summary()} in {t_red:.2f} s | certified {cert.status} by {cert.proof}: "
          f"{cert.cost:.3f} ({len(cert.setups)} setups, bound {cert.dual_bound:.3f}, greedy {cert.incumbent_cost:.3f}, "
          f"LP {cert.lp_bound:.3f}, {cert.fixed_setups} setups fixed, {cert.enumeration_nodes} enumeration + "
          f"{cert.milp_nodes} HiGHS nodes) {t_cert:.2f} s", flush=True)
    if alg2_nodes is None:
        highs, t_highs = cpu(milp_setup_cover, cover, costs, node_limit=certify.milp_nodes)
        print(f"  HiGHS alone {highs.status}: {highs.cost:.3f} {t_highs:.2f} s", flush=True)
        return t_cert, None
    params = dataclasses.replace(SetupPlannerParams(), algorithm=2, bound="lb", guiding=True, pruning=True,
                                 t_max=None, max_nodes=alg2_nodes)
    alg2, t_alg2 = cpu(dfbnb_setup_cover, red.cover, red.costs, params=params)
    cost = red.forced_cost + alg2.cost
    gap = 100.0 * (cost - cert.cost) / cert.cost if cert.cost > 0 else 0.0
    print(f"  Algorithm 2, {alg2_nodes} nodes: {'finished' if alg2.finished else 'node_limited'}, "
          f"{cost:.3f} ({gap:+.1f} % against certified) {t_alg2:.2f} s", flush=True)
    return t_cert, t_alg2


def main():
    nodes = fast_or_full(20_000, 200_000)
    # HiGHS re-solves an LP per node: ~0.1 s on the bowl, tens of seconds on the sine's fixed instance
    certify = CertifyParams(enumeration_nodes=nodes, milp_nodes=fast_or_full(5, 50))
    print(f"node budget: enumeration and Algorithm 2 {nodes}, HiGHS {certify.milp_nodes}; CPU seconds")
    milp_setup_cover(*read_scp(ROOT / "data" / "orlib" / "scp41.txt"))  # warm up scipy / HiGHS
    for name in ORLIB:
        row(f"OR-Library {name}", *read_scp(ROOT / "data" / "orlib" / f"{name}.txt"), certify, None)
    certified, alg2 = 0.0, 0.0
    for name in OBJECTS:
        cover, costs, _ = table2_instance(name)
        t_cert, t_alg2 = row(f"Table II {name}", cover, costs, certify, nodes)
        certified, alg2 = certified + t_cert, alg2 + t_alg2
    print(f"RATIO certified_vs_alg2 {alg2 / certified:.2f}")


if __name__ == "__main__":
    main()

"""A proven-optimal setup plan: reduce, bound the cover size, enumerate, then the integer program.

Kabir's depth-first branch and bound (:mod:`mavac.planning.setcover`) grows like ``m!`` and a
plain integer program can take minutes on a thousand candidate setups. The structure of setup
planning makes most instances easy to prove:

1. :func:`mavac.planning.reduction.reduce_instance` removes uncoverable, identical and implied
   patches, forced setups and setups dominated at no lower cost;
2. a greedy cover (cheapest cost per newly covered patch, redundant setups removed) gives an
   incumbent ``T``; since every setup costs at least ``c_min``, no cover of more than ``k``
   setups, the largest ``k`` whose ``k`` cheapest costs sum below ``T``, can beat it;
3. an exact enumeration on Python-int bitsets over covers of 1, 2, ... setups improves the
   incumbent and, once it reaches the size bound, proves it: it branches on the uncovered
   patch that the fewest setups reach (every cover holds one of them), cheapest setup first,
   excluding the setups tried in earlier branches, and prunes on cost;
4. when the bound stays above a few setups (or the enumeration's node budget runs out) HiGHS
   solves the reduced instance with the incumbent as an objective cutoff
   (``c.x <= (1 - rel_tol) T``; scipy's ``milp`` takes no start point): infeasible proves the
   incumbent, a solution is the optimum.

Budgets count nodes, never seconds. Every result reports its status and a proven lower bound.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import csr_array

from ..params import CertifyParams
from .iess import row_bitsets
from .reduction import ReducedInstance, reduce_instance


@dataclass
class CertifiedCover:
    """Output of :func:`certified_cover`.

    Attributes
    ----------
    setups : (k,) int
        Chosen rows of the original cover, ascending (empty when nothing is coverable).
    cost : float, s
        ``sum c_j`` over ``setups``.
    status : str
        "optimal" (proven within ``rel_tol``) or "node_limited" (a budget ran out: ``cost`` is
        the best cover found and ``dual_bound`` what was proven).
    dual_bound : float, s
        Proven lower bound on the optimum (``cost`` when optimal).
    proof : str
        What proved it: "reduction" (nothing left to choose), "enumeration", "milp", or "none".
    incumbent_cost : float, s
        The greedy cover's cost, before the proof.
    size_bound : int
        No cover with more setups can beat the incumbent.
    enumeration_nodes : int
    milp_nodes : int
        HiGHS branch-and-bound nodes (0 when not run).
    reduced : ReducedInstance
    seconds : float
        Wall time of the call (reporting only; no budget depends on it).
    """

    setups: np.ndarray
    cost: float
    status: str
    dual_bound: float
    proof: str
    incumbent_cost: float
    size_bound: int
    enumeration_nodes: int
    milp_nodes: int
    reduced: ReducedInstance
    seconds: float

    @property
    def optimal(self) -> bool:
        return self.status == "optimal"


def certified_cover(cover: np.ndarray, costs: np.ndarray, *, params: CertifyParams | None = None,
                    check: bool = True) -> CertifiedCover:
    """Cheapest set of setups reaching every coverable patch, with a proof of optimality.

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i.
    costs : (m,) float, s, >= 0
        Cost of each setup.
    params : CertifyParams, optional
        Node budgets and the optimality tolerance.
    check : bool
        Validate ``cover`` and ``costs`` (callers that already did pass False).

    Returns
    -------
    CertifiedCover
        Patches no setup reaches are left out (``reduced.uncoverable``).
    """
    t0 = time.perf_counter()
    params = CertifyParams() if params is None else params
    if not isinstance(params, CertifyParams):
        raise TypeError(f"params must be a CertifyParams, got {type(params).__name__}")
    red = reduce_instance(cover, costs, check=check)
    if red.cover.shape[1] == 0:
        return _result(red, [], 0.0, "optimal", 0.0, "reduction", 0.0, 0, 0, 0, t0)
    masks, full = row_bitsets(red.cover), (1 << red.cover.shape[1]) - 1
    cost_list = red.costs.tolist()
    best = _greedy(masks, cost_list, full)
    incumbent = best_cost = math.fsum(cost_list[j] for j in best)
    size_bound = _size_bound(red.costs, incumbent, params.rel_tol)
    best, best_cost, nodes, done = _enumerate(red.cover, cost_list, best, best_cost, params)
    if done:
        return _result(red, best, best_cost, "optimal", best_cost, "enumeration", incumbent, size_bound, nodes, 0, t0)
    best, best_cost, status, bound, milp_nodes = _milp_with_cutoff(red, best, best_cost, params)
    return _result(red, best, best_cost, status, bound, "milp" if status == "optimal" else "none", incumbent,
                   size_bound, nodes, milp_nodes, t0)


def _result(red, chosen, cost, status, bound, proof, incumbent, size_bound, nodes, milp_nodes, t0):
    return CertifiedCover(
        setups=red.lift(np.array(chosen, dtype=np.int64)), cost=red.forced_cost + cost, status=status,
        dual_bound=red.forced_cost + bound, proof=proof, incumbent_cost=red.forced_cost + incumbent,
        size_bound=size_bound, enumeration_nodes=nodes, milp_nodes=milp_nodes, reduced=red,
        seconds=time.perf_counter() - t0)


def _greedy(masks: list, costs: list, full: int) -> list:
    """Cheapest cost per newly covered patch until all are covered (ties: lowest index), then
    redundant setups out, most expensive first."""
    left, chosen = full, []
    while left:
        best_j, best_rate = -1, -1.0
        for j, mask in enumerate(masks):
            gain = (mask & left).bit_count()
            rate = (gain / costs[j] if costs[j] > 0 else math.inf) if gain else -1.0
            if rate > best_rate:
                best_j, best_rate = j, rate
        chosen.append(best_j)
        left &= ~masks[best_j]
    for j in sorted(chosen, key=lambda j: (-costs[j], j)):
        union = 0
        for k in chosen:
            union |= masks[k] if k != j else 0
        if union == full:
            chosen.remove(j)
    return sorted(chosen)


def _size_bound(costs: np.ndarray, incumbent: float, rel_tol: float) -> int:
    """Largest k whose k cheapest costs sum below the incumbent's (no larger cover beats it)."""
    cheapest = np.cumsum(np.sort(costs))
    return int(np.count_nonzero(cheapest < incumbent * (1.0 - rel_tol)))


def _enumerate(cover: np.ndarray, costs: list, best: list, best_cost: float, params: CertifyParams):
    """Exact search of :func:`certified_cover`, step 3, within ``params.enumeration_nodes``.

    Iterative deepening: every pass is exact over covers of at most ``depth`` setups, so the
    cheap shallow passes improve the incumbent that prunes the deep ones. A pass that reaches
    the size bound of the incumbent proves it; past ``params.max_enumerated_size`` setups the
    integer program takes over, with the improved incumbent.

    Returns ``(best rows, best cost, nodes, finished)``.
    """
    # Columns relabelled by how few setups reach them, so the rarest uncovered patch is the
    # lowest set bit of the uncovered set.
    rank = np.argsort(cover.sum(axis=0), kind="stable")
    masks = row_bitsets(np.ascontiguousarray(cover[:, rank]))
    by_cost = np.argsort(np.asarray(costs), kind="stable")
    sorted_cols = cover[by_cost][:, rank].T
    reaching = [by_cost[col].tolist() for col in sorted_cols]
    tree = _Tree(masks, costs, reaching, min(costs), params.rel_tol, (1 << cover.shape[1]) - 1)
    nodes, depth = 0, 1
    while True:
        if depth > _size_bound(np.asarray(costs), best_cost, params.rel_tol):
            return sorted(best), best_cost, nodes, True
        if depth > params.max_enumerated_size:
            return sorted(best), best_cost, nodes, False
        found, nodes = tree.search(depth, best_cost, params.enumeration_nodes - nodes, nodes)
        if found is None:
            return sorted(best), best_cost, nodes, False
        if found[0] is not None:
            best, best_cost = found
        depth += 1


@dataclass
class _Tree:
    """The branching of :func:`_enumerate` over one relabelled instance."""

    masks: list
    costs: list
    reaching: list
    cmin: float
    rel_tol: float
    full: int

    def search(self, depth: int, best_cost: float, budget: int, nodes: int):
        """Cheapest cover of at most ``depth`` setups below ``best_cost``, within ``budget`` nodes.

        Returns ``((rows or None, cost), nodes)``, or ``(None, nodes)`` when the budget ran out.
        """
        best, cut, used = None, best_cost * (1.0 - self.rel_tol), 0
        stack = [(self.full, 0, (), 0.0)]  # (uncovered, excluded setups, chosen, cost)
        while stack:
            if used >= budget:
                return None, nodes + used
            left, excluded, chosen, spent = stack.pop()
            used += 1
            children = []
            for j in self.reaching[(left & -left).bit_length() - 1]:
                if excluded >> j & 1:
                    continue
                total = spent + self.costs[j]
                if total >= cut:
                    break  # cheapest first: no later branch does better
                rest = left & ~self.masks[j]
                if rest == 0:
                    best, best_cost, cut = list(chosen) + [j], total, total * (1.0 - self.rel_tol)
                    break
                if len(chosen) + 1 < depth and total + self.cmin < cut:
                    children.append((rest, excluded, chosen + (j,), total))
                # later branches leave j out: every set of setups is met once (and a j pruned
                # here cannot be completed below the cut in any branch)
                excluded |= 1 << j
            stack.extend(reversed(children))
        return (best, best_cost), nodes + used


def _milp_with_cutoff(red: ReducedInstance, best: list, best_cost: float, params: CertifyParams):
    """Step 4: HiGHS on the reduced instance, the incumbent as cutoff, within the node budget.

    Returns ``(rows, cost, status, dual bound, HiGHS nodes)``.
    """
    m = red.cover.shape[0]
    cutoff = best_cost * (1.0 - params.rel_tol)
    rows = csr_array(np.vstack([red.cover.T.astype(float), red.costs[None, :]]))
    lb = np.r_[np.ones(red.cover.shape[1]), -np.inf]
    ub = np.r_[np.full(red.cover.shape[1], np.inf), cutoff]
    options = {"mip_rel_gap": 0.0}
    if params.milp_nodes is not None:
        options["node_limit"] = int(params.milp_nodes)
    res = milp(c=red.costs, constraints=LinearConstraint(rows, lb=lb, ub=ub), integrality=np.ones(m),
               bounds=Bounds(0.0, 1.0), options=options)
    nodes = int(getattr(res, "mip_node_count", 0) or 0)
    if res.status == 2:  # infeasible: nothing is cheaper than the incumbent
        return best, best_cost, "optimal", best_cost, nodes
    if res.x is not None:
        chosen = np.flatnonzero(res.x > 0.5).tolist()
        cost = math.fsum(red.costs[chosen].tolist())
        if cost < best_cost:
            best, best_cost = chosen, cost
    if res.status == 0:
        return best, best_cost, "optimal", best_cost, nodes
    bound = getattr(res, "mip_dual_bound", None)
    bound = float(bound) if bound is not None and np.isfinite(bound) else 0.0
    return best, best_cost, "node_limited", min(bound, best_cost), nodes

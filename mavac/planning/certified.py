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
   incumbent and, once it reaches the size bound, proves it; past three setups it deepens only
   while that bound is small (``CertifyParams.max_enumerated_size``). It branches on the
   uncovered patch that the fewest setups reach (every cover holds one of them), cheapest
   setup first, excluding the setups tried in earlier branches, and prunes on cost;
4. when the bound is larger (or the enumeration's node budget runs out), the LP relaxation
   by column generation (:mod:`mavac.planning.lp_bound`) gives a lower bound and the
   setups that carry it; HiGHS on those setups alone improves the incumbent (the greedy cover
   is often far from the optimum: 60 % above it on the sine's Table II instance);
5. reduced-cost fixing drops every setup whose Lagrangian bound already reaches the incumbent,
   the rest is reduced again, and HiGHS solves it (presolve off, no objective cutoff row: on the
   Table II bowl, 181 setups, the cutoff row ``c.x <= (1 - rel_tol) T`` and HiGHS' presolve
   took 9.4 CPU s where the plain program takes 3.8 s); an optimum no cheaper than
   ``(1 - rel_tol) T`` proves the incumbent, a cheaper one is the optimum.

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
from .lp_bound import fixable, lp_bound
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
        What proved it: "reduction" (nothing left to choose), "enumeration", "lp" (the LP bound
        fixed every setup out), "milp", or "none".
    incumbent_cost : float, s
        The greedy cover's cost, before the proof.
    size_bound : int
        No cover with more setups can beat the incumbent.
    enumeration_nodes : int
    milp_nodes : int
        HiGHS branch-and-bound nodes, both runs (0 when not run).
    lp_bound : float, s
        The LP relaxation's bound (0 when not computed).
    fixed_setups : int
        Setups of the reduced instance that reduced-cost fixing dropped.
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
    lp_bound: float
    fixed_setups: int
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
        return _result(red, _Search([], 0.0, 0.0), "optimal", 0.0, "reduction", t0)
    masks, full = row_bitsets(red.cover), (1 << red.cover.shape[1]) - 1
    cost_list = red.costs.tolist()
    best = _greedy(masks, cost_list, full)
    greedy_cost = math.fsum(cost_list[j] for j in best)
    found = _Search(best, greedy_cost, incumbent=greedy_cost)
    found.size_bound = _size_bound(red.costs, found.cost, params.rel_tol)
    found.rows, found.cost, found.nodes, done = _enumerate(red.cover, cost_list, best, found.cost, params)
    if done:
        return _result(red, found, "optimal", found.cost, "enumeration", t0)
    status, bound, proof = _prove_by_lp_and_milp(red, found, params)
    return _result(red, found, status, bound, proof, t0)


@dataclass
class _Search:
    """What :func:`certified_cover` found so far, in rows of the reduced instance."""

    rows: list
    cost: float
    incumbent: float
    size_bound: int = 0
    nodes: int = 0
    milp_nodes: int = 0
    lp_bound: float = 0.0
    fixed_setups: int = 0


def _result(red, found: _Search, status, bound, proof, t0):
    return CertifiedCover(
        setups=red.lift(np.array(found.rows, dtype=np.int64)), cost=red.forced_cost + found.cost, status=status,
        dual_bound=red.forced_cost + bound, proof=proof, incumbent_cost=red.forced_cost + found.incumbent,
        size_bound=found.size_bound, enumeration_nodes=found.nodes, milp_nodes=found.milp_nodes,
        lp_bound=red.forced_cost + found.lp_bound if found.lp_bound else 0.0, fixed_setups=found.fixed_setups,
        reduced=red, seconds=time.perf_counter() - t0)


def _prove_by_lp_and_milp(red: ReducedInstance, found: _Search, params: CertifyParams):
    """Steps 4-5: the LP bound, HiGHS on the LP's setups for the incumbent, fixing, HiGHS to prove.

    Updates ``found`` in place; returns ``(status, dual bound, proof)``.
    """
    lp = lp_bound(red.cover, red.costs)
    found.lp_bound = lp.bound
    _improve(found, red.cover, red.costs, lp.master, params)
    drop = fixable(lp, found.cost, params.rel_tol)
    found.fixed_setups = int(drop.sum())
    if drop.all():
        return "optimal", found.cost, "lp"
    status, bound = _improve(found, red.cover, red.costs, np.flatnonzero(~drop), params)
    if status == "optimal":
        return "optimal", found.cost, "milp"
    return "node_limited", max(min(bound, found.cost), lp.bound), "none"


def _improve(found: _Search, cover, costs, rows: np.ndarray, params: CertifyParams):
    """HiGHS on ``rows`` of the instance, reduced again, below ``found.cost``; keeps a cheaper cover.

    Returns ``(status, bound)`` over covers drawn from ``rows``.
    """
    sub = reduce_instance(cover[rows], costs[rows], check=False)
    if len(sub.uncoverable):  # no cover from these rows at all
        return "optimal", found.cost
    chosen, cost, status, bound, nodes = _milp_below(sub, found.cost, params)
    found.milp_nodes += nodes
    if chosen is not None and sub.forced_cost + cost < found.cost:
        found.rows = rows[sub.lift(np.array(chosen, dtype=np.int64))].tolist()
        found.cost = math.fsum(costs[found.rows].tolist())
    return status, sub.forced_cost + bound


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


# Ours: covers of up to three setups are always searched (cheap: the rarest patch's setups, their
# children and grandchildren, pruned on cost), since finding one often brings the size bound
# within reach. On the Table II Schwefel instance of the one setup square (1631 setups, greedy
# 635.3 s with a size bound of 6) the third level finds the 3-setup optimum and proves it in
# 144,446 nodes (3 CPU s), where the integer program took 744 CPU s; on OR-Library scp41-48 it
# adds at most 135 nodes.
_PROBE_DEPTH = 3


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
        size_bound = _size_bound(np.asarray(costs), best_cost, params.rel_tol)
        if depth > size_bound:
            return sorted(best), best_cost, nodes, True
        # Past the probe depths, deepen only while the incumbent's size bound is within reach.
        if depth > params.max_enumerated_size or (depth > _PROBE_DEPTH and size_bound > params.max_enumerated_size):
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


def _milp_below(red: ReducedInstance, incumbent: float, params: CertifyParams):
    """HiGHS on a reduced instance within the node budget; keeps only a cover cheaper than the incumbent.

    Parameters
    ----------
    red : ReducedInstance
    incumbent : float, s
        Cost of the best cover known, forced setups of ``red`` included.

    Returns
    -------
    ``(rows or None, cost, status, dual bound, HiGHS nodes)``, rows and costs within ``red``
    (forced setups excluded); status "optimal" when nothing is cheaper than the rows returned
    (or than the incumbent, when the rows are None).
    """
    m, n = red.cover.shape
    cutoff = incumbent * (1.0 - params.rel_tol) - red.forced_cost
    if n == 0:
        return ([], 0.0, "optimal", 0.0, 0) if cutoff >= 0 else (None, 0.0, "optimal", 0.0, 0)
    rows = csr_array(red.cover.T.astype(float))
    lb, ub = np.ones(n), np.full(n, np.inf)
    options = {"mip_rel_gap": 0.0, "presolve": False}
    if params.milp_nodes is not None:
        options["node_limit"] = int(params.milp_nodes)
    res = milp(c=red.costs, constraints=LinearConstraint(rows, lb=lb, ub=ub), integrality=np.ones(m),
               bounds=Bounds(0.0, 1.0), options=options)
    nodes = int(getattr(res, "mip_node_count", 0) or 0)
    if res.status == 2:  # infeasible: nothing is cheaper than the incumbent
        return None, 0.0, "optimal", incumbent - red.forced_cost, nodes
    chosen = np.flatnonzero(res.x > 0.5).tolist() if res.x is not None else None
    cost = math.fsum(red.costs[chosen].tolist()) if chosen is not None else math.inf
    if res.status == 0:
        if cost > cutoff:  # the optimum over these rows is no cheaper than the incumbent
            return None, 0.0, "optimal", incumbent - red.forced_cost, nodes
        return chosen, cost, "optimal", cost, nodes
    bound = getattr(res, "mip_dual_bound", None)
    bound = float(bound) if bound is not None and np.isfinite(bound) else 0.0
    return chosen, cost, "node_limited", bound, nodes

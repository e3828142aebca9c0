"""Setup planning as weighted set cover (Kabir et al. 2017, Sections III and V).

Candidate setups ``j = 0 .. m-1`` each reach a patch set ``P(s_j)``, given as a boolean matrix
``cover (m, n)``. Setup j has the fixed cost ``c_j = t_s + t_e(tau_j)`` (setup time plus the
execution time of its trajectory over all its patches) and a plan costs (eq. 1)
``T(S) = sum_j c_j``. The planner looks for the cheapest set of setups covering every patch.

* :func:`dfbnb_setup_cover`: the paper's depth-first branch and bound, Algorithms 1-2 and
  3-4 (with the setup-size estimate of Algorithm 5, :mod:`mavac.planning.iess`), bounds eq. 2
  and eq. 7, T_decay, the T_max abort and a node counter.
* :func:`milp_setup_cover`: exact certificate, ``min c.x  s.t.  cover^T x >= 1, x binary``
  with ``scipy.optimize.milp`` (HiGHS).
* :func:`brute_force_setup_cover`: enumeration for tests (``m <= 20``).
* :func:`solve_setup_cover`: the entry point, returns a :class:`SetupCoverResult` with the
  setups in execution order (greedy by cleaning rate).

The planner is independent of robots and geometry; setup costs come from
:func:`setup_costs_from_times` with an execution-time model such as
:func:`execution_time_area_passes` (or the tool-path model, same ``(m,)`` interface).
Remove dominated setups first with :func:`mavac.planning.dominance.nondominated`, as the paper
does (Section IV); the planner itself solves the problem it is given.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import csr_array

from ..params import SETUP_COVER_METHODS, CertifyParams, SetupPlannerParams
from ..validate import check_cover
from .iess import initial_estimate_of_setup_size, n_repeat_recommended, row_bitsets
from .certified import certified_cover
from .dominance import row_groups
from .reduction import reduce_instance

# Above this many random trials the Section IX-B choice of N_repeat is refused unless T_max
# bounds the run (C(m, m/2) grows like 2^m: m = 30 already needs ~3.6e8 trials).
_MAX_AUTO_N_REPEAT = 10_000_000


# ---------------------------------------------------------------------------------------------
# Cost model


def execution_time_area_passes(cover, patch_area, passes, rate: float) -> np.ndarray:
    """Execution time of each setup from cleaned area: ``t_e_j = sum_{i in P(s_j)} a_i N_i / rate``.

    A simple stand-in for the trajectory-based ``t_e(tau_j)`` (Kabir, Sec. III); the tool-path
    model plugs into the planner through the same ``(m,)`` array.

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i.
    patch_area : (n,) float, m^2
    passes : (n,) int
        Cleaning passes ``N_i`` of each patch (>= 1).
    rate : float, m^2/s
        Area swept per second by the tool.

    Returns
    -------
    (m,) float, s
    """
    c = check_cover(cover)
    area = _check_patch_vector("patch_area", patch_area, c.shape[1])
    n_pass = _check_patch_vector("passes", passes, c.shape[1])
    if np.any(n_pass < 1):
        raise ValueError("passes must be >= 1 for every patch")
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate must be in (0, inf] m^2/s, got {rate!r}")
    return c.astype(float) @ (area * n_pass) / float(rate)


def setup_costs_from_times(exec_time, setup_time) -> np.ndarray:
    """Fixed cost of each setup, ``c_j = t_s_j + t_e_j`` (eq. 1), seconds.

    Parameters
    ----------
    exec_time : (m,) float, s
        ``t_e(tau_j)`` of each setup, >= 0.
    setup_time : float or (m,) float, s
        ``t_s``, >= 0 (Kabir, Table VI: 0, 60 or 3000 s for every setup).
    """
    te = np.asarray(exec_time, dtype=float)
    if te.ndim != 1:
        raise ValueError(f"exec_time must have shape (m,), got {te.shape}")
    ts = np.broadcast_to(np.asarray(setup_time, dtype=float), te.shape)
    if not np.all(np.isfinite(te)) or np.any(te < 0):
        raise ValueError("exec_time must be finite and >= 0")
    if not np.all(np.isfinite(ts)) or np.any(ts < 0):
        raise ValueError(f"setup_time must be finite and >= 0, got {setup_time!r}")
    return te + ts


def cleaning_rate(cover, setup_costs, *, patch_area=None, remaining=None) -> np.ndarray:
    """Cleaning rate ``R_j = area(P(s_j) & P_r) / (t_e_j + t_s_j)`` (Kabir, Sec. III), m^2/s.

    Parameters
    ----------
    cover : (m, n) bool
    setup_costs : (m,) float, s
    patch_area : (n,) float, m^2, optional
        Unit areas when omitted.
    remaining : (n,) bool, optional
        ``P_r``; all patches when omitted.
    """
    c = check_cover(cover)
    costs = _check_costs(setup_costs, c.shape[0])
    area = _area_or_ones(patch_area, c.shape[1])
    if remaining is not None:
        rem = np.asarray(remaining, dtype=bool)
        if rem.shape != (c.shape[1],):
            raise ValueError(f"remaining must have shape ({c.shape[1]},), got {rem.shape}")
        area = area * rem
    return (c.astype(float) @ area) / costs


def execution_order(cover, setup_costs, chosen, patch_area=None) -> np.ndarray:
    """Order a set of setups greedily by cleaning rate on the patches still dirty.

    Repeatedly picks the setup of ``chosen`` with the highest ``R_j`` on ``P_r`` (ties: lowest
    index), as the paper builds its first branch (Sec. V-A).

    Returns
    -------
    (k,) int
        ``chosen`` reordered.
    """
    c = check_cover(cover)
    costs = _check_costs(setup_costs, c.shape[0])
    area = _area_or_ones(patch_area, c.shape[1])
    left = sorted(int(j) for j in np.asarray(chosen, dtype=np.int64).ravel())
    rem = np.ones(c.shape[1], dtype=bool)
    out = []
    while left:
        gain = np.array([area[c[j] & rem].sum() / costs[j] for j in left])
        k = int(np.argmax(gain))
        j = left.pop(k)
        out.append(j)
        rem &= ~c[j]
    return np.array(out, dtype=np.int64)


# ---------------------------------------------------------------------------------------------
# Input checks and the compressed bitset form


def _check_costs(setup_costs, m: int, allow_zero: bool = False) -> np.ndarray:
    costs = np.asarray(setup_costs, dtype=float)
    if costs.shape != (m,):
        raise ValueError(f"setup_costs must have shape ({m},), got {costs.shape}")
    if not np.all(np.isfinite(costs)) or np.any(costs < 0) or (not allow_zero and np.any(costs == 0)):
        raise ValueError("setup_costs must be finite and > 0 (c_j = t_s + t_e_j, seconds)")
    return costs


def _check_patch_vector(name: str, values, n: int) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if v.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {v.shape}")
    if not np.all(np.isfinite(v)) or np.any(v < 0):
        raise ValueError(f"{name} must be finite and >= 0")
    return v


def _area_or_ones(patch_area, n: int) -> np.ndarray:
    return np.ones(n) if patch_area is None else _check_patch_vector("patch_area", patch_area, n)


@dataclass(frozen=True)
class _Compressed:
    """Coverable patches grouped by identical coverage (an exact reduction: patches covered
    by the same setups are interchangeable for every test of the search)."""

    cover: np.ndarray  # (m, k) bool, one column per group, groups ordered by first patch
    area: np.ndarray  # (k,) float, summed patch area of each group
    time: np.ndarray  # (k,) float, summed patch execution time of each group (0 when not given)
    masks: list  # m Python ints, bit g set when setup j covers group g
    groups_setups: list  # per group, the setups covering it (ascending)
    uncoverable: np.ndarray  # (u,) int, patches no setup covers


def _compress(cover: np.ndarray, area: np.ndarray, patch_time: np.ndarray | None = None) -> _Compressed:
    m, n = cover.shape
    patch_time = np.zeros(n) if patch_time is None else patch_time
    coverable = cover.any(axis=0)
    uncoverable = np.flatnonzero(~coverable)
    cols = cover[:, coverable].T
    if cols.shape[0] == 0:
        return _Compressed(np.zeros((m, 0), bool), np.zeros(0), np.zeros(0), [0] * m, [], uncoverable)
    group = row_groups(np.packbits(cols, axis=1))  # patches with the same setups, by first patch
    first = np.unique(group, return_index=True)[1]
    group_area = np.bincount(group, weights=area[coverable], minlength=len(first))
    group_time = np.bincount(group, weights=patch_time[coverable], minlength=len(first))
    ccover = np.ascontiguousarray(cols[first].T)
    masks = row_bitsets(ccover)
    groups_setups = [np.flatnonzero(ccover[:, g]).tolist() for g in range(ccover.shape[1])]
    return _Compressed(ccover, group_area, group_time, masks, groups_setups, uncoverable)


def _bits_to_bool(bits: int, k: int) -> np.ndarray:
    raw = np.frombuffer(bits.to_bytes(max(1, -(-k // 8)), "little"), dtype=np.uint8)
    return np.unpackbits(raw, bitorder="little", count=k).view(bool)  # 0/1 bytes: a view, no copy


# ---------------------------------------------------------------------------------------------
# Depth-first branch and bound (Algorithms 1-5)


@dataclass
class DFBnBResult:
    """Raw output of :func:`dfbnb_setup_cover`.

    Attributes
    ----------
    setups : (k,) int
        ``S*`` in the order the search built it (empty when no cover was found in time).
    cost : float
        ``T(S*)``, s (``inf`` when no cover was found).
    node_expansions : int
        Number of AddSetUp calls (nodes of the search tree visited, root included).
    seconds : float
        Wall time of FindSetupPlan (Algorithm 5 included for Algorithm 3).
    timed_out : bool
        True when the T_max abort (step 1) ended the search.
    node_limited : bool
        True when ``max_nodes`` ended the search (deterministic, unlike ``timed_out``).
    iess : int or None
        Algorithm 5's estimate (Algorithm 4 only).
    n_repeat : int or None
        ``N_repeat`` used by Algorithm 5.
    uncoverable : (u,) int
        Patches no setup covers; left out of ``P``.
    """

    setups: np.ndarray
    cost: float
    node_expansions: int
    seconds: float
    timed_out: bool
    iess: int | None
    n_repeat: int | None
    uncoverable: np.ndarray
    node_limited: bool = False

    @property
    def finished(self) -> bool:
        """The search ran to the end: neither T_max nor the node limit stopped it."""
        return not (self.timed_out or self.node_limited)


def dfbnb_setup_cover(cover, setup_costs, *, patch_area=None, params: SetupPlannerParams | None = None,
                      patch_time=None, setup_time=None) -> DFBnBResult:
    """FindSetupPlan: Kabir's depth-first branch and bound (Algorithms 1-2 or 3-5).

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i.
    setup_costs : (m,) float, s
        ``c_j = t_s + t_e(tau_j)`` > 0.
    patch_area : (n,) float, m^2, optional
        For the cleaning rate of the branch-guiding heuristic; unit areas when omitted.
    params : SetupPlannerParams
        ``algorithm`` 2 or 4, ``bound`` "lb" (eq. 2) or "b" (eq. 7), ``guiding``, ``pruning``,
        ``t_max``, ``max_nodes``, ``cost_model``, ``t_decay``/``t_decay_rate``,
        ``n_repeat``/``iess_prob``, ``seed``.
    patch_time : (n,) float, s, optional
        Execution time of each patch; needed with ``cost_model="remaining"``.
    setup_time : float or (m,) float, s, optional
        ``t_s``; needed with ``cost_model="remaining"``.

    Returns
    -------
    DFBnBResult

    Notes
    -----
    With ``cost_model="remaining"`` a setup added at a node costs ``t_s + t_e`` of the patches of
    ``P_r`` it reaches (eq. 2 and eq. 7 then take min / max of that over ``S_u``; eq. 2 stays a
    lower bound, since any completion adds a setup whose new patches lie in ``P_r``).

    One node is one call AddSetUp(P_r, S_u, S_curr), run in this order:

    0. stop when ``max_nodes`` nodes have been expanded (ours, deterministic);
    1. abort when the elapsed time exceeds T_max (checked at every node);
    2. (Algorithm 4) return when ``|S_curr| > IESS``;
    3. when ``P_r`` is empty: keep ``S_curr`` if ``T(S_curr) <= T*``, return;
    4. (pruning) return when ``T(S_curr) + bound + T_decay >= T*``, bound = min (eq. 2) or max
       (eq. 7) of ``c_j`` over ``S_u``, ``T_decay`` only for Algorithm 4;
    5. if a patch of ``P_r`` is covered by a single setup of ``S_u``, branch on that setup only
       (the lowest such patch decides); otherwise branch on every ``s`` in ``S_u``, sorted by
       decreasing cleaning rate ``R_j`` on ``P_r`` (guiding, ties by index) or by index.

    The children of a node are all unused setups, those that reach no patch of ``P_r`` too:
    Algorithm 2, step 5 reads "For every s in S_u in decreasing order of cleaning rate". So a
    set is met in several orders, as in the paper whose node counts (Tables V-VI) measure that
    tree. Patches no setup covers are
    removed from ``P`` first (otherwise no branch can ever close). The search is iterative (an
    explicit stack visited in the recursive order), on Python-int bitsets over groups of
    patches with identical coverage.
    """
    params = SetupPlannerParams() if params is None else params
    t0 = time.perf_counter()
    c = check_cover(cover)
    m, n = c.shape
    costs = _check_costs(setup_costs, m)
    area = _area_or_ones(patch_area, n)
    ts, times = _remaining_inputs(params, setup_time, patch_time, m, n)
    comp = _compress(c, area, times)
    deadline = math.inf if params.t_max is None else t0 + params.t_max

    iess = n_repeat = None
    if params.algorithm == 4:
        n_repeat = _n_repeat(params, m)
        iess = initial_estimate_of_setup_size(
            comp.cover, n_repeat, seed=params.seed,
            deadline=None if params.t_max is None else deadline)
    depth_cap = m if iess is None else iess

    best, best_cost, nodes, stop = _search(comp, costs, params, deadline, depth_cap, ts)
    if best_cost < math.inf:
        best_cost = plan_cost(c, costs, best, setup_time=ts, patch_time=times)
    return DFBnBResult(
        setups=np.array(best, dtype=np.int64), cost=best_cost, node_expansions=nodes,
        seconds=time.perf_counter() - t0, timed_out=stop == "timed_out", iess=iess, n_repeat=n_repeat,
        uncoverable=comp.uncoverable, node_limited=stop == "node_limited")


def _remaining_inputs(params: SetupPlannerParams, setup_time, patch_time, m: int, n: int):
    """``(t_s (m,), patch times (n,))`` for ``cost_model="remaining"``, else ``(None, None)``."""
    if params.cost_model != "remaining":
        return None, None
    if setup_time is None or patch_time is None:
        raise ValueError("cost_model='remaining' needs setup_time (s) and patch_time ((n,) s)")
    ts = np.broadcast_to(np.asarray(setup_time, dtype=float), (m,)).copy()
    if not np.all(np.isfinite(ts)) or np.any(ts < 0):
        raise ValueError(f"setup_time must be finite and >= 0, got {setup_time!r}")
    return ts, _check_patch_vector("patch_time", patch_time, n)


def plan_cost(cover, setup_costs, chosen, *, setup_time=None, patch_time=None) -> float:
    """``T(S)`` of a set of setups, s: ``sum c_j`` ("fixed"), or with ``setup_time`` and
    ``patch_time`` given, ``sum t_s_j`` plus the execution time of every patch they reach, each
    once ("remaining": the same in any order)."""
    chosen = [int(j) for j in np.asarray(chosen, dtype=np.int64).ravel()]
    if setup_time is None or patch_time is None:
        return math.fsum(float(setup_costs[j]) for j in chosen)
    c = np.asarray(cover, dtype=bool)
    done = c[chosen].any(axis=0) if chosen else np.zeros(c.shape[1], dtype=bool)
    ts = np.broadcast_to(np.asarray(setup_time, dtype=float), (c.shape[0],))
    return math.fsum([float(ts[j]) for j in chosen] + np.asarray(patch_time, float)[done].tolist())


def _search(comp: _Compressed, costs: np.ndarray, params: SetupPlannerParams, deadline: float,
            depth_cap: int, ts: np.ndarray | None = None) -> tuple[tuple, float, int, str]:
    """The depth-first search of :func:`dfbnb_setup_cover` (steps 0-5 of its Notes).

    Returns ``(S*, T(S*) as summed along the branch, node expansions, stop)``, ``stop`` one of
    "finished", "timed_out", "node_limited".
    """
    m, k = comp.cover.shape
    cost_list = costs.tolist()
    masks = comp.masks
    cover_f = comp.cover.astype(float)
    lower = params.bound == "lb"
    decay = params.algorithm == 4 and params.t_decay > 0
    max_nodes = math.inf if params.max_nodes is None else params.max_nodes

    best_cost = math.inf
    best: tuple = ()
    nodes = 0
    stop = "finished"
    # (P_r, S_u as a bitmask over setups, S_curr, T(S_curr))
    stack = [((1 << k) - 1, (1 << m) - 1, (), 0.0)]
    while stack:
        if nodes >= max_nodes:  # step 0
            stop = "node_limited"
            break
        p_r, s_u, s_curr, t_curr = stack.pop()
        nodes += 1
        if time.perf_counter() > deadline:  # step 1
            stop = "timed_out"
            break
        if len(s_curr) > depth_cap:  # Algorithm 4, step 2
            continue
        if p_r == 0:  # steps 2-3 (Alg. 2), 3-4 (Alg. 4)
            if t_curr <= best_cost:
                best_cost, best = t_curr, s_curr
            continue
        unused = [j for j in range(m) if s_u >> j & 1]
        rem = _bits_to_bool(p_r, k) if (ts is not None or params.guiding) else None
        step = cost_list if ts is None else (ts + cover_f @ (comp.time * rem)).tolist()
        if params.pruning:  # step 4 (Alg. 2), 5 (Alg. 4)
            unused_costs = [step[j] for j in unused]
            bound = min(unused_costs) if lower else max(unused_costs)
            if decay:
                bound += params.t_decay * math.exp(min(700.0, params.t_decay_rate * nodes))
            if t_curr + bound >= best_cost:
                continue
        children = _children(comp, p_r, s_u, unused, step, cover_f, rem, params.guiding)
        for j in reversed(children):
            stack.append((p_r & ~masks[j], s_u & ~(1 << j), s_curr + (j,), t_curr + step[j]))

    return best, best_cost, nodes, stop


def _children(comp: _Compressed, p_r: int, s_u: int, unused: list, step: list, cover_f, rem, guiding: bool):
    """Step 5: a patch reachable from a single unused setup forces that setup; otherwise every
    unused setup, by decreasing cleaning rate on ``P_r`` (guiding; ties by index) or by index."""
    once = twice = 0
    for j in unused:
        twice |= once & comp.masks[j]
        once |= comp.masks[j]
    single = p_r & ~twice
    if single:
        g = (single & -single).bit_length() - 1
        return [next(j for j in comp.groups_setups[g] if s_u >> j & 1)]
    if not guiding:
        return unused
    gain = cover_f @ (comp.area * rem)

    def rate(j):
        return gain[j] / step[j] if step[j] > 0 else (math.inf if gain[j] > 0 else 0.0)

    return sorted(unused, key=lambda j: (-rate(j), j))


def _n_repeat(params: SetupPlannerParams, m: int) -> int:
    if params.n_repeat is not None:
        return params.n_repeat
    n = n_repeat_recommended(m, params.iess_prob)
    if n > _MAX_AUTO_N_REPEAT and params.t_max is None:
        raise ValueError(
            f"n_repeat: the Sec. IX-B choice needs N_repeat = {n} trials for m = {m} setups; "
            "set n_repeat explicitly or bound the run with t_max")
    return n


# ---------------------------------------------------------------------------------------------
# Exact certificate and brute force


@dataclass
class MilpResult:
    """Output of :func:`milp_setup_cover`.

    Attributes
    ----------
    setups : (k,) int
        Chosen setups, ascending (empty if HiGHS returned no feasible point).
    cost : float
        ``sum c_j`` over ``setups`` (``inf`` without a feasible point).
    status : str
        "optimal", "limit_reached" (a time or node limit stopped HiGHS; feasible, not proven) or
        HiGHS' message otherwise.
    optimal : bool
    seconds : float
    uncoverable : (u,) int
        Patches no setup covers, dropped from the constraints.
    dual_bound : float
        HiGHS' proven lower bound on the optimum, s (equal to ``cost`` when optimal; ``-inf``
        when HiGHS proved none).
    proof : str
        What proved it: "milp", or for :func:`mavac.planning.certified.certified_cover`
        "reduction", "enumeration", "lp", "milp" or "none".
    """

    setups: np.ndarray
    cost: float
    status: str
    optimal: bool
    seconds: float
    uncoverable: np.ndarray
    dual_bound: float = -math.inf
    proof: str = "milp"


def milp_setup_cover(cover, setup_costs, time_limit: float | None = None, *, node_limit: int | None = None,
                     fixed_cost: float = 0.0, allow_zero: bool = False) -> MilpResult:
    """Exact weighted set cover: ``min c.x  s.t.  cover^T x >= 1,  x in {0, 1}^m`` (HiGHS), on the
    instance reduced by :func:`mavac.planning.reduction.reduce_instance`.

    Parameters
    ----------
    cover : (m, n) bool
    setup_costs : (m,) float, s, > 0 (>= 0 with ``allow_zero``)
    time_limit : float, optional
        Seconds given to HiGHS; None for no limit (a wall-clock cap: results then depend on
        machine load; prefer ``node_limit``).
    node_limit : int, optional
        Branch-and-bound nodes given to HiGHS; None for no limit.
    fixed_cost : float, s
        Added to the objective (the order-free part of a "remaining" cost).

    Returns
    -------
    MilpResult
        The relative MIP gap is set to 0, so "optimal" is a certificate; otherwise
        ``dual_bound`` is what HiGHS proved.
    """
    t0 = time.perf_counter()
    c = check_cover(cover)
    costs = _check_costs(setup_costs, c.shape[0], allow_zero=allow_zero)
    if time_limit is not None and not (time_limit > 0):
        raise ValueError(f"time_limit must be > 0 s or None, got {time_limit!r}")
    red = reduce_instance(c, costs, check=False)
    base = red.forced_cost + fixed_cost
    if red.cover.shape[1] == 0:
        return MilpResult(red.lift([]), base, "optimal", True, time.perf_counter() - t0, red.uncoverable, base)
    options = {"mip_rel_gap": 0.0}
    if time_limit is not None and math.isfinite(time_limit):
        options["time_limit"] = float(time_limit)
    if node_limit is not None:
        options["node_limit"] = int(node_limit)
    res = milp(c=red.costs, constraints=LinearConstraint(csr_array(red.cover.T.astype(float)), lb=1.0, ub=np.inf),
               integrality=np.ones(len(red.costs)), bounds=Bounds(0.0, 1.0), options=options)
    bound = getattr(res, "mip_dual_bound", None)
    bound = -math.inf if bound is None or not np.isfinite(bound) else float(bound) + base
    if res.x is None:
        return MilpResult(np.zeros(0, np.int64), math.inf, str(res.message), False,
                          time.perf_counter() - t0, red.uncoverable, bound)
    chosen = red.lift(np.flatnonzero(res.x > 0.5))
    status = {0: "optimal", 1: "limit_reached"}.get(res.status, str(res.message))
    cost = math.fsum(costs[chosen].tolist()) + fixed_cost
    return MilpResult(chosen, cost, status, res.status == 0, time.perf_counter() - t0,
                      red.uncoverable, cost if res.status == 0 else bound)


def milp_remaining_cover(cover, setup_time, patch_time, time_limit: float | None = None) -> MilpResult:
    """Exact optimum of the "remaining" cost model: every reachable patch is cleaned once,
    whatever the order, so ``T(S) = sum_{j in S} t_s_j + sum_i t_e_i`` and the MILP minimises
    the setup times (with ``t_s = 0`` every cover is optimal).

    Parameters
    ----------
    cover : (m, n) bool
    setup_time : float or (m,) float, s, >= 0
    patch_time : (n,) float, s
    time_limit : float, optional
    """
    c = check_cover(cover)
    ts, times = _remaining_inputs(SetupPlannerParams(cost_model="remaining"), setup_time, patch_time, *c.shape)
    const = math.fsum(times[c.any(axis=0)].tolist())
    if not np.any(ts > 0):  # every cover costs the same: all setups that reach a patch
        return MilpResult(np.flatnonzero(c.any(axis=1)).astype(np.int64), const, "optimal", True, 0.0,
                          np.flatnonzero(~c.any(axis=0)), const)
    return milp_setup_cover(c, ts, time_limit, fixed_cost=const, allow_zero=True)


def brute_force_setup_cover(cover, setup_costs, max_size: int | None = None):
    """Cheapest cover by enumerating all ``2^m`` subsets (tests; ``m <= 20``).

    Parameters
    ----------
    cover : (m, n) bool
        Patches no setup covers are ignored.
    setup_costs : (m,) float, s, > 0
    max_size : int, optional
        Only subsets of at most this many setups.

    Returns
    -------
    setups : (k,) int
        Ascending; the first cheapest subset in binary-counting order.
    cost : float
        ``inf`` when no subset within ``max_size`` covers.
    """
    c = check_cover(cover)
    m, n = c.shape
    if m > 20:
        raise ValueError(f"cover: brute force is limited to m <= 20 setups, got {m}")
    costs = _check_costs(setup_costs, m).tolist()
    comp = _compress(c, np.ones(n))
    full = (1 << comp.cover.shape[1]) - 1
    cap = m if max_size is None else int(max_size)
    union = [0] * (1 << m)
    total = [0.0] * (1 << m)
    best, best_cost = 0, (0.0 if full == 0 else math.inf)
    for s in range(1, 1 << m):
        low = s & -s
        j = low.bit_length() - 1
        union[s] = union[s ^ low] | comp.masks[j]
        total[s] = total[s ^ low] + costs[j]
        if union[s] == full and total[s] < best_cost and s.bit_count() <= cap:
            best, best_cost = s, total[s]
    chosen = [j for j in range(m) if best >> j & 1]
    if best_cost < math.inf:
        best_cost = math.fsum(costs[j] for j in chosen)
    return np.array(chosen, dtype=np.int64), best_cost


# ---------------------------------------------------------------------------------------------
# Entry point


@dataclass
class SetupCoverResult:
    """A setup plan.

    Attributes
    ----------
    setups : (k,) int
        Chosen setups (rows of ``cover``) in execution order: greedy by cleaning rate on the
        patches still dirty.
    cost : float
        ``T(S)`` (eq. 1), s; 0 for an empty stain, ``inf`` when there is no plan (no setup
        reaches any patch, or the search stopped before any cover).
    step_costs : (k,) float, s
        Cost of each step (``c_j``; with ``cost_model="remaining"`` ``t_s`` plus the time of
        the patches it cleans first).
    step_area : (k,) float, m^2
        Area first cleaned at each step.
    setup_time_total, execution_time_total : float or None
        Split of ``cost`` when the setup time was given.
    method : str
        "auto", "milp", "dfbnb" or "both" (the plan is then DFBnB's).
    status : str
        "optimal" (proven: "auto" or "milp" finished, or DFBnB Algorithm 2 with eq. 2 run to the
        end), "converged" (Algorithm 4 or eq. 7 run to the end: heuristic, see
        ``certificate_gap``), "timed_out" (T_max stopped the search; best plan found, if any),
        "node_limited" (a node budget stopped the search or the proof), "no_solution" (no setup
        reaches any patch: ``uncoverable`` lists them all), "empty" (no patches).
    node_expansions : int
        DFBnB nodes (0 for "auto" and "milp").
    seconds : float
        Wall time of the whole call (both methods for "both").
    timed_out : bool
    uncoverable : (u,) int
        Patches no candidate setup covers (the plan cannot clean them).
    iess : int or None
        Algorithm 5's estimate (Algorithm 4).
    certificate_cost : float or None
        The proven optimum ("auto", "both", "milp"), only when proven.
    certificate_gap : float or None
        ``(cost - certificate_cost) / certificate_cost`` ("both" and "auto", proven optimum only).
    certificate_seconds : float or None
    certificate_status : str or None
        "optimal", "node_limited" or HiGHS' message.
    certificate_bound : float or None
        Proven lower bound on the optimum, s.
    certificate_proof : str or None
        What proved it: "reduction", "enumeration", "lp" or "milp" (see
        :func:`mavac.planning.certified.certified_cover`).
    node_limited : bool
    warnings : list of str
        E.g. a large instance given to DFBnB.
    """

    setups: np.ndarray
    cost: float
    step_costs: np.ndarray
    step_area: np.ndarray
    setup_time_total: float | None
    execution_time_total: float | None
    method: str
    status: str
    node_expansions: int
    seconds: float
    timed_out: bool
    uncoverable: np.ndarray
    iess: int | None = None
    certificate_cost: float | None = None
    certificate_gap: float | None = None
    certificate_seconds: float | None = None
    certificate_status: str | None = None
    certificate_bound: float | None = None
    certificate_proof: str | None = None
    node_limited: bool = False
    warnings: list = field(default_factory=list)


#: More candidate setups than this make DFBnB's tree (up to m! orders) too large to finish in
#: general: :func:`solve_setup_cover` says so and recommends the MILP (ours: 30 setups).
LARGE_INSTANCE = 30


def solve_setup_cover(cover, setup_costs, *, patch_area=None, params: SetupPlannerParams | None = None,
                      method: str = "auto", setup_time=None, patch_time=None,
                      certify: CertifyParams | None = None) -> SetupCoverResult:
    """Cheapest set of setups cleaning every coverable patch (Kabir, eq. 1).

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i.
    setup_costs : (m,) float, s
        ``c_j = t_s + t_e(tau_j)`` > 0 (see :func:`setup_costs_from_times`).
    patch_area : (n,) float, m^2, optional
        Cleaning rates (guiding heuristic, execution order); unit areas when omitted.
    params : SetupPlannerParams, optional
        DFBnB settings; ``t_max`` and ``max_nodes`` bound the search (60 s, 200,000 nodes).
    method : {"auto", "milp", "dfbnb", "both"}
        "auto": the proven optimum of :func:`mavac.planning.certified.certified_cover`
        (reduction, size bound, enumeration, integer program); "milp": HiGHS alone on the
        reduced instance; "dfbnb": the paper's search; "both": DFBnB's plan with the proven
        optimum as certificate.
    setup_time : float or (m,) float, s, optional
        The ``t_s`` part of ``setup_costs``: splits the cost in the result; needed with
        ``params.cost_model="remaining"``.
    patch_time : (n,) float, s, optional
        Execution time of each patch; needed with ``params.cost_model="remaining"``.
    certify : CertifyParams, optional
        Node budgets of "auto", "both" and "milp".

    Returns
    -------
    SetupCoverResult

    Notes
    -----
    Every method solves the reduced instance (:func:`mavac.planning.reduction.reduce_instance`),
    except DFBnB with ``params.reduce`` False (the paper's search) or under
    ``cost_model="remaining"``, whose step costs depend on every patch's time.
    """
    t0 = time.perf_counter()
    params = SetupPlannerParams() if params is None else params
    certify = CertifyParams() if certify is None else certify
    if method not in SETUP_COVER_METHODS:
        raise ValueError(f"method must be one of {SETUP_COVER_METHODS}, got {method!r}")
    c = check_cover(cover)
    m, n = c.shape
    costs = _check_costs(setup_costs, m)
    area = _area_or_ones(patch_area, n)
    ts = _split_setup_time(setup_time, costs)
    remaining = _remaining_inputs(params, setup_time, patch_time, m, n)
    if n == 0 or not c.any():
        return _nothing_to_plan(m, n, method, time.perf_counter() - t0)
    notes = _size_warnings(m, method)
    cert = None if method == "dfbnb" else _certificate(c, costs, remaining, method, certify)
    if method in ("auto", "milp"):
        chosen, cost, nodes, iess = cert.setups, cert.cost, 0, None
        status = "optimal" if cert.optimal else "node_limited"
        stop = "finished" if cert.optimal else "node_limited"
    else:
        chosen, cost, nodes, iess, stop = _dfbnb_on_reduced(c, costs, area, params, setup_time, patch_time,
                                                            t0, remaining)
        exact = params.algorithm == 2 and params.bound == "lb"  # Algorithm 4 and eq. 7 are heuristics
        status = stop if stop != "finished" else "optimal" if exact else "converged"
    result = _plan_result(c, costs, area, ts, remaining, chosen, cost, method, status, nodes, stop, iess)
    result.warnings = notes
    _attach_certificate(result, cert, method)
    result.seconds = time.perf_counter() - t0
    return result


def _dfbnb_on_reduced(c, costs, area, params: SetupPlannerParams, setup_time, patch_time, t0: float, remaining):
    """DFBnB within what is left of ``t_max``; on the reduced instance when ``params.reduce`` and
    the cost model is "fixed".

    Returns ``(setups, cost, nodes, iess, stop)``.
    """
    left = max(t0 + params.t_max - time.perf_counter(), 1e-9) if params.t_max is not None else None
    p = dataclasses.replace(params, t_max=left)
    if remaining[0] is not None or not params.reduce:
        dfb = dfbnb_setup_cover(c, costs, patch_area=area, params=p, setup_time=setup_time, patch_time=patch_time)
        return dfb.setups, dfb.cost, dfb.node_expansions, dfb.iess, _stop(dfb)
    red = reduce_instance(c, costs, check=False)
    if red.cover.shape[1] == 0:
        return red.lift([]), red.forced_cost, 0, None, "finished"
    dfb = dfbnb_setup_cover(red.cover, red.costs, patch_area=area[red.patches], params=p)
    chosen = red.lift(dfb.setups) if len(dfb.setups) else dfb.setups
    cost = red.forced_cost + dfb.cost
    return chosen, cost, dfb.node_expansions, dfb.iess, _stop(dfb)


def _stop(dfb: DFBnBResult) -> str:
    return "timed_out" if dfb.timed_out else "node_limited" if dfb.node_limited else "finished"


def _split_setup_time(setup_time, costs):
    if setup_time is None:
        return None
    ts = np.broadcast_to(np.asarray(setup_time, dtype=float), costs.shape)
    if not np.all(np.isfinite(ts)) or np.any(ts < 0) or np.any(ts > costs):
        raise ValueError("setup_time must be finite, >= 0 and <= setup_costs")
    return ts


def _size_warnings(m: int, method: str) -> list:
    """A large instance given to DFBnB: say so, recommend the MILP."""
    if method in ("auto", "milp") or m <= LARGE_INSTANCE:
        return []
    note = (f"cover: {m} candidate setups is a large instance for DFBnB (its tree grows like m!); it stops at "
            "params.t_max / params.max_nodes with the best plan found. method='auto' proves the optimum, "
            "usually in seconds")
    warnings.warn(note, stacklevel=3)
    return [note]


def _certificate(c, costs, remaining, method: str, certify: CertifyParams) -> MilpResult:
    """The proven optimum ("auto", "both": :func:`certified_cover`) or HiGHS alone ("milp"),
    under the fixed or the remaining cost model, as a :class:`MilpResult`."""
    ts, times = remaining
    fixed = 0.0 if ts is None else math.fsum(times[c.any(axis=0)].tolist())
    weights = costs if ts is None else ts
    if method == "milp":
        return milp_setup_cover(c, weights, node_limit=certify.milp_nodes, fixed_cost=fixed, allow_zero=ts is not None)
    res = certified_cover(c, weights, params=certify, check=False)
    return MilpResult(res.setups, res.cost + fixed, res.status, res.optimal, res.seconds, res.reduced.uncoverable,
                      res.dual_bound + fixed, proof=res.proof)


def _nothing_to_plan(m: int, n: int, method: str, seconds: float) -> SetupCoverResult:
    """No patches ("empty", cost 0), or no setup reaching any ("no_solution", no cost, all listed)."""
    empty = n == 0
    return SetupCoverResult(
        setups=np.zeros(0, np.int64), cost=0.0 if empty else math.inf, step_costs=np.zeros(0),
        step_area=np.zeros(0), setup_time_total=0.0 if empty else None,
        execution_time_total=0.0 if empty else None, method=method, status="empty" if empty else "no_solution", node_expansions=0, seconds=seconds, timed_out=False,
        uncoverable=np.arange(n, dtype=np.int64), certificate_cost=0.0 if empty else None,
        certificate_gap=0.0 if empty and method in ("both", "auto") else None,
        certificate_status="optimal" if empty and method != "dfbnb" else None)


def _plan_result(c, costs, area, ts, remaining, chosen, cost, method, status, nodes, stop, iess):
    order = execution_order(c, costs, chosen, area) if len(chosen) else np.zeros(0, np.int64)
    rem = np.ones(c.shape[1], dtype=bool)
    step_area, step_costs = [], []
    for j in order:
        new = c[j] & rem
        step_area.append(float(area[new].sum()))
        step_costs.append(costs[j] if remaining[0] is None else remaining[0][j] + remaining[1][new].sum())
        rem &= ~c[j]
    step_costs = np.array(step_costs, dtype=float)
    setup_total = None if ts is None else math.fsum(ts[order].tolist())
    return SetupCoverResult(
        setups=order, cost=float(cost), step_costs=step_costs, step_area=np.array(step_area),
        setup_time_total=setup_total,
        execution_time_total=None if ts is None else math.fsum(step_costs.tolist()) - setup_total,
        method=method, status=status, node_expansions=int(nodes), seconds=0.0,
        timed_out=stop == "timed_out", uncoverable=np.flatnonzero(~c.any(axis=0)).astype(np.int64), iess=iess,
        node_limited=stop == "node_limited")


def _attach_certificate(result: SetupCoverResult, milp_res: MilpResult | None, method: str) -> None:
    """The MILP value is a certificate only when HiGHS proved it; otherwise its status and dual
    bound are reported and no certificate is claimed."""
    if milp_res is None:
        return
    result.certificate_status = milp_res.status
    result.certificate_bound = milp_res.dual_bound
    result.certificate_seconds = milp_res.seconds
    result.certificate_proof = milp_res.proof
    if not milp_res.optimal:
        return
    result.certificate_cost = milp_res.cost
    if method in ("both", "auto") and math.isfinite(result.cost):
        ref = milp_res.cost
        result.certificate_gap = 0.0 if result.cost == ref else (result.cost - ref) / ref if ref > 0 else math.inf

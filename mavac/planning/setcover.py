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
Remove dominated setups first with :func:`mavac.setups.dominance.nondominated`, as the paper
does (Section IV); the planner itself solves the problem it is given.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import csr_array

from ..params import SetupPlannerParams
from ..validate import check_cover
from .iess import initial_estimate_of_setup_size, n_repeat_recommended, row_bitsets

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


def _check_costs(setup_costs, m: int) -> np.ndarray:
    costs = np.asarray(setup_costs, dtype=float)
    if costs.shape != (m,):
        raise ValueError(f"setup_costs must have shape ({m},), got {costs.shape}")
    if not np.all(np.isfinite(costs)) or np.any(costs <= 0):
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
    masks: list  # m Python ints, bit g set when setup j covers group g
    groups_setups: list  # per group, the setups covering it (ascending)
    uncoverable: np.ndarray  # (u,) int, patches no setup covers


def _compress(cover: np.ndarray, area: np.ndarray) -> _Compressed:
    m, _ = cover.shape
    coverable = cover.any(axis=0)
    uncoverable = np.flatnonzero(~coverable)
    cols = cover[:, coverable].T
    if cols.shape[0] == 0:
        return _Compressed(np.zeros((m, 0), bool), np.zeros(0), [0] * m, [], uncoverable)
    uniq, first, inverse = np.unique(cols, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    group_area = np.bincount(rank[inverse.ravel()], weights=area[coverable], minlength=len(order))
    ccover = np.ascontiguousarray(uniq[order].T)
    masks = row_bitsets(ccover)
    groups_setups = [np.flatnonzero(ccover[:, g]).tolist() for g in range(ccover.shape[1])]
    return _Compressed(ccover, group_area, masks, groups_setups, uncoverable)


def _bits_to_bool(bits: int, k: int) -> np.ndarray:
    raw = np.frombuffer(bits.to_bytes(max(1, -(-k // 8)), "little"), dtype=np.uint8)
    return np.unpackbits(raw, bitorder="little", count=k).astype(bool)


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
    iess : int or None
        Algorithm 5's estimate (Algorithm 4 only).
    n_repeat : int or None
        ``N_repeat`` used by Algorithm 5.
    uncoverable : (u,) int
        Patches no setup covers; left out of ``P``.
    node_limited : bool
        True when the ``max_nodes`` budget ended the search.
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


def dfbnb_setup_cover(cover, setup_costs, *, patch_area=None,
                      params: SetupPlannerParams | None = None) -> DFBnBResult:
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
        ``t_max``, ``t_decay``/``t_decay_rate``, ``n_repeat``/``iess_prob``, ``seed``.

    Returns
    -------
    DFBnBResult

    Notes
    -----
    One node is one call AddSetUp(P_r, S_u, S_curr), run in this order:

    1. abort when the elapsed time exceeds T_max (checked at every node);
    2. (Algorithm 4) return when ``|S_curr| > IESS``;
    3. when ``P_r`` is empty: keep ``S_curr`` if ``T(S_curr) <= T*``, return;
    4. (pruning) return when ``T(S_curr) + bound + T_decay >= T*``, bound = min (eq. 2) or max
       (eq. 7) of ``c_j`` over ``S_u``, ``T_decay`` only for Algorithm 4;
    5. if a patch of ``P_r`` is covered by a single setup of ``S_u``, branch on that setup only
       (the lowest such patch decides); otherwise branch on every ``s`` in ``S_u``, sorted by
       decreasing cleaning rate ``R_j`` on ``P_r`` (guiding, ties by index) or by index.

    The children of a node are all unused setups, so a set is met in several orders, as in
    the paper whose node counts (Tables V-VI) measure that tree. Patches no setup covers are
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
    comp = _compress(c, area)
    deadline = math.inf if params.t_max is None else t0 + params.t_max

    iess = n_repeat = None
    if params.algorithm == 4:
        n_repeat = _n_repeat(params, m)
        iess = initial_estimate_of_setup_size(
            comp.cover, n_repeat, seed=params.seed,
            deadline=None if params.t_max is None else deadline)
    depth_cap = m if iess is None else iess

    best, best_cost, nodes, timed_out, node_limited = _search(comp, costs, params, deadline, depth_cap)
    if best_cost < math.inf:
        best_cost = math.fsum(float(costs[j]) for j in best)
    return DFBnBResult(
        setups=np.array(best, dtype=np.int64), cost=best_cost, node_expansions=nodes,
        seconds=time.perf_counter() - t0, timed_out=timed_out, iess=iess, n_repeat=n_repeat,
        uncoverable=comp.uncoverable, node_limited=node_limited)


def _search(comp: _Compressed, costs: np.ndarray, params: SetupPlannerParams, deadline: float,
            depth_cap: int) -> tuple[tuple, float, int, bool, bool]:
    """The depth-first search of :func:`dfbnb_setup_cover` (steps 1-5 of its Notes).

    Returns ``(S*, T(S*) as summed along the branch, node expansions, timed out, node limited)``.
    """
    m, k = comp.cover.shape
    full = (1 << k) - 1
    cost_list = costs.tolist()
    masks = comp.masks
    cover_f = comp.cover.astype(float)
    lower = params.bound == "lb"
    decay = params.algorithm == 4 and params.t_decay > 0

    best_cost = math.inf
    best: tuple = ()
    nodes = 0
    timed_out = node_limited = False
    max_nodes = math.inf if params.max_nodes is None else params.max_nodes
    # (P_r, S_u as a bitmask over setups, S_curr, T(S_curr))
    stack = [(full, (1 << m) - 1, (), 0.0)]
    while stack:
        if nodes >= max_nodes:
            node_limited = True
            break
        p_r, s_u, s_curr, t_curr = stack.pop()
        nodes += 1
        if time.perf_counter() > deadline:  # step 1
            timed_out = True
            break
        if len(s_curr) > depth_cap:  # Algorithm 4, step 2
            continue
        if p_r == 0:  # steps 2-3 (Alg. 2), 3-4 (Alg. 4)
            if t_curr <= best_cost:
                best_cost, best = t_curr, s_curr
            continue
        unused = [j for j in range(m) if s_u >> j & 1]
        if params.pruning:  # step 4 (Alg. 2), 5 (Alg. 4)
            unused_costs = [cost_list[j] for j in unused]
            bound = min(unused_costs) if lower else max(unused_costs)
            if decay:
                bound += params.t_decay * math.exp(min(700.0, params.t_decay_rate * nodes))
            if t_curr + bound >= best_cost:
                continue
        # Step 5: a patch reachable from a single unused setup forces that setup.
        once = twice = 0
        for j in unused:
            twice |= once & masks[j]
            once |= masks[j]
        single = p_r & ~twice
        if single:
            g = (single & -single).bit_length() - 1
            forced = next(j for j in comp.groups_setups[g] if s_u >> j & 1)
            children = [forced]
        elif params.guiding:
            rem_area = comp.area * _bits_to_bool(p_r, k)
            gain = cover_f @ rem_area
            children = sorted(unused, key=lambda j: (-gain[j] / cost_list[j], j))
        else:
            children = unused
        for j in reversed(children):
            stack.append((p_r & ~masks[j], s_u & ~(1 << j), s_curr + (j,), t_curr + cost_list[j]))

    return best, best_cost, nodes, timed_out, node_limited


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
        "optimal", "time_limit" (feasible, not proven) or HiGHS' message otherwise.
    optimal : bool
    seconds : float
    uncoverable : (u,) int
        Patches no setup covers, dropped from the constraints.
    """

    setups: np.ndarray
    cost: float
    status: str
    optimal: bool
    seconds: float
    uncoverable: np.ndarray


def milp_setup_cover(cover, setup_costs, time_limit: float | None = None) -> MilpResult:
    """Exact weighted set cover: ``min c.x  s.t.  cover^T x >= 1,  x in {0, 1}^m`` (HiGHS).

    Parameters
    ----------
    cover : (m, n) bool
    setup_costs : (m,) float, s, > 0
    time_limit : float, optional
        Seconds given to HiGHS; None for no limit.

    Returns
    -------
    MilpResult
        The relative MIP gap is set to 0, so "optimal" is a certificate.
    """
    t0 = time.perf_counter()
    c = check_cover(cover)
    m, n = c.shape
    costs = _check_costs(setup_costs, m)
    if time_limit is not None and not (time_limit > 0):
        raise ValueError(f"time_limit must be > 0 s or None, got {time_limit!r}")
    comp = _compress(c, np.ones(n))
    if comp.cover.shape[1] == 0:
        return MilpResult(np.zeros(0, np.int64), 0.0, "optimal", True,
                          time.perf_counter() - t0, comp.uncoverable)
    a = csr_array(comp.cover.T.astype(float))
    options = {"mip_rel_gap": 0.0}
    if time_limit is not None and math.isfinite(time_limit):
        options["time_limit"] = float(time_limit)
    res = milp(c=costs, constraints=LinearConstraint(a, lb=1.0, ub=np.inf),
               integrality=np.ones(m), bounds=Bounds(0.0, 1.0), options=options)
    if res.x is None:
        return MilpResult(np.zeros(0, np.int64), math.inf, str(res.message), False,
                          time.perf_counter() - t0, comp.uncoverable)
    chosen = np.flatnonzero(res.x > 0.5)
    status = {0: "optimal", 1: "time_limit"}.get(res.status, str(res.message))
    return MilpResult(chosen.astype(np.int64), math.fsum(costs[chosen].tolist()), status,
                      res.status == 0, time.perf_counter() - t0, comp.uncoverable)


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
        ``T(S) = sum_j (t_s + t_e_j)`` (eq. 1), s; 0 for an empty stain, ``inf`` when the
        search stopped before any cover.
    step_costs : (k,) float, s
        ``c_j`` of each step.
    step_area : (k,) float, m^2
        Area first cleaned at each step.
    setup_time_total, execution_time_total : float or None
        Split of ``cost`` when the setup time was given.
    method : str
        "milp", "dfbnb" or "both" (the plan is then DFBnB's).
    status : str
        "optimal" (MILP, or DFBnB Algorithm 2 with eq. 2 run to the end), "converged"
        (Algorithm 4 or eq. 7 run to the end: heuristic, see ``certificate_gap``), "timed_out"
        (best found before T_max), "no_solution" (T_max hit before any cover), "empty"
        (nothing to cover); for "milp" also "time_limit" or HiGHS' message.
    node_expansions : int
        DFBnB nodes (0 for "milp").
    seconds : float
        Time of the method that produced the plan.
    timed_out : bool
    uncoverable : (u,) int
        Patches no candidate setup covers (the plan cannot clean them).
    iess : int or None
        Algorithm 5's estimate (Algorithm 4).
    certificate_cost : float or None
        MILP optimum (method "both", or "milp").
    certificate_gap : float or None
        ``(cost - certificate_cost) / certificate_cost`` (method "both").
    certificate_seconds : float or None
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


def solve_setup_cover(cover, setup_costs, *, patch_area=None,
                      params: SetupPlannerParams | None = None, method: str = "milp",
                      setup_time=None) -> SetupCoverResult:
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
        DFBnB settings; ``t_max`` also bounds the MILP.
    method : {"milp", "dfbnb", "both"}
        "both" returns DFBnB's plan with the MILP optimum as certificate.
    setup_time : float or (m,) float, s, optional
        The ``t_s`` part of ``setup_costs``, only to split the cost in the result.

    Returns
    -------
    SetupCoverResult
    """
    params = SetupPlannerParams() if params is None else params
    if method not in ("milp", "dfbnb", "both"):
        raise ValueError(f"method must be 'milp', 'dfbnb' or 'both', got {method!r}")
    c = check_cover(cover)
    m, n = c.shape
    costs = _check_costs(setup_costs, m)
    area = _area_or_ones(patch_area, n)
    ts = None
    if setup_time is not None:
        ts = np.broadcast_to(np.asarray(setup_time, dtype=float), (m,))
        if not np.all(np.isfinite(ts)) or np.any(ts < 0) or np.any(ts > costs):
            raise ValueError("setup_time must be finite, >= 0 and <= setup_costs")

    milp_res = None
    if method in ("milp", "both"):
        milp_res = milp_setup_cover(c, costs, time_limit=params.t_max)
    if method == "milp":
        chosen, cost, seconds = milp_res.setups, milp_res.cost, milp_res.seconds
        nodes, timed_out, iess = 0, milp_res.status == "time_limit", None
        uncoverable = milp_res.uncoverable
        status = milp_res.status
    else:
        dfb = dfbnb_setup_cover(c, costs, patch_area=area, params=params)
        chosen, cost, seconds = dfb.setups, dfb.cost, dfb.seconds
        nodes, timed_out, iess = dfb.node_expansions, dfb.timed_out, dfb.iess
        uncoverable = dfb.uncoverable
        # Only Algorithm 2 with eq. 2 is exact; Algorithm 4 and eq. 7 are heuristics.
        exact = params.algorithm == 2 and params.bound == "lb"
        status = "optimal" if exact else "converged"
        if timed_out:
            status = "timed_out" if math.isfinite(cost) else "no_solution"
    if len(uncoverable) == n:
        status = "empty"

    order = execution_order(c, costs, chosen, area) if len(chosen) else np.zeros(0, np.int64)
    rem = np.ones(n, dtype=bool)
    step_area = []
    for j in order:
        step_area.append(float(area[c[j] & rem].sum()))
        rem &= ~c[j]
    result = SetupCoverResult(
        setups=order, cost=float(cost), step_costs=costs[order], step_area=np.array(step_area),
        setup_time_total=None if ts is None else math.fsum(ts[order].tolist()),
        execution_time_total=None if ts is None else math.fsum((costs - ts)[order].tolist()),
        method=method, status=status, node_expansions=int(nodes), seconds=float(seconds),
        timed_out=bool(timed_out), uncoverable=np.asarray(uncoverable, dtype=np.int64), iess=iess)
    if milp_res is not None:
        result.certificate_cost = milp_res.cost
        result.certificate_seconds = milp_res.seconds
    if method == "both" and milp_res.optimal:
        ref = milp_res.cost
        result.certificate_gap = 0.0 if cost == ref else (cost - ref) / ref if ref > 0 else math.inf
    return result

"""RRT-Connect (Kuffner and LaValle 2000) through OMPL 2.0.1's Python bindings.

MAVAC ("Trajectory generation") plans the arm's approach motions with RRT-connect from the
Open Motion Planning Library. This wrapper plans in a box of joint space
``[lower, upper]`` with any Python validity function (e.g.
``lambda q: not checker.in_collision(q)``), simplifies the path and interpolates it at the
motion-checking resolution, so consecutive states are at most ``resolution x`` the box
diagonal apart and every returned state has been declared valid.

Determinism: OMPL gives every RNG instance a seed drawn from one process-wide seed
generator. Each call re-seeds that generator (``ou.RNG.setSeed``) before allocating the
space, planner and simplifier, and RRT-Connect stops at its first solution and the
simplifier runs to convergence (``simplifyMax``, no time budget), so the same inputs and
seed give the same path bit for bit. The search stops after ``max_iterations`` evaluations of
its termination condition (RRT-Connect evaluates it once per sample: one iteration of its main
loop), so whether a problem is solved does not depend on the machine's speed either. The
wall-time ``time_limit`` is only a safety net against a hung validity check: when it fires
before the budget is spent, the call raises :class:`PlanningTimeout` instead of returning a
failure, so no result ever depends on the machine's load.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..validate import check_bounds, check_int, check_range


class PlanningTimeout(RuntimeError):
    """The wall-time safety cap of :func:`plan_rrt_connect` fired before its iteration budget
    was spent. Not a planning failure: the answer would depend on the machine's load, so there
    is none. Raise the cap (it should never bind) or look for a slow validity check."""


@dataclass
class PlanResult:
    """Outcome of :func:`plan_rrt_connect`.

    Attributes
    ----------
    path : (k, nq) float or None
        Joint-space waypoints from ``q_start`` to ``q_goal`` (inclusive), None if unsolved.
    solved : bool
        True iff OMPL found an exact solution.
    seconds : float
        Wall time of the whole call (setup, solve, simplify, interpolate), s.
    reason : str
        ``"solved"``, ``"invalid start"``, ``"invalid goal"``, ``"iteration budget exhausted"``,
        or OMPL's status otherwise (never ``"Timeout"``: the time cap raises).
    """

    path: np.ndarray | None
    solved: bool
    seconds: float
    reason: str = "solved"


def _check_box(lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """The configuration box: finite 1-D ``lower < upper``."""
    lo, hi = check_bounds("lower/upper", lower, upper)
    if lo.ndim != 1 or lo.size == 0:
        raise ValueError(f"lower and upper must be 1-D arrays with nq >= 1 entries, got shape {lo.shape}")
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise ValueError("lower and upper must be finite")
    if np.any(lo == hi):
        raise ValueError(f"lower/upper: empty interval at index {np.flatnonzero(lo == hi).tolist()}")
    return lo, hi


def _check_config(name: str, q, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    a = np.asarray(q, dtype=float)
    if a.shape != lower.shape:
        raise ValueError(f"{name} must have shape {lower.shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    outside = np.flatnonzero((a < lower) | (a > upper))
    if outside.size:
        raise ValueError(f"{name} is outside [lower, upper] at index {outside.tolist()}")
    return a


def plan_rrt_connect(
    is_valid,
    q_start,
    q_goal,
    lower,
    upper,
    *, time_limit: float = 600.0,
    seed: int = 0,
    resolution: float = 0.01,
    max_iterations: int = 5_000,
) -> PlanResult:
    """Plan a valid joint-space path with OMPL's RRT-Connect.

    Parameters
    ----------
    is_valid : callable
        ``is_valid(q: (nq,) float ndarray) -> bool``. An exception raised inside it is
        re-raised after OMPL returns (OMPL itself only sees "invalid").
    q_start, q_goal : (nq,) float
        Start and goal configurations, inside ``[lower, upper]``.
    lower, upper : (nq,) float
        Box of the configuration space (e.g. joint limits); ``lower < upper``.
    time_limit : float, s
        Wall-time safety net of the search, > 0 (simplification is not counted in it). It never
        decides the result: if it fires before ``max_iterations`` are spent, the call raises
        :class:`PlanningTimeout`. Ours, 600 s: ten times the slowest search we measured (30,000
        unsolvable UR10 iterations against a machine took 34-59 s on a loaded 2-core machine),
        so it only fires on a hang or a far slower computer.
    seed : int, >= 0
        Seed of OMPL's random generators for this call.
    resolution : float
        Motion-validation step as a fraction of the box diagonal, in (0, 1]
        (OMPL's longest valid segment fraction); also the spacing of the returned path.
    max_iterations : int, >= 1
        Deterministic budget: the search stops after this many evaluations of OMPL's
        termination condition (one per RRT-Connect iteration, i.e. per random sample).

    Returns
    -------
    PlanResult
        ``path (k, nq)`` or None, ``solved``, ``seconds``, ``reason``.

    Raises
    ------
    PlanningTimeout
        When ``time_limit`` elapsed before the search solved or spent ``max_iterations``.
    """
    t0 = time.perf_counter()
    if not callable(is_valid):
        raise ValueError("is_valid must be callable: is_valid(q) -> bool")
    lo, hi = _check_box(lower, upper)
    qs = _check_config("q_start", q_start, lo, hi)
    qg = _check_config("q_goal", q_goal, lo, hi)
    check_range("time_limit", time_limit, 0.0, np.inf, lo_open=True)
    seed = check_int("seed", seed, 0, 2**31 - 2)
    check_range("resolution", resolution, 0.0, 1.0, lo_open=True)
    max_iterations = check_int("max_iterations", max_iterations, 1)

    # Checked here so the reason is explicit (OMPL would only report "Invalid start").
    if not is_valid(qs.copy()):
        return PlanResult(None, False, time.perf_counter() - t0, "invalid start")
    if not is_valid(qg.copy()):
        return PlanResult(None, False, time.perf_counter() - t0, "invalid goal")
    return _solve_with_ompl(is_valid, qs, qg, lo, hi, float(time_limit), seed, float(resolution), max_iterations,
                            t0)


def _solve_with_ompl(is_valid, qs, qg, lo, hi, time_limit, seed, resolution, max_iterations, t0) -> PlanResult:
    """RRT-Connect on checked inputs: seeded OMPL setup, iteration-bounded solve, simplify,
    interpolate (see the module docstring for the determinism)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    dim = lo.size
    previous_level = ou.getLogLevel()
    # Re-seeding after the first RNG exists is intended here; silence OMPL's error about it.
    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(seed + 1)  # OMPL ignores seed 0
    ou.setLogLevel(ou.LOG_WARN)
    try:
        space = ob.RealVectorStateSpace(0)
        for a, b in zip(lo, hi):
            space.addDimension(float(a), float(b))
        space.setLongestValidSegmentFraction(float(resolution))
        si = ob.SpaceInformation(space)

        errors: list[BaseException] = []

        def checker(state) -> bool:
            if errors:
                return False
            try:
                return bool(is_valid(np.array(state[0:dim])))
            except Exception as exc:  # surfaced after solve(); OMPL cannot carry it
                errors.append(exc)
                return False

        si.setStateValidityChecker(checker)
        si.setup()
        ss = og.SimpleSetup(si)
        ss.setPlanner(og.RRTConnect(si))
        start, goal = space.allocState(), space.allocState()
        for i in range(dim):
            start[i] = float(qs[i])
            goal[i] = float(qg[i])
        ss.setStartAndGoalStates(start, goal)
        # OMPL evaluates the condition once per RRT-Connect iteration (``while (!ptc)``); the
        # count makes the stop deterministic, the deadline is only the safety net (it raises).
        calls = [0]
        deadline = time.perf_counter() + float(time_limit)

        def out_of_iterations() -> bool:
            calls[0] += 1
            return calls[0] > max_iterations

        ptc = ob.plannerOrTerminationCondition(ob.PlannerTerminationCondition(out_of_iterations),
                                               ob.PlannerTerminationCondition(lambda: time.perf_counter() > deadline))
        status = ss.solve(ptc)
        if errors:
            raise errors.pop()  # pop: no cycle exception -> traceback -> checker -> errors
        if not ss.haveExactSolutionPath():
            if calls[0] <= max_iterations and time.perf_counter() > deadline:
                raise PlanningTimeout(
                    f"RRT-Connect hit its wall-time safety cap time_limit={time_limit:g} s after "
                    f"{calls[0]} of max_iterations={max_iterations} iterations; the iteration budget, "
                    f"not the clock, must end the search (raise time_limit)")
            reason = "iteration budget exhausted" if calls[0] > max_iterations else status.asString()
            return PlanResult(None, False, time.perf_counter() - t0, reason)
        ss.simplifySolution()  # duration 0 -> simplifyMax: deterministic, no time budget
        if errors:
            raise errors.pop()
        path = ss.getSolutionPath()
        path.interpolate()  # at the longest-valid-segment resolution
        q = np.array([s[0:dim] for s in path.getStates()], dtype=float)
    finally:
        ou.setLogLevel(previous_level)
    return PlanResult(q, True, time.perf_counter() - t0, "solved")

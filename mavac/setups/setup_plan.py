"""``plan_setups``: from a stained part to an ordered setup plan (Kabir et al. 2017, III-V).

part + stain -> IK targets -> candidate setups (uniform / hierarchical / random sampling with
gradient descent, counted in n_rfc) -> non-dominated setups -> setup costs (eq. 1:
``t_s + t_e``, with ``t_e = sum(area x passes) / cleaning_rate``) -> set-cover planner
(DFBnB and/or the MILP certificate) -> setups in execution order with the patches each cleans.
Patches that no candidate setup reaches are listed, never searched for.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings as _warnings
from dataclasses import dataclass, field

import numpy as np

from ..geometry.stain_marking import oversized_patches
from ..io import write_json
from ..params import SetupPlanParams
from ..planning.setcover import (
    execution_time_area_passes,
    setup_costs_from_times,
    solve_setup_cover,
)
from ..robots.models import puma560
from ..validate import check_callable
from .reach import CountingReach, FeasibleReach, PartReach, patch_reach, reach_targets
from .sampling import hierarchical_sampling, random_sampling, uniform_sampling
from .space import pedestal_clear
from .unreachable import unreachable_causes, unreachable_message
from .viewer import setup_plan_html


def _finite(value) -> float | None:
    """``value`` as a float for JSON, None when absent, infinite or NaN (the status says why)."""
    return float(value) if value is not None and math.isfinite(value) else None


@dataclass
class SetupPlan:
    """An ordered setup plan for one part.

    Attributes
    ----------
    part_name : str
    setups : (k, 3) float
        ``(x [m], y [m], alpha [rad])`` of each setup, in execution order (see
        :class:`mavac.params.SetupSpaceParams` for where the space sits).
    patches : list of (k_j,) int
        Patches (indices into the part's stain) cleaned at each step: those the setup reaches
        that no earlier step cleaned.
    reachable : list of (r_j,) int
        Every patch each setup reaches.
    step_costs : (k,) float, s
        ``t_s + t_e(tau_j)`` per setup (eq. 1).
    cost : float, s
        ``T(S)``, the plan's total time (0 for an empty stain).
    setup_time_total, execution_time_total : float, s
        The two parts of ``cost``.
    node_expansions : int
        DFBnB nodes (0 when only the MILP ran).
    n_rfc : int
        Reach-test calls spent on the candidates (Kabir Sec. IX-A1).
    candidates : int
        Candidate setups found by sampling (distinct).
    nondominated : int
        Candidates left after dominance elimination (the planner's input).
    certificate_cost : float or None
        Proven optimum of the same instance; None when there is no solution, no proof within
        the node budgets, or only DFBnB ran.
    certificate_gap : float or None
        ``(cost - certificate_cost) / certificate_cost``; 0 means the plan is proven optimal
        over the candidates; None without a certificate.
    status : str
        The planner's status ("optimal", "converged", "timed_out", "node_limited", "no_solution",
        "empty"; see :class:`mavac.planning.setcover.SetupCoverResult`).
    uncoverable : (u,) int
        Patches no candidate setup reaches (not in the plan).
    seconds : float
        Wall time of the whole call.
    uncoverable_causes : (u,) str
        Likely cause for each uncoverable patch (:data:`mavac.setups.unreachable.CAUSES`).
    warnings : list of str
        What the user should know: unreachable share of the stain and why, oversized patches.
    method : str
        The planner method (:data:`mavac.planning.setcover.SETUP_COVER_METHODS`).
    certificate_bound : float or None, s
        Proven lower bound on the optimum.
    certificate_proof : str or None
        What proved the optimum: "reduction", "enumeration", "lp" or "milp".
    collision_refused : int
        Patches left out (in ``uncoverable``) that the IK reaches from a sampled setup only with
        the arm through the part or its table (0 without the reach test's collision check).
    """

    part_name: str
    setups: np.ndarray
    patches: list
    reachable: list
    step_costs: np.ndarray
    cost: float
    setup_time_total: float
    execution_time_total: float
    node_expansions: int
    n_rfc: int
    candidates: int
    nondominated: int
    certificate_cost: float | None
    certificate_gap: float | None
    status: str
    uncoverable: np.ndarray
    seconds: float
    uncoverable_causes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U18"))
    warnings: list = field(default_factory=list)
    method: str = "auto"
    certificate_bound: float | None = None
    certificate_proof: str | None = None
    collision_refused: int = 0

    def to_dict(self, timings: bool = False) -> dict:
        """Plain-JSON description: setups in order with their patches, costs, certificate, warnings.

        Wall time is left out unless asked for, so the same seed gives the same file.
        """
        out = {
            "part": self.part_name, "status": self.status, "method": self.method,
            "cost_s": _finite(self.cost), "setup_time_s": float(self.setup_time_total),
            "execution_time_s": float(self.execution_time_total),
            "certificate_cost_s": _finite(self.certificate_cost), "certificate_gap": _finite(self.certificate_gap),
            "certificate_bound_s": _finite(self.certificate_bound),
            "certificate_proof": self.certificate_proof,
            "n_rfc": int(self.n_rfc), "candidates": int(self.candidates), "nondominated": int(self.nondominated),
            "node_expansions": int(self.node_expansions),
            "setups": [{"x": float(s[0]), "y": float(s[1]), "alpha": float(s[2]), "step_cost_s": float(c),
                        "patches": [int(i) for i in p], "reachable": [int(i) for i in r]}
                       for s, c, p, r in zip(self.setups, self.step_costs, self.patches, self.reachable)],
            "uncoverable": [int(i) for i in self.uncoverable],
            "collision_refused": int(self.collision_refused),
            "uncoverable_causes": [str(c) for c in self.uncoverable_causes],
            "warnings": list(self.warnings),
        }
        if timings:
            out["seconds"] = float(self.seconds)
        return out

    @property
    def found(self) -> bool:
        """Whether there is a plan: the stain is empty or setups of finite cost cover it."""
        return self.status == "empty" or (len(self.setups) > 0 and math.isfinite(self.cost))

    def to_json(self, path, timings: bool = False):
        """Write :meth:`to_dict` atomically as JSON."""
        return write_json(self.to_dict(timings=timings), path)

    def to_html(self, path, part, robot=None, params=None):
        """Meshcat page of the plan on ``part`` (:func:`mavac.setups.viewer.setup_plan_html`)."""
        return setup_plan_html(self, part, path, robot=robot, params=params)

    def _certificate_lines(self) -> list:
        """What is proven about the plan's cost."""
        if self.status in ("no_solution", "empty") or self.method == "dfbnb":
            return []
        if self.certificate_cost is None:
            bound = "none" if self.certificate_bound is None else f"{self.certificate_bound:.1f} s"
            return [f"  NOT PROVEN OPTIMAL: the node budgets ran out; proven lower bound {bound}"]
        if self.method != "both":
            return [f"  proven optimal (by {self.certificate_proof})"]
        proven = f"the proven optimum {self.certificate_cost:.1f} s (by {self.certificate_proof})"
        if self.certificate_gap == 0:
            return [f"  DFBnB's plan is {proven}"]
        where = "with no plan, against" if self.certificate_gap is None else \
            f"at {self.cost:.1f} s, {100 * self.certificate_gap:.2f} % above"
        return [f"  DFBnB stopped ({self.status}) {where} {proven}; method 'auto' plans the optimum"]

    def summary(self) -> str:
        """A few lines a person can read."""
        if self.status == "no_solution":
            lines = [f"{self.part_name}: NO SOLUTION: none of {self.candidates} candidate setups reaches any "
                     f"stain patch (n_rfc {self.n_rfc}); no plan, no cost, no certificate"]
        elif not self.found:
            lines = [f"{self.part_name}: NO SOLUTION: the search stopped ({self.status}) after "
                     f"{self.node_expansions} nodes before finding any plan"]
        else:
            lines = [f"{self.part_name}: {len(self.setups)} setups, T = {self.cost:.1f} s "
                     f"(setup {self.setup_time_total:.1f} s + execution {self.execution_time_total:.1f} s), "
                     f"status {self.status}, n_rfc {self.n_rfc}, {self.nondominated} non-dominated of "
                     f"{self.candidates} candidates, {self.node_expansions} DFBnB nodes"]
        lines += self._certificate_lines()
        for j, (s, p) in enumerate(zip(self.setups, self.patches)):
            lines.append(f"  setup {j + 1}: x = {s[0]:.3f} m, y = {s[1]:.3f} m, "
                         f"alpha = {math.degrees(s[2]):.1f} deg, {len(p)} patches")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def plan_setups(part, *, robot=None, params: SetupPlanParams | None = None, feasible=None) -> SetupPlan:
    """Plan the setups that clean a part's stain (Kabir et al. 2017).

    Parameters
    ----------
    part : Part
        Anything with ``patch_vertices (n, 3, 3)``, ``patch_normals (n, 3)``,
        ``patch_areas (n,)``, ``passes (n,)`` (part frame, metres) and ``name``; ``mesh`` too
        when ``params.reach.check_collision``. See :func:`mavac.geometry.parts.load_part` and
        :func:`mavac.geometry.parts.part_from_mesh`.
    robot : RobotModel, optional
        Default ``puma560(tool_length=params.reach.tool_length)``; its base frame is where
        :class:`mavac.params.SetupSpaceParams` places the part.
    params : SetupPlanParams, optional
    feasible : callable, optional
        ``feasible(setups (k, 3)) -> (k,) bool``: setups that exist at all (e.g. the holding
        arm of a two-arm cell can present the part there, :class:`mavac.scrubbing.holding.HeldSetups`);
        the others reach nothing and are dropped, and a warning says how many.

    Returns
    -------
    SetupPlan

    Notes
    -----
    Hierarchical sampling refines until every patch is covered; a patch that no setup can reach
    keeps it refining up to ``params.sampling.max_levels`` levels, after which the patch is
    listed in ``SetupPlan.uncoverable``.
    """
    t0 = time.perf_counter()
    params = SetupPlanParams() if params is None else params
    if not isinstance(params, SetupPlanParams):
        raise ValueError(f"params must be a SetupPlanParams, got {type(params).__name__}")
    name = str(getattr(part, "name", "part"))
    vertices = np.asarray(part.patch_vertices, dtype=float).reshape(-1, 3, 3)
    normals = np.asarray(part.patch_normals, dtype=float).reshape(-1, 3)
    area = np.asarray(part.patch_areas, dtype=float).reshape(-1)
    passes = np.asarray(part.passes).reshape(-1)
    n = len(vertices)
    if not (len(normals) == len(area) == len(passes) == n):
        raise ValueError(f"part: patch_vertices, patch_normals, patch_areas and passes must have the same "
                         f"length, got {n}, {len(normals)}, {len(area)}, {len(passes)}")
    if n == 0:
        return _empty_plan(name, time.perf_counter() - t0)
    notes = [m for m in (oversized_patches(area),) if m]  # patches larger than the tool tip
    if robot is None:
        robot = puma560(tool_length=params.reach.tool_length)
    mesh = getattr(part, "mesh", None) if params.reach.check_collision else None
    live = PartReach(robot, reach_targets(vertices, normals), params.space, params=params.reach, part_mesh=mesh)
    tests = [t for t in (_pedestal(robot, part, vertices, params.space), feasible) if t is not None]
    reach_fn = _reach_fn(live, tests)
    reach = CountingReach(reach_fn)
    sampled = _sample(reach, params)
    cover = sampled.nondominated_cover
    setups = sampled.nondominated_setups
    notes += _dropped_notes(reach_fn, reach.n_rfc)
    if len(setups) == 0:
        refused, notes = _refused_note(live, sampled.setups, np.arange(n), tests, notes)
        causes, notes = _left_out(np.arange(n), vertices, normals, area, robot, params, live, notes)
        plan = _no_solution(name, reach.n_rfc, len(sampled.setups), causes, notes, vertices, time.perf_counter() - t0)
        plan.collision_refused = refused
        return plan

    res = _solve(cover, area, passes, params)
    patches, reachable = _patches_per_step(cover, res.setups)
    uncoverable = np.asarray(res.uncoverable, dtype=np.int64)
    refused, notes = _refused_note(live, sampled.setups, uncoverable, tests, notes)
    causes, notes = _left_out(uncoverable, vertices, normals, area, robot, params, live, notes)
    _warn_all(notes)
    return SetupPlan(
        part_name=name, setups=setups[res.setups], patches=patches, reachable=reachable,
        step_costs=res.step_costs, cost=res.cost, setup_time_total=res.setup_time_total or 0.0,
        execution_time_total=res.execution_time_total or 0.0, node_expansions=res.node_expansions,
        n_rfc=reach.n_rfc, candidates=len(sampled.setups), nondominated=len(setups),
        certificate_cost=res.certificate_cost, certificate_gap=res.certificate_gap, status=res.status,
        uncoverable=uncoverable, seconds=time.perf_counter() - t0, uncoverable_causes=causes, warnings=notes,
        method=params.method, certificate_bound=res.certificate_bound, certificate_proof=res.certificate_proof,
        collision_refused=refused)


def _solve(cover, area, passes, params: SetupPlanParams):
    """Eq. 1 costs of the candidates and the planner's answer (:func:`solve_setup_cover`)."""
    t_s = params.planner.setup_time
    costs = setup_costs_from_times(execution_time_area_passes(cover, area, passes, params.cleaning_rate), t_s)
    return solve_setup_cover(cover, costs, patch_area=area, params=params.planner, method=params.method,
                             setup_time=t_s, patch_time=area * passes / params.cleaning_rate, certify=params.certify)


def _patches_per_step(cover, order):
    """Patches each step cleans first, and every patch each step reaches."""
    done = np.zeros(cover.shape[1], dtype=bool)
    patches, reachable = [], []
    for j in order:
        reachable.append(np.flatnonzero(cover[j]))
        patches.append(np.flatnonzero(cover[j] & ~done))
        done |= cover[j]
    return patches, reachable


def _sample(reach, params: SetupPlanParams):
    """Candidate setups by the configured sampling method, counted in ``reach.n_rfc``."""
    if params.sampling_method == "uniform":
        return uniform_sampling(reach, params.space)
    if params.sampling_method == "hierarchical":
        return hierarchical_sampling(reach, params.space, params.sampling, variant=params.variant)
    return random_sampling(reach, params.space, params.sampling, variant=params.variant, seed=params.seed)


def _pedestal(robot, part, vertices, space):
    """The pedestal test of the part's placements (footprint of its mesh, else of its stain)."""
    mesh = getattr(part, "mesh", None)
    return pedestal_clear(robot, vertices if mesh is None else mesh.vertices, space)


def _reach_fn(live, tests):
    """The part's reach test, reaching nothing from setups one of ``tests`` refuses (each a
    :class:`FeasibleReach` layer, so each counts what it refused)."""
    reach_fn = live
    for test in tests:
        reach_fn = FeasibleReach(reach_fn, check_callable("feasible", test, "(setups (k, 3)) -> (k,) bool"))
    return reach_fn


def _refused_note(live, setups, uncoverable, tests, notes):
    """:func:`_collision_refused` and the warning list with a line saying it (when not 0)."""
    refused = _collision_refused(live, setups, uncoverable, tests)
    if refused:
        notes = notes + [f"{refused} stain patches refused: the arm reaches them (IK) only by passing through the "
                         "part or its table (collision check of the reach test)"]
    return refused, notes


def _collision_refused(live, setups, uncoverable, tests) -> int:
    """Patches left out that the IK alone reaches from a sampled setup (the pedestal and
    feasibility tests still apply): those only a colliding arm reaches. 0 without collision."""
    if not live.params.check_collision or len(uncoverable) == 0 or len(setups) == 0:
        return 0
    for test in tests:
        setups = setups[np.asarray(test(setups), dtype=bool)]
    if len(setups) == 0:
        return 0
    ik_only = dataclasses.replace(live.params, check_collision=False)
    sub = reach_targets(live.targets.positions[live.targets.patch_targets[uncoverable]],
                        -live.targets.axes[live.targets.patch_targets[uncoverable, 0]])
    return int(patch_reach(live.robot, sub, setups, live.space, params=ik_only).any(axis=0).sum())


def _dropped_notes(reach_fn, n_rfc: int) -> list:
    """One line per feasibility layer that refused sampled setups: how many and why."""
    notes = []
    while isinstance(reach_fn, FeasibleReach):
        if reach_fn.dropped:
            notes.append(f"{reach_fn.dropped} of {n_rfc} sampled setups dropped: {_why_dropped(reach_fn.feasible)}")
        reach_fn = reach_fn.reach_fn
    return notes


def _why_dropped(feasible) -> str:
    """The feasibility test's own account of what it refused, if it keeps one."""
    return str(getattr(feasible, "summary", lambda: "refused by the feasibility test")())


def _left_out(uncoverable, vertices, normals, area, robot, params, live: PartReach, notes):
    """Causes of the uncoverable patches and the warning list with the share left out (the
    collision test reuses the reach test's checker of the part)."""
    if len(uncoverable) == 0:
        return np.zeros(0, dtype="<U18"), notes
    causes = unreachable_causes(robot, vertices[uncoverable], normals[uncoverable], params.space, params.reach,
                                part_mesh=live.part_mesh, checker=live.checker)
    return causes, notes + [unreachable_message(causes, area[uncoverable], float(area.sum()), len(area))]


def _warn_all(notes, stacklevel: int = 3) -> None:
    for note in notes:
        _warnings.warn(note, stacklevel=stacklevel)


def _no_solution(name, n_rfc, candidates, causes, notes, vertices, seconds) -> SetupPlan:
    """No candidate reaches any patch: no plan, no cost, no certificate, and why."""
    plan = _empty_plan(name, seconds)
    plan.n_rfc, plan.candidates, plan.status = n_rfc, candidates, "no_solution"
    plan.certificate_cost = plan.certificate_gap = None
    plan.uncoverable, plan.uncoverable_causes = np.arange(len(vertices)), causes
    across = float(np.ptp(vertices.reshape(-1, 3), axis=0).max())
    plan.warnings = notes + [f"the stain spans {across:.3g} m; if the part is really much larger or smaller, "
                             "it was read in the wrong units (load_mesh(path, units=...))"]
    _warn_all(plan.warnings, stacklevel=4)
    return plan


def _empty_plan(name: str, seconds: float) -> SetupPlan:
    return SetupPlan(
        part_name=name, setups=np.zeros((0, 3)), patches=[], reachable=[], step_costs=np.zeros(0),
        cost=0.0, setup_time_total=0.0, execution_time_total=0.0, node_expansions=0, n_rfc=0,
        candidates=0, nondominated=0, certificate_cost=0.0, certificate_gap=0.0, status="empty",
        uncoverable=np.zeros(0, dtype=np.int64), seconds=seconds)

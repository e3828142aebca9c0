"""Notebook 12: beyond the papers (issue 15).

* Part 3, offline half: what exact visibility changes in MAVAC's offline plan. Each machine is
  planned with HPR (the paper) and with exact ray casting; the HPR plan's camera poses are then
  re-evaluated with ray casting, which measures the elements HPR counts as observed that no pose
  really sees (its false-visible elements) before any online run.
* Part 4: how often Kabir's Algorithm 4 with the eq. 7 bound returns the certified optimum (the
  MILP of :mod:`mavac.planning.setcover`), over seeds of Algorithm 5, against N_repeat, beside
  the eq. 5 bound the paper proves and the exact probability that Algorithm 5 finds the minimum
  cover size (from counting the covers of every size).

Every sweep goes through :func:`mavac.parallel.map_trials`, so under
``joblib.parallel_backend("dask")`` it runs on a dask cluster unchanged; a trial takes its seed
from its argument and every search is bounded by a node count, so the CSVs do not depend on
scheduling or machine speed.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import binomtest

from ..geometry.machines import MACHINE_NAMES, load_machine
from ..geometry.parts import load_part
from ..inspection.guards import guard_visibility
from ..parallel import map_trials
from ..params import VISIBILITY_METHODS, InspectionParams, ReachParams, SamplingParams, SetupPlannerParams, SetupSpaceParams
from ..planning.iess import n_repeat_recommended, p_find_min_cover, row_bitsets
from ..planning.setcover import brute_force_setup_cover, dfbnb_setup_cover, milp_setup_cover
from ..validate import check_cover, check_int
from ..vision.visibility import VisibilityScene
from ..viz.plots import new_figure
from . import kabir_setups as K
from .mavac_offline import plan_machine

#: N_repeat values of the Part 4 sweep (ours: 1 to 5000 in a 1-2-5 progression; the Sec. IX-B
#: choice for each instance's m is added beside them).
N_REPEAT_GRID = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000)
#: Node budget of every DFBnB run of Part 4 (ours: 100x the largest count of Table VI, 58,065).
MAX_NODES = 5_000_000
#: Relative tolerance for "same cost as the MILP optimum" (costs are sums of ~10 floats).
COST_RTOL = 1e-9


# ============================================================================ Part 4: Algorithm 4


@dataclass(frozen=True)
class IessInstance:
    """One Table V-VI planner instance with its exact answers.

    Attributes
    ----------
    name : str
    cover : (m, n) bool
        Non-dominated level-1 setups (Kabir Tables V-VI).
    costs : (m,) float, s
        Eq. 1 cost of each setup, ``t_s + sum(area x passes) / rate``.
    area : (n,) float, m^2
    setup_time : float, s
    optimum_cost : float, s
        MILP optimum (HiGHS, gap 0), equal to the brute force's.
    optimum_size : int
        Setups in the MILP optimum.
    covers_by_size : (m + 1,) int
        Number of k-subsets of setups that cover every coverable patch, k = 0 .. m.
    """

    name: str
    cover: np.ndarray
    costs: np.ndarray
    area: np.ndarray
    setup_time: float
    optimum_cost: float
    optimum_size: int
    covers_by_size: np.ndarray

    @property
    def m(self) -> int:
        return int(self.cover.shape[0])

    @property
    def q(self) -> int:
        """Size of the minimum set cover (eq. 4)."""
        return int(np.flatnonzero(self.covers_by_size)[0])

    @property
    def n_min_covers(self) -> int:
        """How many minimum set covers there are (eq. 5 assumes one)."""
        return int(self.covers_by_size[self.q])


def covers_by_size(cover) -> np.ndarray:
    """Number of k-subsets of the rows of ``cover`` whose union covers every coverable column.

    Enumerates all ``2^m`` subsets with bitsets (``m <= 20``).

    Parameters
    ----------
    cover : (m, n) bool

    Returns
    -------
    (m + 1,) int
        Entry k counts the covering k-subsets; entry m is 1 (the whole set).
    """
    c = check_cover(cover)
    m = c.shape[0]
    if m > 20:
        raise ValueError(f"cover: counting covers is limited to m <= 20 setups, got {m}")
    cols = np.unique(c[:, c.any(axis=0)], axis=1)
    masks = row_bitsets(np.ascontiguousarray(cols))
    full = (1 << cols.shape[1]) - 1
    union = [0] * (1 << m)
    counts = np.zeros(m + 1, dtype=np.int64)
    for s in range(1, 1 << m):
        low = s & -s
        union[s] = union[s ^ low] | masks[low.bit_length() - 1]
        if union[s] == full:
            counts[s.bit_count()] += 1
    if full == 0:
        counts[0] = 1
    return counts


def iess_probabilities(covers: np.ndarray, n_repeat: int) -> np.ndarray:
    """Exact distribution of Algorithm 5's estimate for ``n_repeat`` trials.

    A trial stops at the first prefix of a random permutation that covers, and the first k
    setups of a uniform permutation are a uniform k-subset, so one trial needs at most k setups
    with probability ``f_k = covers[k] / C(m, k)`` and ``P(IESS <= k) = 1 - (1 - f_k)^N``.
    With a unique minimum cover of size q, ``P(IESS = q)`` is eq. 5.

    Parameters
    ----------
    covers : (m + 1,) int
        From :func:`covers_by_size`.
    n_repeat : int

    Returns
    -------
    (m + 1,) float
        ``P(IESS = k)``, k = 0 .. m.
    """
    n_repeat = check_int("n_repeat", n_repeat, 1)
    m = len(covers) - 1
    f = np.array([covers[k] / math.comb(m, k) for k in range(m + 1)], dtype=float)
    at_most = np.ones(m + 1)
    part = f < 1.0  # f = 1 (the whole set, or every k-subset covers): IESS <= k surely
    at_most[part] = -np.expm1(n_repeat * np.log1p(-f[part]))
    return np.diff(at_most, prepend=0.0)


def level1_instance(name: str, *, fine: SetupSpaceParams | None = None, wide_resolution=K.WIDE_RESOLUTIONS["paper"],
                    reach_params: ReachParams | None = None, sampling: SamplingParams | None = None,
                    seed: int = 0) -> K.PlannerInstance:
    """Kabir's Tables V-VI instance of one object: level-1 grid, no descent, dominated removed.

    The setup space is the one square of the four objects, placed by the paper's procedure
    (:func:`K.placed_space`, as in notebooks 06-08; cached on disk). The 36 level-1 setups do not depend on the fine grid, so they
    are answered by the reach test directly (no uniform baseline sweep is needed).
    """
    reach_params = reach_params or ReachParams()
    space, _ = K.placed_space(name, fine or SetupSpaceParams(), reach_params, wide_resolution=wide_resolution,
                              seed=seed)
    part = load_part(name, seed=seed)
    n = len(part.patch_areas)
    live = K.Baseline(name, space, np.zeros((0, 3)), np.zeros((0, n), dtype=bool), part.patch_areas, part.passes,
                      seed)
    return K.planner_instance(live, reach_params, sampling or SamplingParams())


def iess_instance(inst: K.PlannerInstance, *, setup_time: float, cleaning_rate: float) -> IessInstance:
    """Eq. 1 costs, the certified optimum (MILP, checked by brute force) and the cover counts."""
    costs = K.setup_costs(inst.cover, inst.area, inst.passes, setup_time, cleaning_rate)
    milp = milp_setup_cover(inst.cover, costs)
    if not milp.optimal:
        raise RuntimeError(f"{inst.name}: the MILP did not prove its optimum ({milp.status})")
    _, brute_cost = brute_force_setup_cover(inst.cover, costs)
    if not math.isclose(brute_cost, milp.cost, rel_tol=COST_RTOL):
        raise RuntimeError(f"{inst.name}: MILP optimum {milp.cost} != brute force {brute_cost}")
    return IessInstance(inst.name, inst.cover, costs, inst.area, float(setup_time), float(milp.cost),
                        len(milp.setups), covers_by_size(inst.cover))


@dataclass(frozen=True)
class _Alg4Task:
    """Picklable Algorithm 4 runs of one instance, bound and N_repeat over a chunk of seeds."""

    inst: IessInstance
    bound: str
    n_repeat: int
    seeds: tuple
    max_nodes: int

    def __call__(self, _=None) -> list[dict]:
        rows = []
        for seed in self.seeds:
            # bounded by nodes only: a wall-time T_max would make the rows machine-dependent
            p = SetupPlannerParams(algorithm=4, bound=self.bound, n_repeat=self.n_repeat, seed=seed,
                                   setup_time=self.inst.setup_time, t_max=None, max_nodes=self.max_nodes)
            d = dfbnb_setup_cover(self.inst.cover, self.inst.costs, patch_area=self.inst.area, params=p)
            rows.append(dict(object=self.inst.name, setup_time=self.inst.setup_time, m=self.inst.m,
                             bound=self.bound, n_repeat=self.n_repeat,
                             seed=seed, iess=d.iess, q=self.inst.q, size=len(d.setups), cost=d.cost,
                             optimum_cost=self.inst.optimum_cost, optimum_size=self.inst.optimum_size,
                             optimal=math.isclose(d.cost, self.inst.optimum_cost, rel_tol=COST_RTOL),
                             nodes=d.node_expansions, node_limited=d.node_limited))
        return rows


def _run(task):
    return task()


def n_repeat_values(m: int, grid=N_REPEAT_GRID, prob: float = 0.9) -> list[int]:
    """The sweep's N_repeat values for ``m`` setups: ``grid`` plus Sec. IX-B's choice."""
    return sorted(set(int(n) for n in grid) | {n_repeat_recommended(m, prob)})


def alg4_runs(instances, *, seeds, grid=N_REPEAT_GRID, bounds=("b",), max_nodes: int = MAX_NODES,
              chunk: int = 25, n_jobs: int | None = None, progress: bool = True) -> pd.DataFrame:
    """Algorithm 4 on every instance, bound and N_repeat, one row per seed of Algorithm 5.

    Parameters
    ----------
    instances : iterable of IessInstance
        One per object and setup time.
    seeds : iterable of int
        Seeds of Algorithm 5 (``SetupPlannerParams.seed``).
    grid : iterable of int
        N_repeat values; Sec. IX-B's choice for each instance is added.
    bounds : tuple of str
        ``"b"`` (eq. 7, the question) and optionally ``"lb"`` (eq. 2, a control that isolates
        the IESS depth cap).
    max_nodes : int
        Node budget of every search (``node_limited`` marks a run that hit it).
    chunk : int
        Seeds per task (keeps the workers balanced).

    Returns
    -------
    pandas.DataFrame
        ``object, setup_time, m, bound, n_repeat, seed, iess, q, size, cost, optimum_cost,
        optimum_size, optimal, nodes, node_limited``.
    """
    seeds = tuple(int(s) for s in seeds)
    tasks = [_Alg4Task(inst, bound, n, seeds[a:a + chunk], max_nodes)
             for inst in instances for bound in bounds for n in n_repeat_values(inst.m, grid)
             for a in range(0, len(seeds), chunk)]
    rows = map_trials(_run, tasks, n_jobs=n_jobs, desc="Algorithm 4", progress=progress)
    return pd.DataFrame([r for part in rows for r in part])


def _wilson(k: int, n: int) -> tuple[float, float]:
    ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    return float(ci.low), float(ci.high)


def alg4_summary(runs: pd.DataFrame, instances) -> pd.DataFrame:
    """Probability of optimality per object, bound and N_repeat, beside eq. 5 and the exact law.

    Columns: ``object, setup_time, m, q, n_min_covers, optimum_size, bound, n_repeat, recommended, runs,
    p_optimal, ci_low, ci_high`` (measured, Wilson 95 %), ``p_size_q`` (plans with the minimum
    cover size, the paper's weaker promise), ``gap_mean`` (mean relative cost above the optimum),
    ``p_iess_q`` (measured fraction of
    seeds with IESS = q), ``p_iess_q_exact`` (:func:`iess_probabilities`), ``eq5`` (the paper's
    bound), ``p_optimal_predicted`` (exact IESS law x the outcome observed at each IESS value,
    see :func:`outcome_by_iess`), ``nodes_median, node_limited``.
    """
    by_key = {(i.name, i.setup_time): i for i in instances}
    outcome = outcome_by_iess(runs).set_index(["object", "setup_time", "bound", "iess"]).optimal
    rows = []
    for (name, ts, bound, n), g in runs.groupby(["object", "setup_time", "bound", "n_repeat"], sort=False):
        inst = by_key[(name, ts)]
        law = iess_probabilities(inst.covers_by_size, int(n))
        k = int(g.optimal.sum())
        lo, hi = _wilson(k, len(g))
        pred = _predicted(law, lambda i: outcome.get((name, ts, bound, i), math.nan))
        rows.append(dict(object=name, setup_time=ts, m=inst.m, q=inst.q, n_min_covers=inst.n_min_covers,
                         optimum_size=inst.optimum_size, bound=bound, n_repeat=int(n),
                         recommended=int(n) == n_repeat_recommended(inst.m, 0.9), runs=len(g),
                         p_optimal=k / len(g), ci_low=lo, ci_high=hi, p_size_q=float((g["size"] == inst.q).mean()),
                         gap_mean=float(((g.cost - g.optimum_cost) / g.optimum_cost).mean()),
                         p_iess_q=float((g.iess == inst.q).mean()),
                         p_iess_q_exact=float(law[inst.q]), eq5=p_find_min_cover(inst.q, inst.m, int(n)),
                         p_optimal_predicted=float(pred), nodes_median=float(g.nodes.median()),
                         node_limited=int(g.node_limited.sum())))
    return pd.DataFrame(rows)


def _predicted(law: np.ndarray, optimal_at) -> float:
    """``sum_k P(IESS = k) optimal(k)`` over the k with probability above 1e-9 (NaN when one of
    them was never observed)."""
    ks = np.flatnonzero(law > 1e-9)
    return float(sum(law[k] * float(optimal_at(int(k))) for k in ks))


def outcome_by_iess(runs: pd.DataFrame) -> pd.DataFrame:
    """Whether Algorithm 4 returned the optimum, for each value its IESS took.

    Given IESS the search is deterministic (the seed only drives Algorithm 5), so every run with
    the same object, setup time, bound and IESS must agree; a disagreement raises.

    Returns
    -------
    pandas.DataFrame
        ``object, setup_time, bound, iess, optimal, cost, nodes, runs``.
    """
    g = runs.groupby(["object", "setup_time", "bound", "iess"])
    out = g.agg(optimal=("optimal", "first"), agree=("optimal", "nunique"), cost=("cost", "first"),
                nodes=("nodes", "first"), runs=("seed", "size")).reset_index()
    if (out.agree > 1).any():
        raise RuntimeError("Algorithm 4 gave different results for the same IESS")
    return out.drop(columns="agree")


def plot_alg4(summary: pd.DataFrame, bound: str = "b"):
    """Probability of optimality against N_repeat, one row per setup time and one column per
    object (measured with its 95 % interval, predicted), with eq. 5's bound and the exact
    probability that IESS = q."""
    summary = summary[summary.bound == bound]
    names = list(dict.fromkeys(summary.object))
    times = sorted(summary.setup_time.unique())
    fig, axes = new_figure(ncols=len(names), nrows=len(times), size=(3.6, 2.9))
    axes = np.asarray(axes).reshape(len(times), len(names))
    for (i, ts), (j, name) in itertools.product(enumerate(times), enumerate(names)):
        _alg4_panel(axes[i, j], summary[(summary.object == name) & (summary.setup_time == ts)])
        axes[i, j].set_title(f"{name}, setup time {ts:g} s", fontsize=8)
        axes[i, 0].set_ylabel("probability")
    for j, name in enumerate(names):
        r = summary[summary.object == name].iloc[0]
        axes[-1, j].set_xlabel(f"N_repeat (dotted: Sec. IX-B choice)\nm = {r.m}, q = {r.q} "
                               f"({r.n_min_covers} min. covers), |S*| = {r.optimum_size}", fontsize=8)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, frameon=False, fontsize=8)
    fig.suptitle(f"Algorithm 4 with bound {'eq. 7' if bound == 'b' else 'eq. 2'}: probability of the certified optimum",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


def _alg4_panel(ax, s: pd.DataFrame) -> None:
    s = s.sort_values("n_repeat")
    ax.fill_between(s.n_repeat, s.ci_low, s.ci_high, color="tab:blue", alpha=0.2, lw=0)
    ax.semilogx(s.n_repeat, s.p_optimal, "o-", c="tab:blue", ms=3, label="Alg. 4 optimal (measured, 95 % CI)")
    ax.semilogx(s.n_repeat, s.p_optimal_predicted, ":", c="k", lw=1, label="predicted (exact IESS law)")
    ax.semilogx(s.n_repeat, s.p_iess_q_exact, "-", c="tab:green", label="P(IESS = q), exact")
    ax.semilogx(s.n_repeat, s.eq5, "--", c="tab:red", label="eq. 5 bound (unique cover)")
    ax.axvline(s[s.recommended].n_repeat.iloc[0], color="grey", ls=":", lw=1)
    ax.set_ylim(-0.03, 1.03)


def optimality_table(summary: pd.DataFrame) -> pd.DataFrame:
    """Part 4's table: for each object, setup time and bound, P(optimal) at a few N_repeat and at
    Sec. IX-B's choice, beside eq. 5 and the measured P(IESS = q) there."""
    rec = summary[summary.recommended].set_index(["object", "setup_time", "bound"])
    wide = summary.pivot_table(index=["object", "setup_time", "bound"], columns="n_repeat", values="p_optimal")
    keep = [n for n in (1, 10, 100, 1000) if n in wide.columns]
    out = wide[keep].rename(columns=lambda n: f"p_opt_N{n}")
    out.columns.name = None
    out["N_IX_B"] = rec.n_repeat
    out["p_opt_IX_B"] = rec.p_optimal
    out["ci_IX_B"] = pd.Series([f"[{a:.2f}, {b:.2f}]" for a, b in zip(rec.ci_low, rec.ci_high)], index=rec.index)
    out["p_size_q_IX_B"] = rec.p_size_q
    out["gap_IX_B"] = rec.gap_mean
    out["p_iess_q_IX_B"] = rec.p_iess_q
    out["eq5_IX_B"] = rec.eq5
    return out.reset_index()


# ============================================================================ Part 3: offline half


def _visibility_plan_trial(args) -> list[dict]:
    machine, seed, params = args
    rows = []
    vis_scene = VisibilityScene(load_machine(machine).mesh)
    for method in VISIBILITY_METHODS:
        with warnings.catch_warnings():  # the low-coverage warning repeats C, which the row has
            warnings.simplefilter("ignore", UserWarning)
            plan = plan_machine(machine, dataclasses.replace(params, seed=seed).with_visibility(method))
        rows.append(_plan_row(plan, seed, vis_scene))
    return rows


def _plan_row(plan, seed: int, vis_scene) -> dict:
    """C as the plan counts it, and C of the same camera poses under exact ray casting."""
    exact = dataclasses.replace(plan.params.visibility, method="raycast")
    seen = guard_visibility(plan.world_T_camera, plan.points, plan.normals, plan.params.camera, exact,
                            vis_scene=vis_scene).any(axis=0) if len(plan.poses) else np.zeros(len(plan.points), bool)
    counted = plan.observed
    return dict(machine=plan.machine_name, seed=seed, visibility=plan.visibility, elements=len(plan.points),
                spots=plan.n_spots, guards=plan.n_guards, nos_guards=plan.n_nos_guards, C=plan.C,
                C_raycast=float(seen.mean()), false_visible=float((counted & ~seen).mean()),
                missed=float((seen & ~counted).mean()),
                rrt_timeouts=sum(a.get("reason") == "Timeout" for a in plan.nos_attempts))


def visibility_plans(*, machines=MACHINE_NAMES, seeds=(0,), params: InspectionParams | None = None,
                     n_jobs: int | None = None, progress: bool = True) -> pd.DataFrame:
    """Offline plans of every machine and seed with HPR and with ray casting (Part 3, offline).

    Parameters
    ----------
    machines : iterable of str
    seeds : iterable of int
        ``InspectionParams.seed`` (surface sample, spot candidates, IK restarts).
    params : InspectionParams, optional
        Everything but the visibility method and the seed (default: the paper's values).

    Returns
    -------
    pandas.DataFrame
        One row per machine, seed and method: ``machine, seed, visibility, elements, spots,
        guards, nos_guards, C`` (as the plan counts it), ``C_raycast`` (the plan's camera poses
        under exact ray casting), ``false_visible`` (fraction of S the plan counts but no pose
        sees), ``missed`` (seen, not counted), ``rrt_timeouts`` (NoS searches stopped by the
        wall-time safety cap instead of their iteration budget: such a row depends on load).
    """
    params = InspectionParams() if params is None else params
    items = [(m, int(s), params) for m in machines for s in seeds]
    rows = map_trials(_visibility_plan_trial, items, n_jobs=n_jobs, desc="plans", progress=progress)
    return pd.DataFrame([r for part in rows for r in part])


def visibility_summary(plans: pd.DataFrame) -> pd.DataFrame:
    """Per machine and method: mean and standard deviation over seeds of C, C under ray casting,
    false-visible fraction and guards."""
    g = plans.groupby(["machine", "visibility"], sort=False)
    out = g.agg(seeds=("seed", "size"), C=("C", "mean"), C_sd=("C", "std"), C_raycast=("C_raycast", "mean"),
                C_raycast_sd=("C_raycast", "std"), false_visible=("false_visible", "mean"),
                missed=("missed", "mean"), guards=("guards", "mean"), nos_guards=("nos_guards", "mean"),
                spots=("spots", "mean"), rrt_timeouts=("rrt_timeouts", "sum"))
    return out.reset_index()


def plot_visibility(summary: pd.DataFrame):
    """Offline C per machine: as each plan counts it, and the HPR plan's poses under ray casting."""
    machines = list(dict.fromkeys(summary.machine))
    fig, ax = new_figure(size=(7.0, 3.6))
    x = np.arange(len(machines))
    w = 0.27
    s = summary.set_index(["machine", "visibility"])
    bars = (("hpr", "C", "HPR plan, C as HPR counts it"), ("hpr", "C_raycast", "HPR plan, C under ray casting"),
            ("raycast", "C", "ray-casting plan, C"))
    for k, (method, col, label) in enumerate(bars):
        vals = [s.loc[(m, method), col] for m in machines]
        err = [s.loc[(m, method), f"{col}_sd"] for m in machines]
        ax.bar(x + (k - 1) * w, vals, w, yerr=np.nan_to_num(err), capsize=3, label=label)
    ax.set_xticks(x, machines)
    ax.set_ylabel("offline coverage C (fraction of S)")
    ax.set_title("mean and standard deviation over seeds", fontsize=9)
    ax.set_ylim(0, 1)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    return fig

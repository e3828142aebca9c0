"""Notebook 12, online parts (issue 34): MAVAC's adaptive cleaning against a systematic baseline
(Part 1), and what HPR's false-visible elements cost the online loop (Part 3, online half).

MAVAC says a comparison with systematic coverage "would be valuable" but is "challenging due to
the lack of established baselines". The baseline here is :func:`mavac.cleaning.systematic.run_systematic`:
from the same offline plan's spots, the tool vacuums a boustrophedon raster over every surface dust
can rest on, under the same impedance control and suction. Both run on Table 2's two scenes (the
test bench; the sanding and milling machines together), with the paper's reading and its HPR
plan (notebook 05's), at several dust densities: a share of the 10 cm heap grid, drawn with each
trial's seed (:attr:`mavac.params.DustParams.density`).

MAVAC names HPR's misclassification as its main limit. Part 3 runs the online loop on the HPR
plan and on the exact ray-casting plan of each scene and counts, per trial, the heaps lying on
elements the plan counts as observed that no pose of it sees under ray casting (HPR's
false-visible elements), and how many of them no online image detected: HPR's price in heaps.

Every run goes through :func:`mavac.parallel.map_trials` and takes its seed from its argument, so
the table does not depend on scheduling and runs on a dask cluster unchanged.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
from scipy import stats

from ..cleaning.heaps import density_subset
from ..cleaning.replay import motion_totals
from ..cleaning.systematic import run_systematic
from ..cleaning.trial import run_trial
from ..geometry.machines import load_machine
from ..inspection.guards import guard_visibility
from ..parallel import map_trials
from ..robots.models import ur10_mobile
from ..params import VISIBILITY_METHODS, OnlineParams, PerturbationParams
from ..validate import check_sequence
from ..vision.visibility import VisibilityScene
from ..viz.plots import new_figure
from ..paper import paper_values
from .mavac_online import PAPER_SCENES, SCENES, offline_plan, online_params, paper_scene_means

#: the issue's dust densities: all of the 10 cm grid's heaps, 30 % and 10 %
DENSITIES = (1.0, 0.3, 0.1)
#: the two methods compared
METHODS = ("adaptive", "systematic")
#: per-run columns of ``beyond_adaptive_vs_systematic_runs.csv``
RUN_COLUMNS = ["method", "scene", "density", "seed", "heaps", "cleaned", "cleaning_pct", "sim_time_s", "base_s",
               "arm_s", "vacuum_s", "tool_path_m", "joint_travel_rad", "time_per_cleaned_heap_s"]
#: the quantities summarised per method, scene and density
MEASURES = ("cleaning_pct", "sim_time_s", "tool_path_m", "joint_travel_rad", "time_per_cleaned_heap_s")


def adaptive_unit(scene: str, seed: int, *, offline: str = "hpr", density: float = 1.0,
                  perturbation: PerturbationParams = PerturbationParams(), suction_scale: float = 1.0,
                  fast: bool = False) -> tuple:
    """One online trial (Algorithm 1, the paper's reading) as a hashable unit of work:
    ``("adaptive", scene, offline, density, perturbation, suction_scale, seed, fast)``."""
    return ("adaptive", scene, offline, float(density), perturbation, float(suction_scale), int(seed), bool(fast))


def systematic_unit(scene: str, densities, seed: int, *, fast: bool = False) -> tuple:
    """One run of the systematic baseline, scored at every density: ``("systematic", scene,
    densities, seed, fast)``."""
    return ("systematic", scene, tuple(float(d) for d in densities), int(seed), bool(fast))


def unit_params(unit: tuple) -> OnlineParams:
    """The online parameters of a unit: the paper's reading with its density, perturbation and
    suction radius."""
    if unit[0] == "systematic":
        return online_params("paper", fast=unit[-1])
    _, _, _, density, perturbation, suction_scale, _, fast = unit
    params = online_params("paper", fast=fast)
    vacuum = dataclasses.replace(params.vacuum, suction_radius=params.vacuum.suction_radius * suction_scale)
    return dataclasses.replace(params, dust=dataclasses.replace(params.dust, density=density), vacuum=vacuum,
                               perturbation=perturbation)


def unit_run(unit: tuple) -> dict:
    """Run one unit (module level: picklable for any joblib backend). Returns what every part
    reads from it: the result's ``row``, ``times``, ``heaps``, ``cleaned``, ``seen_by`` and
    ``causes`` (miss cause counts; both None for the baseline) and ``motion`` (tool path, m, and
    joint travel, rad, over the replay). Units: :func:`adaptive_unit`, :func:`systematic_unit`
    and :func:`mavac.experiments.beyond_improved.improved_unit`."""
    scene, seed, fast = unit[1], unit[-2], unit[-1]
    machine = load_machine(scene)
    robot = ur10_mobile()
    if unit[0] == "improved":
        from .beyond_improved import improved_params, improved_plan, improved_robot  # it builds on this module

        robot = improved_robot(unit[2])
        result = run_trial(machine, improved_plan(scene, unit[2], fast=fast), robot=robot,
                           params=improved_params(unit[2], fast=fast), seed=seed)
    elif unit[0] == "adaptive":
        plan = offline_plan(scene, "paper", offline=unit[2], fast=fast)
        result = run_trial(machine, plan, params=unit_params(unit), seed=seed)
    else:
        plan = offline_plan(scene, "paper", offline="hpr", fast=fast)
        result = run_systematic(machine, plan, params=unit_params(unit), seed=seed)
    motion = motion_totals(result.replay, robot) if result.replay is not None else (0.0, 0.0)
    causes = result.miss_counts() if hasattr(result, "miss_counts") else None
    return dict(row=result.row(), times=result.times, heaps=result.heaps, cleaned=result.cleaned,
                seen_by=getattr(result, "seen_by", None), causes=causes, motion=motion)


def run_units(units, *, n_jobs=None, desc: str = "online runs") -> dict:
    """Every distinct unit of ``units`` run once (one :func:`mavac.parallel.map_trials` call, in
    first-seen order): ``{unit: unit_run(unit)}``. Parts that share a trial share its run."""
    distinct = list(dict.fromkeys(check_sequence("units", units)))
    return dict(zip(distinct, map_trials(unit_run, distinct, n_jobs=n_jobs, desc=desc)))


def comparison_items(*, scenes=SCENES, densities=DENSITIES, seeds=range(5), fast: bool = False) -> list[tuple]:
    """The runs of the comparison: one adaptive trial per density (:func:`adaptive_unit`), one
    systematic run for all densities (:func:`systematic_unit`; its motion ignores the dust, so a
    sparser layout, a subset of the full one, is scored on the full run's vacuumed heaps)."""
    scenes, densities, seeds = (check_sequence(n, v) for n, v in
                                (("scenes", scenes), ("densities", densities), ("seeds", seeds)))
    for d in densities:
        if not 0.0 < float(d) <= 1.0:
            raise ValueError(f"densities must be in (0, 1], got {d!r}")
    adaptive = [adaptive_unit(scene, seed, density=d, fast=fast) for scene in scenes for d in densities
                for seed in seeds]
    return adaptive + [systematic_unit(scene, densities, seed, fast=fast) for scene in scenes for seed in seeds]


def _row(method, scene, density, seed, n_heaps, n_cleaned, times, tool_m, joints_rad) -> dict:
    return dict(method=method, scene=scene, density=density, seed=seed, heaps=n_heaps, cleaned=n_cleaned,
                cleaning_pct=round(100.0 * n_cleaned / n_heaps, 3) if n_heaps else 0.0,
                sim_time_s=round(times.sim_time_s, 3), base_s=round(times.base_s, 3), arm_s=round(times.arm_s, 3),
                vacuum_s=round(times.vacuum_s, 3), tool_path_m=round(tool_m, 3), joint_travel_rad=round(joints_rad, 3),
                time_per_cleaned_heap_s=round(times.sim_time_s / n_cleaned, 3) if n_cleaned else np.nan)


def comparison_rows(unit: tuple, outcome: dict) -> list[dict]:
    """The rows of one unit of :func:`comparison_items`, one per density it is scored at."""
    method, scene, seed = unit[0], unit[1], unit[-2]
    densities = unit[2] if method == "systematic" else (unit[3],)
    rows = []
    for d in densities:
        n = len(outcome["cleaned"])
        kept = np.arange(n) if method == "adaptive" else density_subset(n, d, seed)
        rows.append(_row(method, scene, d, seed, len(kept), int(np.count_nonzero(outcome["cleaned"][kept])),
                         outcome["times"], *outcome["motion"]))
    return rows


def comparison_runs(items, *, n_jobs=None, outcomes: dict | None = None) -> pd.DataFrame:
    """Every run of ``items`` (:func:`comparison_items`), one row per run and density
    (:data:`RUN_COLUMNS`), sorted by method, scene, density (dense first) and seed. ``outcomes``:
    the units already run (:func:`run_units`), else they run here."""
    outcomes = run_units(items, n_jobs=n_jobs, desc="adaptive vs systematic") if outcomes is None else outcomes
    runs = pd.DataFrame([row for unit in items for row in comparison_rows(unit, outcomes[unit])], columns=RUN_COLUMNS)
    rank = dict(_m=runs.method.map({m: i for i, m in enumerate(METHODS)}),
                _s=runs.scene.map({s: i for i, s in enumerate(dict.fromkeys(runs.scene))}))
    return (runs.assign(**rank).sort_values(["_m", "_s", "density", "seed"], ascending=[True, True, False, True],
                                            kind="stable").drop(columns=list(rank)).reset_index(drop=True))


def mean_ci(values) -> tuple[float, float, float]:
    """Mean and its 95 % Student-t interval (NaN bounds below two values or with no spread)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not len(v):
        return np.nan, np.nan, np.nan
    mean = float(v.mean())
    if len(v) < 2 or np.ptp(v) == 0.0:
        return mean, mean if len(v) >= 2 else np.nan, mean if len(v) >= 2 else np.nan
    low, high = stats.t.interval(0.95, len(v) - 1, loc=mean, scale=stats.sem(v))
    return mean, float(low), float(high)


def comparison_summary(runs: pd.DataFrame) -> pd.DataFrame:
    """Per method, scene and density: runs, heaps, and the mean of each of :data:`MEASURES` with
    its 95 % interval (``_low``, ``_high``) over the seeds."""
    rows = []
    for (method, scene, density), g in runs.groupby(["method", "scene", "density"], sort=False):
        row = dict(method=method, scene=scene, density=density, runs=len(g), heaps=float(g.heaps.mean()))
        for m in MEASURES:
            row[m], row[f"{m}_low"], row[f"{m}_high"] = mean_ci(g[m])
        rows.append(row)
    return pd.DataFrame(rows).round(3)


def time_ratios(summary: pd.DataFrame) -> pd.DataFrame:
    """Adaptive over systematic mean simulated time, per scene and density and over both scenes
    (the sum of the scenes' mean times), with each method's cleaning percentage beside it."""
    wide = summary.pivot_table(index=["density", "scene"], columns="method",
                               values=["sim_time_s", "cleaning_pct"]).reset_index()
    wide.columns = ["_".join(c).strip("_") for c in wide.columns]
    both = wide.groupby("density", as_index=False).agg(
        {"sim_time_s_adaptive": "sum", "sim_time_s_systematic": "sum", "cleaning_pct_adaptive": "mean",
         "cleaning_pct_systematic": "mean"}).assign(scene="both")
    out = pd.concat([wide, both], ignore_index=True)
    out["time_ratio"] = out.sim_time_s_adaptive / out.sim_time_s_systematic
    return out.sort_values(["density", "scene"], ascending=[False, True]).round(3).reset_index(drop=True)


def plot_comparison(summary: pd.DataFrame):
    """Simulated time (top) and heaps cleaned (bottom) against dust density, per scene, for both
    methods, with the 95 % intervals over seeds."""
    scenes = list(dict.fromkeys(summary.scene))
    fig, axes = new_figure(len(scenes), 2, size=(4.2, 3.0))
    axes = np.asarray(axes).reshape(2, len(scenes))
    for j, scene in enumerate(scenes):
        for method, marker in zip(METHODS, ("o", "s")):
            g = summary[(summary.scene == scene) & (summary.method == method)].sort_values("density")
            x = 100.0 * g.density
            for ax, m in zip(axes[:, j], ("sim_time_s", "cleaning_pct")):
                err = np.vstack([g[m] - g[f"{m}_low"], g[f"{m}_high"] - g[m]])
                ax.errorbar(x, g[m], yerr=np.nan_to_num(err), marker=marker, capsize=3, label=method)
        axes[0, j].set_title(scene.replace("_", " "))
        axes[0, j].set_ylabel("simulated time (s)")
        axes[1, j].set_ylabel("heaps cleaned (%)")
        axes[1, j].set_xlabel("dust density (% of the 10 cm grid)")
        axes[0, j].legend()
    return fig


def comparison_vs_paper(summary: pd.DataFrame) -> pd.DataFrame:
    """Per scene at full density: the paper's Table 2 (cleaning percentage, mean of its trials;
    time, mean of its timed trials, on the real robot with perception and planning) beside our
    adaptive and systematic runs (simulated motion time only: base, arm and vacuum)."""
    times = paper_values("mavac", "Table 2", "time")
    scene = times["condition"].str.extract(r"machine=([^;]+)")[0].map(PAPER_SCENES)
    paper_time_s = (60.0 * times.groupby(scene)["value"].mean()).to_dict()
    paper_pct = paper_scene_means()
    full = summary[summary.density == 1.0]
    rows = []
    for sc in dict.fromkeys(full.scene):
        row = dict(scene=sc, paper_cleaning_pct=paper_pct.get(sc), paper_time_s=paper_time_s.get(sc))
        for method in METHODS:
            hit = full[(full.scene == sc) & (full.method == method)].iloc[0]
            row[f"ours_{method}_cleaning_pct"] = hit.cleaning_pct
            row[f"ours_{method}_sim_time_s"] = hit.sim_time_s
        rows.append(row)
    return pd.DataFrame(rows)


# ============================================================================ Part 3: online half

#: per-trial columns of ``beyond_visibility_online_runs.csv``
VISIBILITY_COLUMNS = ["scene", "offline", "seed", "C", "C_raycast", "guards", "heaps", "cleaned", "cleaning_pct",
                      "heaps_counted", "heaps_false_visible", "false_visible_undetected", "false_visible_cleaned"]


def visibility_items(*, scenes=SCENES, seeds=range(5), fast: bool = False) -> list[tuple]:
    """The online trials of Part 3 (:func:`adaptive_unit`) with the HPR plan (the paper's) and
    the ray-casting plan."""
    scenes, seeds = check_sequence("scenes", scenes), check_sequence("seeds", seeds)
    return [adaptive_unit(scene, seed, offline=offline, fast=fast) for scene in scenes
            for offline in VISIBILITY_METHODS for seed in seeds]


def elements_seen(plan, vis_scene) -> np.ndarray:
    """(m,) bool: which of the plan's surface elements its camera poses see under exact ray
    casting."""
    exact = dataclasses.replace(plan.params.visibility, method="raycast")
    if not len(plan.poses):
        return np.zeros(len(plan.points), bool)
    return guard_visibility(plan.world_T_camera, plan.points, plan.normals, plan.params.camera, exact,
                            vis_scene=vis_scene).any(axis=0)


def heaps_on_elements(plan, heaps, vis_scene, *, seen=None) -> dict:
    """Per heap (its nearest surface element of the plan), whether the plan counts the element
    observed (``counted``) and whether the plan's camera poses see it under exact ray casting
    (``seen``); with ``C`` and ``C_raycast`` over the plan's elements.

    Parameters
    ----------
    plan : InspectionPlan
    heaps : (n, 3) float, metres
    vis_scene : mavac.vision.visibility.VisibilityScene
        The plan's machine, for ray casting.
    seen : (m,) bool, optional
        :func:`elements_seen` of the plan, if already computed.
    """
    from scipy.spatial import cKDTree

    seen = elements_seen(plan, vis_scene) if seen is None else seen
    nearest = cKDTree(plan.points).query(np.asarray(heaps, dtype=float).reshape(-1, 3))[1]
    counted = plan.observed
    return dict(counted=counted[nearest], seen=seen[nearest], C=float(counted.mean()), C_raycast=float(seen.mean()))


def visibility_row(unit: tuple, outcome: dict, on: dict) -> dict:
    """One trial of :func:`visibility_items` and what HPR's false-visible elements cost it: heaps
    on elements the plan counts observed but no pose of it sees, those never detected online
    (``seen_by`` -1), and those cleaned anyway (vacuumed beside a detected heap). ``on``:
    :func:`heaps_on_elements` of the trial's heaps."""
    _, scene, offline, *_, seed, _ = unit
    row, cleaned = outcome["row"], outcome["cleaned"]
    false_visible = on["counted"] & ~on["seen"]
    undetected = np.asarray(outcome["seen_by"]) < 0
    return dict(scene=scene, offline=offline, seed=seed, C=round(on["C"], 4), C_raycast=round(on["C_raycast"], 4),
                guards=row["guards"], heaps=row["heaps"], cleaned=row["cleaned"], cleaning_pct=row["cleaning_pct"],
                heaps_counted=int(on["counted"].sum()), heaps_false_visible=int(false_visible.sum()),
                false_visible_undetected=int((false_visible & undetected).sum()),
                false_visible_cleaned=int((false_visible & cleaned).sum()))


def visibility_runs(items, *, n_jobs=None, outcomes: dict | None = None) -> pd.DataFrame:
    """Every trial of ``items`` (:func:`visibility_items`), one row each (:data:`VISIBILITY_COLUMNS`);
    the ray casting of each plan's poses is done once per scene and plan."""
    outcomes = run_units(items, n_jobs=n_jobs, desc="HPR online") if outcomes is None else outcomes
    seen: dict = {}
    rows = []
    for unit in items:
        scene, offline, fast = unit[1], unit[2], unit[-1]
        plan = offline_plan(scene, "paper", offline=offline, fast=fast)
        vis_scene = VisibilityScene(load_machine(scene).mesh)
        if (scene, offline, fast) not in seen:
            seen[scene, offline, fast] = elements_seen(plan, vis_scene)
        on = heaps_on_elements(plan, outcomes[unit]["heaps"], vis_scene, seen=seen[scene, offline, fast])
        rows.append(visibility_row(unit, outcomes[unit], on))
    return pd.DataFrame(rows, columns=VISIBILITY_COLUMNS)


def visibility_summary(runs: pd.DataFrame) -> pd.DataFrame:
    """Per scene and offline visibility: trials, the means of C, C under ray casting, guards
    visited, heaps, cleaning percentage (with its 95 % interval) and the heaps on false-visible
    elements (all, never detected, cleaned anyway)."""
    rows = []
    for (scene, offline), g in runs.groupby(["scene", "offline"], sort=False):
        mean, low, high = mean_ci(g.cleaning_pct)
        rows.append(dict(scene=scene, offline=offline, trials=len(g), C=g.C.mean(), C_raycast=g.C_raycast.mean(),
                         guards=g.guards.mean(), heaps=g.heaps.mean(), cleaning_pct=mean, cleaning_pct_low=low,
                         cleaning_pct_high=high, heaps_false_visible=g.heaps_false_visible.mean(),
                         false_visible_undetected=g.false_visible_undetected.mean(),
                         false_visible_cleaned=g.false_visible_cleaned.mean()))
    return pd.DataFrame(rows).round(3)

"""Notebook 05: MAVAC online cleaning in simulation (Algorithm 1, Table 2, Fig. 8, miss causes).

Table 2 is run as the paper ran it: two scenes, the test bench and the sanding and milling
machines cleaned in one test (one scene), ten trials each, and the headline figure is the mean
of the cleaning percentage over the trials of both scenes, as the paper's 84 % is the mean of
its ten Table 2 trials. Every trial runs under both readings of the method
(:mod:`mavac.cleaning.readings`): the paper's text and the authors' published code.

Trials run through :func:`mavac.parallel.map_trials`; each takes its seed from its argument, so
the tables do not depend on scheduling, and no wall clock decides anything, so the same seeds
give the same CSVs on any load (wall times are reported apart and never written). The offline
plan of each scene and reading is computed once and kept in the disk cache
(:func:`mavac.cache.verified_cache`).
"""

from __future__ import annotations

import dataclasses

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ..cache import verified_cache
from ..cleaning import readings
from ..cleaning.misses import CAUSES
from ..cleaning.regions import REGIONS, heap_regions
from ..cleaning.trial import run_trial
from ..geometry.machines import load_machine
from ..paper import paper_scalar, paper_values
from ..parallel import map_trials
from ..params import InspectionParams
from ..validate import check_int, check_sequence
from ..viz import meshcat_scene as ms
from ..viz.plots import new_figure, plot_mesh, set_equal_3d
from .mavac_offline import fast_params

#: most trials per scene and reading: 100 times the paper's 10 (Table 2), each minutes of simulation
MAX_TRIALS = 1_000
#: the paper's two Table 2 tests: the test bench, and the sanding and milling machines together
SCENES = ("test_bench", "sanding_milling")
#: paper's Table 2 machine labels -> our scenes
PAPER_SCENES = {"test bench": "test_bench", "sanding and milling": "sanding_milling"}
#: leading columns of the per-trial table (the trial's counters follow)
TRIAL_COLUMNS = ["reading", "scene", "trial", "seed", "heaps", "cleaned", "uncleaned", "cleaning_pct"]
#: fast mode (CI) visits only the first poses of each plan (ours: keeps notebook 05 near 2 min)
FAST_POSES = 10


def _plan(scene: str, params: InspectionParams):
    """Offline plan of one of the package's scenes (module level: joblib caches it)."""
    from ..inspection.inspection_plan import plan_inspection

    return plan_inspection(load_machine(scene), params=params)


def inspection_params(reading: str, *, fast: bool = False) -> InspectionParams:
    """The reading's offline parameters; fast mode takes the sample sizes of
    :func:`mavac.experiments.mavac_offline.fast_params` and keeps the reading's camera,
    visibility and guard stand-off."""
    params = readings.inspection_params(reading)
    if not fast:
        return params
    small = fast_params()
    guard = dataclasses.replace(params.guard, guard_spacing=small.guard.guard_spacing)
    return dataclasses.replace(params, surface_spacing=small.surface_spacing, reach=small.reach,
                               spot=dataclasses.replace(params.spot, ring_spacing=small.spot.ring_spacing),
                               guard=guard, nos=small.nos)


def offline_plan(scene: str, reading: str = "paper", *, fast: bool = False):
    """Cached offline plan of ``scene`` under ``reading``; in fast mode only the first
    :data:`FAST_POSES` poses."""
    plan = verified_cache(_plan)(scene, inspection_params(reading, fast=fast))
    return dataclasses.replace(plan, pose_set=plan.pose_set.head(FAST_POSES)) if fast else plan


def online_params(reading: str = "paper", *, fast: bool = False):
    """The reading's online parameters (fast mode: coarse heaps, same code paths)."""
    return readings.online_params(reading, fast=fast)


def _trial(args) -> dict:
    scene, reading, trial, fast = args
    machine = load_machine(scene)
    result = run_trial(machine, offline_plan(scene, reading, fast=fast), params=online_params(reading, fast=fast),
                       seed=trial)
    return dict(scene=scene, reading=reading, trial=trial, result=result,
                regions=heap_regions(machine, result.heaps))


def run_trials(*, scenes=SCENES, reading_names=readings.READINGS, trials: int = 10, fast: bool = False,
               n_jobs=None) -> list[dict]:
    """``trials`` trials per scene and reading (seed = trial number, so both readings clean the
    same heap layouts; at most :data:`MAX_TRIALS`); plans are made first, once each."""
    scenes, reading_names = check_sequence("scenes", scenes), check_sequence("reading_names", reading_names)
    trials = check_int("trials", trials, 1, MAX_TRIALS)
    for scene in scenes:
        for reading in reading_names:
            offline_plan(scene, reading, fast=fast)
    items = [(s, r, t, fast) for r in reading_names for s in scenes for t in range(1, trials + 1)]
    return map_trials(_trial, items, n_jobs=n_jobs, desc="online trials")


def _region_counts(run: dict) -> dict:
    res, regions = run["result"], run["regions"]
    out = {}
    for region in REGIONS:
        mask = regions == region
        out[f"{region}_heaps"] = int(mask.sum())
        out[f"{region}_cleaned"] = int(np.count_nonzero(res.cleaned & mask))
    return out


def trials_table(runs: list[dict]) -> pd.DataFrame:
    """One row per trial: Table 2's columns, heaps per region, and the trial's counters
    (detections, filters' guards and folds that failed); no wall-time column."""
    rows = []
    for r in runs:
        row = r["result"].row()
        row = {k: v for k, v in row.items() if k not in ("machine", "trial", "wall_s")}
        rows.append(dict(reading=r["reading"], scene=r["scene"], trial=r["trial"]) | row | _region_counts(r))
    table = pd.DataFrame(rows)
    return table[TRIAL_COLUMNS + [c for c in table.columns if c not in TRIAL_COLUMNS]]


def _spread(pct: pd.Series) -> dict:
    return dict(trials=int(len(pct)), cleaning_pct=round(float(pct.mean()), 2),
                cleaning_pct_std=round(float(pct.std(ddof=1)), 2) if len(pct) > 1 else float("nan"),
                cleaning_pct_min=round(float(pct.min()), 2), cleaning_pct_max=round(float(pct.max()), 2))


def _pooled(group: pd.DataFrame, region: str) -> dict:
    heaps, cleaned = int(group[f"{region}_heaps"].sum()), int(group[f"{region}_cleaned"].sum())
    return dict(trials=int(len(group)), heaps=round(heaps / len(group), 1),
                cleaning_pct=round(100.0 * cleaned / heaps, 2) if heaps else float("nan"))


def table2(trials: pd.DataFrame) -> pd.DataFrame:
    """Table 2 summary per reading: the paper-style mean (mean cleaning percentage over every
    trial of both scenes, with its spread), one row per scene, and one row per region (heaps
    pooled over the trials: cleaned / present)."""
    rows = []
    for reading, by_reading in trials.groupby("reading", sort=False):
        rows.append(dict(reading=reading, statistic="paper-style mean", scene="both", region="all")
                    | _spread(by_reading["cleaning_pct"]) | dict(heaps=round(float(by_reading["heaps"].mean()), 1)))
        for scene, g in by_reading.groupby("scene", sort=False):
            rows.append(dict(reading=reading, statistic="scene mean", scene=scene, region="all")
                        | _spread(g["cleaning_pct"]) | dict(heaps=round(float(g["heaps"].mean()), 1),
                                                            uncleaned=round(float(g["uncleaned"].mean()), 1),
                                                            sim_time_min=round(float(g["sim_time_s"].mean()) / 60, 1)))
        for scene, g in [("both", by_reading), *by_reading.groupby("scene", sort=False)]:
            for region in REGIONS:
                rows.append(dict(reading=reading, statistic="pooled heaps", scene=scene, region=region)
                            | _pooled(g, region))
    return pd.DataFrame(rows)


def paper_scene_means() -> dict:
    """The paper's Table 2 cleaning percentage per scene, mean of its trials (``{scene: %}``)."""
    paper = paper_values("mavac", "Table 2", "cleaning_pct")
    scene = paper["condition"].str.extract(r"machine=([^;]+)")[0].map(PAPER_SCENES)
    return paper.groupby(scene)["value"].mean().round(1).to_dict()


def table2_vs_paper(summary: pd.DataFrame) -> pd.DataFrame:
    """Paper beside ours, one column per reading (simulated): the paper-style mean, each
    scene, and the open and enclosed regions (the paper does not report regions)."""
    paper = paper_scene_means()
    lines = [("paper-style mean (all trials of both tests)", "paper-style mean", "both", "all",
              paper_scalar("mavac", "Results", "cleaning_pct_mean", fraction=False))]
    lines += [(scene.replace("_", " "), "scene mean", scene, "all", paper.get(scene)) for scene in SCENES]
    lines += [(f"{region} heaps, both scenes", "pooled heaps", "both", region, None) for region in REGIONS]
    rows = []
    for label, statistic, scene, region, paper_pct in lines:
        row = dict(row=label, paper_cleaning_pct=paper_pct)
        for reading in summary["reading"].unique():
            hit = summary[(summary.reading == reading) & (summary.statistic == statistic) & (summary.scene == scene)
                          & (summary.region == region)]
            row[f"ours_{reading}"] = float(hit["cleaning_pct"].iloc[0]) if len(hit) else float("nan")
            if statistic != "pooled heaps" and len(hit):
                row[f"ours_{reading}_range"] = f"{hit['cleaning_pct_min'].iloc[0]:.1f}-{hit['cleaning_pct_max'].iloc[0]:.1f}"
        rows.append(row)
    return pd.DataFrame(rows)


def miss_causes_table(runs: list[dict]) -> pd.DataFrame:
    """Uncleaned heaps per cause and region, summed over the trials of each reading and scene."""
    rows = []
    for r in runs:
        causes, regions = r["result"].causes, r["regions"]
        for region in REGIONS:
            counts = {c: int(np.count_nonzero((causes == c) & (regions == region))) for c in CAUSES}
            rows.append(dict(reading=r["reading"], scene=r["scene"], region=region) | counts)
    table = pd.DataFrame(rows)
    return table.groupby(["reading", "scene", "region"], sort=False)[list(CAUSES)].sum().reset_index()


def miss_shares(misses: pd.DataFrame) -> pd.DataFrame:
    """Each cause's share (%) of the uncleaned heaps per reading, scene and region: the measured
    explanation of the gap to the paper (rows without misses are dropped)."""
    counts = misses[list(CAUSES)]
    total = counts.sum(axis=1)
    shares = (100.0 * counts.div(total.where(total > 0), axis=0)).round(1)
    out = pd.concat([misses[["reading", "scene", "region"]], total.rename("uncleaned"), shares], axis=1)
    return out[out["uncleaned"] > 0].reset_index(drop=True)


def times_table(runs: list[dict]) -> pd.DataFrame:
    """Simulated time per activity (s), contact forces and filter counts per trial; the
    planning wall time is in ``planning_wall_s`` (not for committed CSVs: it depends on load)."""
    rows = []
    for r in runs:
        res = r["result"]
        t = res.times
        forces = np.asarray(res.peak_forces, dtype=float)
        rows.append(dict(reading=r["reading"], scene=r["scene"], trial=r["trial"], base_s=round(t.base_s, 3),
                         arm_s=round(t.arm_s, 3), vacuum_s=round(t.vacuum_s, 3), sim_time_s=round(t.sim_time_s, 3),
                         guards=res.guards, areas=res.areas, areas_vacuumed=res.areas_cleaned, moves=len(forces),
                         median_peak_force_n=round(float(np.median(forces)), 2) if len(forces) else 0.0,
                         max_peak_force_n=round(float(forces.max()), 2) if len(forces) else 0.0,
                         **{f"filtered_{k}": v for k, v in res.filtered.items()},
                         planning_wall_s=round(t.planning_wall_s, 2)))
    return pd.DataFrame(rows)


def plot_fig8(runs: list[dict], *, trial: int = 1, reading: str = "paper"):
    """Fig. 8: each scene, cleaned heaps green and uncleaned red (one trial of one reading)."""
    chosen = [r for r in runs if r["trial"] == trial and r["reading"] == reading]
    fig, axes = new_figure(ncols=max(1, len(chosen)), size=(6.0, 4.5), projection="3d")
    axes = np.atleast_1d(axes)
    for ax, r in zip(axes, chosen):
        res, mesh = r["result"], load_machine(r["scene"]).mesh
        plot_mesh(ax, mesh, alpha=0.25)
        H = res.heaps
        for mask, color, label in ((res.cleaned, "tab:green", "cleaned"), (~res.cleaned, "tab:red", "uncleaned")):
            if mask.any():
                ax.scatter(*H[mask].T, s=10, c=color, label=f"{label} ({int(mask.sum())})", depthshade=False)
        set_equal_3d(ax, *mesh.bounds)
        ax.set_title(f"{r['scene']}, trial {trial}, {reading} reading: {res.cleaning_pct:.0f} % (simulated)",
                     fontsize=9)
        ax.legend(loc="upper left", fontsize=8)
    return fig


def fig8_html(run: dict, path):
    """Fig. 8 as a static meshcat page: scene, cleaned (green) and uncleaned (red) heaps."""
    res = run["result"]
    mesh = load_machine(run["scene"]).mesh
    green, red = (0.1, 0.75, 0.2), (0.85, 0.1, 0.1)
    with ms.scene() as vis:
        ms.add_mesh(vis, "machine", mesh, color=(0.6, 0.6, 0.62), opacity=0.85)
        if len(res.heaps):
            colors = np.where(res.cleaned[:, None], [green], [red])
            ms.add_points(vis, "heaps", res.heaps, colors, size=0.03)
        ms.frame_camera(vis, *mesh.bounds)
        counts = ", ".join(f"{k} {v}" for k, v in res.miss_counts().items() if v)
        legend = ms.legend_html([(green, f"cleaned heap ({res.n_cleaned})"),
                                 (red, f"uncleaned heap ({res.n_heaps - res.n_cleaned})")],
                                title=f"{run['scene']}, trial {run['trial']}, {run['reading']} reading: "
                                      f"{res.cleaning_pct:.0f} % cleaned (simulated)",
                                notes=[f"misses: {counts or 'none'}"])
        return ms.save_html(vis, path, legend=legend)


def plot_miss_causes(misses: pd.DataFrame):
    """Stacked bars of the miss causes per reading, scene and region."""
    labels = [f"{r}\n{s}\n{g}" for r, s, g in zip(misses["reading"], misses["scene"], misses["region"])]
    fig, ax = plt.subplots(figsize=(9, 3.8))
    bottom = np.zeros(len(misses))
    for cause in CAUSES:
        ax.bar(labels, misses[cause], bottom=bottom, label=cause)
        bottom += misses[cause].to_numpy()
    ax.set_ylabel("uncleaned heaps (all trials)")
    ax.tick_params(axis="x", labelsize=7)
    ax.legend(fontsize=8)
    return fig

"""Notebook 05: MAVAC online cleaning in simulation (Algorithm 1, Table 2, Fig. 8, miss causes).

Table 2 is run as the paper ran it: two scenes, the test bench and the sanding and milling
machines cleaned in one test (one scene), ten trials each, and the headline figure is the mean
of the cleaning percentage over the trials of both scenes, as the paper's 84 % is the mean of
its ten Table 2 trials. Every trial runs under each variant of
:data:`mavac.cleaning.readings.VARIANTS`: the paper's text and the authors' published code,
offline with the paper's HPR, and the paper's text again with ray casting offline (the package
default for users).

Trials run through :func:`mavac.parallel.map_trials`; each takes its seed from its argument, so
the tables do not depend on scheduling, and no wall clock decides anything, so the same seeds
give the same CSVs on any load (wall times are reported apart and never written). The offline
plan of each scene, stand-in and variant is computed once and kept in the disk cache
(:func:`mavac.cache.verified_cache`, keyed on the mesh's digest too, so a change of geometry
recomputes it).
"""

from __future__ import annotations

import dataclasses
import hashlib

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ..cache import verified_cache
from ..cleaning import readings
from ..cleaning.misses import CAUSES
from ..cleaning.regions import REGIONS, heap_regions
from ..cleaning.trial import run_trial
from ..geometry.machines import MILL_BENCH_HEIGHT, StandIn, load_machine
from ..paper import paper_scalar, paper_values
from ..parallel import map_trials
from ..params import InspectionParams
from ..validate import check_int, check_sequence
from ..viz import meshcat_scene as ms
from ..viz.plots import new_figure, plot_mesh, set_equal_3d, sparse_3d_ticks
from .mavac_offline import fast_params

#: most trials per scene and reading: 100 times the paper's 10 (Table 2), each minutes of simulation
MAX_TRIALS = 1_000
#: the paper's two Table 2 tests: the test bench, and the sanding and milling machines together
SCENES = ("test_bench", "sanding_milling")
#: paper's Table 2 machine labels -> our scenes
PAPER_SCENES = {"test bench": "test_bench", "sanding and milling": "sanding_milling"}
#: leading columns of the per-trial table (the trial's counters follow)
TRIAL_COLUMNS = ["reading", "offline", "scene", "trial", "seed", "heaps", "cleaned", "uncleaned", "cleaning_pct"]
#: columns that name a variant
VARIANT_COLUMNS = ["reading", "offline"]
#: fast mode (CI) visits only the first poses of each plan (ours: keeps notebook 05 near 2 min)
FAST_POSES = 10
#: Ours: at most this many tick intervals per axis of Fig. 8's 3-D panels, so the labels stay apart
FIG8_TICK_BINS = 4


def _plan(scene: str, params: InspectionParams, stand_in: StandIn, geometry_sha256: str):
    """Offline plan of one of the package's scenes (module level: joblib caches it; the mesh's
    digest is part of the key so that a change of geometry recomputes the plan)."""
    from ..inspection.inspection_plan import plan_inspection

    return plan_inspection(load_machine(scene, stand_in=stand_in), params=params)


def geometry_digest(scene: str, stand_in: StandIn | None = None) -> str:
    """SHA-256 of the scene's mesh (vertices and faces): the geometry part of the plan's cache key."""
    mesh = load_machine(scene, stand_in=stand_in).mesh
    digest = hashlib.sha256(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    return digest.hexdigest()


def inspection_params(reading: str, *, offline: str = "hpr", fast: bool = False) -> InspectionParams:
    """The reading's offline parameters with visibility ``offline``; fast mode takes the
    sample sizes of :func:`mavac.experiments.mavac_offline.fast_params` and keeps the
    reading's camera, visibility and guard stand-off."""
    params = readings.inspection_params(reading, offline=offline)
    if not fast:
        return params
    small = fast_params()
    guard = dataclasses.replace(params.guard, guard_spacing=small.guard.guard_spacing)
    return dataclasses.replace(params, surface_spacing=small.surface_spacing, reach=small.reach,
                               spot=dataclasses.replace(params.spot, ring_spacing=small.spot.ring_spacing),
                               guard=guard, nos=small.nos)


def offline_plan(scene: str, reading: str = "paper", *, offline: str = "hpr", fast: bool = False,
                 stand_in: StandIn | None = None):
    """Cached offline plan of ``scene`` (with ``stand_in``, default the nominal one) under
    ``reading`` and visibility ``offline``; in fast mode only the first :data:`FAST_POSES` poses."""
    stand_in = StandIn() if stand_in is None else stand_in
    plan = verified_cache(_plan)(scene, inspection_params(reading, offline=offline, fast=fast), stand_in,
                                 geometry_digest(scene, stand_in))
    return dataclasses.replace(plan, pose_set=plan.pose_set.head(FAST_POSES)) if fast else plan


def online_params(reading: str = "paper", *, fast: bool = False):
    """The reading's online parameters (fast mode: coarse heaps, same code paths)."""
    return readings.online_params(reading, fast=fast)


def _trial(args) -> dict:
    scene, (reading, offline), trial, fast, stand_in = args
    machine = load_machine(scene, stand_in=stand_in)
    plan = offline_plan(scene, reading, offline=offline, fast=fast, stand_in=stand_in)
    result = run_trial(machine, plan, params=online_params(reading, fast=fast), seed=trial)
    return dict(scene=scene, reading=reading, offline=offline, trial=trial, result=result,
                regions=heap_regions(machine, result.heaps), unseen=unseen_heaps(plan, result.heaps))


def _make_plan(args) -> None:
    scene, (reading, offline), fast, stand_in = args
    offline_plan(scene, reading, offline=offline, fast=fast, stand_in=stand_in)


def trials_of(items: list, *, n_jobs=None) -> list[dict]:
    """Run the trials ``items``, each ``(scene, (reading, offline), seed, fast, stand_in)``:
    their distinct offline plans first, one map over the workers (the disk cache hands each
    to its trials), then every trial in one map, so that no worker waits for a group's last
    trial (ours, because the cores are the cost of ``make reproduce``)."""
    plans = list(dict.fromkeys((scene, variant, fast, stand_in) for scene, variant, _, fast, stand_in in items))
    map_trials(_make_plan, plans, n_jobs=n_jobs, desc="offline plans")
    return map_trials(_trial, items, n_jobs=n_jobs, desc="online trials")


def _trial_items(scenes, variants, seeds, fast, stand_in) -> list:
    return [(s, tuple(v), t, fast, stand_in) for v in variants for s in scenes for t in seeds]


def run_trials(*, scenes=SCENES, variants=readings.VARIANTS, trials: int = 10, fast: bool = False,
               n_jobs=None, stand_in: StandIn | None = None, seeds=None) -> list[dict]:
    """``trials`` trials per scene and variant ``(reading, offline)`` (seed = trial number, so
    every variant cleans the same heap layouts; at most :data:`MAX_TRIALS`), or one per seed of
    ``seeds``, through :func:`trials_of`."""
    scenes, variants = check_sequence("scenes", scenes), check_sequence("variants", variants)
    for reading, offline in variants:
        readings.check_reading(reading), readings.check_offline(offline)
    seeds = range(1, check_int("trials", trials, 1, MAX_TRIALS) + 1) if seeds is None else check_sequence("seeds", seeds)
    return trials_of(_trial_items(scenes, variants, seeds, fast, stand_in), n_jobs=n_jobs)


def unseen_heaps(plan, heaps) -> np.ndarray:
    """(n,) bool: heaps whose nearest surface element of the plan no pose of it observes (the
    plan's own visibility, ``plan.pose_set.visible``): dust on surfaces no camera of the plan sees."""
    from scipy.spatial import cKDTree

    heaps = np.asarray(heaps, dtype=float).reshape(-1, 3)
    if len(heaps) == 0 or len(plan.points) == 0:
        return np.ones(len(heaps), dtype=bool)
    seen = plan.pose_set.visible.any(axis=0)
    return ~seen[cKDTree(plan.points).query(heaps)[1]]


def _region_counts(run: dict) -> dict:
    res, regions, unseen = run["result"], run["regions"], run["unseen"]
    out = {}
    for region in REGIONS:
        mask = regions == region
        out[f"{region}_heaps"] = int(mask.sum())
        out[f"{region}_cleaned"] = int(np.count_nonzero(res.cleaned & mask))
        out[f"{region}_unseen"] = int(np.count_nonzero(unseen & mask))
    return out


def variant_label(reading: str, offline: str) -> str:
    """``"paper_hpr"``: the column name of a variant."""
    return f"{reading}_{offline}"


def trials_table(runs: list[dict]) -> pd.DataFrame:
    """One row per trial: Table 2's columns, heaps per region (present, cleaned, and on surfaces
    no camera of the plan sees), and the trial's counters; no wall-time column."""
    rows = []
    for r in runs:
        row = r["result"].row()
        row = {k: v for k, v in row.items() if k not in ("machine", "trial", "wall_s")}
        rows.append(dict(reading=r["reading"], offline=r["offline"], scene=r["scene"], trial=r["trial"]) | row
                    | _region_counts(r))
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
    """Table 2 summary per variant (reading, offline): the paper-style mean (mean cleaning
    percentage over every trial of both scenes, with its spread), one row per scene, and one
    row per region (heaps pooled over the trials: cleaned / present)."""
    rows = []
    for (reading, offline), by_variant in trials.groupby(VARIANT_COLUMNS, sort=False):
        key = dict(reading=reading, offline=offline)
        rows.append(key | dict(statistic="paper-style mean", scene="both", region="all")
                    | _spread(by_variant["cleaning_pct"]) | dict(heaps=round(float(by_variant["heaps"].mean()), 1)))
        for scene, g in by_variant.groupby("scene", sort=False):
            rows.append(key | dict(statistic="scene mean", scene=scene, region="all")
                        | _spread(g["cleaning_pct"]) | dict(heaps=round(float(g["heaps"].mean()), 1),
                                                            uncleaned=round(float(g["uncleaned"].mean()), 1),
                                                            sim_time_min=round(float(g["sim_time_s"].mean()) / 60, 1)))
        for scene, g in [("both", by_variant), *by_variant.groupby("scene", sort=False)]:
            for region in REGIONS:
                rows.append(key | dict(statistic="pooled heaps", scene=scene, region=region) | _pooled(g, region))
    return pd.DataFrame(rows)


def paper_scene_means() -> dict:
    """The paper's Table 2 cleaning percentage per scene, mean of its trials (``{scene: %}``)."""
    paper = paper_values("mavac", "Table 2", "cleaning_pct")
    scene = paper["condition"].str.extract(r"machine=([^;]+)")[0].map(PAPER_SCENES)
    return paper.groupby(scene)["value"].mean().round(1).to_dict()


def table2_vs_paper(summary: pd.DataFrame) -> pd.DataFrame:
    """Paper beside ours, one column per variant ``ours_<reading>_<offline>`` (simulated): the
    paper-style mean, each scene, and the open and enclosed regions (the paper does not report
    regions)."""
    paper = paper_scene_means()
    lines = [("paper-style mean (all trials of both tests)", "paper-style mean", "both", "all",
              paper_scalar("mavac", "Results", "cleaning_pct_mean", fraction=False))]
    lines += [(scene.replace("_", " "), "scene mean", scene, "all", paper.get(scene)) for scene in SCENES]
    lines += [(f"{region} heaps, {scene.replace('_', ' ')}", "pooled heaps", scene, region, None)
              for scene in ("both", *SCENES) for region in REGIONS]
    variants = summary[VARIANT_COLUMNS].drop_duplicates().itertuples(index=False)
    variants = list(variants)
    rows = []
    for label, statistic, scene, region, paper_pct in lines:
        row = dict(row=label, paper_cleaning_pct=paper_pct)
        for reading, offline in variants:
            hit = summary[(summary.reading == reading) & (summary.offline == offline) & (summary.statistic == statistic)
                          & (summary.scene == scene) & (summary.region == region)]
            name = f"ours_{variant_label(reading, offline)}"
            row[name] = float(hit["cleaning_pct"].iloc[0]) if len(hit) else float("nan")
            if statistic != "pooled heaps" and len(hit):
                row[f"{name}_range"] = f"{hit['cleaning_pct_min'].iloc[0]:.1f}-{hit['cleaning_pct_max'].iloc[0]:.1f}"
        rows.append(row)
    return pd.DataFrame(rows)


def unseen_table(trials: pd.DataFrame) -> pd.DataFrame:
    """Per variant and scene: mean heaps per trial, and how many lie on surfaces no camera of
    the plan sees (:func:`unseen_heaps`), open and enclosed."""
    cols = [f"{region}_{what}" for region in REGIONS for what in ("heaps", "unseen")]
    out = trials.groupby([*VARIANT_COLUMNS, "scene"], sort=False)[["heaps", *cols]].mean().round(1).reset_index()
    out.insert(len(out.columns), "unseen", out[[f"{region}_unseen" for region in REGIONS]].sum(axis=1))
    return out


def miss_causes_table(runs: list[dict]) -> pd.DataFrame:
    """Uncleaned heaps per cause and region, summed over the trials of each variant and scene."""
    rows = []
    for r in runs:
        causes, regions = r["result"].causes, r["regions"]
        for region in REGIONS:
            counts = {c: int(np.count_nonzero((causes == c) & (regions == region))) for c in CAUSES}
            rows.append(dict(reading=r["reading"], offline=r["offline"], scene=r["scene"], region=region) | counts)
    table = pd.DataFrame(rows)
    return table.groupby([*VARIANT_COLUMNS, "scene", "region"], sort=False)[list(CAUSES)].sum().reset_index()


def miss_shares(misses: pd.DataFrame) -> pd.DataFrame:
    """Each cause's share (%) of the uncleaned heaps per variant, scene and region: the measured
    explanation of the gap to the paper (rows without misses are dropped)."""
    counts = misses[list(CAUSES)]
    total = counts.sum(axis=1)
    shares = (100.0 * counts.div(total.where(total > 0), axis=0)).round(1)
    out = pd.concat([misses[[*VARIANT_COLUMNS, "scene", "region"]], total.rename("uncleaned"), shares], axis=1)
    return out[out["uncleaned"] > 0].reset_index(drop=True)


def top_causes(misses: pd.DataFrame, n: int = 3) -> pd.DataFrame:
    """The ``n`` causes that missed the most heaps per variant and scene (both regions), with
    their counts over the trials: ``cause_1``, ``count_1``, ..."""
    rows = []
    for key, g in misses.groupby([*VARIANT_COLUMNS, "scene"], sort=False):
        totals = g[list(CAUSES)].sum().sort_values(ascending=False, kind="stable")
        row = dict(zip([*VARIANT_COLUMNS, "scene"], key))
        for i, (cause, count) in enumerate(totals.head(n).items(), 1):
            row |= {f"cause_{i}": cause if count else "", f"count_{i}": int(count)}
        rows.append(row)
    return pd.DataFrame(rows)


def times_table(runs: list[dict]) -> pd.DataFrame:
    """Simulated time per activity (s), contact forces and filter counts per trial; the
    planning wall time is in ``planning_wall_s`` (not for committed CSVs: it depends on load)."""
    rows = []
    for r in runs:
        res = r["result"]
        t = res.times
        forces = np.asarray(res.peak_forces, dtype=float)
        rows.append(dict(reading=r["reading"], offline=r["offline"], scene=r["scene"], trial=r["trial"],
                         base_s=round(t.base_s, 3), arm_s=round(t.arm_s, 3), vacuum_s=round(t.vacuum_s, 3),
                         sim_time_s=round(t.sim_time_s, 3), guards=res.guards, areas=res.areas,
                         areas_vacuumed=res.areas_cleaned, moves=len(forces),
                         median_peak_force_n=round(float(np.median(forces)), 2) if len(forces) else 0.0,
                         max_peak_force_n=round(float(forces.max()), 2) if len(forces) else 0.0,
                         **{f"filtered_{k}": v for k, v in res.filtered.items()},
                         planning_wall_s=round(t.planning_wall_s, 2)))
    return pd.DataFrame(rows)


def plot_fig8(runs: list[dict], *, trial: int = 1, reading: str = "paper", offline: str = "hpr"):
    """Fig. 8: each scene, cleaned heaps green and uncleaned red (one trial of one variant)."""
    chosen = [r for r in runs if r["trial"] == trial and r["reading"] == reading and r["offline"] == offline]
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
        sparse_3d_ticks(ax, nbins=FIG8_TICK_BINS)
        ax.set_title(f"{r['scene']}, trial {trial}, {reading} reading, {offline}: {res.cleaning_pct:.0f} % (simulated)",
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
                                title=f"{run['scene']}, trial {run['trial']}, {run['reading']} reading, {run['offline']}: "
                                      f"{res.cleaning_pct:.0f} % cleaned (simulated)",
                                notes=[f"misses: {counts or 'none'}"])
        return ms.save_html(vis, path, legend=legend)


def plot_miss_causes(misses: pd.DataFrame):
    """Stacked bars of the miss causes per variant, scene and region."""
    labels = [f"{r} {o}\n{s}\n{g}" for r, o, s, g in zip(misses["reading"], misses["offline"], misses["scene"],
                                                           misses["region"])]
    fig, ax = plt.subplots(figsize=(12, 4.2))
    bottom = np.zeros(len(misses))
    for cause in CAUSES:
        ax.bar(labels, misses[cause], bottom=bottom, label=cause)
        bottom += misses[cause].to_numpy()
    ax.set_ylabel("uncleaned heaps (all trials)")
    ax.tick_params(axis="x", labelsize=7)
    ax.legend(fontsize=8)
    return fig


#: The stand-in's free dimensions and the values the sensitivity table tries, one at a time
#: around the nominal :class:`StandIn` (ours): the bench under the mill 0.30 m, nominal, and
#: 0.65 m (the previous stand-in's stand, roof at 1.08 m); the sill of the enclosure's opening
#: 0, 3.5 cm and 7 cm (the previous stand-in's lip); the sander's shelf open or closed (the
#: previous stand-in's cabinet).
SENSITIVITY = {"mill_bench_height": (0.30, MILL_BENCH_HEIGHT, 0.65), "mill_sill": (0.0, 0.035, 0.07),
               "sander_shelf": ("open", "closed")}
#: the variant the sensitivity table runs (the paper's text with its HPR)
SENSITIVITY_VARIANT = ("paper", "hpr")


def sensitivity_points(*, fast: bool = False) -> list[tuple[str, object, StandIn]]:
    """``(dimension, value, stand_in)`` for every value of :data:`SENSITIVITY` that is not the
    nominal (one at a time); fast mode only the first dimension's last value (ours, because
    each point needs its own offline plan: CI time)."""
    nominal = StandIn()
    points = [(dimension, value, dataclasses.replace(nominal, **{dimension: value}))
              for dimension, values in SENSITIVITY.items() for value in values
              if value != getattr(nominal, dimension)]
    if fast:
        first = next(iter(SENSITIVITY))
        return [p for p in points if p[:2] == (first, SENSITIVITY[first][-1])]
    return points


def run_sensitivity(*, seeds=(1, 2, 3), fast: bool = False, n_jobs=None) -> list[dict]:
    """Sanding + milling trials (:data:`SENSITIVITY_VARIANT`, seeds ``seeds``) at each point of
    :func:`sensitivity_points`; each run carries its ``dimension``, ``value`` and ``stand_in``.
    The nominal point's runs are Table 2's (:func:`run_trials`), not repeated here."""
    seeds = check_sequence("seeds", seeds)
    points = sensitivity_points(fast=fast)
    items = [item for _, _, stand_in in points
             for item in _trial_items(["sanding_milling"], [SENSITIVITY_VARIANT], seeds, fast, stand_in)]
    runs = trials_of(items, n_jobs=n_jobs)
    point_of_run = [point for point in points for _ in seeds]
    return [run | dict(dimension=dimension, value=value, stand_in=stand_in)
            for (dimension, value, stand_in), run in zip(point_of_run, runs)]


def sensitivity_table(nominal_runs: list[dict], runs: list[dict]) -> pd.DataFrame:
    """One row per stand-in (nominal first, then :func:`run_sensitivity`'s points): the
    dimension changed and its value, the seeds, mean heaps, the cleaning percentage (mean,
    min, max over the seeds), enclosed heaps cleaned (pooled) and heaps on surfaces no camera
    of the plan sees (mean). ``nominal_runs``: Table 2's sanding + milling runs of
    :data:`SENSITIVITY_VARIANT` with the same seeds."""
    nominal = [r | dict(dimension="nominal", value="", stand_in=StandIn()) for r in nominal_runs
               if r["scene"] == "sanding_milling" and (r["reading"], r["offline"]) == SENSITIVITY_VARIANT]
    rows = []
    for r in nominal + runs:
        res = r["result"]
        rows.append(dict(dimension=r["dimension"], value=str(r["value"])) | dataclasses.asdict(r["stand_in"])
                    | dict(seed=r["trial"], heaps=res.n_heaps, cleaning_pct=res.cleaning_pct) | _region_counts(r))
    table = pd.DataFrame(rows)
    keys = ["dimension", "value", *dataclasses.asdict(StandIn())]
    out = []
    for key, g in table.groupby(keys, sort=False):
        enclosed = int(g["enclosed_heaps"].sum())
        out.append(dict(zip(keys, key)) | dict(seeds=" ".join(map(str, g["seed"])), heaps=round(float(g["heaps"].mean()), 1))
                   | {k: v for k, v in _spread(g["cleaning_pct"]).items() if k != "trials"}
                   | dict(enclosed_heaps=round(enclosed / len(g), 1),
                          enclosed_cleaning_pct=round(100.0 * g["enclosed_cleaned"].sum() / enclosed, 2) if enclosed else float("nan"),
                          unseen=round(float((g["open_unseen"] + g["enclosed_unseen"]).mean()), 1)))
    return pd.DataFrame(out)

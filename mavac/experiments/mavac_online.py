"""Notebook 05: MAVAC online cleaning in simulation (Algorithm 1, Table 2, Fig. 8, miss causes).

Trials run through :func:`mavac.parallel.map_trials`; each takes its seed from its argument, so
the tables do not depend on scheduling and the same seeds give the same CSVs (except the
wall-time columns). The offline plan of each machine is computed once and kept in the disk
cache (:func:`mavac.cache.verified_cache`).

The paper cleaned the sanding and the milling machine "during the same cleaning test". Our
machines are separate scenes, so the ``sanding+milling`` row of a trial is the sum of the
sanding and the milling trial with the same seed.
"""

from __future__ import annotations

import dataclasses

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ..cache import verified_cache
from ..cleaning.misses import CAUSES
from ..cleaning.trial import run_trial
from ..geometry.machines import load_machine
from ..paper import paper_scalar, paper_values
from ..parallel import map_trials
from ..params import DustParams, InspectionParams, OnlineParams
from ..viz import meshcat_scene as ms
from ..viz.plots import new_figure, plot_mesh, set_equal_3d
from .mavac_offline import fast_params

ONLINE_MACHINES = ("test_bench", "sanding_machine", "milling_machine")
COMBINED = "sanding+milling"
TABLE2_COLUMNS = ["machine", "trial", "seed", "heaps", "cleaned", "uncleaned", "cleaning_pct", "detected",
                  "precision", "recall", "sim_time_s", "wall_s"]
#: paper's Table 2 machine labels -> ours
PAPER_MACHINES = {"test bench": "test_bench", "sanding and milling": COMBINED}


def _plan(machine: str, params: InspectionParams):
    """Offline plan of one of the package's machines (module level: joblib caches it)."""
    from ..inspection.inspection_plan import plan_inspection

    return plan_inspection(load_machine(machine), params=params)


#: fast mode (CI) visits only the first poses of each plan (ours: keeps notebook 05 near 2 min)
FAST_POSES = 10


def offline_plan(machine: str, *, fast: bool = False):
    """Cached offline plan: paper-default :class:`InspectionParams` (ray casting); in fast mode
    the reduced sizes of :func:`mavac.experiments.mavac_offline.fast_params` and only the first
    :data:`FAST_POSES` poses."""
    plan = verified_cache(_plan)(machine, fast_params() if fast else InspectionParams())
    return dataclasses.replace(plan, pose_set=plan.pose_set.head(FAST_POSES)) if fast else plan


def online_params(*, fast: bool = False) -> OnlineParams:
    """Paper parameters; fast mode (CI) uses coarse heaps, 0.2 m apart (same code paths)."""
    return OnlineParams(dust=DustParams(spacing=0.2)) if fast else OnlineParams()


def _trial(args) -> dict:
    machine, trial, seed, fast = args
    result = run_trial(load_machine(machine), offline_plan(machine, fast=fast), params=online_params(fast=fast),
                       seed=seed)
    return dict(machine=machine, trial=trial, result=result)


def run_trials(*, machines=ONLINE_MACHINES, trials: int = 10, fast: bool = False, n_jobs=None) -> list[dict]:
    """``trials`` trials per machine (seed = trial number); plans are made first, once each."""
    for m in machines:
        offline_plan(m, fast=fast)
    items = [(m, t, t, fast) for m in machines for t in range(1, trials + 1)]
    return map_trials(_trial, items, n_jobs=n_jobs, desc="online trials")


def _combined_row(rows: list[dict]) -> dict:
    heaps = sum(r["heaps"] for r in rows)
    cleaned = sum(r["cleaned"] for r in rows)
    detected = sum(r["detected"] for r in rows)
    tp = sum(r["_tp"] for r in rows)
    recalled = sum(r["_recalled"] for r in rows)
    return dict(machine=COMBINED, trial=rows[0]["trial"], seed=rows[0]["seed"], heaps=heaps, cleaned=cleaned,
                uncleaned=heaps - cleaned, cleaning_pct=round(100.0 * cleaned / heaps, 3) if heaps else 0.0,
                detected=detected, precision=round(tp / detected, 4) if detected else float("nan"),
                recall=round(recalled / heaps, 4) if heaps else float("nan"),
                sim_time_s=round(sum(r["sim_time_s"] for r in rows), 3), wall_s=round(sum(r["wall_s"] for r in rows), 2))


def table2(runs: list[dict]) -> pd.DataFrame:
    """Table 2, one row per trial and machine, plus ``sanding+milling`` (sum of the two
    machines' trials with the same seed) when both were run."""
    rows = []
    for r in runs:
        row = r["result"].row() | {"trial": r["trial"]}
        rows.append(row | {"_tp": r["result"].true_positives, "_recalled": r["result"].recalled})
    by_trial = {}
    for row in rows:
        if row["machine"] in ("sanding_machine", "milling_machine"):
            by_trial.setdefault(row["trial"], []).append(row)
    rows += [_combined_row(pair) for _, pair in sorted(by_trial.items()) if len(pair) == 2]
    return pd.DataFrame(rows)[TABLE2_COLUMNS]


def miss_causes_table(runs: list[dict]) -> pd.DataFrame:
    """Uncleaned heaps per cause, summed over each machine's trials."""
    rows = [dict(machine=r["machine"], trial=r["trial"], **r["result"].miss_counts()) for r in runs]
    return pd.DataFrame(rows).groupby("machine", sort=False)[list(CAUSES)].sum().reset_index()


def times_table(runs: list[dict]) -> pd.DataFrame:
    """Simulated time per activity (s), planning wall time, and contact forces, per trial."""
    rows = []
    for r in runs:
        res = r["result"]
        t = res.times
        forces = np.asarray(res.peak_forces, dtype=float)
        rows.append(dict(machine=r["machine"], trial=r["trial"], base_s=round(t.base_s, 3), arm_s=round(t.arm_s, 3),
                         vacuum_s=round(t.vacuum_s, 3), sim_time_s=round(t.sim_time_s, 3), guards=res.guards,
                         areas=res.areas, areas_vacuumed=res.areas_cleaned,
                         moves=len(forces), median_peak_force_n=round(float(np.median(forces)), 2) if len(forces) else 0.0,
                         max_peak_force_n=round(float(forces.max()), 2) if len(forces) else 0.0,
                         **{f"filtered_{k}": v for k, v in res.filtered.items()},
                         planning_wall_s=round(t.planning_wall_s, 2)))
    return pd.DataFrame(rows)


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Mean and standard deviation per machine of the Table 2 columns."""
    g = table.groupby("machine", sort=False)
    out = g[["cleaning_pct", "heaps", "uncleaned", "precision", "recall", "sim_time_s"]].mean()
    out["cleaning_pct_std"] = g["cleaning_pct"].std(ddof=1)
    out["trials"] = g.size()
    return out.reset_index()


def table2_vs_paper(table: pd.DataFrame) -> pd.DataFrame:
    """Paper (Table 2, mean per machine; Results: 84 % overall) beside ours (simulated)."""
    paper = paper_values("mavac", "Table 2")
    paper = paper.assign(machine=paper["condition"].str.extract(r"machine=([^;]+)")[0].map(PAPER_MACHINES))
    wide = paper.pivot_table(index="machine", columns="quantity", values="value", aggfunc="mean")
    ours = summary(table).set_index("machine")
    rows = []
    for m in ours.index:
        p = wide.loc[m] if m in wide.index else None
        rows.append(dict(machine=m, paper_cleaning_pct=None if p is None else round(float(p["cleaning_pct"]), 1),
                         ours_cleaning_pct_simulated=round(float(ours.loc[m, "cleaning_pct"]), 1),
                         paper_heaps=None if p is None else round(float(p["heaps"]), 1),
                         ours_heaps=round(float(ours.loc[m, "heaps"]), 1),
                         paper_uncleaned=None if p is None else round(float(p["uncleaned"]), 1),
                         ours_uncleaned=round(float(ours.loc[m, "uncleaned"]), 1),
                         paper_time_min=None if p is None or pd.isna(p.get("time")) else round(float(p["time"]), 1),
                         ours_sim_time_min=round(float(ours.loc[m, "sim_time_s"]) / 60.0, 1),
                         trials=int(ours.loc[m, "trials"])))
    rows.append(dict(machine="all (paper: 10 trials)", paper_cleaning_pct=paper_scalar(
        "mavac", "Results", "cleaning_pct_mean", fraction=False), ours_cleaning_pct_simulated=round(
        float(table[table["machine"].isin(ONLINE_MACHINES)]["cleaning_pct"].mean()), 1)))
    return pd.DataFrame(rows)


def plot_fig8(runs: list[dict], *, trial: int = 1):
    """Fig. 8: each machine, cleaned heaps green and uncleaned red (one trial)."""
    chosen = [r for r in runs if r["trial"] == trial]
    fig, axes = new_figure(ncols=max(1, len(chosen)), size=(5.0, 4.5), projection="3d")
    axes = np.atleast_1d(axes)
    for ax, r in zip(axes, chosen):
        res, mesh = r["result"], load_machine(r["machine"]).mesh
        plot_mesh(ax, mesh, alpha=0.25)
        H = res.heaps
        for mask, color, label in ((res.cleaned, "tab:green", "cleaned"), (~res.cleaned, "tab:red", "uncleaned")):
            if mask.any():
                ax.scatter(*H[mask].T, s=10, c=color, label=f"{label} ({int(mask.sum())})", depthshade=False)
        set_equal_3d(ax, *mesh.bounds)
        ax.set_title(f"{r['machine']}, trial {trial}: {res.cleaning_pct:.0f} % (simulated)")
        ax.legend(loc="upper left", fontsize=8)
    return fig


def fig8_html(run: dict, path):
    """Fig. 8 as a static meshcat page: machine, cleaned (green) and uncleaned (red) heaps."""
    res = run["result"]
    mesh = load_machine(run["machine"]).mesh
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
                                title=f"{run['machine']}, trial {run['trial']}: {res.cleaning_pct:.0f} % cleaned "
                                      "(simulated)", notes=[f"misses: {counts or 'none'}"])
        return ms.save_html(vis, path, legend=legend)


def plot_miss_causes(misses: pd.DataFrame):
    """Stacked bars of the miss causes per machine."""
    fig, ax = plt.subplots(figsize=(7, 3.5))
    bottom = np.zeros(len(misses))
    for cause in CAUSES:
        ax.bar(misses["machine"], misses[cause], bottom=bottom, label=cause)
        bottom += misses[cause].to_numpy()
    ax.set_ylabel("uncleaned heaps (all trials)")
    ax.legend(fontsize=8)
    return fig


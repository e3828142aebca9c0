"""Kabir et al., Sec. VIII / IX-C: GPR operation-parameter learning on the SIMULATED scrub.

Tables for ``notebooks/10_gpr_parameters.ipynb``: GPR and random search over seeds for the
bowl (``C_p^th``, ``P_th`` of the paper's bowl) and the hull settings, the true optimum of
the noise-free simulated model, learning curves and the paper-vs-ours table. The thresholds
are read from ``data/paper_values.csv``. The cleaning physics is our simulated model
(:mod:`mavac.scrubbing.wear`), so the learned parameters are not expected to match the paper's.
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import pandas as pd

from ..geometry.parts import load_part
from ..paper import paper_scalar
from ..parallel import map_trials
from ..params import OPERATION_PARAMS, GPRParams
from ..scrubbing import execution
from ..scrubbing.gpr import dense_optimum, experiments_to_reach, learn_parameters, objective, random_search
from ..scrubbing.wear import ScrubExperiment
from ..seeding import rng_for

PARTS = ("bowl", "hull")
_REF = "Sec. IX-C GPR"


def gpr_params_for(part: str, **changes) -> GPRParams:
    """GPRParams with the paper's ``C_p^th`` and ``P_th`` for ``part`` (bowl or hull)."""
    if part not in PARTS:
        raise ValueError(f"part must be one of {PARTS}, got {part!r}")
    cond = f"part={part}"
    base = GPRParams(Cp_th=paper_scalar("kabir", _REF, "Cp_th", cond),
                     P_th=paper_scalar("kabir", _REF, "P_th", cond))
    return replace(base, **changes)


@functools.lru_cache(maxsize=8)
def scrub_experiment(part: str, seed: int = 0) -> ScrubExperiment:
    """:func:`mavac.scrubbing.execution.scrub_experiment` of the package's part ``part`` (stain
    drawn from ``seed``, hardness from the stream "scrub hardness" of ``seed``). Cached per process."""
    return execution.scrub_experiment(load_part(part, seed=seed), rng_for(seed, "scrub hardness"))


@functools.lru_cache(maxsize=8)
def _optimum(part: str):
    return dense_optimum(scrub_experiment(part).mean, gpr_params_for(part))


def dense_optima(parts=PARTS) -> pd.DataFrame:
    """True feasible optimum of the noise-free simulated model per part.

    Returns
    -------
    DataFrame: part, v, f_n, kappa, f_x, A_x, objective, C_p, Cp_th, feasible.
    """
    rows = []
    for part in parts:
        opt = _optimum(part)
        row = {"part": part, **(opt.chosen or {n: np.nan for n in OPERATION_PARAMS})}
        row.update(objective=opt.objective, C_p=opt.C_p, Cp_th=opt.Cp_th, feasible=opt.feasible)
        rows.append(row)
    return pd.DataFrame(rows)


def run_trial(args) -> dict:
    """One search: ``args = (part, method, seed, budget)`` with method ``gpr`` or ``random``.


    Returns a dict with the ``summary`` row and the ``history`` DataFrame (tagged with
    part, method, seed). Picklable, takes all randomness from ``seed``.
    """
    part, method, seed, budget = args
    ex = scrub_experiment(part)
    rng = rng_for(seed, "gpr learner")
    if method == "gpr":
        params = gpr_params_for(part, max_experiments=budget, seed=seed)
        result = learn_parameters(ex, params, rng=rng)
    elif method == "random":
        params = gpr_params_for(part, seed=seed)
        result = random_search(ex, params, budget=budget, rng=rng)
    else:
        raise ValueError(f"method must be 'gpr' or 'random', got {method!r}")
    history = result.history.assign(part=part, method=method, seed=seed)
    row = {"part": part, "method": method, "seed": seed, "experiments": result.experiments,
           "stop_reason": result.stop_reason}
    if result.chosen is not None:
        x = np.array([[result.chosen[n] for n in OPERATION_PARAMS]])
        row.update(result.chosen)
        row.update(C_p_mean=float(ex.mean(x)[0]), objective=float(objective(x, params)[0]))
    else:
        row.update({n: np.nan for n in OPERATION_PARAMS}, C_p=np.nan, C_p_mean=np.nan, objective=np.nan)
    row.update(acceptance_columns(result.feasible, row["C_p"], row["C_p_mean"], params.Cp_th))
    return {"summary": row, "history": history}


def acceptance_columns(accepted: bool, cp_measured: float, cp_true: float, cp_th: float) -> dict:
    """Three readings of "the answer is feasible" (issue: predicted is not measured).

    ``predicted_feasible``: the method's own acceptance rule (GPR: the paper's
    ``P(C_p >= C_p^th) >= P_th`` on the final GP; random search: the measured C_p met the
    threshold); ``measured_meets``: the measured C_p of the answer meets ``C_p^th``;
    ``true_meets``: the noise-free model's C_p meets it. All False without an answer.
    """
    return {"predicted_feasible": bool(accepted),
            "measured_meets": bool(np.isfinite(cp_measured) and cp_measured >= cp_th),
            "true_meets": bool(np.isfinite(cp_true) and cp_true >= cp_th)}


def gpr_vs_random(*, parts=PARTS, seeds=range(3), gpr_budget: int = 80, random_budget: int = 300,
                  n_jobs: int | None = None):
    """GPR and random search for every part and seed.

    Returns
    -------
    summary : DataFrame
        One row per (part, method, seed): part, method, seed, experiments,
        experiments_to_reach (``cp_tol`` 0.02) and experiments_to_reach_strict (``cp_tol`` 0),
        NaN if never within the budget, budget, stop_reason, the chosen v, f_n, kappa, f_x, A_x,
        its measured C_p, noise-free C_p_mean and objective, and the three acceptance columns
        of :func:`acceptance_columns`.
    histories : DataFrame
        Every experiment of every run.
    """
    items = [(p, m, int(s), gpr_budget if m == "gpr" else random_budget)
             for p in parts for s in seeds for m in ("gpr", "random")]
    out = map_trials(run_trial, items, n_jobs=n_jobs, desc="GPR vs random")
    summary = pd.DataFrame([o["summary"] for o in out])
    for k, (column, cp_tol) in enumerate(REACH_COLUMNS.items()):
        reach = [experiments_to_reach(o["history"], _optimum(o["summary"]["part"]), cp_tol=cp_tol) for o in out]
        summary.insert(4 + k, column, [np.nan if r is None else float(r) for r in reach])
    summary.insert(4 + len(REACH_COLUMNS), "budget", [b for _, _, _, b in items])
    histories = pd.concat([o["history"] for o in out], ignore_index=True)
    return summary, histories


#: ``experiments_to_reach`` columns of :func:`gpr_vs_random` and their ``cp_tol``: 0.02 is about
#: one standard deviation of a simulated C_p measurement, 0 demands the threshold itself.
REACH_COLUMNS = {"experiments_to_reach": 0.02, "experiments_to_reach_strict": 0.0}


def speedup(summary: pd.DataFrame) -> pd.DataFrame:
    """Experiments saved by GPR: per part and ``cp_tol``, median(random) / median(GPR) of the
    experiments to reach the optimum, a run that never reaches it counting as its budget + 1
    (a lower bound for random search, a penalty for GPR).

    Returns
    -------
    DataFrame: part, cp_tol, gpr_median, random_median, ratio, gpr_never, random_never.
    """
    rows = []
    for part, runs in summary.groupby("part", sort=True):
        for column, cp_tol in REACH_COLUMNS.items():
            row = {"part": part, "cp_tol": cp_tol}
            for method in ("gpr", "random"):
                sub = runs[runs["method"] == method]
                r = sub[column].to_numpy(float)
                row[f"{method}_median"] = float(np.median(np.where(np.isnan(r), sub["budget"] + 1, r)))
                row[f"{method}_never"] = int(np.isnan(r).sum())
            row["ratio"] = row["random_median"] / row["gpr_median"]
            rows.append(row)
    return pd.DataFrame(rows)[["part", "cp_tol", "gpr_median", "random_median", "ratio", "gpr_never", "random_never"]]


def learning_curves(histories: pd.DataFrame, parts=PARTS, cp_tol: float = 0.02) -> pd.DataFrame:
    """Best truly feasible objective found so far versus experiments, median over seeds.

    A point counts as feasible when the noise-free C_p meets the threshold up to ``cp_tol``
    (the measurement noise, as in :func:`mavac.scrubbing.gpr.experiments_to_reach`; evaluation
    only, the learners see measured C_p). Before any feasible point a run scores 0 (the
    objective's floor); a run that stopped early keeps its final value, so every curve
    is a median over all seeds and never decreases.

    Returns
    -------
    DataFrame: part, method, experiment, best_objective (median over seeds), optimum.
    """
    optima = dense_optima(parts).set_index("part")
    out = []
    for (part, method), runs in histories.groupby(["part", "method"], sort=True):
        th = gpr_params_for(part).Cp_th
        n = int(runs["experiment"].max())
        table = []
        for _, h in runs.groupby("seed", sort=True):
            ok = h["C_p_mean"].to_numpy() >= th - cp_tol
            best = np.maximum.accumulate(np.where(ok, h["objective"].to_numpy(), 0.0))
            table.append(np.concatenate([best, np.full(n - len(best), best[-1])]))
        out.append(pd.DataFrame({"part": part, "method": method, "experiment": np.arange(1, n + 1),
                                 "best_objective": np.median(table, axis=0),
                                 "optimum": optima.loc[part, "objective"]}))
    return pd.concat(out, ignore_index=True)


def paper_vs_ours(summary: pd.DataFrame) -> pd.DataFrame:
    """The paper's chosen operation parameters (Sec. IX-C) against ours (median over the GPR
    seeds whose answer the paper's rule accepts, ``predicted_feasible``), per part and quantity, with the thresholds used."""
    rows = []
    gpr = summary[(summary["method"] == "gpr") & summary["predicted_feasible"].astype(bool)]
    for part in sorted(set(summary["part"])):
        mine = gpr[gpr["part"] == part]
        params = gpr_params_for(part)
        for q in OPERATION_PARAMS:
            rows.append({"part": part, "quantity": q,
                         "paper": paper_scalar("kabir", _REF, q, f"part={part}"),
                         "ours": float(mine[q].median()) if len(mine) else np.nan})
        rows.append({"part": part, "quantity": "Cp_th", "paper": paper_scalar("kabir", _REF, "Cp_th", f"part={part}"),
                     "ours": params.Cp_th})
        rows.append({"part": part, "quantity": "P_th", "paper": paper_scalar("kabir", _REF, "P_th", f"part={part}"),
                     "ours": params.P_th})
    return pd.DataFrame(rows)

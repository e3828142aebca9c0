"""Kabir et al., Sec. VIII / IX-C: GPR operation-parameter learning on the SIMULATED scrub.

Tables for ``notebooks/10_gpr_parameters.ipynb``: GPR and random search over seeds for the
bowl (``C_p^th``, ``P_th`` of the paper's bowl) and the hull settings, the true optimum of
the noise-free simulated model, learning curves and the paper-vs-ours table. The thresholds
are read from ``data/paper_values.csv``. The cleaning physics is our simulated model
(:mod:`mavac.sim.wear`), so the learned parameters are not expected to match the paper's.
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
from ..sim.wear import ScrubExperiment

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
    drawn from ``seed``, hardness from ``(seed, 1)``). Cached per process."""
    return execution.scrub_experiment(load_part(part, seed=seed), np.random.default_rng([seed, 1]))


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
    rng = np.random.default_rng([seed, 7])
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
           "stop_reason": result.stop_reason, "feasible": result.feasible}
    if result.chosen is not None:
        x = np.array([[result.chosen[n] for n in OPERATION_PARAMS]])
        row.update(result.chosen)
        row.update(C_p_mean=float(ex.mean(x)[0]), objective=float(objective(x, params)[0]))
    else:
        row.update({n: np.nan for n in OPERATION_PARAMS}, C_p=np.nan, C_p_mean=np.nan, objective=np.nan)
    return {"summary": row, "history": history}


def gpr_vs_random(*, parts=PARTS, seeds=range(3), gpr_budget: int = 80, random_budget: int = 300,
                  n_jobs: int | None = None):
    """GPR and random search for every part and seed.

    Returns
    -------
    summary : DataFrame
        One row per (part, method, seed): part, method, seed, experiments,
        experiments_to_reach (NaN if never within the budget), stop_reason, feasible, the
        chosen v, f_n, kappa, f_x, A_x, its measured C_p, noise-free C_p_mean and objective.
    histories : DataFrame
        Every experiment of every run.
    """
    items = [(p, m, int(s), gpr_budget if m == "gpr" else random_budget)
             for p in parts for s in seeds for m in ("gpr", "random")]
    out = map_trials(run_trial, items, n_jobs=n_jobs, desc="GPR vs random")
    summary = pd.DataFrame([o["summary"] for o in out])
    reach = [experiments_to_reach(o["history"], _optimum(o["summary"]["part"])) for o in out]
    summary.insert(4, "experiments_to_reach", [np.nan if r is None else float(r) for r in reach])
    histories = pd.concat([o["history"] for o in out], ignore_index=True)
    return summary, histories


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
    seeds that ended feasible), per part and quantity, with the thresholds used."""
    rows = []
    gpr = summary[(summary["method"] == "gpr") & summary["feasible"].astype(bool)]
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

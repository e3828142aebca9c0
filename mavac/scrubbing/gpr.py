"""Operation-parameter learning with a Gaussian-process surrogate (Kabir et al., Sec. VIII).

The cleaning performance ``C_p`` is a black-box inequality constraint ``C_p >= C_p^th``;
the objective is known: maximise tool speed and minimise normal force. Procedure:

1. coarse uniform exploration: a cell-centred grid with ``grid_points`` per axis over the
   bounded 5-D box of ``(v, f_n, kappa, f_x, A_x)`` (with 2 points per axis, by default the
   resolution-V half fraction: 16 of the 32 points), plus its centre;
2. fit a GP surrogate of C_p (scikit-learn, Matern 5/2 with ARD + white noise, inputs
   normalised to [0, 1]^5 -- by default on log scales: speeds, forces, stiffnesses and
   frequencies act multiplicatively, e.g. a resonance ``f ~ sqrt(kappa / m)`` is a straight
   line in log coordinates);
3. the current *answer* is the best-objective point run so far whose probability
   ``P(C_p >= C_p^th) = 1 - Phi((th - mu) / sigma)`` is at least ``P_th`` (mu, sigma of the
   noise-free C_p: the fitted white noise is taken out of the GP's std);
4. candidates: seeded scrambled Sobol points, the grid, clouds around the answer and the
   last exploitation point, and every point already run; among those with probability
   ``>= P_th`` the best objective is run next (an exploitation experiment; a run point
   chosen again is replicated, so its noise averages out). If no candidate reaches
   ``P_th`` (ours) the most probably feasible one is run instead (phase ``search``).
   Refit and repeat;
5. stop when the answer itself is chosen again ("same point chosen twice"), when the
   answer's objective improved by less than ``tol`` over ``patience`` iterations, or at the
   ``max_experiments`` budget -- so an unreachable threshold ends as infeasible after a
   bounded number of experiments.

Objective (our scalarisation of "maximise tool speed and minimise applied force"):
``J = w (v - v_lo) / (v_hi - v_lo) + (1 - w) (f_hi - f_n) / (f_hi - f_lo)`` in [0, 1],
``w = speed_weight`` (0.5: equal weights on the normalised axes), maximised.

The result is the answer under the GP refitted on all experiments; no run point with
probability ``>= P_th`` -> infeasible. With a small ``P_th`` (the paper's bowl uses 0.1) the
answer is deliberately optimistic: it approaches the threshold from slightly below.

An ``experiment`` is any callable ``experiment(x (5,), rng) -> C_p``; if it also has
``mean(X (n, 5)) -> (n,)`` (a noise-free model, as :class:`mavac.scrubbing.wear.ScrubExperiment`)
the history records it as ``C_p_mean`` for evaluation only -- the learner never reads it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import norm, qmc
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel
from tqdm.auto import tqdm

from ..parallel import single_thread
from ..params import MAX_EXPERIMENTS, OPERATION_PARAMS, GPRParams
from ..seeding import rng_for
from ..validate import (ParameterTypeError, check_array, check_callable, check_instance, check_int,
                        check_nonnegative, check_points, check_real)

__all__ = ["GPRParams", "GPRResult", "DenseOptimum", "OPERATION_PARAMS", "objective", "coarse_grid",
           "fit_surrogate", "feasibility_probability", "learn_parameters", "random_search",
           "dense_optimum", "experiments_to_reach"]


@dataclass
class GPRResult:
    """Outcome of a parameter search.

    Attributes
    ----------
    history : pandas.DataFrame
        One row per experiment: ``experiment`` (1-based), ``phase`` (explore / exploit /
        search / random), the five parameters, measured ``C_p``, ``objective``, ``p_feasible`` (GP
        probability when chosen, NaN otherwise) and ``C_p_mean`` when the experiment has a
        noise-free model.
    chosen : dict or None
        Parameter name -> value of the answer, plus its measured ``C_p`` (and for GPR its
        final ``p_feasible``); None when infeasible.
    feasible : bool
        Whether a point meeting ``C_p^th`` was found within the budget.
    experiments : int
        Experiments run.
    stop_reason : str
    """

    history: pd.DataFrame
    chosen: dict | None
    feasible: bool
    experiments: int
    stop_reason: str


@dataclass
class DenseOptimum:
    """True feasible optimum of a noise-free model, found by dense search.

    Attributes
    ----------
    x : (5,) float or None
    chosen : dict or None
    objective : float (NaN when infeasible)
    C_p : float
    Cp_th : float
    feasible : bool
    """

    x: np.ndarray | None
    chosen: dict | None
    objective: float
    C_p: float
    Cp_th: float
    feasible: bool


def _box(params: GPRParams):
    lo, hi = np.array(params.lower), np.array(params.upper)
    return (np.log(lo), np.log(hi)) if params.log_inputs else (lo, hi)


def _to_unit(X, params):
    """Operation vectors -> [0, 1]^5 (log-scaled when ``params.log_inputs``)."""
    lo, hi = _box(params)
    X = np.asarray(X, dtype=float)
    return ((np.log(X) if params.log_inputs else X) - lo) / (hi - lo)


def _from_unit(U, params):
    lo, hi = _box(params)
    X = lo + np.asarray(U, dtype=float) * (hi - lo)
    return np.exp(X) if params.log_inputs else X


def objective(X, params: GPRParams = GPRParams()) -> np.ndarray:
    """Scalarised objective (maximised) for operation vectors ``X`` (n, 5) -> (n,) in [0, 1]
    (linear in v and f_n whatever the input scaling)."""
    X = check_points("X", X, len(OPERATION_PARAMS))
    lo, hi = np.array(params.lower), np.array(params.upper)
    U = (X - lo) / (hi - lo)
    w = params.speed_weight
    return w * U[:, 0] + (1 - w) * (1 - U[:, 1])


def coarse_grid(params: GPRParams = GPRParams()) -> np.ndarray:
    """Coarse uniform exploration design, (m, 5): a cell-centred grid with ``grid_points``
    per axis (at ``(i + 1/2) / grid_points`` of each normalised range, so no experiment sits
    on the extreme corners of the safety box), the 2^(5-1) half fraction of it when
    ``grid_points == 2`` and ``half_fraction``, plus the box centre."""
    g = params.grid_points
    axes = [(np.arange(g) + 0.5) / g] * len(OPERATION_PARAMS)
    U = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(OPERATION_PARAMS))
    if g == 2 and params.half_fraction:
        # 2^(5-1) design, defining relation I = ABCDE (resolution V): main effects and
        # two-factor interactions stay unaliased with half the experiments.
        U = U[np.prod(np.where(U > 0.5, 1, -1), axis=1) == 1]
    if g % 2 == 0:
        U = np.vstack([U, np.full(len(OPERATION_PARAMS), 0.5)])
    return _from_unit(U, params)


def fit_surrogate(U, y, seed: int = 0) -> GaussianProcessRegressor:
    """GP surrogate of C_p on normalised inputs ``U`` (n, 5) in [0, 1]^5.

    Kernel: constant x Matern(nu = 5/2, one length scale per axis) + white noise;
    targets normalised.
    """
    kernel = (ConstantKernel(1.0, (1e-3, 1e3))
              * Matern(length_scale=np.full(U.shape[1], 0.5), length_scale_bounds=(0.03, 30.0), nu=2.5)
              + WhiteKernel(1e-3, (1e-6, 1e-1)))
    gp = GaussianProcessRegressor(kernel, normalize_y=True, n_restarts_optimizer=1, random_state=seed)
    # Small matrices: multithreaded BLAS only adds contention (10-30x slower on a busy box).
    with warnings.catch_warnings(), single_thread():
        warnings.simplefilter("ignore", ConvergenceWarning)
        gp.fit(U, y)
    return gp


def latent_prediction(gp: GaussianProcessRegressor, U):
    """Mean and std of the noise-free C_p at ``U``: the fitted white noise is removed from
    scikit-learn's predictive std, so repeated experiments make the model certain."""
    with single_thread():
        mu, sigma = gp.predict(U, return_std=True)
    # kernel_ = C * Matern + White (fit_surrogate); with normalize_y the white noise level is
    # in normalised units, scikit-learn keeps the scale in _y_train_std.
    noise = gp.kernel_.k2.noise_level * float(np.mean(gp._y_train_std)) ** 2
    return mu, np.sqrt(np.maximum(sigma**2 - noise, 1e-12))


def feasibility_probability(gp: GaussianProcessRegressor, U, threshold: float) -> np.ndarray:
    """``P(C_p >= threshold) = 1 - Phi((threshold - mu) / sigma)`` at normalised points ``U``,
    for the noise-free C_p (latent GP)."""
    mu, sigma = latent_prediction(gp, U)
    return norm.sf((threshold - mu) / sigma)


def _candidates(params: GPRParams, rng: np.random.Generator, grid_U, run_U, centres_U):
    """Scrambled Sobol points, the grid, the run points, and Gaussian clouds (normalised
    scales 0.05 and 0.15, clipped to the box so bounds can be chosen) around ``centres_U``."""
    sobol = qmc.Sobol(len(OPERATION_PARAMS), scramble=True, seed=rng).random(params.n_candidates)
    parts = [sobol, grid_U, run_U]
    n_local = params.n_candidates // (4 * max(len(centres_U), 1))
    for centre in centres_U:
        for scale in (0.05, 0.15):
            local = centre + rng.normal(0.0, scale, (n_local, len(OPERATION_PARAMS)))
            parts.append(np.clip(local, 0.0, 1.0))
    return np.vstack(parts)


def _run(experiment, x, rng) -> float:
    """One experiment, the only place its results enter: ``C_p`` must be a finite real number
    (a NaN or ``None`` would otherwise fail inside scikit-learn, far from its cause)."""
    cp = experiment(x, rng)
    if isinstance(cp, np.ndarray) and cp.size == 1:
        cp = cp.reshape(())[()]
    try:
        value = check_real("experiment", cp)
    except TypeError:
        raise ParameterTypeError(f"experiment must return C_p as a real number, got {cp!r} "
                                 f"({type(cp).__name__}) at {_where(x)}") from None
    if not np.isfinite(value):
        raise ValueError(f"experiment returned C_p = {cp!r} at {_where(x)}; it must be a finite "
                         "number (a failed measurement has to be repeated or reported, not passed on)")
    return value


def _where(x) -> str:
    return ", ".join(f"{n}={v:.4g}" for n, v in zip(OPERATION_PARAMS, x))


def _record(rows, x, cp, phase, p, params, experiment):
    row = {"experiment": len(rows) + 1, "phase": phase}
    row.update(dict(zip(OPERATION_PARAMS, map(float, x))))
    row["C_p"] = cp
    row["objective"] = float(objective(x[None], params)[0])
    row["p_feasible"] = float(p)
    if hasattr(experiment, "mean"):
        row["C_p_mean"] = float(np.asarray(experiment.mean(np.asarray(x)[None]))[0])
    rows.append(row)


def _best_row(history: pd.DataFrame, ok: np.ndarray) -> int | None:
    """Index of the best-objective row among ``ok`` (earliest on ties), None if none."""
    if not ok.any():
        return None
    J = np.where(ok, history["objective"].to_numpy(), -np.inf)
    return int(np.argmax(J))


def _chosen(history: pd.DataFrame, i: int | None, p_feasible=None) -> dict | None:
    if i is None:
        return None
    out = {n: float(history[n].iloc[i]) for n in OPERATION_PARAMS} | {"C_p": float(history["C_p"].iloc[i])}
    if p_feasible is not None:
        out["p_feasible"] = float(p_feasible)
    return out


def _fit_history(history: pd.DataFrame, params: GPRParams, seed: int):
    U_run = _to_unit(history[list(OPERATION_PARAMS)].to_numpy(), params)
    gp = fit_surrogate(U_run, history["C_p"].to_numpy(), seed=seed)
    return U_run, gp, feasibility_probability(gp, U_run, params.Cp_th)


def _check_learner_inputs(experiment, params, rng) -> None:
    check_callable("experiment", experiment, "(x (5,), rng) -> C_p")
    check_instance("params", params, GPRParams)
    if rng is not None:
        check_instance("rng", rng, np.random.Generator)


def learn_parameters(experiment, params: GPRParams = GPRParams(),
                     *, rng: np.random.Generator | None = None, progress: bool = False,
                     admissible=None) -> GPRResult:
    """Learn operation parameters meeting ``C_p >= C_p^th`` (Kabir, Sec. VIII); see the module doc.

    Parameters
    ----------
    experiment : callable ``(x (5,), rng) -> float``
        The black box (a physical experiment in the paper; the simulated scrub here).
    params : GPRParams
    rng : numpy.random.Generator, optional
        Drives candidates and the experiment's noise; default the stream "gpr" of ``params.seed`` (:func:`mavac.seeding.rng_for`).
    progress : bool
        tqdm bar over experiments.
    admissible : callable ``(X (n, 5)) -> (n,) bool``, optional
        A known constraint of the robot (e.g. the cell's path-deviation cap,
        :func:`mavac.scrubbing.lissajous.vector_excursions`): a point outside it is never run
        nor chosen -- part of the feasibility rule, beside ``P(C_p >= C_p^th) >= P_th``.

    Returns
    -------
    GPRResult
    """
    _check_learner_inputs(experiment, params, rng)
    if admissible is not None:
        check_callable("admissible", admissible, "(X (n, 5)) -> (n,) bool")
    rng = rng_for(params.seed, "gpr") if rng is None else rng
    allowed = (lambda X: np.ones(len(X), dtype=bool)) if admissible is None else admissible
    rows: list = []
    grid = coarse_grid(params)
    grid = grid[np.asarray(allowed(grid), dtype=bool)]
    if len(grid) == 0:
        raise ValueError("admissible: it refuses every point of the exploration grid")
    bar = tqdm(total=params.max_experiments, disable=not progress, leave=False, desc="GPR")
    for x in grid[: params.max_experiments]:
        _record(rows, x, _run(experiment, x, rng), "explore", np.nan, params, experiment)
        bar.update()
    grid_U = _to_unit(grid, params)
    stop_reason = "budget"
    best_J, stale = np.nan, 0
    while len(rows) < params.max_experiments:
        history = pd.DataFrame(rows)
        U_run, gp, prob_run = _fit_history(history, params, int(rng.integers(2**31 - 1)))
        answer = _best_row(history, prob_run >= params.P_th)
        if answer is not None:  # convergence: the answer's objective stopped improving
            J_answer = float(history["objective"].iloc[answer])
            if not np.isfinite(best_J) or J_answer > best_J + params.tol:
                best_J, stale = J_answer, 0
            else:
                stale += 1
            if stale >= params.patience:
                stop_reason = "converged (no improvement)"
                break
        centres = [U_run[-1]] if rows[-1]["phase"] != "explore" else []
        if answer is not None:
            centres.append(U_run[answer])
        cand_U = _candidates(params, rng, grid_U, U_run, centres)
        prob = feasibility_probability(gp, cand_U, params.Cp_th)
        prob[~np.asarray(allowed(_from_unit(cand_U, params)), dtype=bool)] = -1.0  # never chosen
        ok = np.flatnonzero(prob >= params.P_th)
        if ok.size:
            J = objective(_from_unit(cand_U[ok], params), params)
            pick, phase = ok[int(np.argmax(J))], "exploit"
        else:  # nothing looks feasible enough yet: run the most probably feasible candidate
            pick, phase = int(np.argmax(prob)), "search"
        if answer is not None and np.abs(U_run[answer] - cand_U[pick]).max() < 1e-9:
            stop_reason = "same point chosen twice"
            break
        # Another run point chosen again is replicated (its noise gets averaged).
        x = _from_unit(cand_U[pick], params)
        _record(rows, x, _run(experiment, x, rng), phase, prob[pick], params, experiment)
        bar.update()
    bar.close()
    history = pd.DataFrame(rows)
    _, _, prob_run = _fit_history(history, params, params.seed)
    answer = _best_row(history, prob_run >= params.P_th)
    chosen = _chosen(history, answer, None if answer is None else prob_run[answer])
    return GPRResult(history, chosen, chosen is not None, len(history), stop_reason)


def random_search(experiment, params: GPRParams = GPRParams(), *, budget: int = 100,
                  rng: np.random.Generator | None = None) -> GPRResult:
    """Baseline: ``budget`` experiments at uniform random points of the box (uniform in the
    same normalised coordinates as the GPR design, i.e. log-uniform with ``log_inputs``).

    The answer is the best-objective point whose measured C_p met the threshold.
    """
    budget = check_int("budget", budget, 1, MAX_EXPERIMENTS)
    _check_learner_inputs(experiment, params, rng)
    rng = rng_for(params.seed, "gpr") if rng is None else rng
    rows: list = []
    for _ in range(budget):
        x = _from_unit(rng.uniform(size=len(OPERATION_PARAMS)), params)
        _record(rows, x, _run(experiment, x, rng), "random", np.nan, params, experiment)
    history = pd.DataFrame(rows)
    chosen = _chosen(history, _best_row(history, history["C_p"].to_numpy() >= params.Cp_th))
    return GPRResult(history, chosen, chosen is not None, budget, "budget")


def _model_values(experiment_mean, X) -> np.ndarray:
    """``experiment_mean(X)`` checked: one finite C_p per row of ``X``."""
    cp = check_array("experiment_mean", experiment_mean(X), float)
    if cp.shape != (len(X),):
        raise ValueError(f"experiment_mean must return ({len(X)},) C_p values, got shape {cp.shape}")
    if not np.all(np.isfinite(cp)):
        raise ValueError("experiment_mean returned NaN or infinite C_p values; it must be finite")
    return cp


def dense_optimum(experiment_mean, params: GPRParams = GPRParams(), *, points_per_axis=(33, 33, 13, 13, 13),
                  chunk: int = 200_000) -> DenseOptimum:
    """Feasible optimum of a noise-free model by dense grid search, refined once.

    Parameters
    ----------
    experiment_mean : callable ``(X (n, 5)) -> (n,)``
        Noise-free C_p (e.g. ``ScrubExperiment.mean``).
    params : GPRParams
    points_per_axis : 5 ints
        Grid resolution per parameter (v and f_n, which the objective sees, finest). A
        second grid of the same size over +-1 cell around the best point refines it.
    chunk : int
        Points evaluated per call.

    Returns
    -------
    DenseOptimum
    """
    check_callable("experiment_mean", experiment_mean, "(X (n, 5)) -> (n,) C_p")
    check_instance("params", params, GPRParams)
    counts = [check_int("points_per_axis", n, 2) for n in points_per_axis]
    if len(counts) != len(OPERATION_PARAMS):
        raise ValueError(f"points_per_axis must have {len(OPERATION_PARAMS)} entries, got {len(counts)}")
    check_int("chunk", chunk, 1)

    def search(lo_u, hi_u):
        axes = [np.linspace(a, b, n) for a, b, n in zip(lo_u, hi_u, counts)]
        U = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(counts))
        X = _from_unit(U, params)
        J = objective(X, params)
        order = np.argsort(-J, kind="stable")
        for start in range(0, len(order), chunk):  # best objective first: stop at first feasible
            idx = order[start:start + chunk]
            cp = _model_values(experiment_mean, X[idx])
            hit = np.flatnonzero(cp >= params.Cp_th)
            if hit.size:
                i = idx[hit[0]]
                top = J[i]
                # Among equal-objective feasible points keep the one with the largest C_p.
                same = idx[hit][np.isclose(J[idx[hit]], top)]
                cps = _model_values(experiment_mean, X[same])
                j = same[int(np.argmax(cps))]
                return U[j], float(J[j]), float(cps.max())
        return None, np.nan, np.nan

    u, J, cp = search(np.zeros(5), np.ones(5))
    if u is None:
        return DenseOptimum(None, None, np.nan, np.nan, params.Cp_th, False)
    cell = 1.0 / (np.array(counts) - 1)
    u2, J2, cp2 = search(np.clip(u - cell, 0, 1), np.clip(u + cell, 0, 1))
    if u2 is not None and J2 > J:
        u, J, cp = u2, J2, cp2
    x = _from_unit(u, params)
    return DenseOptimum(x, dict(zip(OPERATION_PARAMS, map(float, x))), J, cp, params.Cp_th, True)


def experiments_to_reach(history: pd.DataFrame, optimum: DenseOptimum, *, tol: float = 0.05,
                         cp_tol: float = 0.02) -> int | None:
    """Experiments run until the first point that is feasible and within ``tol`` of the optimum.

    A point counts when its objective is at least ``optimum.objective - tol`` (objective in
    [0, 1], so ``tol`` = 0.05 is 5 % of its range) and it meets the threshold up to the
    measurement noise: ``C_p_mean >= Cp_th - cp_tol`` with the noise-free column when the
    history has it, else the measured C_p. (The learner targets ``P(C_p >= th) >= P_th``, so
    with a small ``P_th`` it converges onto the threshold from slightly below; ``cp_tol``
    0.02 is about the standard deviation of a C_p measurement in the simulated pipeline.)

    Returns
    -------
    int (1-based experiment count) or None when never reached (or the optimum is infeasible).
    """
    check_nonnegative("tol", tol)
    check_nonnegative("cp_tol", cp_tol)
    if not optimum.feasible or len(history) == 0:
        return None
    cp = history["C_p_mean"] if "C_p_mean" in history else history["C_p"]
    hit = (history["objective"] >= optimum.objective - tol) & (cp >= optimum.Cp_th - cp_tol)
    return int(history.loc[hit, "experiment"].iloc[0]) if hit.any() else None

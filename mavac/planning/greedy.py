"""The paper's iterative greedy selection, shared by spot and guard selection.

MAVAC, "Robot base placement" (after Paus et al.) and "Guard selection": candidates are scored
by the surface elements they add; in three steps,

1. the candidate with the highest score is selected;
2. its elements are removed from every remaining candidate's set;
3. candidates are rescored, and the loop repeats until the new highest score falls below a
   threshold fixed at the first iteration as ``P`` x the first highest score.

Spots use the score ``N / |S|`` (the number of new accessible elements); guards use eq. 3,
``I_m^k1 x (N / |S|)^k2``. Both are ``weight^k1 x (N / |S|)^k2`` with a weight of 1 for spots,
so one function serves both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..tolerances import GREEDY_TIE_RTOL
from ..validate import check_array, check_bool_array, check_unit


@dataclass(frozen=True)
class GreedyResult:
    """Outcome of :func:`greedy_select`.

    Attributes
    ----------
    selected : (k,) int
        Candidate indices in selection order.
    scores : (k,) float
        Score of each selected candidate when it was selected.
    gains : (k,) int
        New elements each selected candidate added.
    threshold : float
        Absolute stopping threshold, ``P`` x the first highest score (0 if nothing was selectable).
    covered : (n,) bool
        Elements covered after selection (including those covered beforehand).
    """

    selected: np.ndarray
    scores: np.ndarray
    gains: np.ndarray
    threshold: float
    covered: np.ndarray


def greedy_scores(new_counts, n_elements: int, *, weights=None, k1: float = 1.0, k2: float = 1.0):
    """Score ``weight^k1 x (N / |S|)^k2`` (MAVAC eq. 3); candidates adding nothing score 0.

    Parameters
    ----------
    new_counts : (m,) int
        N, the number of not-yet-covered elements each candidate covers.
    n_elements : int
        |S|.
    weights : (m,) float in [0, 1], optional
        I_m per candidate; ``None`` means 1 (spot selection).
    k1, k2 : float in [0, 1]
        Exponents of eq. 3.
    """
    counts = np.asarray(new_counts, dtype=float)
    w = np.ones_like(counts) if weights is None else np.asarray(weights, dtype=float)
    # 0^0 = 1 in numpy, which is eq. 3's value at k = 0; a candidate that adds nothing is out.
    score = np.power(w, k1) * np.power(counts / max(n_elements, 1), k2)
    return np.where(counts > 0, score, 0.0)


def _check_greedy_inputs(access, P, weights, k1, k2, covered):
    """``access`` (m, n) bool, ``weights`` (m,) float or None, and a copy of ``covered`` (n,) bool."""
    check_unit("P", P)
    check_unit("k1", k1)
    check_unit("k2", k2)
    access = check_bool_array("access", access)
    if access.ndim != 2:
        raise ValueError(f"access must be a 2-D (candidates, elements) bool array, got shape {access.shape}")
    m, n = access.shape
    if weights is not None:
        weights = check_array("weights", weights, float)
        if weights.shape != (m,):
            raise ValueError(f"weights must have shape ({m},), got {weights.shape}")
        if np.any(~np.isfinite(weights)) or np.any(weights < 0) or np.any(weights > 1):
            raise ValueError("weights must be in [0, 1]")
    done = np.zeros(n, dtype=bool) if covered is None else check_bool_array("covered", covered).copy()
    if done.shape != (n,):
        raise ValueError(f"covered must have shape ({n},), got {done.shape}")
    return access, weights, done


def greedy_select(access, P: float, *, weights=None, k1: float = 1.0, k2: float = 1.0,
                  covered=None, evaluate=None, batch: int = 8) -> GreedyResult:
    """Iterative greedy selection with threshold ``P`` x first maximum score (MAVAC).

    Parameters
    ----------
    access : (m, n) bool
        ``access[i, j]``: candidate i covers (sees and reaches) element j. With ``evaluate``,
        an upper bound (superset) of each candidate's set instead, e.g. the FOV pyramid alone.
    P : float in [0, 1]
        P_s for spots, P_g for guards. 0 keeps selecting while anything new is covered.
    weights : (m,) float in [0, 1], optional
        Maneuverability I_m of each candidate (guards); ``None`` for spots.
    k1, k2 : float in [0, 1]
        Weighting exponents of eq. 3.
    covered : (n,) bool, optional
        Elements already covered (e.g. by another spot's guards); they never count as new.
    evaluate : callable, optional
        ``evaluate(indices (k,) int) -> (k, n) bool``: the exact sets of those candidates (each a
        subset of its ``access`` row). Exact sets are then computed lazily, only for candidates
        whose bound score could still beat the best exact score, so the result is the same as
        with every exact set given up front (the bound score is never below the exact one).
    batch : int
        Candidates evaluated per ``evaluate`` call.

    Returns
    -------
    GreedyResult
        Ties are broken by the lowest candidate index, so the result is deterministic.
    """
    access, weights, done = _check_greedy_inputs(access, P, weights, k1, k2, covered)
    m, n = access.shape

    exact = access.copy()
    known = np.full(m, evaluate is None)  # rows of ``exact`` that hold exact sets

    def settle(counts):
        """Evaluate candidates until the best exact score beats every bound; return its index."""
        while True:
            score = greedy_scores(counts, n, weights=weights, k1=k1, k2=k2)
            best_known = np.where(known, score, -1.0)
            top = float(best_known.max()) if m else -1.0
            pending = np.flatnonzero(~known & (score >= top) & (score > 0.0))
            if len(pending) == 0:
                return int(np.argmax(best_known)) if m else 0, score
            pending = pending[np.argsort(-score[pending], kind="stable")][:batch]
            rows = np.asarray(evaluate(pending), dtype=bool).reshape(len(pending), n)
            exact[pending] = rows & access[pending]
            known[pending] = True
            counts[pending] = exact[pending][:, ~done].sum(axis=1)

    counts = exact[:, ~done].sum(axis=1).astype(np.int64)
    selected, scores, gains = [], [], []
    threshold = 0.0
    while True:
        best, score = settle(counts)
        if m == 0 or not known[best] or score[best] <= 0.0:
            break
        if not selected:
            threshold = P * float(score[best])
        elif score[best] < threshold * (1.0 - GREEDY_TIE_RTOL):  # a tie with the threshold is kept
            break
        new = exact[best] & ~done
        selected.append(best)
        scores.append(float(score[best]))
        gains.append(int(counts[best]))
        done |= new
        # incremental rescoring: only the newly covered columns change the counts
        counts -= exact[:, new].sum(axis=1)
    return GreedyResult(np.asarray(selected, dtype=np.int64), np.asarray(scores, dtype=float),
                        np.asarray(gains, dtype=np.int64), threshold, done)

"""The linear-programming bound of a set-cover instance, by column generation.

The LP relaxation ``min c.x, A x >= 1, x >= 0`` of a setup-planning instance has thousands of
dense columns (the sine's reduced Table II instance: 6466 setups x 2660 patches, 5.3 M
non-zeros), and HiGHS spends most of a minute on its first solve. Few setups carry the LP
optimum, so :func:`lp_bound` solves it on a growing subset (the *master*): start from the
cheapest setup of every patch, price every setup with the master's duals ``u``
(``r_j = c_j - sum_{i in P(s_j)} u_i``) and add the most negative, until none is negative
(Desrosiers and Luebbecke 2005, "A primer in column generation"). Patches that another patch
implies within the master are dropped from its LP (their dual is 0), which keeps each master
solve small.

Whatever the round, ``u >= 0`` gives the Lagrangian bound ``sum u + sum_j min(0, r_j)``, a
valid lower bound on every cover; at convergence it equals the LP optimum. With an incumbent
``T``, a setup with ``bound + r_j >= T`` is in no cover cheaper than ``T`` (reduced-cost fixing,
:func:`fixable`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import csc_array

from .reduction import minimal_columns

# Rows priced per block: bounds the float64 copy of the cover at 512 x n.
_BLOCK = 512


@dataclass(frozen=True)
class LpBound:
    """Output of :func:`lp_bound`.

    Attributes
    ----------
    duals : (n,) float, s per patch, >= 0
        ``u``: the master's duals (0 on patches dropped from it).
    bound : float, s
        Lagrangian bound of ``duals``: no cover costs less.
    value : float, s
        The last master's LP optimum (the LP optimum itself when ``converged``).
    reduced_costs : (m,) float, s
        ``r_j = c_j - sum_{i in P(s_j)} u_i``.
    master : (k,) int
        Setups in the last master, ascending.
    rounds : int
        Master solves.
    converged : bool
        No setup prices below ``-tol``: ``bound`` is the LP optimum.
    """

    duals: np.ndarray
    bound: float
    value: float
    reduced_costs: np.ndarray
    master: np.ndarray
    rounds: int
    converged: bool


def lp_bound(cover: np.ndarray, costs: np.ndarray, *, max_rounds: int = 100) -> LpBound:
    """LP relaxation of the set cover by column generation (inputs trusted: every patch coverable).

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]``: setup j reaches patch i; every column has a True.
    costs : (m,) float, s, > 0
    max_rounds : int
        Master solves at most (ours: the reduced Table II instances converge in under 10).

    Returns
    -------
    LpBound
    """
    tol = 1e-9 * float(costs.max()) * cover.shape[1]
    master = _cheapest_per_patch(cover, costs)
    best = None
    for rounds in range(1, max_rounds + 1):
        value, duals = _solve_master(cover, costs, master)
        reduced = reduced_costs(cover, costs, duals)
        bound = float(duals.sum() + np.minimum(reduced, 0.0).sum())
        if best is None or bound > best.bound:
            best = LpBound(duals, bound, value, reduced, master, rounds, False)
        entering = np.flatnonzero(reduced < -tol)
        if len(entering) == 0 or value - best.bound <= 1e-9 * abs(value):
            break
        # The most negative, a quarter of the master at least 50 (ours: few rounds, small masters).
        take = max(50, len(master) // 4)
        master = np.union1d(master, entering[np.argsort(reduced[entering], kind="stable")[:take]])
    converged = value - best.bound <= 1e-9 * abs(value) + tol
    return LpBound(best.duals, best.bound, value, best.reduced_costs, best.master, rounds, converged)


def reduced_costs(cover: np.ndarray, costs: np.ndarray, duals: np.ndarray) -> np.ndarray:
    """``r_j = c_j - sum_{i in P(s_j)} u_i`` in float64, a block of setups at a time.

    Parameters
    ----------
    cover : (m, n) bool
    costs : (m,) float, s
    duals : (n,) float, s

    Returns
    -------
    (m,) float, s
    """
    priced = np.empty(len(costs))
    for a in range(0, len(costs), _BLOCK):
        priced[a:a + _BLOCK] = cover[a:a + _BLOCK].astype(np.float64) @ duals
    return costs - priced


def fixable(lp: LpBound, incumbent: float, rel_tol: float) -> np.ndarray:
    """Setups in no cover cheaper than ``(1 - rel_tol) * incumbent``.

    A cover holding setup j costs at least ``bound + max(r_j, 0)`` (the Lagrangian bound with
    ``x_j = 1``).

    Returns
    -------
    (m,) bool
    """
    return lp.bound + np.maximum(lp.reduced_costs, 0.0) >= incumbent * (1.0 - rel_tol)


def _cheapest_per_patch(cover: np.ndarray, costs: np.ndarray) -> np.ndarray:
    """The cheapest setup reaching each patch (a feasible first master), ascending."""
    order = np.argsort(costs, kind="stable")
    return np.unique(order[np.argmax(cover[order], axis=0)])


def _solve_master(cover: np.ndarray, costs: np.ndarray, master: np.ndarray):
    """LP optimum and duals ``(n,)`` of the master; implied patches carry dual 0."""
    sub = cover[master]
    rows = minimal_columns(sub)
    res = linprog(costs[master], A_ub=-csc_array(sub[:, rows].T.astype(np.float64)), b_ub=-np.ones(len(rows)),
                  bounds=(0, None), method="highs")
    if res.status != 0:
        raise RuntimeError(f"HiGHS could not solve the LP master: {res.message}")
    duals = np.zeros(cover.shape[1])
    duals[rows] = np.maximum(-res.ineqlin.marginals, 0.0)
    return float(res.fun), duals

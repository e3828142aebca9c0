"""Exact reductions of a weighted set-cover instance (setups x patches).

The classic presolve rules of set covering (Garfinkel and Nemhauser 1972; Beasley 1987), each
of which keeps at least one optimal cover:

* **uncoverable patches**: no setup reaches them; they are reported and left out;
* **forced setups**: a patch only one setup reaches puts that setup in every cover;
* **identical and implied patches**: when every setup reaching patch k also reaches patch i,
  covering k covers i, so column i is dropped (identical columns keep the lowest index);
* **dominated setups**: a setup whose patches another setup reaches too, at no lower cost, can
  be swapped for it in any cover, so it is dropped (identical rows at equal cost keep the
  lowest index); setups left with no patch are dropped.

The rules run to a fixed point. :func:`reduce_instance` is pure: it returns the reduced
instance and the map back to the original rows (:meth:`ReducedInstance.lift`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..validate import check_cover
from .dominance import dominated_by_any, nondominated, pack_rows

# Rows tested against each other in one vectorised block of the dominance test.
_BLOCK = 256


@dataclass(frozen=True)
class ReducedInstance:
    """A set-cover instance after :func:`reduce_instance`.

    Attributes
    ----------
    cover : (m', n') bool
        Rows: the setups still free to choose; columns: the patches still to cover.
    costs : (m',) float, s
    setups : (m',) int
        Original row of each reduced row.
    patches : (n',) int
        Original column of each reduced column.
    forced : (f,) int
        Original rows every cover contains, ascending.
    forced_cost : float, s
        Their summed cost.
    uncoverable : (u,) int
        Original columns no setup reaches.
    shape : (int, int)
        ``(m, n)`` of the original instance.
    """

    cover: np.ndarray
    costs: np.ndarray
    setups: np.ndarray
    patches: np.ndarray
    forced: np.ndarray
    forced_cost: float
    uncoverable: np.ndarray
    shape: tuple

    def lift(self, chosen) -> np.ndarray:
        """Original rows of a cover of the reduced instance, forced setups added.

        Parameters
        ----------
        chosen : (k,) int
            Rows of :attr:`cover`.

        Returns
        -------
        (k + f,) int, ascending
        """
        idx = self.setups[np.asarray(chosen, dtype=np.int64)]
        return np.unique(np.concatenate([self.forced, idx])).astype(np.int64)

    def summary(self) -> str:
        """``m x n -> m' x n'`` with the forced setups."""
        m, n = self.shape
        return (f"{m} x {n} -> {self.cover.shape[0]} x {self.cover.shape[1]} "
                f"({len(self.forced)} forced, {len(self.uncoverable)} uncoverable patches)")


def reduce_instance(cover: np.ndarray, costs: np.ndarray, *, check: bool = True) -> ReducedInstance:
    """Apply the exact set-cover reductions of this module to a fixed point.

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i.
    costs : (m,) float, s, >= 0
        Cost of each setup.
    check : bool
        Validate ``cover`` and ``costs`` (callers that already did pass False).

    Returns
    -------
    ReducedInstance
        Every optimal cover of the reduced instance, lifted, is an optimal cover of the
        coverable patches of the original, and the optimum is preserved:
        ``opt(original) = forced_cost + opt(reduced)``.
    """
    if check:
        cover, costs = check_instance(cover, costs)
    m, n = cover.shape
    coverable = cover.any(axis=0)
    rows = np.flatnonzero(cover.any(axis=1))
    cols = np.flatnonzero(coverable)
    forced: list[int] = []
    # Columns only become forced or implied when rows go, rows only dominated when columns go.
    rows_dirty = cols_dirty = True
    while rows_dirty or cols_dirty:
        if rows_dirty:
            rows, cols_f, new = _apply_forced(cover[np.ix_(rows, cols)], rows, cols)
            forced += new
            keep = cols_f[minimal_columns(cover[np.ix_(rows, cols_f)])]
            cols_dirty = cols_dirty or len(keep) < len(cols)
            cols, rows_dirty = keep, False
        if cols_dirty:
            keep = rows[_undominated_rows(cover[np.ix_(rows, cols)], costs[rows])]
            rows_dirty, cols_dirty = len(keep) < len(rows), False
            rows = keep
    forced_arr = np.array(sorted(forced), dtype=np.int64)
    return ReducedInstance(
        cover=np.ascontiguousarray(cover[np.ix_(rows, cols)]), costs=costs[rows].copy(),
        setups=rows.astype(np.int64), patches=cols.astype(np.int64), forced=forced_arr,
        forced_cost=math.fsum(costs[forced_arr].tolist()), uncoverable=np.flatnonzero(~coverable),
        shape=(m, n))


def check_instance(cover, costs) -> tuple[np.ndarray, np.ndarray]:
    """``cover (m, n) bool`` and ``costs (m,) float``, finite and >= 0, or a ValueError naming
    the parameter."""
    cover = check_cover(cover)
    costs = np.asarray(costs, dtype=float)
    if costs.shape != (cover.shape[0],):
        raise ValueError(f"costs must have shape ({cover.shape[0]},), one per row of cover, got {costs.shape}")
    if not np.all(np.isfinite(costs)) or np.any(costs < 0):
        raise ValueError("costs must be finite and >= 0 (seconds per setup)")
    return cover, costs


def _apply_forced(sub: np.ndarray, rows: np.ndarray, cols: np.ndarray):
    """Rows that alone reach some column: taken, with every column they reach."""
    if sub.size == 0:
        return rows, cols, []
    single = sub.sum(axis=0) == 1
    if not single.any():
        return rows, cols, []
    taken = np.unique(np.argmax(sub[:, single], axis=0))
    done = sub[taken].any(axis=0)
    keep_rows = np.ones(len(rows), dtype=bool)
    keep_rows[taken] = False
    keep_rows &= sub[:, ~done].any(axis=1)
    return rows[keep_rows], cols[~done], rows[taken].tolist()


def minimal_columns(sub: np.ndarray) -> np.ndarray:
    """Columns whose covering set contains no other column's (lowest index among equals).

    Column k implies column i when ``set(k) <= set(i)``, i.e. when the complement of column i
    is a subset of the complement of column k: :func:`nondominated` on the complements.
    """
    if sub.shape[1] <= 1:
        return np.arange(sub.shape[1])
    # A column every row reaches has an empty complement, which nondominated drops: any other
    # column implies it. When all columns are such, the first stands for them.
    keep = nondominated(~sub.T)
    return keep if len(keep) else np.zeros(1, dtype=np.int64)


def _undominated_rows(sub: np.ndarray, costs: np.ndarray) -> np.ndarray:
    """Rows no other row dominates at no lower cost, ascending; empty rows dropped.

    Rows are visited by (cost, decreasing patch count, index): a row is dominated exactly when
    an earlier row is a superset, and it suffices to test the rows kept so far (a dominator's
    dominator dominates too), and of those only the ones with at least as many patches.
    """
    words = pack_rows(sub)
    counts = np.bitwise_count(words).sum(axis=1, dtype=np.int64)
    idx = np.arange(len(words))
    order = np.lexsort((idx, -counts, costs))
    order = order[counts[order] > 0]
    kept: list[np.ndarray] = []
    kept_words = np.zeros((0, words.shape[1]), dtype=np.uint64)
    kept_counts = np.zeros(0, dtype=np.int64)
    for a in range(0, len(order), _BLOCK):
        blk = order[a:a + _BLOCK]
        big = kept_counts >= counts[blk].min()
        blk = blk[~dominated_by_any(words[blk], kept_words[big])]
        w = words[blk]
        inside = ((w[:, None, :] & ~w[None, :, :]) == 0).all(axis=2)
        blk = blk[~np.tril(inside, k=-1).any(axis=1)]
        if len(blk):
            kept.append(blk)
            kept_words = np.concatenate([kept_words, words[blk]])
            kept_counts = np.concatenate([kept_counts, counts[blk]])
    return np.sort(np.concatenate(kept)) if kept else np.zeros(0, dtype=np.int64)

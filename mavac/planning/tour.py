"""A short open tour through points: nearest neighbour, then 2-opt (generic planning).

MAVAC orders its spots, the guards of a spot and the dust areas of a view with it
(:mod:`mavac.inspection.inspection_plan`, :mod:`mavac.cleaning.clustering`).
"""

from __future__ import annotations

import numpy as np

from ..tolerances import TOUR_GAIN_TOL


def short_open_path(dist, start: int = 0) -> np.ndarray:
    """A short open path through all nodes from ``start``: nearest neighbour, then 2-opt.

    Parameters
    ----------
    dist : (k, k) float
        Symmetric distances.
    start : int
        First node (kept first).

    Returns
    -------
    (k,) int
        Visiting order, deterministic (ties by lowest index).
    """
    d = np.asarray(dist, dtype=float)
    k = len(d)
    if d.shape != (k, k):
        raise ValueError(f"dist must be square, got {d.shape}")
    if k == 0:
        return np.zeros(0, dtype=np.int64)
    if not 0 <= start < k:
        raise ValueError(f"start must be in [0, {k - 1}], got {start}")
    order = [start]
    left = np.ones(k, dtype=bool)
    left[start] = False
    while left.any():
        cand = np.flatnonzero(left)
        nxt = int(cand[np.argmin(d[order[-1], cand])])
        order.append(nxt)
        left[nxt] = False
    p = np.array(order)
    improved = True
    while improved:
        improved = False
        for i in range(1, k - 1):
            for j in range(i + 1, k):
                before = d[p[i - 1], p[i]] + (d[p[j], p[j + 1]] if j + 1 < k else 0.0)
                after = d[p[i - 1], p[j]] + (d[p[i], p[j + 1]] if j + 1 < k else 0.0)
                if after < before - TOUR_GAIN_TOL:
                    p[i:j + 1] = p[i:j + 1][::-1].copy()
                    improved = True
    return p

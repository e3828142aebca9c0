"""Areas to clean (MAVAC, "Trajectory generation"): the nodes D split into subsets with DBSCAN,
each visited in a short order (Algorithm 1, ``detectClusterizeTspDust``)."""

from __future__ import annotations

import numpy as np

from ..planning.tour import short_open_path
from ..validate import check_int, check_positive


def areas_from_nodes(nodes, *, eps: float, min_samples: int = 1) -> list[np.ndarray]:
    """DBSCAN areas of nodes, each as node indices in a short visiting order.

    Parameters
    ----------
    nodes : (k, 3) float, metres
    eps : float, metres
        DBSCAN neighbourhood radius (> 0).
    min_samples : int
        DBSCAN core size; nodes labelled noise are dropped (none with the default 1).

    Returns
    -------
    list of (m,) int
        Areas in order of their first node (deterministic); inside an area, nearest neighbour
        then 2-opt from the node closest to the area's centroid.
    """
    from sklearn.cluster import DBSCAN

    check_positive("eps", eps)
    check_int("min_samples", min_samples, 1)
    N = np.asarray(nodes, dtype=float).reshape(-1, 3)
    if not len(N):
        return []
    labels = DBSCAN(eps=float(eps), min_samples=int(min_samples)).fit_predict(N)
    areas = []
    for label in sorted(set(labels.tolist()) - {-1}, key=lambda a: int(np.flatnonzero(labels == a)[0])):
        idx = np.flatnonzero(labels == label)
        P = N[idx]
        start = int(np.argmin(np.linalg.norm(P - P.mean(axis=0), axis=1)))
        order = short_open_path(np.linalg.norm(P[:, None] - P[None], axis=2), start)
        areas.append(idx[order])
    return areas

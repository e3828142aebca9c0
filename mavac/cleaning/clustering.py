"""Areas to clean (MAVAC, "Trajectory generation"): the nodes D split into subsets with DBSCAN
(scikit-learn), each visited in a short order (Algorithm 1, line 4, ``detectClusterizeTspDust``).

The TSP is solved with fast-tsp, the solver of the authors' code (will-44/cleaning,
``script/robot.py``, ``Robot.generate_trajectory``): exact (Held-Karp) up to
:data:`TSP_EXACT_MAX` nodes; above, its greedy nearest-neighbour tour improved by a 2-opt of
ours. The authors also take ``fast_tsp.find_tour`` with a 2 s wall-clock budget, which we do not:
a result must not depend on machine load. Everything here is deterministic.
"""

from __future__ import annotations

import numpy as np

from ..planning.tour import short_open_path
from ..validate import check_int, check_positive

#: Ours: largest node count solved exactly (Held-Karp, O(2^n n^2): 16 nodes take ~10 ms here).
TSP_EXACT_MAX = 16
#: fast-tsp takes integer distances in [0, 65535]. The authors' code rounds to millimetres
#: (script/dust.py, Dust.dust_path: euclidean_distance_matrix(...) * 1000, astype int); ours
#: rounds to 0.1 mm, finer, and shrinks the unit if a set is wider than 6.5 m.
TSP_UNITS_PER_M = 10_000.0
_TSP_MAX_INT = 65_535
_GAIN_TOL = 1e-12


def _tour_length(d: np.ndarray, tour: np.ndarray) -> float:
    return float(d[tour, np.roll(tour, -1)].sum())


def _two_opt_cycle(d: np.ndarray, tour: np.ndarray) -> np.ndarray:
    """First-improvement 2-opt on a closed tour, node ``tour[0]`` kept first (deterministic)."""
    t = np.array(tour, dtype=np.int64)
    k, improved = len(t), True
    while improved:
        improved = False
        for i in range(1, k - 1):
            for j in range(i + 1, k):
                a, b, c, e = t[i - 1], t[i], t[j], t[(j + 1) % k]
                if d[a, c] + d[b, e] < d[a, b] + d[c, e] - _GAIN_TOL:
                    t[i:j + 1] = t[i:j + 1][::-1].copy()
                    improved = True
    return t


def tsp_order(points) -> np.ndarray:
    """Shortest closed tour through ``points`` (Euclidean), starting at point 0.

    Parameters
    ----------
    points : (k, 3) float, metres

    Returns
    -------
    (k,) int
        Visiting order, ``order[0] == 0``. Optimal (up to the 0.1 mm rounding of
        :data:`TSP_UNITS_PER_M`) for ``k <=`` :data:`TSP_EXACT_MAX`; nearest neighbour + 2-opt
        above. The same points always give the same order.
    """
    import fast_tsp

    P = np.asarray(points, dtype=float).reshape(-1, 3)
    if not np.all(np.isfinite(P)):
        raise ValueError("points must be finite")
    k = len(P)
    if k <= 3:
        return np.arange(k, dtype=np.int64)  # every closed tour of <= 3 points has the same length
    d = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
    scale = min(TSP_UNITS_PER_M, _TSP_MAX_INT / max(float(d.max()), 1e-12))
    dist = np.rint(d * scale).astype(np.int64)
    if k <= TSP_EXACT_MAX:
        tour = np.asarray(fast_tsp.solve_tsp_exact(dist), dtype=np.int64)
    else:
        tour = _two_opt_cycle(d, np.asarray(fast_tsp.greedy_nearest_neighbor(dist), dtype=np.int64))
    return np.roll(tour, -int(np.flatnonzero(tour == 0)[0]))


def _node_order(P: np.ndarray, node_order: str) -> np.ndarray:
    """Visiting order of one area's nodes ``P`` (m, 3)."""
    start = int(np.argmin(np.linalg.norm(P - P.mean(axis=0), axis=1)))
    if node_order == "path":
        return short_open_path(np.linalg.norm(P[:, None] - P[None], axis=2), start)
    tour = tsp_order(P)  # a closed tour: any start is as short; begin near the centroid too
    return np.roll(tour, -int(np.flatnonzero(tour == start)[0]))


def areas_from_nodes(nodes, *, eps: float, min_samples: int = 1, node_order: str = "tsp",
                     area_order: str = "detection") -> list[np.ndarray]:
    """DBSCAN areas of nodes, each as node indices in visiting order.

    Parameters
    ----------
    nodes : (k, 3) float, metres
    eps : float, metres
        DBSCAN neighbourhood radius (> 0).
    min_samples : int
        DBSCAN core size, the node itself included (scikit-learn); nodes labelled noise are
        dropped (none with the default 1).
    node_order : {"tsp", "path"}
        Inside an area: the shortest closed tour (:func:`tsp_order`), or a nearest-neighbour +
        2-opt open path; both start at the node nearest the area's centroid.
    area_order : {"detection", "tsp"}
        Areas in the order of their first node, or along the shortest closed tour through their
        centroids from the first area.

    Returns
    -------
    list of (m,) int
        Deterministic.
    """
    from sklearn.cluster import DBSCAN

    check_positive("eps", eps)
    check_int("min_samples", min_samples, 1)
    if node_order not in ("tsp", "path"):
        raise ValueError(f"node_order must be 'tsp' or 'path', got {node_order!r}")
    if area_order not in ("detection", "tsp"):
        raise ValueError(f"area_order must be 'detection' or 'tsp', got {area_order!r}")
    N = np.asarray(nodes, dtype=float).reshape(-1, 3)
    if not len(N):
        return []
    labels = DBSCAN(eps=float(eps), min_samples=int(min_samples)).fit_predict(N)
    areas = []
    for label in sorted(set(labels.tolist()) - {-1}, key=lambda a: int(np.flatnonzero(labels == a)[0])):
        idx = np.flatnonzero(labels == label)
        areas.append(idx[_node_order(N[idx], node_order)])
    if area_order == "tsp" and len(areas) > 1:
        areas = [areas[i] for i in tsp_order(np.array([N[a].mean(axis=0) for a in areas]))]
    return areas

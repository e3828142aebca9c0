"""The paper's node filters (MAVAC, "Dust detection"): "filters are applied to eliminate
non-reachable dust particles and false detections", here

* ``depth``: no valid depth (outside the sensor range ``[min_depth, max_depth]``, whose far
  end is MAVAC's reliable detection limit L_d);
* ``reach``: farther from the arm's shoulder than its reach plus the tool (the "theoretically
  reachable workspace" from the current spot);
* ``duplicate``: within ``duplicate_radius`` of a node already vacuumed from an earlier guard.

Nodes whose area was unreachable from an earlier guard are not duplicates: the paper lets
another guard try them.
"""

from __future__ import annotations

import numpy as np

from ..params import DetectionParams

#: filter names in the order they are applied; ``""`` = kept
FILTERS = ("depth", "reach", "duplicate")


def filter_nodes(nodes, depth, *, shoulder, vacuumed, params: DetectionParams) -> np.ndarray:
    """Why each node is dropped, ``""`` if it is kept.

    Parameters
    ----------
    nodes : (k, 3) float, metres (NaN rows allowed)
    depth : (k,) float, metres (NaN: no depth)
    shoulder : (3,) float
        World position of the arm's shoulder (centre of its reachable sphere).
    vacuumed : (m, 3) float
        Nodes already vacuumed in this trial.
    params : DetectionParams

    Returns
    -------
    (k,) str
        ``"depth"``, ``"reach"``, ``"duplicate"`` or ``""``.
    """
    N = np.asarray(nodes, dtype=float).reshape(-1, 3)
    z = np.asarray(depth, dtype=float).reshape(-1)
    reason = np.full(len(N), "", dtype="<U9")
    bad_depth = ~np.isfinite(z) | (z < params.min_depth) | (z > params.max_depth) | ~np.all(np.isfinite(N), axis=1)
    reason[bad_depth] = "depth"
    far = np.linalg.norm(np.nan_to_num(N) - np.asarray(shoulder, dtype=float), axis=1) > params.reach
    reason[(reason == "") & far] = "reach"
    V = np.asarray(vacuumed, dtype=float).reshape(-1, 3)
    if len(V) and len(N):
        d = np.linalg.norm(np.nan_to_num(N)[:, None, :] - V[None, :, :], axis=2).min(axis=1)
        reason[(reason == "") & (d <= params.duplicate_radius)] = "duplicate"
    return reason

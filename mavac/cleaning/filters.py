"""The paper's node filters (MAVAC, "Dust detection"): "filters are applied to eliminate
non-reachable dust particles and false detections ... beyond the robot's theoretically reachable
workspace or are incorrectly identified due to noise", here

* ``depth``: no valid depth, outside the sensor's operating range ``[min_depth, max_depth]``
  (Azure Kinect DK datasheet, 0.25-2.88 m). The reliable detection limit L_d is not a cut here:
  the paper uses it offline only (FOV pyramid, guard stand-off);
* ``reach``: farther from the arm's shoulder than its reach plus the tool (the "theoretically
  reachable workspace" from the current spot);
* ``tip`` (optional, off by default): farther than ``max_tip_distance`` from the vacuum tip at
  the guard, the authors' code's filter (see :class:`mavac.params.DetectionParams`);
* ``duplicate`` (optional, ours, off by default): within ``duplicate_radius`` of a node already
  vacuumed from an earlier guard.

Nodes whose area was unreachable from an earlier guard are never duplicates: the paper lets
another guard try them.
"""

from __future__ import annotations

import numpy as np

from ..params import DetectionParams
from ..validate import check_instance, check_points

#: filter names in the order they are applied; ``""`` = kept
FILTERS = ("depth", "reach", "tip", "duplicate")


def filter_nodes(nodes, depth, *, shoulder, vacuumed, params: DetectionParams, tip=None) -> np.ndarray:
    """Why each node is dropped, ``""`` if it is kept (the first failing filter of
    :data:`FILTERS`).

    Parameters
    ----------
    nodes : (k, 3) float, metres (NaN rows allowed)
    depth : (k,) float, metres (NaN: no depth)
    shoulder : (3,) float, metres
        World position of the arm's shoulder (centre of its reachable sphere).
    vacuumed : (m, 3) float, metres
        Nodes already vacuumed in this trial (used only when ``params.duplicate``).
    params : DetectionParams
    tip : (3,) float, metres, optional
        World position of the vacuum tip at the guard; required when
        ``params.max_tip_distance`` is set.

    Returns
    -------
    (k,) str
        ``"depth"``, ``"reach"``, ``"tip"``, ``"duplicate"`` or ``""``.
    """
    check_instance("params", params, DetectionParams)
    N = np.asarray(nodes, dtype=float).reshape(-1, 3)
    z = np.asarray(depth, dtype=float).reshape(-1)
    if len(z) != len(N):
        raise ValueError(f"depth must have one value per node ({len(N)}), got {len(z)}")
    reason = np.full(len(N), "", dtype="<U9")
    located = np.all(np.isfinite(N), axis=1)
    bad_depth = ~np.isfinite(z) | (z < params.min_depth) | (z > params.max_depth) | ~located
    reason[bad_depth] = "depth"
    P = np.nan_to_num(N)
    far = np.linalg.norm(P - check_points("shoulder", shoulder)[0], axis=1) > params.reach
    reason[(reason == "") & far] = "reach"
    if params.max_tip_distance is not None:
        if tip is None:
            raise ValueError("tip (the vacuum tip position) is required when max_tip_distance is set")
        off = np.linalg.norm(P - check_points("tip", tip)[0], axis=1) >= params.max_tip_distance
        reason[(reason == "") & off] = "tip"  # strict "<" keeps, as the authors' filter_dust
    V = np.asarray(vacuumed, dtype=float).reshape(-1, 3)
    if params.duplicate and len(V) and len(N):
        d = np.linalg.norm(P[:, None, :] - V[None, :, :], axis=2).min(axis=1)
        reason[(reason == "") & (d <= params.duplicate_radius)] = "duplicate"
    return reason

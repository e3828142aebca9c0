"""Time of a trial, SIMULATED: base travel, arm motion, vacuuming (plus planning wall time,
reported apart because it depends on the computer).

The base drives kinematically; its travel time is the length of the shortest path between
spots around the machine at the MiR200's speed. The path avoids the machine's footprint grown
by half the base's width plus a clearance, the base driving alongside the machine as it parks
(a visibility graph over the grown convex footprint: straight when the segment is free, else
around the polygon). Spots lie 0.45 m or more from the footprint, outside that polygon.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import ConvexHull

from ..robots.models import MIR200_SIZE

#: points per circle when growing the footprint (ours)
_CIRCLE_POINTS = 16
#: samples per segment in the free-segment test (ours)
_SEGMENT_SAMPLES = 64


@dataclass
class TrialTimes:
    """Simulated seconds per activity (``planning_wall_s`` is wall time, not simulated)."""

    base_s: float = 0.0
    arm_s: float = 0.0
    vacuum_s: float = 0.0
    planning_wall_s: float = 0.0

    @property
    def sim_time_s(self) -> float:
        """Simulated time of the trial: base travel + arm motion + vacuuming, s."""
        return self.base_s + self.arm_s + self.vacuum_s


def grown_footprint(footprint, clearance: float) -> np.ndarray:
    """(k, 2) convex polygon (counter-clockwise): the footprint's hull grown by half the
    MiR200's width plus ``clearance`` (m)."""
    radius = 0.5 * MIR200_SIZE[1] + float(clearance)
    a = np.linspace(0.0, 2 * np.pi, _CIRCLE_POINTS, endpoint=False)
    circle = radius / np.cos(np.pi / _CIRCLE_POINTS) * np.column_stack([np.cos(a), np.sin(a)])
    pts = (np.asarray(footprint, dtype=float)[:, None, :] + circle[None]).reshape(-1, 2)
    return pts[ConvexHull(pts).vertices]


def _inside(points, polygon) -> np.ndarray:
    """Strictly inside a counter-clockwise convex polygon (1 mm tolerance)."""
    edges = np.roll(polygon, -1, axis=0) - polygon
    rel = points[:, None, :] - polygon[None]
    cross = edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0]
    return np.all(cross > 1e-3 * np.linalg.norm(edges, axis=1)[None], axis=1)


def _free(a, b, polygon) -> bool:
    s = np.linspace(0.0, 1.0, _SEGMENT_SAMPLES)[:, None]
    return not _inside(a + s * (b - a), polygon).any()


def base_path_length(start, goal, footprint, clearance: float) -> float:
    """Shortest path length (m) between two base positions (x, y) around the grown footprint."""
    polygon = grown_footprint(footprint, clearance)
    nodes = np.vstack([np.asarray(start, float)[:2], np.asarray(goal, float)[:2], polygon])
    n = len(nodes)
    graph = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1, n):
            if _free(nodes[i], nodes[j], polygon):
                graph[i, j] = graph[j, i] = max(np.linalg.norm(nodes[i] - nodes[j]), 1e-12)
    length = dijkstra(graph, indices=0)[1]
    return float(length) if np.isfinite(length) else float(np.linalg.norm(nodes[1] - nodes[0]))

"""Spot selection: where to park the mobile base (MAVAC, "Robot base placement").

Candidate SE(2) base poses lie on rings around the machine footprint, parked alongside it, and are
kept only if the robot in its home configuration is free of collision with the machine there.
The accessible set of a spot is, as in the paper, the set of surface elements that are

* *reachable*: the camera pose that inspects the element (on its normal at the guard stand-off,
  ``L_d`` by default, looking back at it) falls in a reachable cell of the reachability map placed at the spot;
* *visible* from the spot: seen (HPR, as in the paper, or exact ray casting) from a viewpoint
  above the base at one of ``SpotParams.view_heights``, a stand-in for where the arm holds the
  camera (the arm reaches around the near side of the machine, not through it).

Guards are later placed only on accessible elements whose normal segment to the guard point is
free (:func:`guard_clearance`).

Spots are then chosen by the paper's greedy selection with threshold ``P_s`` x the first maximum
score (:func:`mavac.planning.greedy.greedy_select`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry.transforms import se2_matrices
from ..params import SpotParams, Visibility
from ..planning.greedy import GreedyResult, greedy_select
from ..robots.collision import CollisionChecker
from ..validate import check_instance, check_points, check_positive
from .coverage import coverage_overlap, mean_pairwise_overlap
from .nos import first_hit_distance


def _ring(footprint: np.ndarray, distance: float, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Dense closed curve at ``distance`` outside a CCW polygon: points (k, 2) and tangents (k, 2).

    Offset edges plus arcs at convex corners; points closer than ``distance`` to the polygon
    (possible at reflex corners) are dropped.
    """
    poly = np.asarray(footprint, dtype=float)
    k = len(poly)
    pts, tans = [], []
    for i in range(k):
        a, b = poly[i], poly[(i + 1) % k]
        e = b - a
        length = float(np.linalg.norm(e))
        if length < 1e-12:
            continue
        t = e / length
        n = np.array([t[1], -t[0]])  # outward for a counter-clockwise polygon
        s = np.arange(0.0, length, step)[:, None]
        pts.append(a + s * t + distance * n)
        tans.append(np.broadcast_to(t, (len(s), 2)))
        # arc around the corner b, from this edge's normal to the next edge's normal
        c = poly[(i + 2) % k] - b
        c = c / max(np.linalg.norm(c), 1e-12)
        n2 = np.array([c[1], -c[0]])
        a0, a1 = math.atan2(n[1], n[0]), math.atan2(n2[1], n2[0])
        sweep = (a1 - a0) % (2.0 * math.pi)
        if 0.0 < sweep < math.pi:  # convex corner
            ang = a0 + np.arange(0.0, sweep, step / max(distance, 1e-9))
            pts.append(b + distance * np.column_stack([np.cos(ang), np.sin(ang)]))
            tans.append(np.column_stack([-np.sin(ang), np.cos(ang)]))
    pts, tans = np.vstack(pts), np.vstack(tans)
    keep = _distance_to_polygon(pts, poly) >= distance - 1e-6
    return pts[keep], tans[keep]


def _distance_to_polygon(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Distance of 2-D points to the polygon boundary, (n,)."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    ab = b - a
    t = np.clip(np.einsum("nkd,kd->nk", points[:, None, :] - a[None], ab) / np.maximum((ab * ab).sum(1), 1e-24), 0, 1)
    closest = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(points[:, None, :] - closest, axis=2).min(axis=1)


def candidate_spots(footprint, params: SpotParams, rng: np.random.Generator) -> np.ndarray:
    """Candidate base poses ``(x, y, theta)`` on rings around the machine footprint.

    Poses are spaced ``ring_spacing`` apart along each ring (starting at a random phase), the
    base heading is the ring tangent (long side of the base alongside the machine) plus each of
    ``heading_offsets``, and every pose is jittered by ``+- jitter_xy`` m and ``+- jitter_theta``
    rad (all drawn from ``rng``).

    Parameters
    ----------
    footprint : (k, 2) float, m
        Counter-clockwise floor polygon of the machine.
    params : SpotParams
    rng : numpy.random.Generator

    Returns
    -------
    (m, 3) float
        ``(x, y, theta)`` in metres and radians, theta in (-pi, pi].
    """
    poly = check_points("footprint", footprint, dim=2)
    if len(poly) < 3:
        raise ValueError(f"footprint must have at least 3 vertices, got {len(poly)}")
    x, y = poly[:, 0], poly[:, 1]
    if 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) < 0:
        poly = poly[::-1]  # make it counter-clockwise
    poses = []
    for d in params.ring_distances:
        dense, tangent = _ring(poly, float(d), step=min(0.01, params.ring_spacing / 10))
        seg = np.linalg.norm(np.diff(np.vstack([dense, dense[:1]]), axis=0), axis=1)
        arc = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
        total = float(seg.sum())
        n = max(1, int(round(total / params.ring_spacing)))
        s = (rng.uniform(0.0, total / n) + np.arange(n) * total / n) % total
        j = np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(dense) - 1)
        heading = np.arctan2(tangent[j, 1], tangent[j, 0])
        for off in params.heading_offsets:
            poses.append(np.column_stack([dense[j], heading + off]))
    poses = np.vstack(poses)
    poses[:, :2] += rng.uniform(-params.jitter_xy, params.jitter_xy, size=(len(poses), 2))
    poses[:, 2] += rng.uniform(-params.jitter_theta, params.jitter_theta, size=len(poses))
    poses[:, 2] = np.angle(np.exp(1j * poses[:, 2]))
    return poses


def collision_free_spots(robot, mesh, poses, margin: float = 0.0) -> np.ndarray:
    """Which base poses leave the robot, in its home configuration, clear of the machine, (m,) bool."""
    checker = CollisionChecker(robot, mesh, margin=margin, floor=True)
    free = np.zeros(len(poses), dtype=bool)
    for i, T in enumerate(se2_matrices(poses)):
        checker.set_base(T)
        free[i] = not bool(checker.in_collision(robot.q_home))
    return free


def guard_clearance(scene, points, normals, distance: float, offset: float = 1e-3) -> np.ndarray:
    """Whether the segment from each element along its normal to the guard point is free, (n,) bool.

    Parameters
    ----------
    scene : open3d RaycastingScene
        Machine plus floor (:func:`mavac.inspection.nos.raycasting_scene`).
    points, normals : (n, 3) float
    distance : float, m
        Guard stand-off (:attr:`mavac.params.InspectionParams.guard_standoff`).
    """
    t = first_hit_distance(scene, points + offset * normals, normals)
    return t >= distance - offset


def spot_viewpoints(poses, view_heights) -> np.ndarray:
    """Viewpoints above each spot: ``(x, y, h)`` for every pose and height, (m * len(heights), 3),
    pose-major."""
    poses = check_points("poses", poses)
    return np.array([[x, y, h] for x, y, _ in poses for h in view_heights], dtype=float).reshape(-1, 3)


def spot_visibility(points, normals, poses, params: SpotParams, visibility: Visibility, *,
                    vis_scene=None) -> np.ndarray:
    """Elements visible from a viewpoint above each spot, at any of ``params.view_heights``, (m, n) bool.

    Parameters
    ----------
    points, normals : (n, 3) float
    poses : (m, 3) float
        SE(2) spots.
    params : SpotParams
        ``view_heights`` (m).
    visibility : Visibility
        Ray casting (exact, with a back-face test) or MAVAC's HPR with the spot radius
        (:meth:`Visibility.at_spots`: calibrated at these farther viewpoints).
    vis_scene : mavac.vision.visibility.VisibilityScene
        Required for ray casting.
    """
    poses = check_points("poses", poses)
    check_instance("visibility", visibility, Visibility)
    heights = params.view_heights
    views = spot_viewpoints(poses, heights)
    vis = visibility.at_spots().visible(points, normals, views, scene=vis_scene)
    return vis.reshape(len(poses), len(heights), len(points)).any(axis=1)


@dataclass(frozen=True)
class SpotSelection:
    """Candidate spots, their accessible sets, and the greedy choice.

    Attributes
    ----------
    candidates : (m, 3) float
        Collision-free candidate SE(2) poses.
    accessible : (m, n) bool
        Visible AND reachable elements per candidate.
    greedy : GreedyResult
        Selection over ``accessible`` with ``P_s`` (``greedy.selected`` indexes ``candidates``).
    C, O : float
        Coverage and overlap (eq. 1-2) of the selected spots' accessible sets, fractions of |S|.
    O_pairwise : float
        Mean over the pairs of selected spots of ``|A_i & A_j| / |S|`` (the other reading of O).
    """

    candidates: np.ndarray
    accessible: np.ndarray
    greedy: GreedyResult
    C: float
    O: float
    O_pairwise: float = 0.0

    @property
    def spots(self) -> np.ndarray:
        """(k, 3) selected SE(2) poses, in selection order."""
        return self.candidates[self.greedy.selected]


def reachable_sets(rmap, poses, points, normals, standoff: float) -> np.ndarray:
    """Elements whose inspecting camera pose the arm reaches from each spot, (m, n) bool.

    The camera inspecting element s sits at ``s + standoff n_s`` (the guard stand-off, m:
    :attr:`mavac.params.InspectionParams.guard_standoff`) with its optical axis along ``-n_s``;
    the element is reachable when that pose's (voxel, direction) cell of the map is reachable.
    """
    check_positive("standoff", standoff)
    guard_points = points + standoff * normals
    reach = np.zeros((len(poses), len(points)), dtype=bool)
    for i, T in enumerate(se2_matrices(poses)):
        reach[i] = rmap.is_reachable_from(T, guard_points, -normals)
    return reach


def accessible_sets(rmap, poses, points, normals, visible, standoff: float) -> np.ndarray:
    """Accessible = visible AND reachable (map) with the guard ``standoff`` (m), for each spot,
    (m, n) bool (MAVAC's definition)."""
    return reachable_sets(rmap, poses, points, normals, standoff) & visible


def select_spots(accessible, candidates, P_s: float) -> SpotSelection:
    """The paper's greedy spot selection over precomputed accessible sets."""
    g = greedy_select(accessible, P_s)
    chosen = np.asarray(accessible)[g.selected]
    C, O = coverage_overlap(chosen, accessible.shape[1])
    return SpotSelection(np.asarray(candidates), np.asarray(accessible), g, C, O,
                         mean_pairwise_overlap(chosen, accessible.shape[1]))

"""Multi-pass tool paths by parallel-plane slicing, and their execution time (Kabir, Sec. VI).

For one setup (the part at ``world_T_part`` and the stain patches assigned to it), pass ``k``
cleans the patches that need at least ``k`` passes (Kabir, Sec. VI: pass 1 covers every patch
of the setup, pass 2 those needing 2 or 3, ...). For each pass:

1. The pass's stain submesh is split into connected components (face adjacency).
2. Each component is cut by equally spaced parallel planes, spacing = tool width
   (``trimesh`` ``section_multiplane``); planes are centred on the component so its two
   outer strips are equally wide. The plane normal is as perpendicular as possible to the
   component's face normals (even strips on curved stains) and, among such directions,
   across its longest extent, so the sweeps are long and few (:func:`sweep_frame`).
3. Each section curve is resampled at the waypoint spacing; the curves of a component are
   visited in boustrophedon order (alternate sweep direction from one plane to the next).
4. Waypoints the robot cannot reach with tool z = -n are dropped, splitting the curve there;
   n is the outward normal of the plane the flat pad rests on (the area-weighted mean normal
   of the part's faces within the pad's radius, on the stain's side).
5. Consecutive pieces are joined in contact when the straight link between them, projected
   on the part, stays on the pass's stain (within 5 % of the tool width) with no gap larger
   than two waypoint spacings and is reachable; otherwise by a repositioning move: lift along
   the normal by the lift height, move, lower (Kabir, Sec. VI: "an intermediate pose where
   the tool is not in contact"); a move that would pass within half a lift height of the
   part is raised until it clears it.
6. Each contact piece becomes SciPy B-splines through its waypoints (``make_splprep``),
   one per section curve and per link, joined end to end (one spline through a
   boustrophedon corner would overshoot it off the stain): the nominal trajectory.

Execution time (Kabir, Sec. III): ``t^e = t^c + t^r`` with ``t^c`` = contact path length /
tool speed and ``t^r`` = repositioning length (lift + move + lower) / repositioning speed.
The move into the start of pass ``k + 1`` from the end of pass ``k`` is a repositioning move
of pass ``k + 1`` (a pass runs backwards when that starts it nearer to where the previous one
ended); the approach from the robot's home pose is not part of a setup's time.

:func:`execution_time_fn` gives the setup planner this ``t^e(tau_j)`` through the same
``setup_costs`` array interface as its simple area model.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import trimesh
from scipy.interpolate import make_splprep
from scipy.spatial import cKDTree

from ..geometry.transforms import check_transform, rotate_vectors, transform_points
from ..params import SetupSpaceParams, ToolpathParams
from ..robots.kinematics import ik_axis
from ..setups.reach import base_T_part
from ..tolerances import COUNT_SLACK
from ..validate import check_indices, check_instance, check_int, check_points, check_positive, check_size

# Dense samples per waypoint interval when a spline is evaluated (length, coverage, output).
_SPLINE_SUBDIVISION = 4
# A link point counts as on the stain within this fraction of the tool width of it.
_ON_STAIN_TOLERANCE = 0.05
# Consecutive link points farther apart than this many waypoint spacings mean a jump.
_MAX_LINK_GAP = 2.0
# At most this many raises of a repositioning move to clear the part.
_MAX_RAISES = 20
# Size limits of one setup's tool path, far above any real use, so that a tiny tool width or
# waypoint spacing typed by mistake fails at once instead of slicing and running IK for hours:
# cutting planes (stain extent / tool width; Sine at paper scale has ~55) and waypoints (stain
# area / (tool width x spacing) + extent / spacing; Sine has ~2,000).
MAX_PLANES = 10_000
MAX_WAYPOINTS = 100_000

Reachable = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class PassPath:
    """Tool path of one cleaning pass of one setup (world frame, metres).

    Attributes
    ----------
    pass_number : int
        1-based pass index k; the pass cleans the setup's patches needing >= k passes.
    patch_ids : (p,) int
        Indices (into the part's stain arrays) of the patches this pass cleans.
    segments : list of (k_i, 3) float
        Contact splines, sampled densely, in execution order.
    normals : list of (k_i, 3) float
        Outward surface normal under each segment point (tool z = -normal).
    repositions : list of (4, 3) or (6, 3) float
        Lift-move-lower polylines ``[start, start + h n, end + h n, end]`` (with the move
        raised further where it would pass too close to the part), including the move into
        this pass from the end of the previous pass.
    covered : (p,) bool
        Patches whose centroid is within ``tool_width / 2`` of the contact path.
    coverage : float
        Area fraction of the pass's patches that are covered (``nan`` when it has none).
    """

    pass_number: int
    patch_ids: np.ndarray
    segments: list = field(default_factory=list)
    normals: list = field(default_factory=list)
    repositions: list = field(default_factory=list)
    covered: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    coverage: float = float("nan")

    @property
    def path_length_m(self) -> float:
        """Contact path length, m."""
        return float(sum(_polyline_length(s) for s in self.segments))

    @property
    def reposition_length_m(self) -> float:
        """Repositioning length (lift + move + lower), m."""
        return float(sum(_polyline_length(r) for r in self.repositions))


@dataclass(frozen=True)
class ToolPath:
    """The trajectory tau_j of one setup: one :class:`PassPath` per pass (Kabir, Sec. VI).

    Attributes
    ----------
    world_T_part : (4, 4) float
        Pose of the part for this setup.
    passes : tuple of PassPath
        Pass 1 .. N_j^max.
    params : ToolpathParams
        Tool width, speeds and lift height used.
    """

    world_T_part: np.ndarray
    passes: tuple
    params: ToolpathParams

    @property
    def path_length_m(self) -> float:
        """Total contact path length over all passes, m."""
        return float(sum(p.path_length_m for p in self.passes))

    @property
    def reposition_length_m(self) -> float:
        """Total repositioning length over all passes, m."""
        return float(sum(p.reposition_length_m for p in self.passes))

    @property
    def t_contact_s(self) -> float:
        """t^c: contact time = path length / tool speed, s."""
        return self.path_length_m / self.params.tool_speed_m_s

    @property
    def t_reposition_s(self) -> float:
        """t^r: repositioning time = repositioning length / repositioning speed, s."""
        return self.reposition_length_m / self.params.reposition_speed_m_s

    @property
    def t_execution_s(self) -> float:
        """t^e = t^c + t^r (Kabir, Sec. III), s."""
        return self.t_contact_s + self.t_reposition_s

    @property
    def repositionings(self) -> int:
        """Number of repositioning moves over all passes."""
        return int(sum(len(p.repositions) for p in self.passes))

    @property
    def coverage(self) -> np.ndarray:
        """(n_passes,) per-pass coverage (see :class:`PassPath`)."""
        return np.array([p.coverage for p in self.passes], dtype=float)

    def longest_segment(self, pass_number: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """The longest contact segment of pass ``pass_number`` (by point count) and its normals."""
        p = self.passes[pass_number - 1]
        i = int(np.argmax([len(s) for s in p.segments]))
        return p.segments[i], p.normals[i]


def _polyline_length(points: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum()) if len(points) > 1 else 0.0


def patches_for_pass(passes, k: int) -> np.ndarray:
    """Mask of the patches pass ``k`` cleans: those needing at least ``k`` passes.

    Parameters
    ----------
    passes : (p,) int
        Required passes N_i of each patch.
    k : int
        Pass number, >= 1.

    Returns
    -------
    (p,) bool
    """
    k = check_int("k", k, lo=1)
    return np.asarray(passes) >= k


def reachable_from_robot(robot, *, world_T_base=None, frame: str | None = None) -> Reachable:
    """Reach test for tool paths: IK with the tool z axis along the given approach axes.

    Parameters
    ----------
    robot : mavac.robots.models.RobotModel
    world_T_base : (4, 4) float, optional
        Pose of the robot base (default identity: world = robot base frame).
    frame : str, optional
        Tool frame (default the robot's).

    Returns
    -------
    callable
        ``reachable(positions (n,3) world m, axes (n,3) unit) -> (n,) bool`` with one batched
        :func:`mavac.robots.kinematics.ik_axis` call.
    """
    base_T_world = np.linalg.inv(np.eye(4) if world_T_base is None else check_transform("world_T_base", world_T_base))

    def reachable(positions: np.ndarray, axes: np.ndarray) -> np.ndarray:
        if len(positions) == 0:
            return np.zeros(0, dtype=bool)
        p = transform_points(base_T_world, positions)
        a = rotate_vectors(base_T_world, axes)
        return np.asarray(ik_axis(robot, p, a, frame=frame).success, dtype=bool)

    return reachable


def sweep_frame(mesh: trimesh.Trimesh, extent_weight: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Slicing-plane normal and sweep direction of a stain region.

    Parallel planes ``w`` apart leave strips ``w / sqrt(1 - (d . n)^2)`` wide on a surface of
    normal ``n`` (``d`` the plane normal), so ``d`` should be as perpendicular as possible to
    every face normal: it minimises the area-weighted mean of ``(d . n)^2``. Among nearly
    equal choices (a flat region leaves a whole tangent plane), a small term
    ``extent_weight`` x the normalised centroid covariance picks the direction of smallest
    extent, so the section curves run along the region's long side and are few.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Stain region (metres).
    extent_weight : float
        Weight of the extent term against the normal term (both have trace 1).

    Returns
    -------
    plane_normal, sweep_direction : (3,) float, unit
        The sweep direction lies in the planes, along the region's principal axis.
    """
    w = mesh.area_faces / mesh.area_faces.sum()
    n = mesh.face_normals
    normal_moment = (n * w[:, None]).T @ n
    c = mesh.triangles_center
    centred = c - (c * w[:, None]).sum(axis=0)
    cov = (centred * w[:, None]).T @ centred
    spread = cov / max(float(np.trace(cov)), 1e-300)
    plane_normal = np.linalg.eigh(normal_moment + extent_weight * spread)[1][:, 0]
    return plane_normal, sweep_direction(mesh, plane_normal)


def sweep_direction(mesh: trimesh.Trimesh, plane_normal) -> np.ndarray:
    """Principal axis (area-weighted) of the face centroids within the planes of normal
    ``plane_normal``: the direction the section curves run along, (3,) unit."""
    d = np.asarray(plane_normal, float) / np.linalg.norm(plane_normal)
    w = mesh.area_faces / mesh.area_faces.sum()
    c = mesh.triangles_center
    centred = c - (c * w[:, None]).sum(axis=0)
    in_plane = np.eye(3) - np.outer(d, d)
    cov = in_plane @ ((centred * w[:, None]).T @ centred) @ in_plane
    return np.linalg.eigh(cov)[1][:, -1]


def slice_heights(projections: np.ndarray, spacing: float) -> np.ndarray:
    """Plane offsets covering ``[min, max]`` of ``projections`` with equal strips.

    ``ceil(extent / spacing)`` planes, ``spacing`` apart, centred on the extent, so every point
    is within ``spacing / 2`` of a plane when the extent is a multiple of the spacing.
    """
    lo, hi = float(np.min(projections)), float(np.max(projections))
    check_size("spacing", spacing, (hi - lo) / check_positive("spacing", spacing), MAX_PLANES, "cutting planes")
    n = max(1, int(np.ceil((hi - lo) / spacing - COUNT_SLACK)))
    return lo + 0.5 * ((hi - lo) - (n - 1) * spacing) + spacing * np.arange(n)


def slice_curves(mesh: trimesh.Trimesh, plane_normal, spacing: float) -> list[list[np.ndarray]]:
    """Cut a region with parallel planes ``spacing`` apart (``trimesh`` section_multiplane).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Region to slice (metres).
    plane_normal : (3,) float
        Normal of the cutting planes.
    spacing : float
        Plane spacing, metres (the tool width).

    Returns
    -------
    list (one per plane, in increasing offset) of lists of (k, 3) float polylines
        The connected section curves in each plane (a hole or a gap splits a plane's section
        into several curves).
    """
    normal = np.asarray(plane_normal, float)
    normal = normal / np.linalg.norm(normal)
    heights = slice_heights(mesh.vertices @ normal, spacing)
    sections = mesh.section_multiplane(plane_origin=np.zeros(3), plane_normal=normal, heights=heights)
    out = []
    for path in sections:
        curves = []
        if path is not None:
            to_3d = path.metadata["to_3D"]
            for entity in path.entities:
                xy = entity.discrete(path.vertices)
                xyz = np.column_stack([xy, np.zeros(len(xy)), np.ones(len(xy))]) @ to_3d.T
                curves.append(xyz[:, :3])
        out.append(curves)
    return out


def resample_polyline(points: np.ndarray, spacing: float) -> np.ndarray:
    """Points at equal arc length (at most ``spacing`` apart) along a polyline, ends included."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    check_size("spacing", spacing, s[-1] / check_positive("spacing", spacing), MAX_WAYPOINTS, "waypoints")
    n = max(2, int(np.ceil(s[-1] / spacing - COUNT_SLACK)) + 1)
    t = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(t, s, points[:, i]) for i in range(3)])


def boustrophedon(slices: list[list[np.ndarray]], sweep_direction) -> list[np.ndarray]:
    """Order section curves back and forth: even planes along ``sweep_direction``, odd against.

    Within a plane, curves are visited in the sweep order and each is oriented along it.
    """
    d = np.asarray(sweep_direction, float)
    ordered = []
    for i, curves in enumerate(p for p in slices if p):
        sign = 1.0 if i % 2 == 0 else -1.0
        oriented = [c if sign * (c[-1] - c[0]) @ d >= 0 else c[::-1] for c in curves]
        oriented.sort(key=lambda c: sign * float(c.mean(axis=0) @ d))
        ordered.extend(oriented)
    return ordered


def _fit_spline(points: np.ndarray) -> np.ndarray:
    """Dense samples of the B-spline through ``points`` (cubic when there are >= 4)."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(points, axis=0), axis=1) > 1e-9])
    pts = points[keep]
    if len(pts) < 2:
        return pts
    spline, u = make_splprep(pts.T, k=min(3, len(pts) - 1), s=0)
    dense = np.interp(np.linspace(0, len(u) - 1, (len(u) - 1) * _SPLINE_SUBDIVISION + 1),
                      np.arange(len(u)), u)
    return np.asarray(spline(dense)).T


def _split_runs(valid: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of the runs of True with at least two elements."""
    edges = np.diff(np.concatenate([[0], valid.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(a, b) for a, b in zip(starts, stops) if b - a >= 2]


class _Surface:
    """Closest-point queries on the part and on the current pass's stain (world frame)."""

    def __init__(self, part_world: trimesh.Trimesh, stain: trimesh.Trimesh, tool_width: float):
        self.part = part_world
        self.stain = stain
        self.tol = _ON_STAIN_TOLERANCE * tool_width
        self.radius = tool_width / 2
        self._faces = None  # KD-tree of the part's face centres, built on first use

    def stain_normals(self, points: np.ndarray) -> np.ndarray:
        """The pad's outward axis at each point (n, 3), unit: the area-weighted mean normal of the
        part's faces within the pad's radius, those facing the way the closest stain face does
        (the plane a flat pad rests on; one face's normal turns it abruptly over a crease)."""
        _, _, tri = trimesh.proximity.closest_point(self.stain, points)
        own = self.stain.face_normals[tri]
        if self._faces is None:
            self._faces = cKDTree(self.part.triangles_center)
        normals, areas = self.part.face_normals, self.part.area_faces
        out = own.copy()
        for i, near in enumerate(self._faces.query_ball_point(points, self.radius)):
            near = np.asarray(near, dtype=np.int64)
            near = near[normals[near] @ own[i] > 0]
            if near.size:
                mean = areas[near] @ normals[near]
                out[i] = mean / np.linalg.norm(mean)
        return out

    def link(self, a: np.ndarray, b: np.ndarray, spacing: float) -> np.ndarray | None:
        """Interior points of an in-contact link a -> b on the stain, or None.

        The chord is checked every ``tol`` (not every waypoint spacing) so that a stain-free
        notch wider than the tolerance is never crossed in contact.
        """
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / self.tol - COUNT_SLACK)) + 1)
        chord = a + np.linspace(0.0, 1.0, n)[1:-1, None] * (b - a)
        if len(chord) == 0:
            return chord
        on_part, _, _ = trimesh.proximity.closest_point(self.part, chord)
        _, d_stain, _ = trimesh.proximity.closest_point(self.stain, on_part)
        path = np.vstack([a, on_part, b])
        gaps = np.linalg.norm(np.diff(path, axis=0), axis=1)
        if np.all(d_stain <= self.tol) and np.all(gaps <= _MAX_LINK_GAP * spacing):
            return on_part
        return None


def _reposition(a, na, b, nb, lift: float, part: trimesh.Trimesh) -> np.ndarray:
    """Lift-move-lower polyline ``[a, a + h na, b + h nb, b]`` (h = lift height).

    If the straight move would come closer than h / 2 to the part (it would cut through a
    convex bump between far-apart pieces), it is raised along the mean normal m by the
    clearance it misses (at least h) until it clears:
    ``[a, a + h na, a + h na + e m, b + h nb + e m, b + h nb, b]``. The raise stops at the
    part's bounding-box diagonal: pieces on opposite sides of a closed part (which one setup
    rarely reaches) would need a move around it, which this model does not plan.
    """
    up = na + nb
    up = up / np.linalg.norm(up) if np.linalg.norm(up) > 1e-9 else na
    p, q = a + lift * na, b + lift * nb
    n = max(2, int(np.ceil(np.linalg.norm(q - p) / (0.5 * lift))) + 1)
    raised, ceiling = 0.0, float(np.linalg.norm(part.extents))
    for _ in range(_MAX_RAISES):
        samples = p + raised * up + np.linspace(0.0, 1.0, n)[:, None] * (q - p)
        closest, _, tri = trimesh.proximity.closest_point(part, samples)
        deficit = 0.5 * lift - np.min(np.sum((samples - closest) * part.face_normals[tri], axis=1))
        if deficit <= 0 or raised >= ceiling:
            break
        raised = min(raised + max(deficit, lift), ceiling)
    if raised == 0.0:
        return np.array([a, p, q, b])
    e = raised * up
    return np.array([a, p, p + e, q + e, q, b])


def _components(mesh: trimesh.Trimesh) -> list[trimesh.Trimesh]:
    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency, node_count=len(mesh.faces))
    return [mesh.submesh([np.flatnonzero(labels == c)], append=True) for c in np.unique(labels)]


def _section_waypoints(stain: trimesh.Trimesh, params: ToolpathParams, plane_normal):
    """Waypoint curves of a pass in execution order, and the component each comes from."""
    comps = _components(stain)
    # Components in order of their first corner along the main axis of the whole pass.
    axis = sweep_frame(stain)[1]
    comps.sort(key=lambda c: float(np.min(c.vertices @ axis)))
    curves, owner = [], []
    for ci, comp in enumerate(comps):
        # Each component gets its own frame unless the planes are imposed.
        if plane_normal is None:
            normal, sweep = sweep_frame(comp)
        else:
            normal = np.asarray(plane_normal, float) / np.linalg.norm(plane_normal)
            sweep = sweep_direction(comp, normal)
        for c in boustrophedon(slice_curves(comp, normal, params.tool_width_m), sweep):
            curves.append(resample_polyline(c, params.waypoint_spacing_m))
            owner.append(ci)
    return curves, owner


def _contact_pieces(curves, owner, surface: _Surface, reachable, spacing: float) -> list[list[np.ndarray]]:
    """Split the curves at unreachable waypoints and join consecutive runs in contact where
    the link between them stays on the stain; each piece is a list of polylines end to end."""
    waypoints = np.vstack(curves)
    ok = np.ones(len(waypoints), bool)
    if reachable is not None:
        ok = np.asarray(reachable(waypoints, -surface.stain_normals(waypoints)), bool)
    bounds = np.cumsum([0] + [len(c) for c in curves])
    # Runs of reachable waypoints, each tagged with the curve it comes from.
    runs = [(ci, bounds[ci] + a, bounds[ci] + b)
            for ci in range(len(curves)) for a, b in _split_runs(ok[bounds[ci]:bounds[ci + 1]])]
    pieces = []
    for r, (ci, a, b) in enumerate(runs):
        run = waypoints[a:b]
        if pieces:
            prev_ci, _, prev_b = runs[r - 1]
            link = None
            # Never link across an IK failure (same curve) or between components.
            if prev_ci != ci and owner[prev_ci] == owner[ci]:
                link = surface.link(waypoints[prev_b - 1], waypoints[a], spacing)
                if link is not None and len(link) and reachable is not None:
                    link = link if np.all(reachable(link, -surface.stain_normals(link))) else None
            if link is not None:
                pieces[-1] += [np.vstack([waypoints[prev_b - 1], link, waypoints[a]]), run]
                continue
        pieces.append([run])
    return pieces


def _pass_path(part_world, faces, pass_number, patch_ids, params, reachable, plane_normal, previous_end):
    """Contact segments, repositions and coverage of one pass (see module docstring)."""
    stain = part_world.submesh([faces], append=True)
    surface = _Surface(part_world, stain, params.tool_width_m)
    curves, owner = _section_waypoints(stain, params, plane_normal)
    segments, normals = [], []
    for piece in (_contact_pieces(curves, owner, surface, reachable, params.waypoint_spacing_m) if curves else []):
        # One spline per curve and per link, joined end to end: a single spline through
        # a boustrophedon turn would overshoot the corner off the stain.
        seg = np.vstack([s if i == 0 else s[1:] for i, s in enumerate(map(_fit_spline, piece))])
        if len(seg) < 2:  # coincident waypoints: nothing to scrub
            continue
        segments.append(seg)
        normals.append(surface.stain_normals(seg))
    if segments and previous_end is not None:
        # Run the pass backwards when that starts it nearer to where the previous pass ended.
        if np.linalg.norm(segments[-1][-1] - previous_end[0]) < np.linalg.norm(segments[0][0] - previous_end[0]):
            segments = [seg[::-1] for seg in segments[::-1]]
            normals = [nrm[::-1] for nrm in normals[::-1]]
    lift = params.lift_height_m
    repositions = [_reposition(segments[i - 1][-1], normals[i - 1][-1], segments[i][0], normals[i][0], lift,
                               part_world) for i in range(1, len(segments))]
    if segments and previous_end is not None:
        repositions.insert(0, _reposition(previous_end[0], previous_end[1], segments[0][0], normals[0][0], lift,
                                          part_world))
    covered = _covered(part_world, faces, segments, params.tool_width_m)
    areas = part_world.area_faces[faces]
    coverage = float(areas[covered].sum() / areas.sum()) if len(faces) else float("nan")
    return PassPath(pass_number, np.asarray(patch_ids), segments, normals, repositions, covered, coverage)


def _covered(part_world, faces, segments, tool_width) -> np.ndarray:
    """Which ``faces`` have their centroid within tool_width / 2 of the path.

    The path is known at dense samples ``d`` apart at most; a centroid within w/2 of the
    continuous path is within ``sqrt((w/2)^2 + (d/2)^2)`` of a sample, the threshold used.
    """
    if not segments:
        return np.zeros(len(faces), dtype=bool)
    pts = np.vstack(segments)
    steps = [np.linalg.norm(np.diff(s, axis=0), axis=1).max() for s in segments if len(s) > 1]
    d = float(max(steps)) if steps else 0.0
    dist, _ = cKDTree(pts).query(part_world.triangles_center[faces])
    return dist <= np.hypot(0.5 * tool_width, 0.5 * d)


def _check_path_size(part, faces: np.ndarray, params: ToolpathParams) -> None:
    """Refuse a tool width or waypoint spacing that would make an absurdly large path."""
    if faces.size == 0:
        return
    corners = np.asarray(part.mesh.vertices)[np.asarray(part.mesh.faces)[faces]].reshape(-1, 3)
    extent = float(np.linalg.norm(np.ptp(corners, axis=0)))
    area = float(np.asarray(part.mesh.area_faces)[faces].sum())
    w, s = params.tool_width_m, params.waypoint_spacing_m
    check_size("tool_width_m", w, extent / w, MAX_PLANES, "cutting planes")
    check_size("waypoint_spacing_m", s, area / (w * s) + extent / s, MAX_WAYPOINTS, "waypoints")


def toolpath_for_setup(part, world_T_part, patch_ids, params: ToolpathParams = ToolpathParams(),
                       *, reachable: Reachable | None = None, plane_normal=None) -> ToolPath:
    """Multi-pass tool path of one setup (Kabir, Sec. VI).

    Parameters
    ----------
    part : mavac.geometry.parts.Part
        Needs ``mesh``, ``stain_faces (p,)`` and ``passes (p,)``.
    world_T_part : (4, 4) float
        Pose of the part in this setup.
    patch_ids : (q,) int or (p,) bool
        The setup's patches (indices into the part's stain arrays, or a mask over them).
    params : ToolpathParams
        Tool width (plane spacing), waypoint spacing, speeds, lift height.
    reachable : callable, optional
        ``reachable(positions (n,3), axes (n,3)) -> (n,) bool`` in the world frame, e.g.
        :func:`reachable_from_robot`; ``None`` treats every waypoint as reachable.
    plane_normal : (3,) float, optional
        Normal of the cutting planes in the world frame (default: :func:`sweep_frame`,
        computed per pass).

    Returns
    -------
    ToolPath
        One :class:`PassPath` per pass 1 .. max passes of the setup's patches.
    """
    T = check_transform("world_T_part", world_T_part)
    stain_faces = np.asarray(part.stain_faces, dtype=np.int64)
    passes = np.asarray(part.passes, dtype=np.int64)
    ids = check_indices("patch_ids", patch_ids, len(stain_faces))
    _check_path_size(part, stain_faces[ids], check_instance("params", params, ToolpathParams))
    if plane_normal is not None:
        plane_normal = check_points("plane_normal", plane_normal)[0]
        if np.linalg.norm(plane_normal) == 0:
            raise ValueError("plane_normal must be non-zero")
    part_world = part.mesh.copy()
    part_world.apply_transform(T)
    n_passes = int(passes[ids].max()) if ids.size else 0
    out, previous_end = [], None
    for k in range(1, n_passes + 1):
        sel = ids[patches_for_pass(passes[ids], k)]
        pp = _pass_path(part_world, stain_faces[sel], k, sel, params, reachable, plane_normal, previous_end)
        if pp.segments:
            previous_end = (pp.segments[-1][-1], pp.normals[-1][-1])
        out.append(pp)
    return ToolPath(T, tuple(out), params)


def execution_time_fn(part, *, robot=None, params: ToolpathParams = ToolpathParams(),
                      space: SetupSpaceParams = SetupSpaceParams(),
                      world_T_part_from_setup: Callable | None = None):
    """Execution time t^e(tau_j) of candidate setups, for the setup planner's cost array.

    Parameters
    ----------
    part : mavac.geometry.parts.Part
    robot : RobotModel, optional
        IK splits the paths when given (:func:`reachable_from_robot`, world = robot base
        frame); ``None`` skips it.
    params : ToolpathParams
    space : SetupSpaceParams
        Where a setup ``(x, y, alpha)`` puts the part (:func:`mavac.setups.reach.base_T_part`,
        the reach test's convention).
    world_T_part_from_setup : callable, optional
        ``(3,) setup -> (4, 4)`` pose of the part, overriding ``space``.

    Returns
    -------
    callable
        ``exec_times(cover (m, n) bool, setups (m, 3)) -> (m,) float`` seconds, where
        ``cover[j]`` marks the patches of setup j. Use as
        ``setup_costs = setup_costs_from_times(exec_times(cover, setups), t_s)`` in
        :func:`mavac.planning.setcover.solve_setup_cover`.
    """
    if world_T_part_from_setup is None:
        def world_T_part_from_setup(s):
            return base_T_part(np.asarray(s, dtype=float)[None], space)[0]

    reachable = None if robot is None else reachable_from_robot(robot)

    def exec_times(cover, setups) -> np.ndarray:
        C = np.asarray(cover, dtype=bool)
        S = check_points("setups", setups)
        if C.ndim != 2 or C.shape[0] != S.shape[0] or C.shape[1] != len(part.stain_faces):
            raise ValueError(f"cover must have shape ({S.shape[0]}, {len(part.stain_faces)}), got {C.shape}")
        return np.array([toolpath_for_setup(part, world_T_part_from_setup(s), np.flatnonzero(c), params,
                                            reachable=reachable).t_execution_s if c.any() else 0.0
                         for c, s in zip(C, S)])

    return exec_times

"""Non-observed surfaces (NoS): clusters, gateways and the spot to reach them from.

MAVAC, "Non-observed surface (NoS)": elements no guard observes are clustered with DBSCAN; rays
are cast outward from each cluster centre; rays that leave without hitting the machine are grouped
into gateways; the gateway with the most rays is the best; the spot used is the one closest to the
gateway's mean exit direction projected on the floor. The NoS guard is then kept only if a
collision-free path to it exists (:func:`nos_guards`, the whole stage: clusters, gateways, IK on
the gateway's rays, RRT-Connect from the spot's home configuration, the attempt record).

Here the floor (z = 0) is part of the scene, so a ray that goes down and hits the floor is blocked,
and gateways are connected components of escaping rays on the fan's neighbour graph.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from sklearn.cluster import DBSCAN

from ..geometry.mesh import local_origin
from ..geometry.transforms import compose, se2_matrices
from ..params import InspectionParams, NoSParams
from ..planning.rrt import plan_rrt_connect
from ..robots.kinematics import fk
from ..seeding import rng_for
from ..validate import check_int, check_points, check_positive
from .guards import camera_configurations, guard_visibility


@dataclass(frozen=True)
class Gateway:
    """A bundle of neighbouring rays that leave a NoS cluster without hitting the machine.

    Attributes
    ----------
    cluster : int
        NoS cluster label.
    origin : (3,) float, m
        Where the rays start (cluster centre, lifted off the surface).
    ray_directions : (r, 3) float
        Unit directions of the escaping rays of this gateway.
    direction : (3,) float
        Unit exit direction: the gateway's escaping ray closest to the mean of its rays (so the
        direction itself is known to escape).
    """

    cluster: int
    origin: np.ndarray
    ray_directions: np.ndarray
    direction: np.ndarray

    @property
    def n_rays(self) -> int:
        return int(len(self.ray_directions))


@dataclass(frozen=True)
class NoSCluster:
    """One cluster of non-observed elements with its ray fan and gateways.

    Attributes
    ----------
    label : int
    members : (k,) int
        Indices into S.
    origin : (3,) float, m
        Ray origin: the member nearest the cluster mean, lifted along its normal.
    directions : (r, 3) float
        Ray fan (unit vectors).
    escaping : (r,) bool
        Rays that leave without hitting the machine or the floor within the ray length.
    hit_distance : (r,) float, m
        Distance to each ray's first hit (``inf`` if it escapes the scene).
    gateways : list of Gateway
        Sorted by decreasing ray count; ``gateways[0]`` is the best one (if any).
    """

    label: int
    members: np.ndarray
    origin: np.ndarray
    directions: np.ndarray
    escaping: np.ndarray
    hit_distance: np.ndarray
    gateways: list

    @property
    def best_gateway(self) -> Gateway | None:
        return self.gateways[0] if self.gateways else None


def sphere_directions(n: int) -> np.ndarray:
    """Evenly spread unit vectors on the sphere (Fibonacci lattice), deterministic.

    Returns
    -------
    (n, 3) float
    """
    n = check_int("n_rays", n, lo=4)
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def cluster_unobserved(points, observed, eps: float, min_samples: int) -> np.ndarray:
    """DBSCAN over the elements no pose observes (Ester et al., as in MAVAC).

    Parameters
    ----------
    points : (n, 3) float, m
    observed : (n,) bool
    eps : float, m
        DBSCAN neighbourhood radius.
    min_samples : int

    Returns
    -------
    (n,) int
        Cluster label per element; -1 for observed elements and DBSCAN noise.
    """
    points = check_points("points", points)
    observed = np.asarray(observed, dtype=bool)
    if observed.shape != (len(points),):
        raise ValueError(f"observed must have shape ({len(points)},), got {observed.shape}")
    check_positive("eps", eps)
    min_samples = check_int("min_samples", min_samples, lo=1)
    labels = np.full(len(points), -1, dtype=np.int64)
    idx = np.flatnonzero(~observed)
    if len(idx) >= min_samples:
        labels[idx] = DBSCAN(eps=eps, min_samples=min_samples).fit_predict(points[idx])
    return labels


@dataclass
class RayScene:
    """An Open3D ``RaycastingScene`` whose float32 geometry is relative to ``origin``
    (:func:`mavac.geometry.mesh.local_origin`); ray origins are moved by it before casting."""

    scene: object
    origin: np.ndarray


def raycasting_scene(mesh, floor_z: float | None = 0.0) -> RayScene:
    """The machine mesh, plus a large floor quad at ``floor_z``, for :func:`first_hit_distance`.

    The floor quad sits 1 mm below ``floor_z`` so it never hides the machine's own bottom.
    """
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    origin = local_origin(mesh.vertices)
    scene.add_triangles(np.asarray(np.asarray(mesh.vertices) - origin, dtype=np.float32),
                        np.asarray(mesh.faces, dtype=np.uint32))
    if floor_z is not None:
        c = np.asarray(mesh.bounds, dtype=float).mean(axis=0)
        h = 100.0
        z = floor_z - 1e-3
        v = np.array([[c[0] - h, c[1] - h, z], [c[0] + h, c[1] - h, z],
                      [c[0] + h, c[1] + h, z], [c[0] - h, c[1] + h, z]]) - origin
        scene.add_triangles(v.astype(np.float32), np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32))
    return RayScene(scene, origin)


def first_hit_distance(scene, origins, directions) -> np.ndarray:
    """Distance to the first hit of each ray (``inf`` when it escapes).

    Parameters
    ----------
    scene : RayScene
        From :func:`raycasting_scene`.
    origins, directions : (k, 3) float
        Directions need not be unit; distances are in units of their length.

    Returns
    -------
    (k,) float
    """
    import open3d as o3d

    rays = np.hstack([np.asarray(origins, dtype=float) - scene.origin, np.asarray(directions, dtype=float)])
    if len(rays) == 0:
        return np.zeros(0)
    out = scene.scene.cast_rays(o3d.core.Tensor(rays.astype(np.float32)))
    return out["t_hit"].numpy().astype(float)


def group_gateways(directions, escaping, neighbour_factor: float = 1.6) -> list[np.ndarray]:
    """Group escaping rays of a fan into gateways: connected components on the sphere.

    Two rays are neighbours when the angle between them is below ``neighbour_factor`` times the
    fan's mean angular spacing ``sqrt(4 pi / r)``.

    Parameters
    ----------
    directions : (r, 3) float, unit
    escaping : (r,) bool

    Returns
    -------
    list of (k_i,) int arrays
        Ray indices per gateway, sorted by decreasing size (ties by smallest index).
    """
    directions = np.asarray(directions, dtype=float)
    idx = np.flatnonzero(np.asarray(escaping, dtype=bool))
    if len(idx) == 0:
        return []
    spacing = math.sqrt(4.0 * math.pi / len(directions))
    chord = 2.0 * math.sin(min(neighbour_factor * spacing, math.pi) / 2.0)
    pairs = cKDTree(directions[idx]).query_pairs(chord, output_type="ndarray")
    k = len(idx)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(k, k)) if len(pairs) \
        else coo_matrix((k, k))
    n_comp, comp = connected_components(graph, directed=False)
    groups = [idx[comp == c] for c in range(n_comp)]
    groups.sort(key=lambda g: (-len(g), int(g[0])))
    return groups


def nos_clusters(mesh, points, normals, observed, params: NoSParams, *, spacing: float,
                 floor_z: float | None = 0.0, scene=None) -> list[NoSCluster]:
    """Cluster the non-observed elements, cast a ray fan from each centre, find gateways.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Machine, metres.
    points, normals : (n, 3) float
        Surface elements S and their outward normals.
    observed : (n,) bool
        Elements covered by the guards.
    params : NoSParams
        DBSCAN ``eps_factor`` and ``min_samples``; ``n_rays`` of the fan (Fibonacci sphere);
        ``ray_length`` (m) a ray must travel without hitting the machine or the floor to
        escape; ``origin_offset`` (m) the ray origin is lifted off the surface.
    spacing : float, m
        Spacing of S; the DBSCAN radius is ``params.eps_factor * spacing``.
    floor_z : float or None
        Height of the floor that blocks rays (None: no floor).
    scene : RayScene, optional
        Reuse a scene built by :func:`raycasting_scene`.

    Returns
    -------
    list of NoSCluster, in label order
    """
    points = check_points("points", points)
    normals = check_points("normals", normals)
    check_positive("spacing", spacing)
    labels = cluster_unobserved(points, observed, params.eps_factor * spacing, params.min_samples)
    n_labels = int(labels.max()) + 1 if len(labels) else 0
    if n_labels == 0:
        return []
    if scene is None:
        scene = raycasting_scene(mesh, floor_z)
    fan = sphere_directions(params.n_rays)
    members, origins = [], []
    for lab in range(n_labels):
        m = np.flatnonzero(labels == lab)
        centre = points[m].mean(axis=0)
        j = m[np.argmin(np.linalg.norm(points[m] - centre, axis=1))]
        members.append(m)
        origins.append(points[j] + params.origin_offset * normals[j])
    origins = np.asarray(origins)
    # one batched cast for every cluster's fan
    o = np.repeat(origins, len(fan), axis=0)
    d = np.tile(fan, (n_labels, 1))
    t = first_hit_distance(scene, o, d).reshape(n_labels, len(fan))
    out = []
    for lab in range(n_labels):
        esc = t[lab] > params.ray_length
        gws = []
        for g in group_gateways(fan, esc):
            dirs = fan[g]
            mean = dirs.mean(axis=0)
            best = dirs[int(np.argmax(dirs @ mean))]
            gws.append(Gateway(lab, origins[lab], dirs, best))
        out.append(NoSCluster(lab, members[lab], origins[lab], fan, esc, t[lab], gws))
    return out


def spot_along_direction(spots_xy, origin, direction) -> int:
    """Index of the spot closest to the exit direction projected on the floor.

    The exit direction is projected on the floor as a half-line from the cluster origin; the spot
    nearest to that half-line is chosen. If the exit direction is (near) vertical, the spot nearest
    to the origin on the floor is chosen.

    Parameters
    ----------
    spots_xy : (k, 2) float, m
    origin : (3,) float, m
    direction : (3,) float

    Returns
    -------
    int
    """
    spots_xy = check_points("spots_xy", spots_xy, dim=2)
    o = np.asarray(origin, dtype=float)[:2]
    d = np.asarray(direction, dtype=float)[:2]
    rel = spots_xy - o
    norm = np.linalg.norm(d)
    if norm < 1e-6:
        return int(np.argmin(np.linalg.norm(rel, axis=1)))
    d = d / norm
    t = np.clip(rel @ d, 0.0, None)
    return int(np.argmin(np.linalg.norm(rel - t[:, None] * d, axis=1)))


# ---------------------------------------------------------------- the NoS stage of the plan


@dataclass(frozen=True)
class NoSGuard:
    """A NoS guard: a camera configuration on a gateway ray that RRT-Connect reaches.

    Attributes
    ----------
    spot : int
        Index into the plan's spots (tour order).
    q : (nq,) float, rad
    world_T_camera : (4, 4) float
    visible : (n,) bool
        Elements of S it sees (FOV + HPR or ray casting).
    """

    spot: int
    q: np.ndarray
    world_T_camera: np.ndarray
    visible: np.ndarray


def gateway_rays(gateway: Gateway, max_tries: int) -> np.ndarray:
    """The gateway's rays closest to its exit direction, best first, at most ``max_tries``, (r, 3)."""
    d = gateway.ray_directions
    return d[np.argsort(-(d @ gateway.direction), kind="stable")[:max_tries]]


def attempt_nos_guard(cluster: NoSCluster, spot: int, world_T_base, robot, checker, params: NoSParams,
                      standoff: float, rng: np.random.Generator) -> tuple[dict, np.ndarray | None]:
    """One NoS guard attempt from a spot: IK on the best gateway's rays, then RRT-Connect.

    The camera sits ``standoff`` (m; a NoS guard is a guard: the guard stand-off
    :attr:`mavac.params.InspectionParams.guard_standoff`) out along the first of
    :func:`gateway_rays` that has a collision-free IK solution, looking back along it; the guard
    is kept when RRT-Connect finds a path to that configuration from the robot's home
    configuration (MAVAC, "Non-observed surface").

    Returns
    -------
    record : dict
        ``cluster, n_elements, spot, n_rays, ik, solved, reason, seconds``.
    q : (nq,) float or None
        The NoS guard configuration when RRT-Connect solved, else None.

    Raises
    ------
    mavac.planning.rrt.PlanningTimeout
        If the wall-time safety net ``params.rrt_time_limit`` fires before the iteration budget
        ``params.rrt_max_iterations`` is spent (the plan would depend on the machine's load).
    """
    gw = cluster.best_gateway
    rays = gateway_rays(gw, params.max_ray_tries)
    ok, q, _ = camera_configurations(robot, checker, world_T_base, cluster.origin + standoff * rays, -rays, rng)
    record = {"cluster": int(cluster.label), "n_elements": int(len(cluster.members)), "spot": int(spot),
              "n_rays": gw.n_rays, "ik": bool(ok.any()), "solved": False, "reason": "no collision-free IK",
              "seconds": 0.0}
    if not ok.any():
        return record, None
    q_goal = q[int(np.argmax(ok))]
    checker.set_base(world_T_base)
    res = plan_rrt_connect(lambda qq: not bool(checker.in_collision(qq)), robot.q_home, q_goal,
                           robot.q_lower, robot.q_upper, time_limit=params.rrt_time_limit,
                           seed=int(rng.integers(2**31 - 1)), resolution=params.rrt_resolution,
                           max_iterations=params.rrt_max_iterations)
    record.update(solved=bool(res.solved), reason=res.reason, seconds=float(res.seconds))
    return record, (q_goal if res.solved else None)


def nos_guards(ctx, spots, observed, params: InspectionParams) -> tuple[list, list, list]:
    """The NoS stage: clusters of what the guards left unobserved, gateways, NoS guards.

    Parameters
    ----------
    ctx : mavac.inspection.inspection_plan.OfflineContext
        Machine mesh, robot, collision checker, S and its scenes.
    spots : (k, 3) float
        Spots in tour order; a cluster is tried from the spot along its exit direction
        (:func:`spot_along_direction`), IK restarts and RRT seeded by ``(seed, 2, label)``.
    observed : (n,) bool
        Elements the regular guards cover.
    params : InspectionParams
        ``nos``, ``camera``, ``visibility`` and ``guard_standoff`` of a NoS guard, ``surface_spacing``,
        ``seed``.

    Returns
    -------
    clusters : list of NoSCluster
    guards : list of NoSGuard
        In cluster order.
    attempts : list of dict
        One :func:`attempt_nos_guard` record per cluster with a gateway.
    """
    if not params.nos.enabled:
        return [], [], []
    clusters = nos_clusters(ctx.machine.mesh, ctx.points, ctx.normals, observed, params.nos,
                            spacing=params.surface_spacing, scene=ctx.scene)
    world_T_bases = se2_matrices(spots)
    robot, guards, attempts = ctx.robot, [], []
    for c in clusters:
        if c.best_gateway is None:
            continue
        k = spot_along_direction(spots[:, :2], c.origin, c.best_gateway.direction)
        rng = rng_for(params.seed, "nos guard", c.label)
        record, q = attempt_nos_guard(c, k, world_T_bases[k], robot, ctx.checker, params.nos,
                                      params.guard_standoff, rng)
        if q is not None:
            T = compose(world_T_bases[k], fk(robot, q, robot.camera_frame))
            vis = guard_visibility(T[None], ctx.points, ctx.normals, params.camera, params.visibility, ctx.vis_scene)[0]
            guards.append(NoSGuard(k, q, T, vis))
        attempts.append(record)
    return clusters, guards, attempts

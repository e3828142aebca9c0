"""Evenly spaced surface points with outward normals (MAVAC's surface model S).

The MAVAC paper represents the machine by points on its surface; the same sampler places
the evaluation dust heaps "evenly distributed at intervals of 10 cm" (MAVAC, Experimental
setup). We use Open3D's Poisson-disk sample elimination (Yuksel 2015), which returns exactly
the requested number of blue-noise points, so ``n = round(area / spacing**2)`` points lie
roughly ``spacing`` apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from ..tolerances import BURIED_TOLERANCE
from ..validate import check_int, check_positive
from .mesh import check_mesh, local_origin

#: most points :func:`sample_surface` makes (about 100 MB of Poisson-disk work)
MAX_POINTS = 2_000_000


@dataclass(frozen=True)
class SurfacePoints:
    """Points on a mesh surface.

    Attributes
    ----------
    points : (n, 3) float, metres
    normals : (n, 3) float, unit, outward (the face normal of the face each point lies on)
    face_index : (n,) int, index of that face in the sampled mesh
    """

    points: np.ndarray
    normals: np.ndarray
    face_index: np.ndarray

    def __len__(self) -> int:
        return len(self.points)

    def subset(self, mask_or_index) -> SurfacePoints:
        """The points selected by a boolean mask or an index array."""
        return SurfacePoints(self.points[mask_or_index], self.normals[mask_or_index],
                             self.face_index[mask_or_index])


def sample_surface(mesh: trimesh.Trimesh, spacing: float, seed: int = 0) -> SurfacePoints:
    """Sample ``round(mesh.area / spacing**2)`` points about ``spacing`` apart.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Surface to sample, metres; its face normals are taken as outward.
    spacing : float, metres
        Target distance between neighbouring points (> 0). Poisson-disk elimination gives a
        nearest-neighbour distance of about 0.85 ``spacing``, with no clumps.
    seed : int
        Seed of the initial uniform sampling; the same seed gives the same points.

    Returns
    -------
    SurfacePoints
        ``normals`` are the face normals of the faces the points lie on.
    """
    import open3d as o3d

    check_positive("spacing", spacing)
    seed = check_int("seed", seed, 0, 2**31 - 1)
    check_mesh("mesh", mesh)
    count = int(round(mesh.area / spacing**2))
    if count < 1 or count > MAX_POINTS:
        across = float(np.ptp(np.asarray(mesh.vertices), axis=0).max())
        units = (f"; the mesh is {across:.3g} m across: if it is really "
                 f"{'larger' if count < 1 else 'smaller'}, it was read in the wrong units "
                 "(load_mesh(path, units=...))")
        if count < 1:
            raise ValueError(f"spacing={spacing} m is larger than the mesh itself "
                             f"(area {mesh.area:.3g} m^2); pass a smaller spacing{units}")
        raise ValueError(f"spacing={spacing} m would give {count:,} points on "
                         f"{mesh.area:.3g} m^2 (at most {MAX_POINTS:,}); pass a larger spacing{units}")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int32)
    o3d_mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(vertices),
                                         o3d.utility.Vector3iVector(faces))
    # Open3D only has a global seed; setting it right before the call makes this reproducible.
    o3d.utility.random.seed(seed)
    cloud = o3d_mesh.sample_points_poisson_disk(number_of_points=count, init_factor=5)
    points = np.asarray(cloud.points, dtype=np.float64)
    # Open3D does not say which triangle a sample came from: ask the closest-point query.
    scene = o3d.t.geometry.RaycastingScene()
    origin = local_origin(vertices)  # float32 queries, relative to a point near the mesh
    scene.add_triangles(o3d.core.Tensor((vertices - origin).astype(np.float32)),
                        o3d.core.Tensor(faces.astype(np.uint32)))
    closest = scene.compute_closest_points(o3d.core.Tensor((points - origin).astype(np.float32)))
    face_index = closest["primitive_ids"].numpy().astype(np.int64)
    normals = np.asarray(mesh.face_normals, dtype=np.float64)[face_index]
    return SurfacePoints(points=points, normals=normals, face_index=face_index)


def buried(mesh: trimesh.Trimesh, surf: SurfacePoints, tolerance: float = BURIED_TOLERANCE) -> np.ndarray:
    """Which points of ``surf`` lie strictly inside another body of ``mesh``.

    A mesh may hold several bodies (connected sets of faces, as :meth:`trimesh.Trimesh.split`
    finds them) that overlap without a boolean union, e.g. two boxes written into one file. A
    point on a face of body A that lies inside body B is not on the outer surface of the
    machine: nothing can see or reach it.

    Only bodies that are closed volumes (watertight, consistently wound, positive volume:
    :attr:`trimesh.Trimesh.is_volume`) can bury points; an open or inside-out body has no
    well-defined inside and buries nothing. Points of a body are never tested against their own
    body, so a single body crossing itself is not handled. A mesh of one body returns at once.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The mesh ``surf`` was sampled on (metres).
    surf : SurfacePoints
        ``n`` points on ``mesh``; ``surf.face_index`` names the body each lies on.
    tolerance : float, metres
        Depth inside another body beyond which a point is buried
        (:data:`mavac.tolerances.BURIED_TOLERANCE`); points on that body's boundary are kept.

    Returns
    -------
    (n,) bool
        True for the buried points.
    """
    out = np.zeros(len(surf), dtype=bool)
    bodies = trimesh.graph.connected_components(mesh.face_adjacency, nodes=np.arange(len(mesh.faces)), min_len=1)
    if len(bodies) < 2:
        return out
    body_of_face = np.empty(len(mesh.faces), dtype=np.int64)
    for i, faces in enumerate(bodies):
        body_of_face[faces] = i
    body_of_point = body_of_face[surf.face_index]
    triangles = np.asarray(mesh.triangles)
    tree = cKDTree(surf.points)  # finds the points near one body without a pass over all of them
    for i, faces in enumerate(bodies):
        if len(faces) < 4:  # no closed body has fewer faces (a tetrahedron); skips triangle soup cheaply
            continue
        lo, hi = triangles[faces].min(axis=(0, 1)), triangles[faces].max(axis=(0, 1))
        # only points deeper than ``tolerance`` inside the bounding box can be deeper inside the body
        near = np.asarray(tree.query_ball_point((lo + hi) / 2, np.linalg.norm(hi - lo) / 2), dtype=np.int64)
        near = near[(body_of_point[near] != i) & ~out[near]
                    & np.all((surf.points[near] > lo + tolerance) & (surf.points[near] < hi - tolerance), axis=1)]
        if len(near) == 0:
            continue
        body = mesh.submesh([faces], append=True)
        if body.is_volume:
            out[near] = trimesh.proximity.signed_distance(body, surf.points[near]) > tolerance
    return out

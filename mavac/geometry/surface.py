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

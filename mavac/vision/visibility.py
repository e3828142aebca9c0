"""Visibility of surface points from camera poses: HPR (the paper's method) and exact ray casting.

MAVAC ("Camera field of view (FOV)") first keeps the surface points inside the FOV pyramid,
then removes hidden ones with hidden point removal (HPR, Katz, Tal and Basri 2007, "Direct
visibility of point sets"), because the pyramid "may extend beyond the machine walls". The
Discussion attributes part of the low coverage to HPR misclassifications, so this module also
gives the exact answer -- a segment test against the mesh with Open3D's Embree
``RaycastingScene`` -- and :func:`hpr_error_rates` measures how far HPR is from it.

What HPR receives (``hpr_input``):

* ``"surface"`` (default, what the paper implies): HPR runs on the **whole** surface sample S
  from the camera origin; a point is visible iff it is in the FOV and HPR keeps it. The
  paper describes HPR as a property of the surface seen from the camera, not of a cropped
  cloud, and Fig. 3's caption presents the HPR-visible points (purple) and the FOV pyramid
  as two separate sets that are intersected.
* ``"fov"``: HPR runs only on the points inside the FOV. Every occluder of an in-FOV point
  lies on the segment from the camera to it, hence inside the (convex) pyramid too, so the
  crop loses no true occluder. It is much cheaper (the crop is a few percent of S). It is
  not the same classifier: for a fixed radius the hull of a subset keeps a superset of
  points, but the radius is relative to the farthest *input* point, so the crop also gets a
  smaller radius (which hides more); :func:`hpr_error_rates` measures both variants.

HPR uses positions only (the paper's method); ray casting can also require the point to face
the camera, ``n . (v - p) > 0``, when normals are given.

The choice between the two, HPR's radius and its input set are one value,
:class:`mavac.params.Visibility` (also importable from here); :func:`visible_points` is the one
place that dispatches on it.
"""

from __future__ import annotations

import time

import numpy as np
import trimesh

from ..geometry.mesh import check_mesh, local_origin
from ..geometry.transforms import check_transforms
from ..params import CameraParams, Visibility
from ..tolerances import RAY_EPS_RELATIVE
from ..validate import check_instance, check_points, check_positive
from .camera import fov_masks

# Rays per Embree call: 2**20 rays x 6 float32 = 24 MB.
_RAYS_PER_CALL = 1 << 20
__all__ = ["Visibility", "VisibilityScene", "classification_rates", "hpr_error_rates", "hpr_visible",
           "raycast_visible", "visible_each", "visible_from", "visible_points"]


def _point_cloud(points: np.ndarray):
    import open3d as o3d

    return o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))


def _hpr_on_cloud(pcd, points: np.ndarray, viewpoint: np.ndarray, vis: Visibility) -> np.ndarray:
    """HPR mask over ``points`` (already held by the Open3D cloud ``pcd``)."""
    n = points.shape[0]
    if n == 0:
        return np.ones(0, dtype=bool)
    rel = points - viewpoint
    max_distance = float(np.sqrt(np.max(np.sum(rel**2, axis=1))))
    # Spherical flipping keeps each point on its ray from the viewpoint, so if the points and
    # the viewpoint span less than 3-D, so does the hull: it has no interior, every point is
    # on its boundary (Katz et al.'s visibility criterion), and Qhull would refuse the input.
    singular = np.linalg.svd(rel, compute_uv=False)
    if len(singular) < 3 or singular[-1] <= 1e-9 * singular[0]:
        return np.ones(n, dtype=bool)
    _, kept = pcd.hidden_point_removal(viewpoint, vis.hpr_radius(max_distance))
    mask = np.zeros(n, dtype=bool)
    mask[np.asarray(kept, dtype=np.int64)] = True
    return mask


def hpr_visible(points, viewpoint, radius_factor: float = Visibility.radius_factor, *,
                radius: float | None = None) -> np.ndarray:
    """Hidden point removal (Katz et al. 2007) with Open3D.

    Parameters
    ----------
    points : (n, 3) float, metres
        Point cloud (a sample of the whole surface).
    viewpoint : (3,) float, metres
        Camera origin.
    radius_factor : float
        Spherical-flipping radius ``R = radius_factor * max_i |p_i - viewpoint|``; must be > 1.
        Larger R keeps more points (fewer false hidden on convex parts, more false visible
        in concavities).
    radius : float, optional, metres
        Absolute R instead (must exceed the farthest point distance).

    Returns
    -------
    (n,) bool
        ``True`` for points HPR keeps as visible.
    """
    P = check_points("points", points)
    v = check_points("viewpoint", viewpoint)
    if v.shape[0] != 1:
        raise ValueError(f"viewpoint must have shape (3,), got {np.shape(viewpoint)}")
    vis = Visibility("hpr", radius_factor=radius_factor, radius=radius)
    return _hpr_on_cloud(_point_cloud(P), P, v[0], vis)


def _hpr_in_fov(points, fov, viewpoints, vis: Visibility) -> np.ndarray:
    """``fov & HPR`` for every camera; HPR input set (``vis.hpr_input``) as in the module docstring."""
    out = np.zeros_like(fov)
    whole = _point_cloud(points) if vis.hpr_input == "surface" else None
    for i in np.flatnonzero(fov.any(axis=1)):
        if whole is not None:
            out[i] = fov[i] & _hpr_on_cloud(whole, points, viewpoints[i], vis)
        else:
            idx = np.flatnonzero(fov[i])
            sub = points[idx]
            out[i, idx] = _hpr_on_cloud(_point_cloud(sub), sub, viewpoints[i], vis)
    return out


class VisibilityScene:
    """Exact point visibility against one mesh, with the Embree scene built once.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Occluding geometry (metres).
    eps : float, optional
        A point counts as reached when nothing is hit before ``|p - v| - eps``. Default
        :data:`mavac.tolerances.RAY_EPS_RELATIVE` (1e-4) x the mesh bounding-box diagonal.

    Notes
    -----
    Picklable (for joblib workers): only the vertices and faces are pickled, the Open3D scene
    is rebuilt on first use.
    """

    def __init__(self, mesh: trimesh.Trimesh, eps: float | None = None):
        check_mesh("mesh", mesh)
        self.origin = local_origin(mesh.vertices)  # rays are cast relative to it, in float32
        self.vertices = np.ascontiguousarray(np.asarray(mesh.vertices) - self.origin, dtype=np.float32)
        self.faces = np.ascontiguousarray(mesh.faces, dtype=np.uint32)
        self.scale = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
        self.eps = RAY_EPS_RELATIVE * self.scale if eps is None else float(check_positive("eps", eps))
        self._scene = None

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_scene"] = None
        return state

    @property
    def scene(self):
        """The ``open3d.t.geometry.RaycastingScene`` (built lazily)."""
        if self._scene is None:
            import open3d as o3d

            scene = o3d.t.geometry.RaycastingScene()
            scene.add_triangles(o3d.core.Tensor(self.vertices), o3d.core.Tensor(self.faces))
            self._scene = scene
        return self._scene

    def unoccluded(self, origins, targets) -> np.ndarray:
        """Segment test: nothing of the mesh between each origin and ``target - eps``.

        Parameters
        ----------
        origins, targets : (k, 3) float, metres

        Returns
        -------
        (k,) bool
            ``True`` if the segment from ``origins[i]`` to within ``eps`` of ``targets[i]``
            hits no triangle (targets closer than ``eps`` count as unoccluded).
        """
        import open3d as o3d

        O = check_points("origins", origins)
        Tg = check_points("targets", targets)
        if O.shape != Tg.shape:
            raise ValueError(f"origins and targets must have the same shape, got {O.shape} vs {Tg.shape}")
        d = Tg - O
        length = np.linalg.norm(d, axis=1)
        free = np.ones(len(O), dtype=bool)
        far = length > self.eps
        # Scale each direction so that t = 1 is eps short of the target: one tfar for all rays.
        rays = np.empty((int(far.sum()), 6), dtype=np.float32)
        rays[:, :3] = O[far] - self.origin
        rays[:, 3:] = d[far] * ((length[far] - self.eps) / length[far])[:, None]
        hit = np.empty(len(rays), dtype=bool)
        for s in range(0, len(rays), _RAYS_PER_CALL):
            chunk = o3d.core.Tensor(rays[s : s + _RAYS_PER_CALL])
            hit[s : s + _RAYS_PER_CALL] = self.scene.test_occlusions(chunk, tnear=0.0, tfar=1.0).numpy()
        free[far] = ~hit
        return free

    def visible(self, points, normals, viewpoints, candidates=None) -> np.ndarray:
        """Exact visibility of every point from every viewpoint.

        Parameters
        ----------
        points : (n, 3) float, metres
            Points on the mesh surface.
        normals : (n, 3) float or None
            Outward normals; if given, a point must also face the viewpoint,
            ``n . (v - p) > 0``.
        viewpoints : (m, 3) float, metres
            Camera origins (outside the solid).
        candidates : (m, n) bool, optional
            Only these pairs are tested (e.g. the FOV mask); the others are ``False``.

        Returns
        -------
        (m, n) bool
        """
        P = check_points("points", points)
        V = check_points("viewpoints", viewpoints)
        N = None if normals is None else check_points("normals", normals)
        if N is not None and N.shape != P.shape:
            raise ValueError(f"normals must have the same shape as points {P.shape}, got {N.shape}")
        if candidates is None:
            cand = np.ones((len(V), len(P)), dtype=bool)
        else:
            cand = np.asarray(candidates, dtype=bool)
            if cand.shape != (len(V), len(P)):
                raise ValueError(f"candidates must have shape {(len(V), len(P))}, got {cand.shape}")
        out = np.zeros((len(V), len(P)), dtype=bool)
        block = max(1, _RAYS_PER_CALL // max(1, len(P)))
        for start in range(0, len(V), block):
            iv, ip = np.nonzero(cand[start : start + block])
            iv += start
            if N is not None:
                # Back-facing points cannot be seen: no ray needed for them.
                facing = np.einsum("ij,ij->i", N[ip], V[iv] - P[ip]) > 0.0
                iv, ip = iv[facing], ip[facing]
            out[iv, ip] = self.unoccluded(V[iv], P[ip])
        return out


def raycast_visible(mesh, points, normals, viewpoints) -> np.ndarray:
    """Exact visibility by ray casting (Open3D ``RaycastingScene``, batched).

    Parameters
    ----------
    mesh : trimesh.Trimesh or VisibilityScene
        Occluders; pass a :class:`VisibilityScene` to reuse its Embree scene across calls.
    points : (n, 3) float, metres
        Points on the mesh surface.
    normals : (n, 3) float or None
        Outward normals; if given, back-facing points are not visible.
    viewpoints : (m, 3) or (3,) float, metres

    Returns
    -------
    (m, n) bool
        Point j is visible from viewpoint i iff the segment from the viewpoint stops no
        earlier than ``|p - v| - eps`` (and the point faces the viewpoint if normals given).
    """
    scene = mesh if isinstance(mesh, VisibilityScene) else VisibilityScene(mesh)
    return scene.visible(points, normals, viewpoints)


def _as_scene(scene, method: str):
    """The ray-casting scene of ``scene`` (a mesh or a :class:`VisibilityScene`); HPR needs none."""
    if method != "raycast":
        return None
    if scene is None:
        raise ValueError("scene (the occluding mesh or a VisibilityScene) is required for method='raycast'")
    return scene if isinstance(scene, VisibilityScene) else VisibilityScene(scene)


def visible_points(visibility: Visibility, points, normals, viewpoints, *, scene=None,
                   candidates=None) -> np.ndarray:
    """Surface points seen from each viewpoint, by ``visibility``'s method: the one dispatch.

    Parameters
    ----------
    visibility : Visibility
        ``"raycast"``: nothing of ``scene`` on the segment and, with normals, the point faces the
        viewpoint; ``"hpr"``: HPR (radius and input set from ``visibility``) keeps the point.
    points : (n, 3) float, metres
        Surface sample S.
    normals : (n, 3) float or None
        Outward normals (ray casting only; HPR is position-only, as in the paper).
    viewpoints : (m, 3) float, metres
    scene : trimesh.Trimesh or VisibilityScene, optional
        Occluders; required for ``"raycast"``.
    candidates : (m, n) bool, optional
        Only these pairs can be visible (e.g. the FOV pyramid); default all.

    Returns
    -------
    (m, n) bool
    """
    check_instance("visibility", visibility, Visibility)
    P = check_points("points", points)
    V = check_points("viewpoints", viewpoints)
    ray_scene = _as_scene(scene, visibility.method)
    if ray_scene is not None:
        return ray_scene.visible(P, normals, V, candidates=candidates)
    cand = np.ones((len(V), len(P)), dtype=bool) if candidates is None else np.asarray(candidates, dtype=bool)
    if cand.shape != (len(V), len(P)):
        raise ValueError(f"candidates must have shape {(len(V), len(P))}, got {cand.shape}")
    return _hpr_in_fov(P, cand, V, visibility)


def visible_each(visibility: Visibility, points, normals, viewpoints, *, scene=None) -> np.ndarray:
    """Whether point i is seen from viewpoint i, (n,) bool (e.g. each element from its own
    camera pose); HPR runs on the whole of ``points`` from each viewpoint.

    Parameters
    ----------
    visibility : Visibility
    points, viewpoints : (n, 3) float, metres
    normals : (n, 3) float or None
        Ray casting only: a point must face its viewpoint.
    scene : trimesh.Trimesh or VisibilityScene, optional
        Required for ``"raycast"``.
    """
    check_instance("visibility", visibility, Visibility)
    P = check_points("points", points)
    V = check_points("viewpoints", viewpoints)
    if V.shape != P.shape:
        raise ValueError(f"viewpoints must have the shape of points {P.shape}, got {V.shape}")
    ray_scene = _as_scene(scene, visibility.method)
    if ray_scene is None:
        whole = _point_cloud(P)
        return np.array([_hpr_on_cloud(whole, P, v, visibility)[i] for i, v in enumerate(V)], dtype=bool)
    seen = ray_scene.unoccluded(V, P)
    if normals is not None:
        seen &= np.einsum("ij,ij->i", check_points("normals", normals), V - P) > 0.0
    return seen


def visible_from(points, normals, world_T_cameras, camera: CameraParams, visibility: Visibility = Visibility(),
                 *, scene=None) -> np.ndarray:
    """Surface points seen by each camera pose: FOV pyramid AND ``visibility`` (HPR or ray casting).

    Parameters
    ----------
    points : (n, 3) float, metres
        Surface sample S.
    normals : (n, 3) float or None
        Outward normals; used by ray casting only.
    world_T_cameras : (m, 4, 4) or (4, 4) float
        Camera poses; the viewpoint is the translation.
    camera : CameraParams
    visibility : Visibility
        Default: the package's (exact ray casting); ``Visibility("hpr")`` reproduces MAVAC.
    scene : trimesh.Trimesh or VisibilityScene, optional
        Required for ray casting.

    Returns
    -------
    (m, n) bool
    """
    P = check_points("points", points)
    T = check_transforms("world_T_cameras", world_T_cameras)
    return visible_points(visibility, P, normals, T[:, :3, 3], scene=scene, candidates=fov_masks(P, T, camera))


def hpr_error_rates(mesh, points, normals, world_T_cameras, camera: CameraParams, *,
                    visibility: Visibility = Visibility("hpr")) -> dict:
    """HPR's misclassifications against exact ray casting, over many camera poses.

    Only (pose, point) pairs inside the FOV pyramid are scored (outside, both methods say
    "not visible"). With ray casting as ground truth:

    * ``false_visible = FP / (FP + TN)``: fraction of in-FOV, ray-hidden pairs that HPR marks
      visible (false-positive rate);
    * ``false_hidden = FN / (FN + TP)``: fraction of in-FOV, ray-visible pairs that HPR marks
      hidden (false-negative rate).

    A rate whose denominator is zero is ``nan``.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    points, normals : (n, 3) float
        Surface sample and outward normals (normals may be None).
    world_T_cameras : (m, 4, 4) float
    camera : CameraParams
    visibility : Visibility
        HPR's radius and input set (its method is ignored: HPR is scored).

    Returns
    -------
    dict
        ``false_visible``, ``false_hidden`` (fractions), ``hpr_seconds``, ``raycast_seconds``
        (wall time of each method after the shared FOV test; ray casting includes building
        the Embree scene), ``n_poses``, ``n_in_fov`` (scored pairs), ``n_ray_visible``,
        ``n_ray_hidden``, ``n_false_visible``, ``n_false_hidden``, ``agreement`` (fraction of
        scored pairs on which both agree).
    """
    check_instance("visibility", visibility, Visibility)
    P = check_points("points", points)
    T = check_transforms("world_T_cameras", world_T_cameras)
    fov = fov_masks(P, T, camera)
    viewpoints = T[:, :3, 3]

    t0 = time.perf_counter()
    hpr = _hpr_in_fov(P, fov, viewpoints, visibility)
    hpr_seconds = time.perf_counter() - t0

    t0 = time.perf_counter()
    scene = VisibilityScene(mesh)
    ray = scene.visible(P, normals, viewpoints, candidates=fov)
    raycast_seconds = time.perf_counter() - t0

    rates = classification_rates(hpr, ray, fov)
    return {
        "false_visible": rates["false_visible"],
        "false_hidden": rates["false_hidden"],
        "hpr_seconds": hpr_seconds,
        "raycast_seconds": raycast_seconds,
        "n_poses": int(T.shape[0]),
        "n_in_fov": rates["n_scored"],
        "n_ray_visible": rates["n_visible"],
        "n_ray_hidden": rates["n_hidden"],
        "n_false_visible": rates["n_false_visible"],
        "n_false_hidden": rates["n_false_hidden"],
        "agreement": rates["agreement"],
    }


def classification_rates(predicted, truth, scored=None) -> dict:
    """How a visibility classifier (e.g. HPR) compares with the truth (e.g. ray casting).

    Parameters
    ----------
    predicted, truth : (m, n) bool
        Visible pairs (viewpoint, element) by each method.
    scored : (m, n) bool, optional
        Pairs to score (e.g. those in the FOV); default all.

    Returns
    -------
    dict
        ``false_visible = FP / (FP + TN)`` (fraction of the truly hidden pairs called visible),
        ``false_hidden = FN / (FN + TP)`` (fraction of the truly visible pairs called hidden),
        ``agreement`` (fraction of scored pairs on which both agree), and the counts
        ``n_scored, n_visible, n_hidden, n_false_visible, n_false_hidden``. A rate whose
        denominator is zero is ``nan``.
    """
    pred = np.asarray(predicted, dtype=bool)
    true = np.asarray(truth, dtype=bool)
    if pred.shape != true.shape:
        raise ValueError(f"predicted and truth must have the same shape, got {pred.shape} vs {true.shape}")
    mask = np.ones_like(true) if scored is None else np.asarray(scored, dtype=bool)
    if mask.shape != true.shape:
        raise ValueError(f"scored must have shape {true.shape}, got {mask.shape}")
    n_scored = int(mask.sum())
    n_visible = int((true & mask).sum())
    n_hidden = n_scored - n_visible
    n_fv = int((pred & ~true & mask).sum())
    n_fh = int((true & ~pred & mask).sum())
    nan = float("nan")
    return {
        "false_visible": n_fv / n_hidden if n_hidden else nan,
        "false_hidden": n_fh / n_visible if n_visible else nan,
        "agreement": 1.0 - (n_fv + n_fh) / n_scored if n_scored else nan,
        "n_scored": n_scored, "n_visible": n_visible, "n_hidden": n_hidden,
        "n_false_visible": n_fv, "n_false_hidden": n_fh,
    }

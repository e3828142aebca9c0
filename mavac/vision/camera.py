"""MAVAC's emulated camera: the FOV pyramid test and guard camera poses.

Camera frame (MAVAC, "Camera field of view (FOV)"): the optical axis is the camera **x** axis,
``y`` spans the image width and ``z`` the image height. A world point ``s`` seen from
``world_T_camera`` is written ``p_m = [x_c, y_c, z_c]`` in the camera frame and lies in the FOV
iff

1. ``0 < x_c <= L_d`` (in front of the camera, within the reliable detection limit),
2. ``|atan2(y_c, x_c)| <= theta_a`` (projection on the camera XY plane),
3. ``|atan2(z_c, x_c)| <= theta_b`` (projection on the camera XZ plane).

With ``x_c > 0`` conditions 2-3 are evaluated as ``|y_c| <= x_c tan(theta_a)`` (identical
sets, no trigonometry per point). A guard camera sits ``L_d`` from its target along the
normal, so a flat surface facing it lies *on* the far plane ``x_c = L_d``, and the guard's pose
(the FK of an IK solution) misses the nominal one by up to the IK tolerances; condition 1 is
therefore tested as ``x_c <= L_d + FAR_PLANE_TOL`` (:data:`mavac.tolerances.FAR_PLANE_TOL`,
1 mm) so that a guard always sees its own target face.
"""

from __future__ import annotations

import numpy as np

from ..geometry.transforms import check_transform, check_transforms, points_in_frame
from ..params import CameraParams
from ..tolerances import FAR_PLANE_TOL, PARALLEL_TOL
from ..validate import check_instance, check_points, check_positive

#: Column of the camera frame's rotation that is MAVAC's optical axis (camera x, see
#: :class:`mavac.params.CameraParams`); ``ik_axis(..., frame=camera_frame, frame_axis=OPTICAL_AXIS)``.
OPTICAL_AXIS = 0

# Cameras x points evaluated per block in fov_masks: bounds the (block, n, 3) temporaries.
_FOV_BLOCK_ELEMENTS = 2_000_000


def points_in_camera(points_world, world_T_cameras) -> np.ndarray:
    """World points expressed in each camera frame.

    Parameters
    ----------
    points_world : (n, 3) float, metres
    world_T_cameras : (m, 4, 4) or (4, 4) float
        Camera poses in the world.

    Returns
    -------
    (m, n, 3) float, metres
        ``camera_T_world @ s`` for every camera and point.
    """
    P = check_points("points_world", points_world)
    T = check_transforms("world_T_cameras", world_T_cameras)
    return points_in_frame(T, P)


def fov_masks(points_world, world_T_cameras, camera: CameraParams) -> np.ndarray:
    """MAVAC FOV pyramid test of every point against every camera.

    Parameters
    ----------
    points_world : (n, 3) float, metres
        Surface points S in the world frame.
    world_T_cameras : (m, 4, 4) float
        Camera poses (optical axis = camera x).
    camera : CameraParams
        Half-angles ``theta_a``, ``theta_b`` (rad) and depth limit ``L_d`` (m).

    Returns
    -------
    (m, n) bool
        ``True`` where point j is inside the FOV pyramid of camera i (boundaries included,
        far plane ``L_d`` plus :data:`mavac.tolerances.FAR_PLANE_TOL` = 1 mm).
    """
    P = check_points("points_world", points_world)
    T = check_transforms("world_T_cameras", world_T_cameras)
    check_instance("camera", camera, CameraParams)
    tan_a, tan_b = np.tan(camera.theta_a), np.tan(camera.theta_b)
    far = camera.L_d + FAR_PLANE_TOL
    out = np.zeros((T.shape[0], P.shape[0]), dtype=bool)
    block = max(1, _FOV_BLOCK_ELEMENTS // max(1, P.shape[0]))
    for start in range(0, T.shape[0], block):
        pc = points_in_camera(P, T[start : start + block])
        x, y, z = pc[..., 0], pc[..., 1], pc[..., 2]
        out[start : start + block] = (
            (x > 0.0) & (x <= far) & (np.abs(y) <= x * tan_a) & (np.abs(z) <= x * tan_b)
        )
    return out


def fov_mask(points_world, world_T_camera, camera: CameraParams) -> np.ndarray:
    """MAVAC FOV pyramid test for one camera.

    Parameters
    ----------
    points_world : (n, 3) float, metres
    world_T_camera : (4, 4) float
        Camera pose in the world (optical axis = camera x).
    camera : CameraParams

    Returns
    -------
    (n,) bool
        ``True`` for points inside the pyramid (see :func:`fov_masks`).
    """
    return fov_masks(points_world, check_transform("world_T_camera", world_T_camera)[None], camera)[0]


def camera_pose_looking_at(target, normal, distance) -> np.ndarray:
    """Guard camera pose: ``distance`` along the surface normal, looking back at the target.

    MAVAC ("Local exploration"): the guard point is placed along the surface normal at the
    reliable detection limit and the tool is oriented by the normal. The camera origin is
    ``target + n * distance`` and its x (optical) axis is ``-n``, so the target lies on the
    optical axis at ``x_c = distance``. Roll about the optical axis is fixed deterministically:
    camera z (image up) is world z projected orthogonally to the optical axis, or world x when
    the optical axis is vertical to within ~5e-5 rad (camera looking straight down or up);
    camera y completes a right-handed frame.

    Parameters
    ----------
    target : (3,) float, metres
        Surface point to look at.
    normal : (3,) float
        Outward surface normal at the target (normalised here; must be non-zero).
    distance : float, metres
        Stand-off, > 0 (usually ``CameraParams.L_d``).

    Returns
    -------
    (4, 4) float
        ``world_T_camera``.
    """
    p = check_points("target", target)
    if p.shape[0] != 1:
        raise ValueError(f"target must have shape (3,), got {np.shape(target)}")
    n = check_points("normal", normal)
    if n.shape[0] != 1:
        raise ValueError(f"normal must have shape (3,), got {np.shape(normal)}")
    check_positive("distance", distance)
    norm = np.linalg.norm(n[0])
    if norm < 1e-12:
        raise ValueError("normal must be a non-zero vector")
    n = n[0] / norm
    x_axis = -n
    up = np.array([0.0, 0.0, 1.0])
    if abs(x_axis @ up) > 1.0 - PARALLEL_TOL:
        up = np.array([1.0, 0.0, 0.0])
    z_axis = up - (up @ x_axis) * x_axis
    z_axis /= np.linalg.norm(z_axis)
    y_axis = np.cross(z_axis, x_axis)
    world_T_camera = np.eye(4)
    world_T_camera[:3, :3] = np.column_stack([x_axis, y_axis, z_axis])
    world_T_camera[:3, 3] = p[0] + n * float(distance)
    return world_T_camera


def fov_pyramid_corners(world_T_camera, camera: CameraParams) -> np.ndarray:
    """Apex and the four far corners of the FOV pyramid, in the world frame.

    Returns
    -------
    (5, 3) float, metres
        Row 0 is the camera origin; rows 1-4 the corners at ``x_c = L_d`` in the order
        (+y,+z), (-y,+z), (-y,-z), (+y,-z).
    """
    T = check_transform("world_T_camera", world_T_camera)
    L = camera.L_d
    wy, wz = L * np.tan(camera.theta_a), L * np.tan(camera.theta_b)
    local = np.array(
        [[0.0, 0.0, 0.0], [L, wy, wz], [L, -wy, wz], [L, -wy, -wz], [L, wy, -wz]]
    )
    return local @ T[:3, :3].T + T[:3, 3]


def fov_pyramid_lines(world_T_camera, camera: CameraParams) -> np.ndarray:
    """Edges of the FOV pyramid for plotting (MAVAC Fig. 3).

    Parameters
    ----------
    world_T_camera : (4, 4) float
    camera : CameraParams

    Returns
    -------
    (8, 2, 3) float, metres
        Segments ``[start, end]``: four from the apex to the far corners, then the four edges
        of the far rectangle at ``x_c = L_d``.
    """
    c = fov_pyramid_corners(world_T_camera, camera)
    apex_edges = [(0, k) for k in range(1, 5)]
    base_edges = [(1, 2), (2, 3), (3, 4), (4, 1)]
    return np.array([[c[i], c[j]] for i, j in apex_edges + base_edges])

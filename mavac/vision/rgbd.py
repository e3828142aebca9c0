"""Back-projection of RGB-D pixels to 3-D points (pinhole model, OpenCV camera frame).

A pixel ``(u, v)`` (column, row, pixel-index coordinates) with metric depth ``z`` along the
optical axis is the camera point ``z K^-1 [u, v, 1]^T``; the camera pose ``world_T_camera``
(OpenCV convention: z forward, x right, y down) takes it to the world.
"""

from __future__ import annotations

import numpy as np

from ..geometry.transforms import check_transform, transform_points
from ..validate import check_array


def check_intrinsics(K) -> np.ndarray:
    """A (3, 3) pinhole matrix with positive focal lengths and last row (0, 0, 1)."""
    a = check_array("K", K, float)
    if a.shape != (3, 3) or not np.all(np.isfinite(a)) or a[0, 0] <= 0 or a[1, 1] <= 0 \
            or not np.allclose(a[2], [0.0, 0.0, 1.0]):
        raise ValueError(f"K must be a finite (3, 3) pinhole matrix with fx, fy > 0 and last row (0, 0, 1), got {a!r}")
    return a


def back_project(uv, depth, K, world_T_camera=None) -> np.ndarray:
    """3-D points of pixels with known depth.

    Parameters
    ----------
    uv : (n, 2) float
        Pixel coordinates (column u, row v), pixel-index convention (centre of the top-left
        pixel = (0, 0)); sub-pixel values allowed (e.g. blob centroids).
    depth : (n,) float, metres
        Depth along the optical axis, finite and > 0.
    K : (3, 3) float
        Intrinsics (:func:`mavac.sim.render.intrinsics_from_fov`).
    world_T_camera : (4, 4) float, optional
        Camera pose (OpenCV convention); default: points in the camera frame.

    Returns
    -------
    (n, 3) float, metres
    """
    P = check_array("uv", uv, float).reshape(-1, 2) if np.size(uv) else np.zeros((0, 2))
    z = check_array("depth", depth, float).reshape(-1)
    if len(z) != len(P):
        raise ValueError(f"depth must have one value per pixel ({len(P)}), got {len(z)}")
    if not np.all(np.isfinite(P)) or not np.all(np.isfinite(z)) or np.any(z <= 0):
        raise ValueError("uv must be finite and depth finite and > 0")
    K = check_intrinsics(K)
    x = (P[:, 0] - K[0, 2]) / K[0, 0]
    y = (P[:, 1] - K[1, 2]) / K[1, 1]
    points = np.column_stack([x * z, y * z, z])
    if world_T_camera is None:
        return points
    return transform_points(check_transform("world_T_camera", world_T_camera), points)

"""RGB-D images from a pybullet world with the TinyRenderer (CPU, no display needed).

Camera frame: OpenCV convention, z forward (optical axis), x right, y down. (MAVAC's camera
frame has the optical axis along x; :func:`mavac_T_opencv` converts.) The
OpenGL depth buffer ``b`` in [0, 1] becomes metric depth along the optical axis,
``z = far near / (far - (far - near) b)``; pixels where no body was drawn (segmentation -1)
get ``inf``. Inputs are checked before pybullet sees them: the TinyRenderer can hang or crash on a
non-finite view, ``near >= far`` or a huge image.
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry.transforms import check_transform
from ..validate import check_int, check_range

#: largest image side we render (px): the TinyRenderer is single-threaded CPU code
MAX_IMAGE_SIDE = 2048
# camera frame (OpenCV: x right, y down, z forward) -> OpenGL eye frame (x right, y up, z back)
_GL_T_CV = np.diag([1.0, -1.0, -1.0, 1.0])
#: MAVAC camera frame (x optical, y left in the image, z up) -> OpenCV camera frame, as a
#: rotation ``mavac_R_opencv``: OpenCV x = -MAVAC y, OpenCV y = -MAVAC z, OpenCV z = MAVAC x.
MAVAC_R_OPENCV = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def mavac_T_opencv() -> np.ndarray:
    """(4, 4) ``mavac_T_opencv``: ``world_T_mavac @ mavac_T_opencv()`` is the OpenCV camera pose."""
    T = np.eye(4)
    T[:3, :3] = MAVAC_R_OPENCV
    return T


def intrinsics_from_fov(width: int, height: int, fov_y_deg: float) -> np.ndarray:
    """Pinhole intrinsics of a ``width`` x ``height`` image with vertical field of view
    ``fov_y_deg`` and square pixels (as pybullet's projection with aspect = width / height).

    Returns
    -------
    (3, 3) float
        ``K`` with ``fx = fy = (height / 2) / tan(fov_y / 2)`` and the principal point at the
        image centre in pixel-index coordinates, ``((width - 1) / 2, (height - 1) / 2)``.
    """
    w = check_int("width", width, 1, MAX_IMAGE_SIDE)
    h = check_int("height", height, 1, MAX_IMAGE_SIDE)
    check_range("fov_y_deg", fov_y_deg, 0.0, 180.0, lo_open=True, hi_open=True)
    f = (h / 2.0) / math.tan(math.radians(fov_y_deg) / 2.0)
    return np.array([[f, 0.0, (w - 1) / 2.0], [0.0, f, (h - 1) / 2.0], [0.0, 0.0, 1.0]])


def _view_projection(p, world_T_camera, width, height, fov_y_deg, near, far):
    eye_T_world = np.linalg.inv(world_T_camera @ _GL_T_CV)
    view = eye_T_world.T.reshape(-1).tolist()  # column-major for OpenGL
    projection = p.computeProjectionMatrixFOV(fov=float(fov_y_deg), aspect=width / height,
                                              nearVal=float(near), farVal=float(far))
    return view, projection


def render_rgbd(client: int, world_T_camera, *, width: int, height: int, fov_y_deg: float, near: float,
                far: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Colour, metric depth and segmentation of one view (``ER_TINY_RENDERER``).

    Parameters
    ----------
    client : int
        pybullet client (:attr:`mavac.sim.world.SimWorld.client`).
    world_T_camera : (4, 4) float
        Camera pose, OpenCV convention (z forward, x right, y down).
    width, height : int, pixels, in [1, 2048]
    fov_y_deg : float, degrees, in (0, 180)
        Vertical field of view.
    near, far : float, metres, 0 < near < far
        Clipping planes.

    Returns
    -------
    rgb : (height, width, 3) uint8
    depth_m : (height, width) float
        Metres along the optical axis; ``inf`` where nothing was hit before ``far``.
    seg : (height, width) int
        pybullet body id per pixel, -1 for background.
    """
    import pybullet as p

    T = check_transform("world_T_camera", world_T_camera)
    w = check_int("width", width, 1, MAX_IMAGE_SIDE)
    h = check_int("height", height, 1, MAX_IMAGE_SIDE)
    check_range("fov_y_deg", fov_y_deg, 0.0, 180.0, lo_open=True, hi_open=True)
    check_range("near", near, 0.0, math.inf, lo_open=True)
    check_range("far", far, float(near), math.inf, lo_open=True)
    client = check_int("client", client, 0)
    if not p.isConnected(physicsClientId=client):
        raise ValueError(f"client {client} is not a connected pybullet client")
    view, projection = _view_projection(p, T, w, h, fov_y_deg, near, far)
    _, _, rgba, buffer, seg = p.getCameraImage(w, h, viewMatrix=view, projectionMatrix=projection,
                                               renderer=p.ER_TINY_RENDERER, physicsClientId=client)
    rgb = np.asarray(rgba, dtype=np.uint8).reshape(h, w, 4)[:, :, :3].copy()
    b = np.asarray(buffer, dtype=float).reshape(h, w)
    depth = far * near / (far - (far - near) * b)
    seg = np.asarray(seg, dtype=np.int64).reshape(h, w)
    depth[(b >= 1.0) | (seg < 0)] = np.inf  # the cleared buffer reads ~1 - 1e-7, not 1
    return rgb, depth, seg

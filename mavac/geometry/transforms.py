"""Rigid transforms, in one place (pytransform3d's conventions).

``a_T_b`` is a (4, 4) float64 homogeneous matrix, the pose of frame *b* in frame *a*: a point
``p_b`` in *b* is ``p_a = R p_b + t`` in *a*, and ``a_T_c = a_T_b @ b_T_c``
(:func:`compose`). Stacks ``(m, 4, 4)`` are accepted wherever one transform is. Points and
vectors are row arrays ``(n, 3)``.

A mobile base pose is SE(2) ``(x, y, theta)`` (m, m, rad) -> ``world_T_base``
(:func:`se2_matrices`, :func:`se2_to_matrix`): a rotation about the world z axis
(:func:`rz`) and a translation in the floor plane.

Every function here that takes a pose checks it with :func:`check_transforms` (finite,
orthonormal rotation of determinant +1, last row ``0 0 0 1``): a scale or shear typed by
mistake is refused, never silently applied. Functions elsewhere that take a pose call it too.
"""

from __future__ import annotations

import numpy as np

from ..tolerances import RIGID_ATOL
from ..validate import check_array, check_points, check_range


def check_transforms(name: str, transforms) -> np.ndarray:
    """Validate homogeneous rigid transforms.

    Parameters
    ----------
    name : str
        Parameter name used in the error message.
    transforms : (4, 4) or (m, 4, 4) float

    Returns
    -------
    (m, 4, 4) float
        The transforms (a single one is promoted).

    Raises
    ------
    ValueError
        Unless finite, with a rotation orthonormal to :data:`mavac.tolerances.RIGID_ATOL`,
        of determinant +1, and a last row ``0 0 0 1``.
    """
    T = check_array(name, transforms, float)
    shape = T.shape
    if T.ndim == 2:
        T = T[None]
    if T.ndim != 3 or T.shape[1:] != (4, 4):
        raise ValueError(f"{name} must have shape (4, 4) or (m, 4, 4), got {shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError(f"{name} contains NaN or infinite values")
    R = T[:, :3, :3]
    deviation = np.abs(np.einsum("mji,mjk->mik", R, R) - np.eye(3))
    last_row = np.abs(T[:, 3] - [0.0, 0.0, 0.0, 1.0])
    if np.max(deviation, initial=0.0) > RIGID_ATOL or np.max(last_row, initial=0.0) > RIGID_ATOL:
        worst = int(np.argmax(np.maximum(deviation.max(axis=(1, 2)), last_row.max(axis=1))))
        lengths = ", ".join(f"{v:.4g}" for v in np.linalg.norm(R[worst], axis=0))
        raise ValueError(f"{name} must be rigid transforms (orthonormal rotation, last row 0 0 0 1); "
                         f"transform {worst} has rotation columns of length {lengths} and last row "
                         f"{T[worst, 3].tolist()} (a scale or shear is not a pose)")
    if np.any(np.linalg.det(R) < 0):
        raise ValueError(f"{name} rotation has determinant -1 (a reflection), expected +1")
    return T


def check_transform(name: str, transform) -> np.ndarray:
    """:func:`check_transforms` for exactly one transform; returns it as (4, 4) float."""
    T = check_array(name, transform, float)
    if T.shape != (4, 4):
        raise ValueError(f"{name} must have shape (4, 4), got {T.shape}")
    return check_transforms(name, T)[0]


def check_rotations(name: str, rotations) -> np.ndarray:
    """Rotation matrices (orthonormal, determinant +1), ``(3, 3)`` or ``(m, 3, 3)``, checked
    as the rotation parts of poses by :func:`check_transforms`; returns them as float, shape
    kept."""
    R = check_array(name, rotations, float)
    if R.shape[-2:] != (3, 3) or R.ndim not in (2, 3):
        raise ValueError(f"{name} must have shape (3, 3) or (m, 3, 3), got {R.shape}")
    T = np.tile(np.eye(4), (len(R.reshape(-1, 3, 3)), 1, 1))
    T[:, :3, :3] = R.reshape(-1, 3, 3)
    check_transforms(name, T)
    return R


def check_rotation(name: str, rotation) -> np.ndarray:
    """:func:`check_rotations` for exactly one (3, 3) rotation."""
    R = check_rotations(name, rotation)
    if R.shape != (3, 3):
        raise ValueError(f"{name} must have shape (3, 3), got {R.shape}")
    return R


def rz(theta) -> np.ndarray:
    """Rotations about z by ``theta`` (rad): ``(3, 3)`` for a scalar, ``(..., 3, 3)`` else."""
    theta = check_array("theta", theta, float)
    if not np.all(np.isfinite(theta)):
        raise ValueError("theta contains NaN or infinite values")
    c, s = np.cos(theta), np.sin(theta)
    R = np.zeros(theta.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1] = c, -s, s, c
    R[..., 2, 2] = 1.0
    return R


def se2_matrices(poses) -> np.ndarray:
    """``world_T_base`` (m, 4, 4) from planar poses ``(x, y, theta)`` (m, 3), m and rad."""
    p = check_points("poses", poses)
    T = np.tile(np.eye(4), (len(p), 1, 1))
    T[:, :3, :3] = rz(p[:, 2])
    T[:, :2, 3] = p[:, :2]
    return T


def se2_to_matrix(x: float, y: float, theta: float) -> np.ndarray:
    """Planar base pose ``(x, y, theta)`` (m, m, rad) -> ``world_T_base`` (4, 4)."""
    for name, v in (("x", x), ("y", y), ("theta", theta)):
        check_range(name, v)
    return se2_matrices(np.array([[x, y, theta]], dtype=float))[0]


def matrix_to_se2(world_T_base) -> np.ndarray:
    """``(x, y, theta)`` (3,), m and rad, of a base pose that turns about z only: the inverse
    of :func:`se2_to_matrix` (theta in (-pi, pi])."""
    T = check_transform("world_T_base", world_T_base)
    return np.array([T[0, 3], T[1, 3], np.arctan2(T[1, 0], T[0, 0])])


def _rigid(name: str, transforms) -> np.ndarray:
    """:func:`check_transforms`, keeping the shape given: (4, 4) stays (4, 4)."""
    T = check_array(name, transforms, float)
    return check_transforms(name, T).reshape(T.shape)


def compose(*transforms) -> np.ndarray:
    """``a_T_b @ b_T_c @ ...`` (stacks broadcast): ``compose(world_T_base, base_T_camera)``."""
    if not transforms:
        raise ValueError("compose needs at least one transform")
    out = _rigid("transforms[0]", transforms[0])
    for i, T in enumerate(transforms[1:], start=1):
        out = out @ _rigid(f"transforms[{i}]", T)
    return out


def transform_points(a_T_b, points_b) -> np.ndarray:
    """Points of frame *b* expressed in frame *a*, ``R p + t``: (4, 4) and (n, 3) -> (n, 3)."""
    T = check_transform("a_T_b", a_T_b)
    return np.asarray(points_b, dtype=float) @ T[:3, :3].T + T[:3, 3]


def transform_each_point(a_T_bs, points_b) -> np.ndarray:
    """Point k of frame *b_k* expressed in frame *a*, ``R_k p_k + t_k``: (n, 4, 4) and (n, 3) ->
    (n, 3), no input checks (one point per pose, e.g. a contact per simulation step)."""
    T = np.asarray(a_T_bs, dtype=float).reshape(-1, 4, 4)
    return (np.asarray(points_b, dtype=float).reshape(-1, 1, 3) @ T[:, :3, :3].transpose(0, 2, 1))[:, 0] + T[:, :3, 3]


def rotate_vectors(a_T_b, vectors_b) -> np.ndarray:
    """Directions of frame *b* expressed in frame *a*, ``R v``: (n, 3) -> (n, 3)."""
    return np.asarray(vectors_b, dtype=float) @ check_transform("a_T_b", a_T_b)[:3, :3].T


def points_in_frame(a_T_b, points_a) -> np.ndarray:
    """Points of frame *a* expressed in frame *b*, ``R^T (p - t)``.

    ``a_T_b`` (4, 4) gives (n, 3); a stack (m, 4, 4) gives (m, n, 3), one set per frame.
    """
    T = _rigid("a_T_b", a_T_b)
    P = np.asarray(points_a, dtype=float)
    if T.ndim == 3:
        return (P[None, :, :] - T[:, None, :3, 3]) @ T[:, :3, :3]
    return (P - T[:3, 3]) @ T[:3, :3]


def vectors_in_frame(a_T_b, vectors_a) -> np.ndarray:
    """Directions of frame *a* expressed in frame *b*, ``R^T v``: (n, 3) -> (n, 3)."""
    return np.asarray(vectors_a, dtype=float) @ check_transform("a_T_b", a_T_b)[:3, :3]


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """``world_T_camera`` (4, 4) of a camera at ``eye`` looking at ``target``, OpenCV axes
    (z forward, x right, y down), with ``up`` (world) pointing up in the image."""
    eye, target = check_points("eye", eye)[0], check_points("target", target)[0]
    z = target - eye
    if np.linalg.norm(z) < 1e-12:
        raise ValueError("eye and target must differ")
    z = z / np.linalg.norm(z)
    x = np.cross(z, np.asarray(up, float))
    if np.linalg.norm(x) < 1e-9:
        x = np.cross(z, [1.0, 0.0, 0.0])
    x = x / np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = eye
    return T

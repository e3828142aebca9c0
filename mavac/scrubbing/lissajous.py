"""Lissajous force oscillation overlaid on a nominal tool path (Kabir et al., Sec. VIII, Fig. 3b).

The scrubbing action is a force oscillation in the XY plane of the tool frame,

    F_x(t) = A_x sin(2 pi f_x t + phase),   F_y(t) = A_y sin(2 pi f_y t),   f_y = 0.4 f_x,

while the cleaning force ``f_n`` pushes along tool z (into the surface). Under Cartesian
impedance control with stiffness ``kappa`` the tool deviates from the nominal path by
``F / kappa`` (quasi-static; the dynamic response lives in :mod:`mavac.scrubbing.wear`).

Tool frame (README, Conventions): z is the tool axis pointing into the surface (``z = -n`` for the
outward normal ``n``); we put x along the direction of travel, y = z x x.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ..geometry.transforms import check_rotations, check_transforms
from ..params import LissajousParams
from ..validate import check_array, check_instance, check_points, check_positive, check_size

#: Time samples an overlay may have: ~2,000 times a paper-scale pass (~20 s at 240 Hz); a tiny
#: ``dt`` would otherwise exhaust memory.
MAX_SAMPLES = 10_000_000


class Overlay(NamedTuple):
    """Nominal path with the Lissajous overlay, sampled in time.

    Attributes
    ----------
    t : (m,) float, seconds
    positions : (m, 3) float, metres -- nominal path plus the impedance deviation F / kappa.
    forces : (m, 3) float, newtons -- commanded force in the world frame: oscillation in the
        tool XY plane plus ``f_n`` along tool z.
    nominal : (m, 3) float, metres -- the nominal path at the same times (no oscillation).
    rotations : (m, 3, 3) float -- tool frames at the same times (world).
    """

    t: np.ndarray
    positions: np.ndarray
    forces: np.ndarray
    nominal: np.ndarray | None = None
    rotations: np.ndarray | None = None


def lissajous_force(t, params: LissajousParams = LissajousParams()) -> np.ndarray:
    """Oscillating force in the tool XY plane.

    Parameters
    ----------
    t : (n,) float, seconds
    params : LissajousParams

    Returns
    -------
    (n, 2) float, newtons -- ``(F_x, F_y)`` in the tool frame.
    """
    check_instance("params", params, LissajousParams)
    t = np.atleast_1d(check_array("t", t, float))
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise ValueError(f"t must be a finite 1-D array of times, got shape {t.shape}")
    fx = params.A_x * np.sin(2 * np.pi * params.f_x * t + params.phase)
    fy = params.A_y * np.sin(2 * np.pi * params.f_y * t)
    return np.stack([fx, fy], axis=1)


def lissajous_offset(t, params: LissajousParams = LissajousParams()) -> np.ndarray:
    """Impedance deviation ``F / kappa`` in the tool XY plane, ``(n, 2)`` metres."""
    force = lissajous_force(t, params)
    return force / np.array([params.kappa_x, params.kappa_y])


def excursion(params: LissajousParams) -> float:
    """Largest quasi-static deviation of the tool from its nominal path under the oscillation,
    m: ``hypot(A_x / kappa_x, A_y / kappa_y)``, the corner of the Lissajous figure."""
    check_instance("params", params, LissajousParams)
    return float(np.hypot(params.A_x / params.kappa_x, params.A_y / params.kappa_y))


def vector_excursions(X) -> np.ndarray:
    """:func:`excursion` of operation vectors ``X`` (n, 5) ``(v, f_n, kappa, f_x, A_x)`` with
    ``A_y = A_x`` and ``kappa_y = kappa_x`` (Kabir Sec. VIII), (n,) m."""
    X = check_points("X", X, 5)
    return np.sqrt(2.0) * X[:, 4] / X[:, 2]


def check_excursion(params: LissajousParams, cap: float) -> None:
    """Refuse an oscillation whose :func:`excursion` exceeds the path-deviation ``cap`` (m,
    one pad width in the cell): ValueError naming ``lissajous``. Such parameters are refused
    where they are chosen (the learner's feasibility rule), never clipped in the controller."""
    x = excursion(params)
    if x > check_positive("cap", cap):
        raise ValueError(f"lissajous: A_x = {params.A_x:g} N, A_y = {params.A_y:g} N at kappa = {params.kappa_x:g}, "
                         f"{params.kappa_y:g} N/m swing the pad {1e3 * x:.1f} mm off its path, above the "
                         f"path-deviation cap of one pad width ({1e3 * cap:.1f} mm)")


def _frames_from_normals(path: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Tool rotations (n,3,3): z = -normal, x = direction of travel projected off z."""
    z = -normals / np.linalg.norm(normals, axis=1, keepdims=True)
    tangent = np.gradient(path, axis=0)
    x = tangent - np.sum(tangent * z, axis=1, keepdims=True) * z
    norm = np.linalg.norm(x, axis=1)
    # Travel parallel to the tool axis (or a standing point): any x orthogonal to z.
    bad = norm < 1e-12
    if np.any(bad):
        helper = np.where(np.abs(z[bad, 0:1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        x[bad] = helper - np.sum(helper * z[bad], axis=1, keepdims=True) * z[bad]
        norm[bad] = np.linalg.norm(x[bad], axis=1)
    x /= norm[:, None]
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=2)


def overlay_path(path, frames, params: LissajousParams = LissajousParams(), *, speed=None,
                 dt=None) -> Overlay:
    """Sample a nominal tool path in time and overlay the Lissajous oscillation.

    Parameters
    ----------
    path : (n, 3) float, metres
        Nominal tool-tip waypoints (e.g. a plane-slicing spline), n >= 2.
    frames : (n, 3) float outward surface normals, or (n, 3, 3) / (n, 4, 4) tool orientations
        With normals the tool frame is built as z = -normal, x = direction of travel. Given
        frames are interpolated with SLERP.
    params : LissajousParams
    speed : float, m/s, optional
        Nominal speed along the path; default ``params.tool_speed`` (``v * tool_speed_at_vmax``).
    dt : float, seconds, optional
        Sampling period; default ``1 / (40 f_x)`` (40 samples per x period).

    Returns
    -------
    Overlay
        ``(t, positions, forces)``, see :class:`Overlay`.
    """
    check_instance("params", params, LissajousParams)
    path = check_points("path", path, 3)
    if len(path) < 2:
        raise ValueError(f"path must have at least 2 waypoints, got {len(path)}")
    speed = params.tool_speed if speed is None else speed
    check_positive("speed", speed)
    dt = 1.0 / (40.0 * params.f_x) if dt is None else dt
    check_positive("dt", dt)

    frames = check_array("frames", frames, float)
    if frames.shape == (len(path), 3):
        rotations = _frames_from_normals(path, check_points("frames", frames, 3))
    elif frames.shape == (len(path), 4, 4):
        rotations = check_transforms("frames", frames)[:, :3, :3]
    elif frames.shape == (len(path), 3, 3):
        rotations = check_rotations("frames", frames)
    else:
        raise ValueError(f"frames must be (n, 3) normals or (n, 3, 3)/(n, 4, 4) tool frames for "
                         f"n = {len(path)} waypoints, got shape {frames.shape}")
    if not np.all(np.isfinite(rotations)):
        raise ValueError("frames contains NaN or infinite values")

    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        raise ValueError("path has zero length")
    keep = np.concatenate([[True], seg > 0])  # drop repeated waypoints for interpolation
    s, path, rotations = s[keep], path[keep], rotations[keep]

    duration = s[-1] / speed
    check_size("dt", dt, duration / dt, MAX_SAMPLES, "time samples")
    t = np.arange(0.0, duration + 0.5 * dt, dt)
    t[-1] = min(t[-1], duration)
    s_t = np.clip(t * speed, 0.0, s[-1])
    nominal = np.stack([np.interp(s_t, s, path[:, k]) for k in range(3)], axis=1)
    slerp = Slerp(s, Rotation.from_matrix(rotations))
    R = slerp(s_t).as_matrix()

    force_xy = lissajous_force(t, params)
    offset_xy = force_xy / np.array([params.kappa_x, params.kappa_y])
    force_tool = np.column_stack([force_xy, np.full(len(t), params.f_n)])
    offset_tool = np.column_stack([offset_xy, np.zeros(len(t))])
    positions = nominal + np.einsum("nij,nj->ni", R, offset_tool)
    forces = np.einsum("nij,nj->ni", R, force_tool)
    return Overlay(t, positions, forces, nominal, R)


def end_overshoot(path, positions) -> tuple[float, float]:
    """How far an overlaid trajectory runs past the start and the end of its nominal path, metres.

    Measured along the path's direction of travel at each end: a point before the start (behind
    the first waypoint) or past the end (beyond the last) counts. The force oscillation is
    overlaid on the nominal trajectory (Kabir Sec. VIII), so on a straight end the tool swings past
    it by at most ``A_x / kappa_x`` (its x axis is the travel direction); where the path turns, part
    of the across-path swing ``A_y / kappa_y`` points past the end too, and the bound is
    ``hypot(A_x / kappa_x, A_y / kappa_y)``.

    Parameters
    ----------
    path : (n, 3) float
        Nominal waypoints, n >= 2.
    positions : (m, 3) float
        Overlaid trajectory (e.g. :attr:`Overlay.positions`).

    Returns
    -------
    (before_start, past_end) : float, metres (0 when the overlay stays within the ends)
    """
    path = check_points("path", path, 3)
    pos = check_points("positions", positions, 3)
    if len(path) < 2:
        raise ValueError(f"path must have at least 2 waypoints, got {len(path)}")
    start_dir = path[1] - path[0]
    end_dir = path[-1] - path[-2]
    start_dir /= np.linalg.norm(start_dir)
    end_dir /= np.linalg.norm(end_dir)
    before = float(np.max((path[0] - pos) @ start_dir, initial=0.0))
    past = float(np.max((pos - path[-1]) @ end_dir, initial=0.0))
    return max(before, 0.0), max(past, 0.0)

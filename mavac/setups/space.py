"""Where a part's setup space lies: the narrowing procedure of Kabir et al. (2017), Sec. IV-A.

"Our sampling starts with a coarse resolution over a wide range of configuration space
parameters. We find a narrower feasible sampling range by eliminating setups that do not cover
any patch." Per part:

1. :func:`wide_setup_space`: a wide region of part placements on the robot's table side
   (base x >= 0), so wide that no setup outside it can reach a patch: the part's centre within
   ``R = r_reach + r_part`` of joint 1 in x and y, with ``r_reach`` the exact reach sphere of the
   arm plus its tool (:func:`mavac.setups.reach.reach_bound`) and ``r_part`` the largest
   horizontal distance of a stain vertex from the part origin.
2. Sweep it at a coarse resolution with the reach test.
3. :func:`reaching_box`: drop the setups that reach no patch and take the bounding box (in x
   and y) of the rest; alpha keeps the whole circle. The box becomes the part's
   :class:`mavac.params.SetupSpaceParams` (origin at its corner, so x and y start at 0 as in the
   paper's [0, 1 m] x [0, 1 m] x [0, 2 pi]); the fine grid is then laid over it.

Nothing here looks at how many setups a plan needs: the box is whatever the reach test leaves.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..params import SetupSpaceParams
from ..validate import check_cover, check_instance, check_points, check_positive
from .reach import reach_bound
from .sampling import grid_axes

#: Coarse resolution of the wide sweep, (m, m, rad). Ours: 0.1 m x 0.1 m x 30 deg, twice the
#: paper's fine step in x and y and three times in alpha ("a coarse resolution").
WIDE_RESOLUTION = (0.1, 0.1, math.radians(30.0))


def part_radius(patch_vertices) -> float:
    """Largest horizontal distance (m) of a stain vertex from the part origin (part frame)."""
    v = check_points("patch_vertices", np.asarray(patch_vertices, dtype=float).reshape(-1, 3), 3)
    return float(np.hypot(v[:, 0], v[:, 1]).max()) if len(v) else 0.0


def wide_setup_space(robot, patch_vertices, *, base: SetupSpaceParams | None = None,
                     resolution=WIDE_RESOLUTION) -> SetupSpaceParams:
    """Step 1: the wide region, on the table side of the robot, outside which nothing is reachable.

    Parameters
    ----------
    robot : RobotModel
        The arm (with its tool) of the reach test.
    patch_vertices : (n, 3, 3) float, m
        The stain, part frame.
    base : SetupSpaceParams, optional
        Table height and alpha range to keep (default :class:`SetupSpaceParams`).
    resolution : (3,) float
        Coarse ``(res_x [m], res_y [m], res_alpha [rad])``.

    Returns
    -------
    SetupSpaceParams
        Part centre over ``[0, R] x [-R, R]`` in the base frame, ``R`` rounded up to the
        resolution.
    """
    base = SetupSpaceParams() if base is None else check_instance("base", base, SetupSpaceParams)
    res = [check_positive(f"resolution[{k}]", float(r)) for k, r in enumerate(resolution)]
    bound = reach_bound(robot)
    reach = bound.radius + bound.tool_offset + float(np.hypot(*bound.centre[:2]))
    r = part_radius(patch_vertices) + reach
    rx, ry = math.ceil(r / res[0]) * res[0], math.ceil(r / res[1]) * res[1]
    return dataclasses.replace(base, x_min=0.0, x_max=rx, y_min=0.0, y_max=2.0 * ry, origin_x=0.0,
                               origin_y=-ry, res_x=res[0], res_y=res[1], res_alpha=res[2])


def reaching_box(setups, cover, wide: SetupSpaceParams, *, fine: SetupSpaceParams | None = None) -> SetupSpaceParams:
    """Step 3: the bounding box of the setups that reach some patch.

    Parameters
    ----------
    setups : (k, 3) float
        Setups of ``wide`` (its coordinates).
    cover : (k, n) bool
        Their reach test.
    wide : SetupSpaceParams
        The space ``setups`` are in.
    fine : SetupSpaceParams, optional
        Resolution and alpha range of the result (default ``wide``'s alpha range and the
        paper's 50 mm x 50 mm x 10 deg of :class:`SetupSpaceParams`).

    Returns
    -------
    SetupSpaceParams
        ``origin = (x_lo, y_lo)`` in the base frame and ``x in [0, x_hi - x_lo]``,
        ``y in [0, y_hi - y_lo]``, same table height.

    Raises
    ------
    ValueError
        When no setup reaches any patch (there is no box).
    """
    setups = check_points("setups", setups, 3)
    cover = check_cover(cover)
    if cover.shape[0] != len(setups):
        raise ValueError(f"cover must have one row per setup ({len(setups)}), got {cover.shape[0]}")
    hit = cover.any(axis=1)
    if not hit.any():
        raise ValueError("cover: no setup of the wide sweep reaches any patch, so there is no setup space")
    fine = SetupSpaceParams() if fine is None else check_instance("fine", fine, SetupSpaceParams)
    x = setups[hit, 0] + wide.origin_x
    y = setups[hit, 1] + wide.origin_y
    return dataclasses.replace(
        fine, x_min=0.0, x_max=_snap(x.max() - x.min()), y_min=0.0, y_max=_snap(y.max() - y.min()),
        origin_x=_snap(x.min()), origin_y=_snap(y.min()), alpha_min=wide.alpha_min, alpha_max=wide.alpha_max,
        table_z=wide.table_z)


def _snap(value: float) -> float:
    # grid coordinates are sums of steps: drop the floating-point dust (1e-12 m)
    return float(np.round(value, 9)) + 0.0


def box_summary(space: SetupSpaceParams) -> dict:
    """The box of a space in the robot base frame (m) and its grid size at its resolution."""
    xs, ys, alphas = grid_axes(space)
    return dict(x_lo=space.origin_x, x_hi=space.origin_x + space.x_max, y_lo=space.origin_y,
                y_hi=space.origin_y + space.y_max, width_x=space.x_max - space.x_min,
                width_y=space.y_max - space.y_min, grid_setups=len(xs) * len(ys) * len(alphas))

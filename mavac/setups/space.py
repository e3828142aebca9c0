"""Where the setup space lies: the narrowing procedure of Kabir et al. (2017), Sec. IV-A, run
once for the four Table II objects, and the placements no robot can take.

"Our sampling starts with a coarse resolution over a wide range of configuration space
parameters. We find a narrower feasible sampling range by eliminating setups that do not cover
any patch." The paper ends with one range for all its objects, [0, 1 m] x [0, 1 m] x [0, 2 pi]
("for all the cases in Table II"), and never says where it sits relative to the robot. So:

1. :func:`wide_setup_space`: a wide region of part placements on the robot's table side
   (base x >= 0), so wide that no setup outside it can reach a patch: the part's centre within
   ``R = r_reach + r_part`` of joint 1 in x and y, with ``r_reach`` the exact reach sphere of the
   arm plus its tool (:func:`mavac.setups.reach.reach_bound`) and ``r_part`` the largest
   horizontal distance of a stain vertex from the part origin (the largest over the objects).
2. Sweep it at a coarse resolution with the reach test, for every object; placements whose
   footprint would stand on the robot's pedestal are removed first (:class:`PedestalClear`).
3. :func:`narrowed_square`: eliminate the setups that reach no patch and keep the 1 m square
   holding the largest share of the rest, summed over the objects; alpha keeps the whole
   circle. The fine grid is then laid over that square.

Nothing here looks at how many setups a plan needs: the square is whatever the reach test leaves.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..params import SetupSpaceParams
from ..validate import check_instance, check_points, check_positive
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
                               origin_y=-ry).at_resolution(res)


def square_origins(wide: SetupSpaceParams, size: float, step: float) -> np.ndarray:
    """Lower-left corners (base frame, m) of every ``size`` x ``size`` square inside ``wide``'s
    x-y range on a grid of ``step``, ``(c, 2)``."""
    check_positive("size", size)
    check_positive("step", step)
    x0 = wide.origin_x + wide.x_min
    y0 = wide.origin_y + wide.y_min
    nx = int(math.floor((wide.x_max - wide.x_min - size) / step + 1e-9)) + 1
    ny = int(math.floor((wide.y_max - wide.y_min - size) / step + 1e-9)) + 1
    if nx < 1 or ny < 1:
        raise ValueError(f"size: a {size} m square does not fit in the wide region "
                         f"({wide.x_max - wide.x_min} m x {wide.y_max - wide.y_min} m)")
    gx, gy = np.meshgrid(x0 + step * np.arange(nx), y0 + step * np.arange(ny), indexing="ij")
    return np.round(np.column_stack([gx.ravel(), gy.ravel()]), 9) + 0.0


def narrowed_square(wide: SetupSpaceParams, reaching: dict, *, size: float = 1.0, step: float | None = None,
                    fine: SetupSpaceParams | None = None):
    """The paper's narrowing (Sec. IV-A) run over several objects at once: one square for all.

    The wide sweep of each object leaves the setups that reach some patch; the square kept is
    the ``size`` x ``size`` one (Kabir IX-A: 1 m x 1 m) that keeps the largest share of them,
    summed over the objects (each object weighs the same, whatever its count). Ties go to the
    larger total count, then to the square nearest the robot (smallest ``x``), then to the one
    most nearly centred on ``y = 0``.

    Parameters
    ----------
    wide : SetupSpaceParams
        The wide region every object was swept over (same grid for all).
    reaching : dict name -> (k, 2) float
        Base-frame ``(x, y)`` (m) of each object's wide setups that reach a patch (one row per
        setup, so a position reaching at several alphas counts several times).
    size : float, m
        Side of the square.
    step : float, m, optional
        Grid of candidate corners (default the wide sweep's x resolution).
    fine : SetupSpaceParams, optional
        Resolution, alpha range, table height and clearance of the result (default
        :class:`SetupSpaceParams`).

    Returns
    -------
    space : SetupSpaceParams
        ``x, y in [0, size]`` with ``origin`` the square's corner.
    scores : (c, 4) float
        Every candidate: ``origin_x, origin_y, share`` (sum over objects) and ``count``.
    """
    if not reaching:
        raise ValueError("reaching must name at least one object")
    step = wide.res_x if step is None else step
    corners = square_origins(wide, size, step)
    share, count = np.zeros(len(corners)), np.zeros(len(corners))
    tol = 1e-9
    for name, xy in reaching.items():
        xy = check_points(f"reaching[{name!r}]", xy, 2)
        if len(xy) == 0:
            raise ValueError(f"reaching[{name!r}]: no setup of the wide sweep reaches any patch")
        inside = ((xy[None, :, 0] >= corners[:, None, 0] - tol) & (xy[None, :, 0] <= corners[:, None, 0] + size + tol)
                  & (xy[None, :, 1] >= corners[:, None, 1] - tol) & (xy[None, :, 1] <= corners[:, None, 1] + size + tol))
        kept = inside.sum(axis=1)
        share += kept / len(xy)
        count += kept
    centred = np.abs(corners[:, 1] + size / 2)
    best = np.lexsort((centred, corners[:, 0], -count, -np.round(share, 12)))[0]
    fine = SetupSpaceParams() if fine is None else check_instance("fine", fine, SetupSpaceParams)
    space = dataclasses.replace(fine, x_min=0.0, x_max=float(size), y_min=0.0, y_max=float(size),
                                origin_x=float(corners[best, 0]), origin_y=float(corners[best, 1]),
                                table_z=wide.table_z)
    return space, np.column_stack([corners, share, count])


# ---------------------------------------------------------------- no part inside the robot


def pedestal_radius(robot) -> float | None:
    """Radius (m) of the robot's ``pedestal`` collision cylinder, None when it has none."""
    for g in robot.collision_model.geometryObjects:
        if g.name == "pedestal":
            return float(g.geometry.radius)
    return None


def footprint(part_vertices) -> np.ndarray:
    """The part's footprint on the table: convex hull of its vertices seen from above,
    ``(m, 2)`` counter-clockwise (part frame, m). Convex, so a concave outline counts as
    filled (a hollow part standing around the robot is no more possible than a solid one)."""
    from scipy.spatial import ConvexHull

    xy = check_points("part_vertices", np.asarray(part_vertices, dtype=float).reshape(-1, 3), 3)[:, :2]
    return xy[ConvexHull(xy).vertices]


def axis_distance(hull, setups, space: SetupSpaceParams) -> np.ndarray:
    """Distance (m) from the robot's joint-1 axis to the part's footprint at each setup, 0 when
    the axis passes through it.

    Parameters
    ----------
    hull : (m, 2) float
        :func:`footprint` (part frame).
    setups : (k, 3) float
    space : SetupSpaceParams

    Returns
    -------
    (k,) float
    """
    hull = check_points("hull", hull, 2)
    s = check_points("setups", setups, 3)
    # the axis (base x = y = 0) in the part frame: Rz(-alpha) (-(origin + xy))
    px, py = -(space.origin_x + s[:, 0]), -(space.origin_y + s[:, 1])
    c, sn = np.cos(s[:, 2]), np.sin(s[:, 2])
    q = np.column_stack([c * px + sn * py, -sn * px + c * py])
    a, b = hull, np.roll(hull, -1, axis=0)
    edge = b - a
    t = np.clip(((q[:, None, :] - a[None]) * edge[None]).sum(-1) / (edge * edge).sum(-1)[None], 0.0, 1.0)
    nearest = a[None] + t[..., None] * edge[None]
    dist = np.linalg.norm(q[:, None, :] - nearest, axis=2).min(axis=1)
    cross = edge[None, :, 0] * (q[:, None, 1] - a[None, :, 1]) - edge[None, :, 1] * (q[:, None, 0] - a[None, :, 0])
    inside = np.all(cross >= 0.0, axis=1)
    return np.where(inside, 0.0, dist)


class PedestalClear:
    """``feasible(setups (k, 3)) -> (k,) bool``: the part's footprint stays more than
    ``radius + margin`` from the robot's joint-1 axis (picklable).

    Parameters
    ----------
    part_vertices : (v, 3) float, m
        The part (part frame).
    space : SetupSpaceParams
    radius : float, m
        The robot's pedestal (:func:`pedestal_radius`).
    margin : float, m
        Clearance beyond it (``space.pedestal_margin``).
    """

    def __init__(self, part_vertices, space: SetupSpaceParams, radius: float, margin: float):
        self.hull = footprint(part_vertices)
        self.space = check_instance("space", space, SetupSpaceParams)
        self.clearance = check_positive("radius", radius) + float(margin)
        self.refused = 0

    def __call__(self, setups) -> np.ndarray:
        ok = axis_distance(self.hull, setups, self.space) > self.clearance
        self.refused += int((~ok).sum())
        return ok

    def summary(self) -> str:
        """What it refused, for a plan's warnings."""
        return (f"the part would stand within {self.clearance:.2f} m of the robot's first axis "
                "(its pedestal plus the clearance)")


def pedestal_clear(robot, part_vertices, space: SetupSpaceParams):
    """A :class:`PedestalClear` test for ``robot``, or None when the robot has no pedestal or
    ``space.pedestal_margin`` is None (no test)."""
    radius = pedestal_radius(robot)
    if radius is None or space.pedestal_margin is None:
        return None
    return PedestalClear(part_vertices, space, radius, space.pedestal_margin)


def box_summary(space: SetupSpaceParams) -> dict:
    """The box of a space in the robot base frame (m) and its grid size at its resolution."""
    xs, ys, alphas = grid_axes(space)
    return dict(x_lo=space.origin_x, x_hi=space.origin_x + space.x_max, y_lo=space.origin_y,
                y_hi=space.origin_y + space.y_max, width_x=space.x_max - space.x_min,
                width_y=space.y_max - space.y_min, grid_setups=len(xs) * len(ys) * len(alphas))

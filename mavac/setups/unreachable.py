"""Why stain patches are left out of a setup plan: under the support, too high, too far, facing
away, occluded.

:func:`mavac.setups.setup_plan.plan_setups` lists the patches no candidate setup reaches. A user who
sees "47 % of the stain unreachable" needs the likely cause, so each such patch is tested again
over a uniform grid of the whole setup space, step by step:

0. ``below_support``: the tool would have to come from below the table the part rests on
   (:func:`mavac.setups.reach.below_support`; a stain facing down into the table);
1. ``too_high`` / ``too_far``: no setup puts its three vertices inside the sphere that bounds
   the arm's reach (:func:`mavac.setups.reach.reach_bound`); too high when the vertical
   offset from the shoulder alone is beyond the reach, too far otherwise;
2. ``facing_away``: inside the reach sphere for some setup, but no setup has an IK solution with
   the tool along the patch normal (the normal points where the wrist cannot follow, or the
   patch sits in the hollow around the arm's first axis);
3. ``occluded``: IK exists but the arm collides with the part at every such setup (only when the
   reach test checks collisions);
4. ``missed_by_sampling``: the grid reaches it; the candidate sampling stopped before finding it
   (more hierarchy levels or uniform sampling would).
"""

from __future__ import annotations

import math

import numpy as np

from ..params import ReachParams, SetupSpaceParams
from ..validate import check_int
from .reach import ReachBound, below_support, patch_reach, reach_bound, reach_targets

CAUSES = ("below_support", "too_high", "too_far", "facing_away", "occluded", "missed_by_sampling")
CAUSE_WORDS = {"below_support": "facing down into the table the part rests on (the tool would come from below it)",
               "too_high": "too high for the arm", "too_far": "too far from the arm",
               "facing_away": "facing away or too close to the base (no IK solution along their normal)",
               "occluded": "occluded by the part (arm collides)",
               "missed_by_sampling": "reachable on a finer grid (missed by the sampling)"}


def diagnosis_grid(space: SetupSpaceParams, counts=(5, 5, 12)) -> np.ndarray:
    """A coarse uniform grid over the whole setup space, ``(nx * ny * na, 3)``."""
    xs = np.linspace(space.x_min, space.x_max, counts[0])
    ys = np.linspace(space.y_min, space.y_max, counts[1])
    alphas = space.alpha_min + (space.alpha_max - space.alpha_min) * np.arange(counts[2]) / counts[2]
    return np.stack(np.meshgrid(xs, ys, alphas, indexing="ij"), axis=-1).reshape(-1, 3)


def unreachable_causes(robot, patch_vertices, patch_normals, space: SetupSpaceParams,
                       params: ReachParams | None = None, part_mesh=None, grid=None, checker=None) -> np.ndarray:
    """The likely cause for each patch, one of :data:`CAUSES`.

    Parameters
    ----------
    robot : RobotModel
        The arm of the reach test (its base frame is where ``space`` places the part).
    patch_vertices : (u, 3, 3) float, metres, part frame
    patch_normals : (u, 3) float
    space : SetupSpaceParams
    params : ReachParams, optional
    part_mesh : trimesh.Trimesh, optional
        Needed when ``params.check_collision``.
    grid : (g, 3) float, optional
        Setups tried; default :func:`diagnosis_grid`.
    checker : CollisionChecker, optional
        The reach test's :func:`mavac.setups.reach.part_checker` of ``part_mesh``, if the caller
        has one (else built here when needed).

    Returns
    -------
    (u,) str
    """
    params = ReachParams() if params is None else params
    v = np.asarray(patch_vertices, dtype=float).reshape(-1, 3, 3)
    u = len(v)
    out = np.full(u, "missed_by_sampling", dtype="<U18")
    if u == 0:
        return out
    grid = diagnosis_grid(space) if grid is None else np.asarray(grid, dtype=float)
    bound = reach_bound(robot)
    nrm = np.asarray(patch_normals, dtype=float).reshape(-1, 3)
    nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
    wrist = v + bound.tool_offset * nrm[:, None, :]  # last-joint origin, part frame (tool z = -n)
    # (grid, patches, 3) blocks of about batch_size floats each: 300 x 200k patches at once was 5 GB
    chunk = max(1, params.batch_size // (3 * len(grid)))
    inside_any = inside_reach_anywhere(wrist, grid, space, bound, chunk=chunk)
    dz = wrist[..., 2] + space.table_z - bound.centre[2]
    high = np.abs(dz).max(axis=1) > bound.radius
    out[~inside_any] = np.where(high[~inside_any], "too_high", "too_far")
    under = below_support(reach_targets(v, nrm), params.tool_length) if params.support_plane else np.zeros(u, bool)
    out[under] = "below_support"
    todo = np.flatnonzero(inside_any & ~under)
    if len(todo) == 0:
        return out
    free = ReachParams(tool_length=params.tool_length, check_collision=False, batch_size=params.batch_size,
                       support_plane=params.support_plane)
    targets = reach_targets(v[todo], nrm[todo])
    ik_any = patch_reach(robot, targets, grid, space, params=free).any(axis=0)
    out[todo[~ik_any]] = "facing_away"
    if params.check_collision and part_mesh is not None and ik_any.any():
        keep = todo[ik_any]
        reached = patch_reach(robot, reach_targets(v[keep], nrm[keep]), grid, space, params=params,
                              part_mesh=part_mesh, checker=checker).any(axis=0)
        out[keep[~reached]] = "occluded"
    return out


def inside_reach_anywhere(wrist, grid, space: SetupSpaceParams, bound: ReachBound, *,
                          chunk: int = 1024) -> np.ndarray:
    """Whether some setup of ``grid`` puts all three wrist points of a patch inside the reach
    sphere (:func:`mavac.setups.reach.reach_bound`), in blocks of ``chunk`` patches.

    Parameters
    ----------
    wrist : (u, 3, 3) float, metres, part frame
        Last-joint origin for each corner of each patch (tool z = -n).
    grid : (g, 3) float
        Setups ``(x [m], y [m], alpha [rad])``.
    space : SetupSpaceParams
    bound : ReachBound
    chunk : int
        Patches per block; the answer does not depend on it, the memory does
        (about ``10 * 8 * 3 * g * chunk`` bytes).

    Returns
    -------
    (u,) bool
    """
    chunk = check_int("chunk", chunk, lo=1)
    grid = np.asarray(grid, dtype=float).reshape(-1, 3)
    out = np.zeros(len(wrist), dtype=bool)
    for a in range(0, len(wrist), chunk):
        out[a:a + chunk] = _inside_any(wrist[a:a + chunk], grid, space, bound)
    return out


def _inside_any(wrist, grid, space, bound) -> np.ndarray:
    """:func:`inside_reach_anywhere` of one block of patches, (b,) bool."""
    c, s = np.cos(grid[:, 2]), np.sin(grid[:, 2])
    wx = c[:, None, None] * wrist[None, :, :, 0] - s[:, None, None] * wrist[None, :, :, 1] + space.origin_x + grid[:, 0, None, None]
    wy = s[:, None, None] * wrist[None, :, :, 0] + c[:, None, None] * wrist[None, :, :, 1] + space.origin_y + grid[:, 1, None, None]
    dz = wrist[..., 2] + space.table_z - bound.centre[2]
    d2 = (wx - bound.centre[0]) ** 2 + (wy - bound.centre[1]) ** 2 + dz[None] ** 2
    return (d2 <= bound.radius ** 2).all(axis=2).any(axis=0)


def unreachable_message(causes, areas, total_area: float, n_total: int) -> str:
    """One sentence: how much of the stain is left out, and why."""
    causes = np.asarray(causes)
    areas = np.asarray(areas, dtype=float)
    share = areas.sum() / total_area if total_area > 0 else math.nan
    parts = []
    for cause in CAUSES:
        k = int((causes == cause).sum())
        if k:
            parts.append(f"{k} {CAUSE_WORDS[cause]}")
    return (f"{len(causes)} of {n_total} stain patches ({100 * share:.0f} % of the stain area) are unreachable "
            f"from every candidate setup and left out of the plan: " + "; ".join(parts))

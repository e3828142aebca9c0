"""Why surface elements stay unobserved in an inspection plan: too high, too far, or occluded.

After :func:`mavac.inspection.inspection_plan.plan_from_context`, each element of S that no pose of T sees
gets the likely cause, from what the offline pipeline already knows:

* ``too_high``: from no collision-free candidate spot does the camera pose that inspects it (on
  its normal at the guard stand-off, looking back) fall in a reachable cell of the reachability
  map, and that camera point is above the highest reachable cell of the map;
* ``too_far``: the same, below that height (beyond the arm's horizontal reach from every spot);
* ``occluded``: the map reaches its camera pose from some spot, but the machine hides it from
  every camera the plan could place (not visible from the spots, the normal's stand-off blocked,
  no collision-free IK, or outside every chosen guard's view).

A low coverage (below :data:`LOW_COVERAGE`) is reported with these counts.
"""

from __future__ import annotations

import numpy as np

from .reachability import reachability_map
from .spots import se2_matrices

#: Ours: below this C the plan warns with the causes. MAVAC's recommended settings give
#: C = 0.82-0.93 on its test bench (Table 1); under 0.8 a user should know why.
LOW_COVERAGE = 0.8
CAUSES = ("too_high", "too_far", "occluded")
CAUSE_WORDS = {"too_high": "too high for the camera", "too_far": "too far from every spot",
               "occluded": "occluded (reachable, but the machine hides them from every camera pose)"}


def unobserved_causes(ctx, plan, rmap=None) -> np.ndarray:
    """The cause for each element of S: ``"observed"`` or one of :data:`CAUSES`, (n,) str.

    Parameters
    ----------
    ctx : OfflineContext
        From :func:`mavac.inspection.inspection_plan.prepare_offline`.
    plan : InspectionPlan
        Planned on ``ctx``.
    rmap : ReachabilityMap, optional
        Default: the map of ``ctx.robot`` and ``ctx.params.reach`` (from the disk cache).
    """
    rmap = reachability_map(ctx.robot, ctx.params.reach) if rmap is None else rmap
    n = len(ctx.points)
    out = np.full(n, "observed", dtype="<U8")
    todo = np.flatnonzero(~plan.observed) if len(plan.points) == n else np.arange(n)
    if len(todo) == 0:
        return out
    cam = ctx.points[todo] + ctx.params.guard_standoff * ctx.normals[todo]
    reached = np.zeros(len(todo), dtype=bool)
    for T in se2_matrices(ctx.candidates) if len(ctx.candidates) else []:
        reached |= rmap.is_reachable_from(T, cam, -ctx.normals[todo])
    top = rmap.origin[2] + (np.flatnonzero(rmap.reachable.any(axis=(0, 1, 3))).max() + 1) * rmap.voxel_size
    out[todo] = np.where(reached, "occluded", np.where(cam[:, 2] > top, "too_high", "too_far"))
    return out


def coverage_message(C: float, causes, visibility: str) -> str | None:
    """A warning when ``C`` is below :data:`LOW_COVERAGE`, with the counts per cause."""
    causes = np.asarray(causes)
    if C >= LOW_COVERAGE:
        return None
    n = len(causes)
    parts = [f"{int((causes == c).sum())} {CAUSE_WORDS[c]}" for c in CAUSES if (causes == c).any()]
    return (f"coverage is low: C = {C:.2f} ({visibility} visibility), {int((causes != 'observed').sum())} of {n} "
            f"surface elements unobserved: " + "; ".join(parts))

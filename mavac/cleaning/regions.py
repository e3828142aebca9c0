"""Open and enclosed heaps: where a heap lies on the machine, from geometry alone.

The MAVAC paper's robot "detected dust inside the box" of the milling machine but "the path
planner failed to generate a valid route due to the tool's large size" (Online execution).
To report cleaning separately for open surfaces and for enclosed regions, each heap is
labelled by one geometric rule, independent of the robot, the guards and the trial:

    a heap is **enclosed** when machine material lies directly above it: a ray cast straight
    up (+z) from :data:`RAY_LIFT` above the heap hits the machine mesh (under an overhang,
    inside an enclosure or a tunnel, on a shelf). Otherwise it is **open** (nothing above it,
    for example a top face or the floor of an open-top pocket).

The rays are cast with trimesh (Embree when installed).
"""

from __future__ import annotations

import numpy as np

from ..geometry.machines import Machine
from ..validate import check_instance, check_points, check_positive

#: label of a heap with nothing above it
OPEN = "open"
#: label of a heap with machine material above it
ENCLOSED = "enclosed"
#: every label, in report order
REGIONS = (OPEN, ENCLOSED)
#: height (m) above the heap where the upward ray starts: clears the face the heap lies on
#: (1 mm, far above float error, far below any gap of the machines)
RAY_LIFT = 1e-3


def heap_regions(machine: Machine, heaps, *, lift: float = RAY_LIFT) -> np.ndarray:
    """Label each heap ``"open"`` or ``"enclosed"`` by casting a ray straight up from it.

    Parameters
    ----------
    machine : Machine
    heaps : (n, 3) float, metres
        Heap positions (world frame, on the machine surface), e.g. from
        :func:`mavac.geometry.machines.dust_heaps`.
    lift : float, metres
        Start of each ray above its heap (> 0), so the ray leaves the face the heap lies on.

    Returns
    -------
    (n,) str array of ``"open"`` / ``"enclosed"``: ``"enclosed"`` when the upward ray hits the
    machine mesh.
    """
    check_instance("machine", machine, Machine)
    check_positive("lift", lift)
    if len(np.asarray(heaps)) == 0:
        return np.zeros(0, dtype="<U8")
    P = check_points("heaps", heaps)
    origins = P + np.array([0.0, 0.0, float(lift)])
    directions = np.tile([0.0, 0.0, 1.0], (len(P), 1))
    covered = np.asarray(machine.mesh.ray.intersects_any(origins, directions), dtype=bool)
    return np.where(covered, ENCLOSED, OPEN)


def region_counts(regions) -> dict:
    """Number of heaps per label: ``{"open": int, "enclosed": int}``."""
    labels = np.asarray(regions)
    return {OPEN: int(np.sum(labels == OPEN)), ENCLOSED: int(np.sum(labels == ENCLOSED))}

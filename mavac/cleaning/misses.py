"""Why each uncleaned heap was missed (MAVAC, Results, names two causes anecdotally; we measure).

Per heap, the trial records how far it got; an uncleaned heap's cause is the furthest stage:

1. ``never in view``: never inside the view frustum of a guard image, nor of a skipped one;
2. ``guard not reached``: inside the planned view frustum of a pose the arm never reached
   (its guard motion failed even with the larger budget, or the poses after a failed fold-home
   were skipped), and of no image taken;
3. ``hidden``: inside a frustum but never drawn (occluded by the machine or the robot);
4. ``filtered``: drawn in an image, in a blob of its own (or too small to be one), but no node
   of it survived detection and the filters (blob too small, no valid depth, out of reach,
   beyond the tool-tip distance, duplicate, or DBSCAN noise when an area needs two nodes);
5. ``merged blob``: drawn in images only inside blobs shared with other heaps, whose one node
   (one blob gives one node, as in the paper) went to another heap or to none;
6. ``no approach found``: its area had no collision-free, reachable approach point (eq. 5);
7. ``planner failed``: approach configurations existed, RRT-Connect found no path to any;
8. ``vacuum missed``: the tool was driven into its area but never came within the suction
   radius of it.

The ground truth used here (pybullet's segmentation, true heap positions) serves scoring only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CAUSES = ("never in view", "guard not reached", "hidden", "filtered", "merged blob", "no approach found",
          "planner failed", "vacuum missed")
#: numpy dtype holding any cause
CAUSE_DTYPE = f"<U{max(map(len, CAUSES))}"
#: stages a heap can reach, in order (the cause of a miss is the furthest one)
STAGES = ("in_skipped_view", "in_frustum", "in_image", "merged", "own_blob", "no_approach", "planner_failed",
          "attempted")


@dataclass
class HeapEvents:
    """(n,) bool per stage, one entry per heap (see the module docstring). ``merged``: in a
    blob with other heaps whose node was not its own; ``own_blob``: alone in a blob, or the
    heap its blob's node matched."""

    in_skipped_view: np.ndarray
    in_frustum: np.ndarray
    in_image: np.ndarray
    merged: np.ndarray
    own_blob: np.ndarray
    no_approach: np.ndarray
    planner_failed: np.ndarray
    attempted: np.ndarray

    @classmethod
    def empty(cls, n: int) -> HeapEvents:
        return cls(*(np.zeros(n, dtype=bool) for _ in STAGES))

    def mark(self, stage: str, heaps) -> None:
        """Set ``stage`` for heap indices ``heaps`` (negative indices = unmatched, ignored)."""
        idx = np.asarray(heaps, dtype=np.int64).reshape(-1)
        getattr(self, stage)[idx[idx >= 0]] = True


def miss_causes(events: HeapEvents, cleaned) -> np.ndarray:
    """(n,) str: the cause of each uncleaned heap, ``""`` for cleaned ones."""
    cleaned = np.asarray(cleaned, dtype=bool)
    cause = np.full(len(cleaned), CAUSES[0], dtype=CAUSE_DTYPE)
    cause[events.in_skipped_view] = "guard not reached"
    cause[events.in_frustum] = "hidden"
    cause[events.in_image] = "filtered"
    cause[events.in_image & events.merged & ~events.own_blob] = "merged blob"
    cause[events.no_approach] = "no approach found"
    cause[events.planner_failed] = "planner failed"
    cause[events.attempted] = "vacuum missed"
    cause[cleaned] = ""
    return cause


def mark_blobs(events: HeapEvents, blobs, seg_heaps, heap_of) -> None:
    """Mark ``merged`` and ``own_blob`` from one image (scoring only).

    Parameters
    ----------
    events : HeapEvents
    blobs : (h, w) int
        Node index of each pixel's blob, -1 outside kept blobs (:class:`Detection.blobs`).
    seg_heaps : (h, w) int
        Heap index drawn at each pixel, -1 where no heap is (ground truth segmentation).
    heap_of : (k,) int
        Heap each node matched, -1 for none (:func:`mavac.cleaning.detection.match_nodes`).
    """
    blobs, seg_heaps = np.asarray(blobs).reshape(-1), np.asarray(seg_heaps).reshape(-1)
    drawn = (blobs >= 0) & (seg_heaps >= 0)
    pairs = np.unique(np.stack([blobs[drawn], seg_heaps[drawn]], axis=1), axis=0)
    for blob in np.unique(pairs[:, 0]):
        heaps = pairs[pairs[:, 0] == blob, 1]
        own = heaps if len(heaps) == 1 else heaps[heaps == heap_of[blob]]
        events.mark("own_blob", own)
        events.mark("merged", np.setdiff1d(heaps, own))


def cause_counts(causes) -> dict:
    """Count of each cause (every cause present, zeros included)."""
    c = np.asarray(causes)
    return {name: int(np.count_nonzero(c == name)) for name in CAUSES}


def in_frustum(points, world_T_camera, K, width: int, height: int, near: float, far: float) -> np.ndarray:
    """(n,) bool: world points that project inside the image between ``near`` and ``far`` (m)
    (camera pose in the OpenCV convention)."""
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    T = np.asarray(world_T_camera, dtype=float)
    c = (P - T[:3, 3]) @ T[:3, :3]
    z = c[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = K[0, 0] * c[:, 0] / z + K[0, 2]
        v = K[1, 1] * c[:, 1] / z + K[1, 2]
    return (z > near) & (z < far) & (u >= -0.5) & (u <= width - 0.5) & (v >= -0.5) & (v <= height - 0.5)


def near_frustum(points, world_T_camera, K, width: int, height: int, near: float, far: float,
                 margin: float) -> np.ndarray:
    """(n,) bool: world points within ``margin`` (m) of the view frustum of :func:`in_frustum`
    (a superset of it: spheres of radius below ``margin`` that show in the image are centred on
    such points)."""
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    T = np.asarray(world_T_camera, dtype=float)
    x, y, z = ((P - T[:3, 3]) @ T[:3, :3]).T
    ok = (z > near - margin) & (z < far + margin)
    # each side plane passes through the optical centre: x - a z >= 0 inside, a = tan of its angle
    for coord, lo, hi, f, c in ((x, -0.5, width - 0.5, K[0, 0], K[0, 2]), (y, -0.5, height - 0.5, K[1, 1], K[1, 2])):
        a, b = (lo - c) / f, (hi - c) / f
        ok &= (coord - a * z) / np.hypot(1.0, a) >= -margin
        ok &= (b * z - coord) / np.hypot(1.0, b) >= -margin
    return ok

"""Dust detection in one guard view (MAVAC, "Dust detection").

The green dust is segmented with an OpenCV HSV threshold, split into blobs by connected
components, and each blob's centroid is back-projected through the depth image and the
intrinsics to a world point: the nodes D. Depth is the median of the blob's pixels; a blob with
no finite depth gets NaN (the filters drop it). Ground truth (pybullet's segmentation) is
never used here: :func:`match_nodes` scores detections against the true heaps afterwards.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..params import DetectionParams
from ..validate import check_instance
from ..vision.rgbd import back_project


@dataclass(frozen=True)
class Detection:
    """Nodes found in one image.

    Attributes
    ----------
    nodes : (k, 3) float, metres
        World points (NaN rows for blobs without valid depth).
    depth : (k,) float, metres
        Median blob depth (NaN: no finite depth).
    pixels : (k,) int
        Blob sizes, px.
    centroids : (k, 2) float
        Blob centroids ``(u, v)``, px.
    blobs : (h, w) int or None
        Index of the node whose blob holds each pixel, -1 elsewhere (scoring uses it to tell
        heaps whose blob merged with a neighbour's).
    """

    nodes: np.ndarray
    depth: np.ndarray
    pixels: np.ndarray
    centroids: np.ndarray
    blobs: np.ndarray | None = field(default=None, repr=False, compare=False)

    def __len__(self) -> int:
        return int(len(self.nodes))


def dust_mask(rgb, params: DetectionParams) -> np.ndarray:
    """(h, w) bool: pixels inside the HSV box of ``params`` (OpenCV HSV, H in [0, 180))."""
    import cv2

    image = np.ascontiguousarray(np.asarray(rgb, dtype=np.uint8))
    if image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"rgb must be an (h, w, 3) uint8 image, got shape {image.shape}")
    hsv = cv2.cvtColor(image, cv2.COLOR_RGB2HSV)
    lo = np.array([params.hue_min, params.saturation_min, params.value_min], dtype=np.uint8)
    hi = np.array([params.hue_max, 255, 255], dtype=np.uint8)
    return cv2.inRange(hsv, lo, hi) > 0


def detect_dust(rgb, depth_m, K, world_T_camera, params: DetectionParams) -> Detection:
    """Nodes D of one RGB-D view.

    Parameters
    ----------
    rgb : (h, w, 3) uint8
    depth_m : (h, w) float, metres (inf where nothing was seen)
    K : (3, 3) float
        Intrinsics.
    world_T_camera : (4, 4) float
        Camera pose, OpenCV convention.
    params : DetectionParams

    Returns
    -------
    Detection
    """
    import cv2

    check_instance("params", params, DetectionParams)
    mask = dust_mask(rgb, params)
    depth = np.asarray(depth_m, dtype=float)
    if depth.shape != mask.shape:
        raise ValueError(f"depth_m must have the image's shape {mask.shape}, got {depth.shape}")
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    keep = [i for i in range(1, n) if stats[i, cv2.CC_STAT_AREA] >= params.min_blob_px]
    node_of_label = np.full(n, -1, dtype=np.int64)
    node_of_label[keep] = np.arange(len(keep))
    blobs = node_of_label[labels]
    if not keep:
        return Detection(np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros((0, 2)), blobs)
    flat_labels, flat_depth = labels.reshape(-1), depth.reshape(-1)
    z = np.full(len(keep), np.nan)
    for j, i in enumerate(keep):
        values = flat_depth[flat_labels == i]
        values = values[np.isfinite(values)]
        if len(values):
            z[j] = float(np.median(values))
    uv = np.asarray(centroids, dtype=float)[keep]
    nodes = np.full((len(keep), 3), np.nan)
    ok = np.isfinite(z)
    if ok.any():
        nodes[ok] = back_project(uv[ok], z[ok], K, world_T_camera)
    return Detection(nodes, z, stats[keep, cv2.CC_STAT_AREA].astype(np.int64), uv, blobs)


def match_nodes(nodes, heaps, radius: float) -> np.ndarray:
    """Scoring only: index of the nearest true heap within ``radius`` (m) of each node, -1 if
    none (or the node has no position). (k,) int."""
    N = np.asarray(nodes, dtype=float).reshape(-1, 3)
    H = np.asarray(heaps, dtype=float).reshape(-1, 3)
    out = np.full(len(N), -1, dtype=np.int64)
    if not len(N) or not len(H):
        return out
    d = np.linalg.norm(N[:, None, :] - H[None, :, :], axis=2)
    nearest = np.argmin(np.where(np.isfinite(d), d, np.inf), axis=1)
    best = d[np.arange(len(N)), nearest]
    hit = np.isfinite(best) & (best <= radius)
    out[hit] = nearest[hit]
    return out

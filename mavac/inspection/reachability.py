"""Reachability map of an arm on its base: voxels x sampled viewing-axis directions.

MAVAC ("Robot base placement", after Paus et al.; capability maps of Porges et al.): an accessible
surface element is one that is visible and "within the reachability map of the robot placed at
this spot". The map here is a voxel grid in the robot base frame; for each voxel and each of
``n_directions`` axis directions (Fibonacci sphere) it stores whether some configuration puts the
frame's origin in the voxel with its axis in that direction's cell. The voxel's reachability index
is the fraction of directions that are reachable.

It is built by vectorised forward-kinematics sampling. When joint 1 is a full-turn revolute joint
about a vertical axis attached to the base (the UR10 on its platform), every sample is also copied
exactly by rotating it about that axis, which fills the map ``n_rotations`` times faster. The map is
a *prefilter*: the final decision for a guard is always collision-free IK.

The map is cached on disk under a key made of the robot's name, a kinematic fingerprint (joint
types and placements, limits, frame placement) and the parameters. It uses
:func:`mavac.cache.verified_cache` (a joblib ``Memory`` whose entries are checked against their
checksum before they are loaded), with the robot object left out of the hash: hashing a
pinocchio model by pickling is slow and not stable, the fingerprint stands in for it.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import numpy as np

from ..cache import verified_cache
from ..geometry.transforms import points_in_frame, vectors_in_frame
from ..params import ReachabilityMapParams
from ..robots.kinematics import fk
from ..seeding import rng_for
from ..tolerances import COUNT_SLACK, PARALLEL_TOL
from ..validate import check_points, check_size
from ..vision.camera import OPTICAL_AXIS
from .nos import sphere_directions


#: Cells (voxels x directions, one byte each) a map may have: 1 GB, ~100 times the default
#: UR10 map (5 cm voxels, 50 directions); a tiny voxel size would otherwise exhaust memory.
MAX_MAP_CELLS = 1_000_000_000


@dataclass(frozen=True)
class ReachabilityMap:
    """Voxel x direction reachability of one robot frame, in the robot base frame.

    Attributes
    ----------
    robot_name, frame : str
    origin : (3,) float, m
        Lower corner of voxel (0, 0, 0).
    voxel_size : float, m
    directions : (d, 3) float
        Unit axis directions; a direction is binned to the nearest one.
    reachable : (nx, ny, nz, d) bool
    """

    robot_name: str
    frame: str
    origin: np.ndarray
    voxel_size: float
    directions: np.ndarray
    reachable: np.ndarray

    @property
    def shape(self) -> tuple:
        """(nx, ny, nz)."""
        return tuple(self.reachable.shape[:3])

    @property
    def index(self) -> np.ndarray:
        """(nx, ny, nz) float in [0, 1]: fraction of directions reachable per voxel."""
        return self.reachable.mean(axis=3)

    def voxel_centres(self) -> np.ndarray:
        """(nx, ny, nz, 3) float, m: voxel centres in the base frame."""
        axes = [self.origin[i] + (np.arange(n) + 0.5) * self.voxel_size for i, n in enumerate(self.shape)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def voxels_of(self, base_points) -> tuple[np.ndarray, np.ndarray]:
        """Voxel indices ``(n, 3)`` of base-frame points and whether they fall inside the grid."""
        p = check_points("base_points", base_points)
        ijk = np.floor((p - self.origin) / self.voxel_size).astype(np.int64)
        inside = np.all((ijk >= 0) & (ijk < np.asarray(self.shape)), axis=1)
        return np.where(inside[:, None], ijk, 0), inside

    def direction_bins(self, base_axes) -> np.ndarray:
        """Index of the nearest map direction for each non-zero axis, (n,) int."""
        return direction_bins(self.directions, check_points("base_axes", base_axes))

    def index_at(self, base_points) -> np.ndarray:
        """Reachability index of the voxel containing each point (0 outside the grid), (n,)."""
        ijk, inside = self.voxels_of(base_points)
        return np.where(inside, self.index[ijk[:, 0], ijk[:, 1], ijk[:, 2]], 0.0)

    def is_reachable(self, base_points, base_axes) -> np.ndarray:
        """Whether the map marks (point's voxel, axis's direction cell) reachable, (n,) bool.

        Parameters
        ----------
        base_points : (n, 3) float, m
            Frame origins in the robot base frame.
        base_axes : (n, 3) float
            Frame axis directions in the base frame.
        """
        ijk, inside = self.voxels_of(base_points)
        d = self.direction_bins(base_axes)
        if len(d) != len(ijk):
            raise ValueError(f"base_points and base_axes must have the same length, got {len(ijk)} and {len(d)}")
        return inside & self.reachable[ijk[:, 0], ijk[:, 1], ijk[:, 2], d]

    def is_reachable_from(self, world_T_base, points_world, axes_world) -> np.ndarray:
        """:meth:`is_reachable` for world-frame targets and a base pose ``world_T_base`` (4, 4)."""
        p = points_in_frame(world_T_base, check_points("points_world", points_world))
        a = vectors_in_frame(world_T_base, check_points("axes_world", axes_world))
        return self.is_reachable(p, a)


# Resolution of the (z, azimuth) look-up table that bins directions without a (n, d) product.
_LUT_Z, _LUT_AZ = 256, 512


def _direction_lut(directions: np.ndarray) -> np.ndarray:
    """(LUT_Z, LUT_AZ) int: nearest direction to each equal-area (z, azimuth) cell centre."""
    z = -1.0 + (np.arange(_LUT_Z) + 0.5) * 2.0 / _LUT_Z
    az = -math.pi + (np.arange(_LUT_AZ) + 0.5) * 2.0 * math.pi / _LUT_AZ
    r = np.sqrt(1.0 - z * z)
    cells = np.stack([r[:, None] * np.cos(az)[None, :], r[:, None] * np.sin(az)[None, :],
                      np.broadcast_to(z[:, None], (_LUT_Z, _LUT_AZ))], axis=-1)
    return np.argmax(cells.reshape(-1, 3) @ directions.T, axis=1).reshape(_LUT_Z, _LUT_AZ)


def direction_bins(directions, axes) -> np.ndarray:
    """Bin axes to the nearest of ``directions`` through a (z, azimuth) look-up table.

    Parameters
    ----------
    directions : (d, 3) float, unit
    axes : (n, 3) float, non-zero (normalised here)

    Returns
    -------
    (n,) int
        Exact except within ~0.5 deg of a border between two directions' cells.
    """
    a = np.asarray(axes, dtype=float)
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    key = directions.tobytes()
    lut = _LUTS.get(key)
    if lut is None:
        lut = _LUTS[key] = _direction_lut(np.asarray(directions, dtype=float))
    iz = np.clip(((a[:, 2] + 1.0) * (_LUT_Z / 2.0)).astype(np.int64), 0, _LUT_Z - 1)
    iaz = np.clip(((np.arctan2(a[:, 1], a[:, 0]) + math.pi) * (_LUT_AZ / (2.0 * math.pi))).astype(np.int64),
                  0, _LUT_AZ - 1)
    return lut[iz, iaz]


_LUTS: dict = {}


def _vertical_joint1(robot):
    """``(centre (3,), ok)``: joint 1 turns a full circle about a vertical axis fixed to the base."""
    m = robot.model
    if m.njoints < 2 or m.parents[1] != 0 or m.joints[1].shortname() != "JointModelRZ":
        return np.zeros(3), False
    placement = m.jointPlacements[1]
    vertical = np.allclose(placement.rotation[:, 2], [0.0, 0.0, 1.0], atol=PARALLEL_TOL)
    full_turn = (robot.q_upper[0] - robot.q_lower[0]) >= 2.0 * math.pi - COUNT_SLACK
    return np.asarray(placement.translation, dtype=float), bool(vertical and full_turn)


def robot_fingerprint(robot, frame: str) -> str:
    """Hash of what the map depends on: joint placements, joint types, limits, frame placement."""
    m = robot.model
    h = hashlib.sha1()
    h.update(robot.name.encode())
    for j in range(1, m.njoints):
        h.update(m.joints[j].shortname().encode())
        h.update(np.round(m.jointPlacements[j].homogeneous, 12).tobytes())
    h.update(np.round(robot.q_lower, 12).tobytes())
    h.update(np.round(robot.q_upper, 12).tobytes())
    h.update(np.round(m.frames[m.getFrameId(frame)].placement.homogeneous, 12).tobytes())
    return f"{robot.name}:{frame}:{h.hexdigest()[:16]}"


def _build(robot, key: str, frame: str, params: ReachabilityMapParams, axis_column: int) -> dict:
    """Sample FK, rotate about joint 1 when exact, bin into voxels x directions (cached)."""
    rng = rng_for(params.seed, "reachability map")
    lo = np.maximum(robot.q_lower, -math.pi)
    hi = np.minimum(robot.q_upper, math.pi)
    q = rng.uniform(lo, hi, size=(params.n_samples, robot.nq))
    T = fk(robot, q, frame)
    pos, ax = T[:, :3, 3], T[:, :3, axis_column]
    centre, symmetric = _vertical_joint1(robot)
    n_rot = params.n_rotations if symmetric else 1
    vs = params.voxel_size
    if symmetric:
        # rotation about joint 1 keeps the radius about its axis and the height
        r = np.linalg.norm(pos[:, :2] - centre[:2], axis=1).max()
        lo_b = np.array([centre[0] - r, centre[1] - r, pos[:, 2].min()])
        hi_b = np.array([centre[0] + r, centre[1] + r, pos[:, 2].max()])
    else:
        lo_b, hi_b = pos.min(axis=0), pos.max(axis=0)
    origin = np.floor(lo_b / vs) * vs - vs
    shape = (np.ceil((hi_b - origin) / vs).astype(np.int64) + 1)
    dirs = sphere_directions(params.n_directions)
    n_cells = int(np.prod(shape)) * len(dirs)
    check_size("voxel_size", vs, n_cells, MAX_MAP_CELLS, "map cells (voxels x directions)")
    hit = np.zeros(n_cells, dtype=bool)
    # random phase per sample so the copies do not line up on the same azimuths
    phase = rng.uniform(0.0, 2.0 * math.pi / n_rot, size=len(pos))
    chunk = max(1, 2_000_000 // n_rot)
    for s in range(0, len(pos), chunk):
        p, a, ph = pos[s:s + chunk], ax[s:s + chunk], phase[s:s + chunk]
        ang = ph[:, None] + 2.0 * math.pi * np.arange(n_rot)[None, :] / n_rot
        c, sn = np.cos(ang), np.sin(ang)
        rx, ry = p[:, 0:1] - centre[0], p[:, 1:2] - centre[1]
        P = np.stack([centre[0] + c * rx - sn * ry, centre[1] + sn * rx + c * ry,
                      np.broadcast_to(p[:, 2:3], c.shape)], axis=-1).reshape(-1, 3)
        A = np.stack([c * a[:, 0:1] - sn * a[:, 1:2], sn * a[:, 0:1] + c * a[:, 1:2],
                      np.broadcast_to(a[:, 2:3], c.shape)], axis=-1).reshape(-1, 3)
        ijk = np.floor((P - origin) / vs).astype(np.int64)
        d = direction_bins(dirs, A)
        flat = (np.ravel_multi_index(ijk.T, tuple(shape)) * len(dirs)) + d
        hit[flat] = True
    return {"origin": origin, "voxel_size": vs, "directions": dirs,
            "reachable": hit.reshape(*shape, len(dirs)), "key": key}


def reachability_map(robot, params: ReachabilityMapParams | None = None, *, frame: str | None = None,
                     axis_column: int | None = None, cache: bool = True) -> ReachabilityMap:
    """Build (or load from the disk cache) the reachability map of ``robot``.

    Parameters
    ----------
    robot : RobotModel
    params : ReachabilityMapParams, optional
        Voxel size, number of directions, FK samples and rotations, seed.
    frame : str, optional
        Frame mapped; default the robot's ``camera_frame`` when it has a camera, else the
        tool frame.
    axis_column : int, optional
        Which column of the frame rotation is the mapped axis; default :data:`OPTICAL_AXIS`
        (camera x) for the default camera frame, else 2 (z).
    cache : bool
        Use the on-disk cache (key: robot fingerprint + frame + params).

    Returns
    -------
    ReachabilityMap
    """
    params = ReachabilityMapParams() if params is None else params
    if not isinstance(params, ReachabilityMapParams):
        raise ValueError(f"params must be a ReachabilityMapParams, got {type(params).__name__}")
    if frame is None:
        if robot.camera_frame is not None:
            frame = robot.camera_frame
            axis_column = OPTICAL_AXIS if axis_column is None else axis_column
        else:
            frame = robot.tool_frame
    if not robot.model.existFrame(frame):
        raise ValueError(f"frame {frame!r} does not exist on robot {robot.name}")
    axis_column = 2 if axis_column is None else int(axis_column)
    if axis_column not in (0, 1, 2):
        raise ValueError(f"axis_column must be 0, 1 or 2, got {axis_column}")
    key = robot_fingerprint(robot, frame)
    build = verified_cache(_build, ignore=["robot"]) if cache else _build
    out = build(robot, key, frame, params, axis_column)
    return ReachabilityMap(robot.name, frame, out["origin"], out["voxel_size"], out["directions"], out["reachable"])

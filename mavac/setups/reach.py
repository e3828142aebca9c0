"""Reach test of Kabir et al. (2017), Section IV, and the n_rfc counter of Section IX-A1.

A stain patch is reachable from a setup when all three of its vertices have an IK solution
within joint limits with the tool axis along the patch normal, pointing into the surface
(tool z = -n), rotation about the axis free; optionally the arm must also clear the part.

Where the setup space sits
--------------------------
A setup ``(x, y, alpha)`` places the part frame (origin at the centre of the part's
bounding-box bottom, z up) at

    base_T_part = Trans(origin_x + x, origin_y + y, table_z) @ Rz(alpha)

in the Puma 560 base frame (the shoulder: z0 up along joint 1, the shoulder axis at z = 0, the
floor 0.672 m below). The Puma reaches about 0.86 m from the shoulder (a2 + d4 = 0.864 m). The
paper gives only the range [0, 1 m] x [0, 1 m] x [0, 2 pi] and how it was found (a coarse sweep,
setups reaching no patch eliminated); :mod:`mavac.setups.space` places each part's box that way.

Vectorisation
-------------
Targets are the distinct (vertex, patch normal) pairs of the stain (a vertex shared by faces
with different normals is one target per normal, because the paper tests each patch's vertices
with that patch's normal). Many setups are processed in one batch: all their targets are moved
into the base frame at once, targets outside a sphere that bounds the arm's reach (exact, from
the joint offsets: no IK solution can exist beyond it) are rejected without IK, and the rest go
to one batched call of :func:`mavac.robots.kinematics.ik_axis` (closed form for the Puma 560)
per vertex slot: slot 1 is only solved for patches whose slot-0 vertex was reachable, and so on,
since a patch is lost as soon as one vertex is.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np
import trimesh

from ..cache import verified_cache
from ..geometry.transforms import se2_matrices
from ..parallel import map_trials
from ..params import ReachParams, SetupSpaceParams
from ..robots.collision import CollisionChecker
from ..robots.kinematics import ik_axis, puma_dh_constants
from ..robots.models import load_robot
from ..tolerances import SETUP_KEY_QUANTUM, TARGET_DECIMALS
from ..validate import check_instance, check_int, check_points


# ---------------------------------------------------------------- targets and placement


@dataclass(frozen=True)
class ReachTargets:
    """IK targets of a stain in the part frame.

    Attributes
    ----------
    positions : (t, 3) float, metres
        Distinct patch vertices (one per (vertex, normal) pair).
    axes : (t, 3) float
        Tool z axis for each target: minus the outward patch normal.
    patch_targets : (n, 3) int
        For each patch, its three targets (rows of ``positions``).
    """

    positions: np.ndarray
    axes: np.ndarray
    patch_targets: np.ndarray

    @property
    def n_patches(self) -> int:
        return int(self.patch_targets.shape[0])

    @property
    def n_targets(self) -> int:
        return int(self.positions.shape[0])


def reach_targets(patch_vertices, patch_normals) -> ReachTargets:
    """Distinct (vertex, normal) IK targets of a set of triangular patches.

    Parameters
    ----------
    patch_vertices : (n, 3, 3) float, metres
        Corners of each patch, part frame.
    patch_normals : (n, 3) float
        Outward unit normal of each patch (the tool points along minus it).
    """
    v = np.asarray(patch_vertices, dtype=float)
    nrm = np.asarray(patch_normals, dtype=float)
    if v.ndim != 3 or v.shape[1:] != (3, 3):
        raise ValueError(f"patch_vertices must have shape (n, 3, 3), got {v.shape}")
    if nrm.shape != (v.shape[0], 3):
        raise ValueError(f"patch_normals must have shape ({v.shape[0]}, 3), got {nrm.shape}")
    if not (np.all(np.isfinite(v)) and np.all(np.isfinite(nrm))):
        raise ValueError("patch_vertices and patch_normals must be finite")
    length = np.linalg.norm(nrm, axis=1)
    if np.any(length < 1e-12):
        raise ValueError("patch_normals must be non-zero (degenerate patch?)")
    nrm = nrm / length[:, None]
    n = v.shape[0]
    if n == 0:
        return ReachTargets(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    rows = np.concatenate([v.reshape(-1, 3), np.repeat(nrm, 3, axis=0)], axis=1)
    keys = np.round(rows, TARGET_DECIMALS) + 0.0  # +0.0 folds -0.0 into 0.0
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return ReachTargets(positions=rows[first, :3].copy(), axes=-rows[first, 3:].copy(),
                        patch_targets=inverse.reshape(n, 3).astype(np.int64))


def reach_targets_from_part(part) -> ReachTargets:
    """:func:`reach_targets` of a :class:`mavac.geometry.parts.Part`'s stain patches."""
    return reach_targets(part.patch_vertices, part.patch_normals)


def base_T_part(setups, space: SetupSpaceParams) -> np.ndarray:
    """Pose of the part frame in the robot base frame for each setup.

    Parameters
    ----------
    setups : (k, 3) float
        ``(x [m], y [m], alpha [rad])``.

    Returns
    -------
    (k, 4, 4) float: ``Trans(origin_x + x, origin_y + y, table_z) @ Rz(alpha)``.
    """
    s = check_points("setups", setups, 3)
    check_instance("space", space, SetupSpaceParams)
    T = se2_matrices(np.column_stack([space.origin_x + s[:, 0], space.origin_y + s[:, 1], s[:, 2]]))
    T[:, 2, 3] = space.table_z
    return T


# ---------------------------------------------------------------- exact reach bound


@dataclass(frozen=True)
class ReachBound:
    """A sphere no IK solution can leave: ``|p - tool_offset * a - centre| <= radius``.

    ``p`` is the tool-frame target and ``a`` its axis. When the tool frame lies on the last
    joint's axis, ``p - tool_offset * a`` is that joint's origin exactly; otherwise
    ``tool_offset`` is 0 and the tool offset is added to ``radius``.
    """

    centre: np.ndarray
    radius: float
    tool_offset: float


def reach_bound(robot, frame: str | None = None) -> ReachBound:
    """Triangle-inequality reach sphere of a serial arm about its first joint's origin.

    Every joint placement after the first is a rigid offset, so the last joint's origin lies
    within the sum of their lengths from the first joint's origin whatever the joint angles.
    """
    m = robot.model
    frame = robot.tool_frame if frame is None else frame
    f = m.frames[m.getFrameId(frame)]
    puma = puma_dh_constants(robot, frame)
    if puma is not None:
        # exact for a Puma-type arm: the wrist centre is (c1 x1 + s1 d_off, s1 x1 - c1 d_off,
        # d1 + y1) with |(x1, y1)| <= a2 + hypot(a3, d4)
        radius = float(np.hypot(puma["a2"] + np.hypot(puma["a3"], puma["d4"]), puma["d_off"]))
        return ReachBound(np.array([0.0, 0.0, puma["d1"]]), radius, float(puma["reach"]))
    joints = list(m.supports[f.parentJoint])[1:]
    centre = np.array(m.jointPlacements[joints[0]].translation, dtype=float)
    radius = float(sum(np.linalg.norm(m.jointPlacements[j].translation) for j in joints[1:]))
    p_f = np.asarray(f.placement.translation, dtype=float)
    z_f = np.asarray(f.placement.rotation, dtype=float)[:, 2]
    if np.allclose(p_f[:2], 0.0) and np.allclose(z_f, [0.0, 0.0, 1.0]):
        return ReachBound(centre, radius, float(p_f[2]))
    return ReachBound(centre, radius + float(np.linalg.norm(p_f)), 0.0)


# ---------------------------------------------------------------- the reach test


def patch_reach(robot, targets: ReachTargets, setups, space: SetupSpaceParams,
                *, params: ReachParams | None = None, part_mesh=None, checker=None) -> np.ndarray:
    """Which patches each setup reaches (Kabir Sec. IV), batched over setups.

    Parameters
    ----------
    robot : RobotModel
        Fixed-base arm (e.g. ``puma560(tool_length=params.tool_length)``); its base frame is the
        frame of :func:`base_T_part`.
    targets : ReachTargets
        From :func:`reach_targets_from_part`.
    setups : (k, 3) float
        ``(x [m], y [m], alpha [rad])``.
    space : SetupSpaceParams
    params : ReachParams, optional
    part_mesh : trimesh.Trimesh, optional
        Part mesh (part frame); needed when ``params.check_collision``.
    checker : CollisionChecker, optional
        :func:`part_checker` of ``robot``, ``part_mesh`` and ``params``, when the caller keeps
        one across calls; built here (once per call) when None and ``params.check_collision``.

    Returns
    -------
    (k, n) bool
        ``cover[j, i]``: setup j reaches patch i.
    """
    params = ReachParams() if params is None else params
    setups = check_points("setups", setups, 3)
    k, n, t = len(setups), targets.n_patches, targets.n_targets
    cover = np.zeros((k, n), dtype=bool)
    if k == 0 or n == 0:
        return cover
    if params.check_collision and part_mesh is None:
        raise ValueError("part_mesh is required when params.check_collision is True")
    if params.check_collision and checker is None:
        checker = part_checker(robot, part_mesh, params)
    bound = reach_bound(robot)
    chunk = max(1, params.batch_size // max(1, t))
    for a in range(0, k, chunk):
        cover[a:a + chunk] = _chunk_reach(robot, targets, setups[a:a + chunk], space, params, bound, checker)
    if params.support_plane:
        cover[:, below_support(targets, params.tool_length)] = False
    return cover


#: Shortest tool checked against the table, m: the tool tip's own thickness (ours).
SUPPORT_PROBE = 0.01
#: The table top may sit this far above a target before it counts (mesh rounding), m.
SUPPORT_TOL = 1e-6


def below_support(targets: ReachTargets, tool_length: float) -> np.ndarray:
    """Patches whose tool would come from below the table top (the part frame's z = 0).

    The tool runs from its tip at a vertex back along the outward normal over
    ``max(tool_length, SUPPORT_PROBE)``; a patch is blocked when that segment of one of its
    vertices dips below the table. The part rests on the table in every setup (setups move it
    in x, y and alpha only), so the answer is the same for all setups.

    Returns
    -------
    (n,) bool
    """
    reach_len = max(float(tool_length), SUPPORT_PROBE)
    end_z = targets.positions[:, 2] - reach_len * targets.axes[:, 2]  # axes = -normal
    low = np.minimum(targets.positions[:, 2], end_z) < -SUPPORT_TOL
    return low[targets.patch_targets].any(axis=1)


def support_slab(part_mesh, *, margin: float = 0.05, thickness: float = 0.05):
    """The table under a part as a box (part frame): the part's footprint grown by ``margin``
    on each side (ours), top just under z = 0 so the part's own bottom does not touch it."""
    lo, hi = np.asarray(part_mesh.bounds, dtype=float)
    extents = [hi[0] - lo[0] + 2 * margin, hi[1] - lo[1] + 2 * margin, thickness]
    centre = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, -thickness / 2 - 1e-4]
    return trimesh.creation.box(extents=extents, transform=trimesh.transformations.translation_matrix(centre))


def part_checker(robot, part_mesh, params: ReachParams) -> CollisionChecker:
    """The arm-vs-part collision checker of the reach test, in the part frame.

    Its coal hierarchy costs about 0.3 kB and 1.5 us per part face to build (2.4 M faces: 0.7 GB,
    3.4 s), so callers that test many setups of one part build it once (:class:`PartReach`):
    :meth:`CollisionChecker.set_base` moves the arm per setup and :meth:`CollisionChecker.reset`
    makes each batch answer as a new checker would.

    Parameters
    ----------
    robot : RobotModel
    part_mesh : trimesh.Trimesh
        Part frame, metres.
    params : ReachParams
        ``support_plane`` adds the table under the part (:func:`support_slab`);
        ``collision_margin`` is the clearance, m.
    """
    if part_mesh is None:
        raise ValueError("part_mesh is required when params.check_collision is True")
    obstacle = part_mesh
    if params.support_plane:  # the table under the part
        obstacle = trimesh.util.concatenate([part_mesh, support_slab(part_mesh)])
    return CollisionChecker(robot, obstacle, margin=params.collision_margin)


def _chunk_reach(robot, targets, setups, space, params, bound, checker) -> np.ndarray:
    # base_T_part is a rotation about z plus a translation: apply it by components, only to the
    # targets that need it (einsum over every (setup, target) pair costs more than the IK).
    c, s = np.cos(setups[:, 2]), np.sin(setups[:, 2])
    tx, ty = space.origin_x + setups[:, 0], space.origin_y + setups[:, 1]
    w = targets.positions - bound.tool_offset * targets.axes  # last-joint origin, part frame
    dx = (c[:, None] * w[:, 0] - s[:, None] * w[:, 1]) + (tx - bound.centre[0])[:, None]
    dy = (s[:, None] * w[:, 0] + c[:, None] * w[:, 1]) + (ty - bound.centre[1])[:, None]
    dz = w[:, 2] + (space.table_z - bound.centre[2])
    far = dx * dx + dy * dy + (dz * dz)[None, :] > bound.radius ** 2
    state = np.where(far, np.int8(0), np.int8(-1))  # -1 unknown, 0 unreachable, 1 reachable
    pt = targets.patch_targets
    alive = ~(far[:, pt[:, 0]] | far[:, pt[:, 1]] | far[:, pt[:, 2]])
    for slot in range(3):
        col = pt[:, slot]
        rows, patches = np.nonzero(alive & (state[:, col] < 0))
        if len(rows):
            need = np.zeros(state.shape, dtype=bool)
            need[rows, col[patches]] = True
            si, ti = np.nonzero(need)
            p, a = targets.positions[ti], targets.axes[ti]
            cs, ss = c[si], s[si]
            pos = np.stack([cs * p[:, 0] - ss * p[:, 1] + tx[si], ss * p[:, 0] + cs * p[:, 1] + ty[si],
                            p[:, 2] + space.table_z], axis=1)
            ax = np.stack([cs * a[:, 0] - ss * a[:, 1], ss * a[:, 0] + cs * a[:, 1], a[:, 2]], axis=1)
            state[si, ti] = ik_axis(robot, pos, ax, n_restarts=params.ik_restarts).success
        alive &= state[:, col] == 1
    if params.check_collision and alive.any():
        rows, patches = np.nonzero(alive)
        alive[rows, patches] = _collision_free(robot, targets, rows, patches, setups, space, params, checker)
    return alive


def _collision_free(robot, targets, rows, patches, setups, space, params, checker) -> np.ndarray:
    """Arm-vs-part check of each (setup, patch) pair the IK accepts, with the tool on the patch
    centroid along its axis at a stand-off of ``collision_standoff`` (the tool tip touches the
    surface at the patch itself); one arm pose per patch, the arm that would clean it."""
    T = base_T_part(setups, space)
    corners = targets.positions[targets.patch_targets[patches]]  # (p, 3, 3), part frame
    axis = targets.axes[targets.patch_targets[patches]].mean(axis=1)
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    centre = corners.mean(axis=1) - params.collision_standoff * axis
    R, t = T[rows, :3, :3], T[rows, :3, 3]
    pos = np.einsum("kij,kj->ki", R, centre) + t
    ax = np.einsum("kij,kj->ki", R, axis)
    return _arm_clear(robot, pos, ax, rows, T, params, checker)


def _arm_clear(robot, pos, ax, setup_index, base_T_parts, params, checker) -> np.ndarray:
    """IK at each tool pose (base frame) and a collision test of that arm against the part (and
    the table under it with ``support_plane``; ``checker`` from :func:`part_checker`), (p,) bool."""
    lifted = ik_axis(robot, pos, ax, n_restarts=params.ik_restarts)
    free = lifted.success.copy()
    checker.reset()  # answers independent of earlier batches, as with a checker built per batch
    for j in np.unique(setup_index):
        sel = np.flatnonzero((setup_index == j) & free)
        if len(sel):
            checker.set_base(np.linalg.inv(base_T_parts[j]))  # world = part frame
            free[sel] = ~np.asarray(checker.in_collision(lifted.q[sel]), dtype=bool)
    return free


class PartReach:
    """``reach(setups (k, 3)) -> (k, n) bool`` for one part, robot and setup space (picklable).

    Parameters
    ----------
    robot : RobotModel
    targets : ReachTargets
    space : SetupSpaceParams
    params : ReachParams, optional
    part_mesh : trimesh.Trimesh, optional
        Only for the optional collision check; its checker is built once, on the first call
        (:attr:`checker`), and left out when pickled (a worker builds its own).
    """

    def __init__(self, robot, targets: ReachTargets, space: SetupSpaceParams,
                 *, params: ReachParams | None = None, part_mesh=None):
        self.robot = robot
        self.targets = targets
        self.space = space
        self.params = ReachParams() if params is None else params
        self.part_mesh = part_mesh
        self._checker = None

    def __call__(self, setups) -> np.ndarray:
        return patch_reach(self.robot, self.targets, setups, self.space, params=self.params,
                           part_mesh=self.part_mesh, checker=self.checker)

    @property
    def checker(self) -> CollisionChecker | None:
        """The part's :func:`part_checker`, built on first use and kept (None without
        ``params.check_collision``)."""
        if self.params.check_collision and self._checker is None:  # one build per part, not per call
            self._checker = part_checker(self.robot, self.part_mesh, self.params)
        return self._checker

    def __getstate__(self) -> dict:
        # coal objects do not pickle: a worker builds its own checker
        return {**self.__dict__, "_checker": None}

    @property
    def n_patches(self) -> int:
        return self.targets.n_patches


class FeasibleReach:
    """A reach function that reaches nothing from setups a ``feasible`` test refuses.

    Used when something other than the reach test decides whether a setup exists at all, e.g.
    the holding arm of a two-arm cell must present the part there
    (:class:`mavac.scrubbing.holding.HeldSetups`): a refused setup covers no patch, so the planner
    drops it; ``dropped`` counts the refused setups (each asked once through
    :class:`CountingReach`).

    Parameters
    ----------
    reach_fn : callable
        ``reach_fn(setups (k, 3)) -> (k, n) bool``.
    feasible : callable
        ``feasible(setups (k, 3)) -> (k,) bool``.
    """

    def __init__(self, reach_fn: Callable[[np.ndarray], np.ndarray], feasible: Callable[[np.ndarray], np.ndarray]):
        self.reach_fn = reach_fn
        self.feasible = feasible
        self.dropped = 0

    def __call__(self, setups) -> np.ndarray:
        setups = check_points("setups", setups, 3)
        ok = np.asarray(self.feasible(setups), dtype=bool).reshape(-1)
        if ok.shape != (len(setups),):
            raise ValueError(f"feasible must return a ({len(setups)},) bool array, got shape {ok.shape}")
        out = np.zeros((len(setups), self.n_patches), dtype=bool)
        if ok.any():
            out[ok] = self.reach_fn(setups[ok])
        self.dropped += int((~ok).sum())
        return out

    @property
    def n_patches(self) -> int:
        return int(self.reach_fn.n_patches)


def reach_sweep(reach: Callable[[np.ndarray], np.ndarray], setups, *, n_jobs: int | None = None,
                chunk: int = 256, desc: str = "reach sweep") -> np.ndarray:
    """Evaluate a (picklable) reach function on many setups in parallel chunks.

    Parameters
    ----------
    reach : callable
        ``reach(setups (k, 3)) -> (k, n) bool``, e.g. a :class:`PartReach`.
    setups : (k, 3) float
    n_jobs : int, optional
        Workers for :func:`mavac.parallel.map_trials` (default ``MAVAC_JOBS`` or 1).
    chunk : int
        Setups per task.
    """
    setups = check_points("setups", setups, 3)
    chunk = check_int("chunk", chunk, lo=1)
    pieces = [setups[a:a + chunk] for a in range(0, len(setups), chunk)]
    if not pieces:
        return np.asarray(reach(setups), dtype=bool)
    return np.concatenate(map_trials(reach, pieces, n_jobs=n_jobs, desc=desc))


def cached_reach_sweep(robot_name: str, positions, axes, patch_targets, setups, space: SetupSpaceParams,
                       params: ReachParams, n_jobs: int | None = None, *, part_mesh=None) -> np.ndarray:
    """:func:`reach_sweep` of a registry robot, cached on disk under :func:`mavac.config.cache_dir`.

    The key is the content of every argument but ``n_jobs`` (the answer does not depend on it).
    ``robot_name`` is built with ``load_robot(robot_name, tool_length=params.tool_length)``.
    With ``params.check_collision`` the part's mesh is part of the key (and of the test).

    Parameters
    ----------
    positions, axes : (t, 3) float
    patch_targets : (n, 3) int
        A :class:`ReachTargets`' arrays.
    setups : (k, 3) float
    part_mesh : trimesh.Trimesh, optional
        The part (part frame); required when ``params.check_collision``.

    Returns
    -------
    (k, n) bool
    """
    args = (robot_name, np.asarray(positions, float), np.asarray(axes, float), np.asarray(patch_targets, np.int64),
            np.asarray(setups, float), space, params)
    if not params.check_collision:
        return _sweep_cache()(*args, n_jobs)
    if part_mesh is None:
        raise ValueError("part_mesh is required when params.check_collision is True")
    mesh = (np.asarray(part_mesh.vertices, float), np.asarray(part_mesh.faces, np.int64))
    return _collision_sweep_cache()(*args, *mesh, n_jobs)


@functools.lru_cache(maxsize=1)
def _sweep_cache():
    return verified_cache(_reach_sweep_by_name, ignore=["n_jobs"])


@functools.lru_cache(maxsize=1)
def _collision_sweep_cache():
    return verified_cache(_collision_sweep_by_name, ignore=["n_jobs"])


def _reach_sweep_by_name(robot_name, positions, axes, patch_targets, setups, space, params, n_jobs):
    # Cached body: editing it invalidates every stored sweep, so keep it minimal.
    robot = load_robot(robot_name, tool_length=params.tool_length)
    reach = PartReach(robot, ReachTargets(positions, axes, patch_targets), space, params=params)
    return reach_sweep(reach, setups, n_jobs=n_jobs)


def _collision_sweep_by_name(robot_name, positions, axes, patch_targets, setups, space, params, vertices, faces,
                             n_jobs):
    # Cached body of the sweep with the arm-vs-part collision test (its own entries).
    robot = load_robot(robot_name, tool_length=params.tool_length)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    reach = PartReach(robot, ReachTargets(positions, axes, patch_targets), space, params=params, part_mesh=mesh)
    return reach_sweep(reach, setups, n_jobs=n_jobs)


# ---------------------------------------------------------------- n_rfc


def setup_keys(setups) -> list[tuple[int, int, int]]:
    """Hashable identity of each setup (coordinates quantised to
    :data:`mavac.tolerances.SETUP_KEY_QUANTUM`, m / rad)."""
    q = np.round(np.asarray(setups, dtype=float) / SETUP_KEY_QUANTUM).astype(np.int64)
    return [tuple(row) for row in q.reshape(-1, 3).tolist()]


def _ask_missing(memo: dict, keys: list, setups: np.ndarray, reach_fn) -> int:
    """Ask ``reach_fn`` once for the setups (k, 3) whose key is not in ``memo`` (the first setup
    of each new key) and store the answers under their keys; returns how many it asked for."""
    missing: dict = {}
    for i, key in enumerate(keys):
        if key not in memo and key not in missing:
            missing[key] = i
    if missing:
        rows = np.fromiter(missing.values(), dtype=np.int64, count=len(missing))
        answer = np.asarray(reach_fn(setups[rows]), dtype=bool)
        if answer.ndim != 2 or answer.shape[0] != len(rows):
            raise ValueError(f"reach_fn must return a (k, n) bool array for k={len(rows)} setups, "
                             f"got shape {answer.shape}")
        memo.update(zip(missing, answer))
    return len(missing)


class CountingReach:
    """A reach function that counts n_rfc the way the paper does and remembers its answers.

    n_rfc is "the number of calls made to the reachability test function", one call per setup
    (Kabir Sec. IX-A1; the uniform baseline at 50 mm x 50 mm x 10 deg has n_rfc = 16,317). A setup
    asked for again (a gradient-descent path crossing an earlier one, a hierarchical level
    re-visiting a coarser grid point) is answered from memory and not counted again.

    Parameters
    ----------
    reach_fn : callable
        ``reach_fn(setups (k, 3)) -> (k, n) bool``.
    """

    def __init__(self, reach_fn: Callable[[np.ndarray], np.ndarray]):
        self.reach_fn = reach_fn
        self._memo: dict[tuple[int, int, int], np.ndarray] = {}
        self.n_rfc = 0

    def __call__(self, setups) -> np.ndarray:
        setups = check_points("setups", setups, 3)
        keys = setup_keys(setups)
        self.n_rfc += _ask_missing(self._memo, keys, setups, self.reach_fn)
        if not keys:
            return np.zeros((0, self.n_patches), dtype=bool)
        return np.stack([self._memo[key] for key in keys])

    @property
    def n_patches(self) -> int:
        """Patch count n (known after the first call; 0 before)."""
        return len(next(iter(self._memo.values()))) if self._memo else 0


class SharedReach:
    """A reach function that remembers its answers by the exact floats of each setup.

    Several runs over one part (Table III's seven variants) ask the reach test for many of the
    same setups: wrap the test once in this and give each run its own :class:`CountingReach`
    over it, so each run still counts its own n_rfc. The key is the setup's float bits, not
    :func:`setup_keys`: a setup the test was never asked for (one that rounds to the same key)
    is never answered from memory. Every row of the answer depends on that row's setup alone
    (the reach test is evaluated setup by setup, batched), so a run gets what it would get alone.

    Parameters
    ----------
    reach_fn : callable
        ``reach_fn(setups (k, 3)) -> (k, n) bool``.
    """

    def __init__(self, reach_fn: Callable[[np.ndarray], np.ndarray]):
        self.reach_fn = reach_fn
        self._memo: dict[bytes, np.ndarray] = {}

    def __call__(self, setups) -> np.ndarray:
        setups = np.ascontiguousarray(check_points("setups", setups, 3))
        if len(setups) == 0:
            return np.asarray(self.reach_fn(setups), dtype=bool)
        keys = [row.tobytes() for row in setups]
        _ask_missing(self._memo, keys, setups, self.reach_fn)
        return np.stack([self._memo[key] for key in keys])


def lookup_reach(grid_setups, cover, fallback: Callable[[np.ndarray], np.ndarray] | None = None):
    """A reach function answering from a precomputed cover matrix.

    It returns exactly what the reach test returned for those setups, so experiments that
    revisit grid setups many times (100 random-sampling repetitions, Table IV) do not redo IK.
    Setups not in ``grid_setups`` go to ``fallback`` (or raise ``KeyError``).

    Parameters
    ----------
    grid_setups : (m, 3) float
    cover : (m, n) bool
        ``cover[j, i]``: setup j reaches patch i.
    """
    grid_setups = check_points("grid_setups", grid_setups, 3)
    cover = np.asarray(cover, dtype=bool)
    if cover.ndim != 2 or cover.shape[0] != len(grid_setups):
        raise ValueError(f"cover must be (m, n) with m = {len(grid_setups)} rows, got {cover.shape}")
    index = {key: j for j, key in enumerate(setup_keys(grid_setups))}

    def reach(setups):
        setups = check_points("setups", setups, 3)
        rows = np.array([index.get(key, -1) for key in setup_keys(setups)], dtype=np.int64)
        out = np.empty((len(setups), cover.shape[1]), dtype=bool)
        hit = rows >= 0
        out[hit] = cover[rows[hit]]
        if not hit.all():
            if fallback is None:
                raise KeyError(f"{int((~hit).sum())} setups are not on the precomputed grid")
            out[~hit] = fallback(setups[~hit])
        return out

    return reach

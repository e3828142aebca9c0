"""Guard selection: arm configurations that inspect the machine from a spot (MAVAC, "Local
exploration", "Camera field of view", "Guard selection").

A guard point is placed on each small cluster of surface elements, along its normal at the guard
stand-off (the camera's reliable detection limit ``L_d``, as the paper says, unless
``GuardParams.standoff`` sets another), with the camera looking back along the normal. A guard
configuration is a collision-free IK solution for that camera pose (the camera may spin freely
about its optical axis). Its visible set is FOV pyramid + HPR (or exact ray casting), its score is
eq. 3, ``I_m^k1 x (N / |S|)^k2``, and guards are chosen with the same greedy selection as spots,
threshold ``P_g`` x the first maximum score.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry.mesh import local_origin
from ..geometry.transforms import check_transform, compose, points_in_frame, vectors_in_frame
from ..params import CameraParams, GuardParams, Visibility
from ..planning.greedy import GreedyResult, greedy_select
from ..robots.kinematics import fk, ik_axis, maneuverability
from ..validate import check_indices, check_points, check_positive
from ..vision.camera import OPTICAL_AXIS, fov_masks
from ..vision.visibility import visible_from

# Random IK restarts per target after the first attempt from the home configuration (ours:
# the reachability map already removed most unreachable targets, so few restarts are needed).
IK_RESTARTS = 4


def guard_targets(points, normals, spacing: float) -> np.ndarray:
    """One representative element per small cluster: a voxel of size ``spacing`` and a
    dominant normal direction (+-x, +-y, +-z), so a cluster never straddles an edge.

    Parameters
    ----------
    points, normals : (n, 3) float
    spacing : float, m

    Returns
    -------
    (k,) int
        Indices into S of the representatives (the member nearest its cluster's mean), sorted.
    """
    points = check_points("points", points)
    normals = check_points("normals", normals)
    check_positive("spacing", spacing)
    if len(points) == 0:
        return np.zeros(0, dtype=np.int64)
    points = points - local_origin(points)  # cells and ties move with S, wherever it sits
    cell = np.floor(points / spacing).astype(np.int64)
    axis = np.argmax(np.abs(normals), axis=1)
    sign = np.sign(normals[np.arange(len(normals)), axis]).astype(np.int64)
    keys = np.column_stack([cell, axis, sign])
    _, label = np.unique(keys, axis=0, return_inverse=True)
    label = label.ravel()
    k = label.max() + 1
    counts = np.bincount(label, minlength=k)
    mean = np.column_stack([np.bincount(label, points[:, d], minlength=k) for d in range(3)]) / counts[:, None]
    dist = np.linalg.norm(points - mean[label], axis=1)
    order = np.lexsort((np.arange(len(points)), dist, label))
    first = order[np.r_[True, label[order][1:] != label[order][:-1]]]
    return np.sort(first)


@dataclass(frozen=True)
class GuardCandidates:
    """Feasible guard configurations of one spot.

    Attributes
    ----------
    target : (g,) int
        Index into S of the element each guard looks at.
    q : (g, nq) float, rad
        Collision-free arm configurations.
    world_T_camera : (g, 4, 4) float
        Camera poses (optical axis = camera x).
    maneuverability : (g,) float in [0, 1]
        I_m of each configuration.
    fov : (g, n) bool
        Elements inside each guard's FOV pyramid (a superset of what it sees).
    n_tried, n_ik : int
        Targets tried after the reachability prefilter, and IK successes before collision.
    """

    target: np.ndarray
    q: np.ndarray
    world_T_camera: np.ndarray
    maneuverability: np.ndarray
    fov: np.ndarray
    n_tried: int = 0
    n_ik: int = 0

    def subset(self, idx) -> GuardCandidates:
        return GuardCandidates(self.target[idx], self.q[idx], self.world_T_camera[idx],
                               self.maneuverability[idx], self.fov[idx], self.n_tried, self.n_ik)

    def __len__(self) -> int:
        return int(len(self.target))


@dataclass(frozen=True)
class GuardSelection:
    """Guards chosen at one spot.

    Attributes
    ----------
    guards : GuardCandidates
        The selected guards, in selection order.
    visible : (k, n) bool
        What each selected guard sees (FOV + HPR or ray casting).
    greedy : GreedyResult
        Indices into the spot's candidates, scores, gains, threshold, coverage after selection.
    n_candidates, n_evaluated : int
        Feasible candidates, and how many have a visibility evaluation (lazy greedy; with a shared
        cache, evaluations of earlier calls count too).
    """

    guards: GuardCandidates
    visible: np.ndarray
    greedy: GreedyResult
    n_candidates: int
    n_evaluated: int


def camera_configurations(robot, checker, world_T_base, positions, axes, rng, q0=None):
    """Collision-free IK for camera poses (optical axis along ``axes``), batched.

    Parameters
    ----------
    robot : RobotModel with a ``camera_frame`` (optical axis = its x axis).
    checker : CollisionChecker
        Against the machine; its base is set to ``world_T_base`` here.
    world_T_base : (4, 4) float
    positions, axes : (k, 3) float, world frame
        Camera origins and optical-axis directions.
    rng : numpy.random.Generator
        IK restarts.

    Returns
    -------
    ok : (k,) bool
        IK converged within limits and the configuration is collision-free.
    q : (k, nq) float
    n_ik : int
        IK successes before the collision check.
    """
    T = check_transform("world_T_base", world_T_base)
    if len(positions) == 0:
        return np.zeros(0, dtype=bool), np.zeros((0, robot.nq)), 0
    res = ik_axis(robot, points_in_frame(T, positions), vectors_in_frame(T, axes), frame=robot.camera_frame, frame_axis=OPTICAL_AXIS,
                  q0=robot.q_home if q0 is None else q0, rng=rng, n_restarts=IK_RESTARTS)
    ok = res.success.copy()
    checker.set_base(T)
    if ok.any():
        ok[ok] = ~np.asarray(checker.in_collision(res.q[ok]), dtype=bool)
    return ok, res.q, int(res.success.sum())


def guard_candidates(robot, checker, world_T_base, points, normals, targets, camera: CameraParams,
                     rng, standoff: float | None = None) -> GuardCandidates:
    """Feasible guards of one spot: batched IK + collision check, and their FOV masks.

    Parameters
    ----------
    robot : RobotModel with a ``camera_frame``.
    checker : CollisionChecker against the machine.
    world_T_base : (4, 4) float
        The spot.
    points, normals : (n, 3) float
        Surface elements S.
    targets : (k,) int
        Elements to place a guard on (already prefiltered with the reachability map).
    camera : CameraParams
    rng : numpy.random.Generator
    standoff : float, optional
        Distance of the camera from its target along the normal, m; default ``camera.L_d``
        (:attr:`mavac.params.InspectionParams.guard_standoff`).
    """
    targets = check_indices("targets", targets, len(points))
    standoff = camera.L_d if standoff is None else check_positive("standoff", standoff)
    positions = points[targets] + standoff * normals[targets]
    ok, q, n_ik = camera_configurations(robot, checker, world_T_base, positions, -normals[targets], rng)
    q = q[ok]
    n = len(points)
    if len(q) == 0:
        return GuardCandidates(np.zeros(0, dtype=np.int64), np.zeros((0, robot.nq)), np.zeros((0, 4, 4)),
                               np.zeros(0), np.zeros((0, n), dtype=bool), len(targets), n_ik)
    world_T_camera = compose(world_T_base, fk(robot, q, robot.camera_frame))
    im = np.asarray(maneuverability(robot, q), dtype=float).reshape(-1)
    return GuardCandidates(targets[ok], q, world_T_camera, im, fov_masks(points, world_T_camera, camera),
                           len(targets), n_ik)


def guard_visibility(world_T_cameras, points, normals, camera: CameraParams, visibility: Visibility,
                     vis_scene=None) -> np.ndarray:
    """What guards see: FOV pyramid AND ``visibility`` (HPR or ray casting), (g, n) bool."""
    return visible_from(points, normals, world_T_cameras, camera, visibility, scene=vis_scene)


def select_guards(candidates: GuardCandidates, points, normals, camera: CameraParams, params: GuardParams,
                  *, visibility: Visibility = Visibility(), covered=None, vis_scene=None,
                  cache: dict | None = None) -> GuardSelection:
    """The paper's greedy guard selection (eq. 3 score, threshold ``P_g`` x first maximum).

    Visibility (HPR or ray casting) is evaluated lazily: the FOV count bounds each candidate's
    score from above, so only candidates that could still be the best are evaluated, and the
    choice is the same as with every candidate evaluated.

    Parameters
    ----------
    candidates : GuardCandidates
    points, normals : (n, 3) float
    camera : CameraParams
    params : GuardParams
        ``P_g``, ``k1``, ``k2``.
    visibility : Visibility
        Default: the package's (exact ray casting, needs ``vis_scene``).
    covered : (n,) bool, optional
        Elements already seen by guards chosen at earlier spots: they are no longer new.
    vis_scene : VisibilityScene, optional
        For ray casting.
    cache : dict, optional
        Candidate index -> visible row; pass the same dict to reuse evaluations across calls
        on the same candidates and visibility (e.g. a P_g sweep).
    """
    cache = {} if cache is None else cache

    def evaluate(idx):
        todo = [i for i in np.asarray(idx).tolist() if i not in cache]
        if todo:
            rows = guard_visibility(candidates.world_T_camera[todo], points, normals, camera, visibility, vis_scene)
            cache.update(zip(todo, rows))
        return np.array([cache[i] for i in np.asarray(idx).tolist()], dtype=bool).reshape(len(idx), len(points))

    g = greedy_select(candidates.fov, params.P_g, weights=candidates.maneuverability, k1=params.k1,
                      k2=params.k2, covered=covered, evaluate=evaluate)
    return GuardSelection(candidates.subset(g.selected), evaluate(g.selected), g, len(candidates), len(cache))

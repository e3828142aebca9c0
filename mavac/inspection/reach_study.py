"""A reach study of a machine, as ROS-Industrial's REACH does one for a workpiece.

REACH (Robotic Evaluation And Comparison Heuristic) generates a target pose on every sample of
the workpiece surface, solves IK for each, scores every solution with an evaluator
(manipulability, for instance) and shows the per-target score as a heat map. Here:

* targets: the surface elements S, each inspected the MAVAC way: the camera on the element's
  normal at the guard stand-off (the detection limit ``L_d`` unless ``GuardParams.standoff``),
  looking back at it (MAVAC, "Local exploration");
* robot placements: every collision-free candidate spot of the offline pipeline
  (:func:`mavac.inspection.inspection_plan.prepare_offline`), the reachability map as a prefilter;
* IK: collision-free camera IK (:func:`mavac.inspection.guards.camera_configurations`);
* evaluator: the maneuverability index I_m of the configuration (MAVAC eq. 4, Vahrenkamp et al.),
  times 1 if the camera actually sees the element from there (``params.visibility``: ray casting
  by default, or HPR), else 0.

Each element keeps its best score over all spots; 0 means no spot reaches a camera pose that
sees it. The result goes to a CSV (one row per element) and an HTML heat map with a colour bar
(:func:`mavac.viz.scenes.reach_study_html`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

from ..io import write_csv
from ..params import InspectionParams
from ..robots.kinematics import maneuverability
from ..seeding import rng_for
from ..viz.scenes import reach_study_html
from .guards import camera_configurations
from .inspection_plan import prepare_offline
from .reachability import reachability_map
from .spots import se2_matrices


@dataclass
class ReachStudy:
    """Per-element result of :func:`reach_study`.

    Attributes
    ----------
    machine_name, robot_name : str
    visibility : str
        ``"raycast"`` or ``"hpr"``: what decided ``visible``.
    points, normals : (n, 3) float
        Surface elements S (world frame, m) and outward normals.
    candidates : (m, 3) float
        Collision-free candidate spots ``(x, y, theta)``.
    reached : (n,) bool
        Some spot has a collision-free IK solution for the element's camera pose.
    visible : (n,) bool
        The element is seen from its camera pose (independent of the spot).
    maneuverability : (n,) float in [0, 1]
        Best I_m over the spots that reach it (0 if none).
    score : (n,) float in [0, 1]
        ``maneuverability * visible``: the heat map.
    best_spot : (n,) int
        Candidate of the best score (-1 if none).
    best_q : (n, nq) float
        Arm configuration of the best score (NaN if none).
    params : InspectionParams
    timings : dict
    """

    machine_name: str
    robot_name: str
    visibility: str
    points: np.ndarray
    normals: np.ndarray
    candidates: np.ndarray
    reached: np.ndarray
    visible: np.ndarray
    maneuverability: np.ndarray
    score: np.ndarray
    best_spot: np.ndarray
    best_q: np.ndarray
    params: InspectionParams
    timings: dict = field(default_factory=dict)
    mesh: object = field(default=None, repr=False)

    @property
    def reach_fraction(self) -> float:
        """Share of S with a positive score (reached and seen), REACH's "reach percentage"."""
        return float(np.mean(self.score > 0)) if len(self.score) else 0.0

    @property
    def mean_score(self) -> float:
        """Mean score over S (REACH's normalised total pose score)."""
        return float(np.mean(self.score)) if len(self.score) else 0.0

    def summary(self) -> str:
        """A few lines a person can read."""
        n = len(self.points)
        return (f"{self.machine_name}: reach study ({self.visibility} visibility) over |S| = {n} surface elements "
                f"from {len(self.candidates)} candidate spots: {100 * self.reach_fraction:.1f} % reached and seen "
                f"(reached {int(self.reached.sum())}, seen from their camera pose {int(self.visible.sum())}), "
                f"mean score {self.mean_score:.3f}")

    def to_frame(self):
        """One row per element: position, normal, reached, visible, maneuverability, score, best spot and
        configuration (pandas DataFrame)."""
        import pandas as pd

        cols = {"x": self.points[:, 0], "y": self.points[:, 1], "z": self.points[:, 2],
                "nx": self.normals[:, 0], "ny": self.normals[:, 1], "nz": self.normals[:, 2],
                "reached": self.reached, "visible": self.visible, "maneuverability": self.maneuverability,
                "score": self.score, "best_spot": self.best_spot}
        spot = np.full((len(self.points), 3), np.nan)
        ok = self.best_spot >= 0
        spot[ok] = self.candidates[self.best_spot[ok]]
        cols.update(spot_x=spot[:, 0], spot_y=spot[:, 1], spot_theta=spot[:, 2])
        cols.update({f"q{j + 1}": self.best_q[:, j] for j in range(self.best_q.shape[1])})
        return pd.DataFrame(cols)

    def to_csv(self, path):
        """Write :meth:`to_frame` atomically."""
        return write_csv(self.to_frame(), path)

    def to_html(self, path, robot=None):
        """Heat map with a colour bar (:func:`mavac.viz.scenes.reach_study_html`)."""
        return reach_study_html(self, path, robot=robot)


def seen_from_camera_pose(ctx) -> np.ndarray:
    """Whether each element is seen from its own camera pose (normal at the guard stand-off),
    (n,) bool, by ``ctx.params.visibility``: ray casting (nothing of the machine or the floor on
    the segment) or HPR over S from that viewpoint (one HPR per element).
    """
    vis = ctx.params.visibility
    cam = ctx.points + ctx.params.guard_standoff * ctx.normals
    seen = vis.visible_each(ctx.points, ctx.normals, cam, scene=ctx.vis_scene)
    # The mesh scene has no floor; exact visibility adds it (the guard clearance). HPR is
    # position-only over S, as in the paper.
    return seen & ctx.clear if vis.method == "raycast" else seen


def reach_study(mesh_or_machine, robot=None, params: InspectionParams | None = None, *,
                rmap=None, progress: bool = False) -> ReachStudy:
    """Best reach-and-visibility score of every surface element over the candidate spots.

    Parameters
    ----------
    mesh_or_machine : Machine or trimesh.Trimesh
        Metres, z up, on the floor.
    robot : RobotModel, optional
        Default :func:`mavac.robots.models.ur10_mobile`.
    params : InspectionParams, optional
        Surface spacing, guard stand-off, spot candidates, reachability map, seed, and
        ``visibility``: how "the camera sees the element" is decided (ray casting is exact).
    rmap : ReachabilityMap, optional
    progress : bool
        tqdm progress over the spots.
    """
    t0 = time.perf_counter()
    ctx = prepare_offline(mesh_or_machine, robot=robot, params=params, rmap=rmap)
    rmap = reachability_map(ctx.robot, ctx.params.reach) if rmap is None else rmap
    timings = {"prepare": time.perf_counter() - t0}
    P, N = ctx.points, ctx.normals
    n, nq = len(P), ctx.robot.nq
    cam = P + ctx.params.guard_standoff * N

    t0 = time.perf_counter()
    visible = seen_from_camera_pose(ctx)
    timings["visibility"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    best_im = np.full(n, -1.0)  # any reached configuration beats it, even with I_m = 0
    best_spot = np.full(n, -1, dtype=np.int64)
    best_q = np.full((n, nq), np.nan)
    reached = np.zeros(n, dtype=bool)
    world_T_spots = se2_matrices(ctx.candidates) if len(ctx.candidates) else np.zeros((0, 4, 4))
    for k in tqdm(range(len(world_T_spots)), desc="spots", disable=not progress, leave=False):
        T = world_T_spots[k]
        todo = np.flatnonzero(rmap.is_reachable_from(T, cam, -N))
        if len(todo) == 0:
            continue
        rng = rng_for(ctx.params.seed, "reach study camera", k)
        ok, q, _ = camera_configurations(ctx.robot, ctx.checker, T, cam[todo], -N[todo], rng)
        if not ok.any():
            continue
        hit = todo[ok]
        im = np.asarray(maneuverability(ctx.robot, q[ok]), dtype=float).reshape(-1)
        reached[hit] = True
        better = im > best_im[hit]
        best_im[hit[better]] = im[better]
        best_spot[hit[better]] = k
        best_q[hit[better]] = q[ok][better]
    timings["ik"] = time.perf_counter() - t0
    best_im = np.maximum(best_im, 0.0)
    return ReachStudy(ctx.machine.name, ctx.robot.name, ctx.params.visibility.method, P, N, ctx.candidates, reached, visible,
                      best_im, best_im * visible, best_spot, best_q, ctx.params, timings, ctx.machine.mesh)

"""One MAVAC online trial in simulation (Algorithm 1) on an offline plan.

For every pose ``G_m`` of the plan's pose set T, in order: drive the base to its spot (arm
folded home first), move the arm to the guard configuration (RRT-Connect, tracked in torque
control), take an RGB-D image, detect dust, filter the nodes, cluster them into areas and, per
area, find an approach point (eq. 5), plan to it, vacuum its nodes under impedance control and
return to the approach point. The result scores the heaps (cleaned or the cause of the miss),
detection precision and recall, and the simulated time per activity.

Same seed, same result, on any load: every planner stops on an iteration budget, and the
wall-time caps only raise :class:`mavac.planning.rrt.PlanningTimeout`. Every random stream
comes from :mod:`mavac.seeding`, one stage name per use (``"guard motion"``, ``"fold motion"``,
``"approach"``, ``"approach motion"``), indexed by pose, area and attempt.

No hidden failures, and the arm never teleports. A guard or fold-home motion that RRT-Connect
cannot plan is planned once more with ``rrt_retry_factor`` times the budget. A guard that still
fails is skipped and counted (``guards_unreachable``). A fold-home that still fails is counted
(``fold_failures``) and the arm retraces, in reverse, the joint path it executed since it left
home (collision-free when executed, at the same base pose: ``folds_retraced``); only if that
path is no longer free does the trial stop, counting the poses it skipped. Heaps that only a
skipped pose would have seen get the miss cause ``"guard not reached"``.

Under a :class:`mavac.params.PerturbationParams` (``params.perturbation``) the world departs
from the plan (:mod:`mavac.cleaning.perturbation`): the simulator places the base, renders and
scores in the true frame, while the robot plans, detects and filters in the frame it believes.
Every contact the arm makes with the machine while it tracks a planned motion (not while it
vacuums) is logged (``transit_contacts``).

A trial never raises for a hard scene: no heaps, an empty plan, nothing in view, no dust
detected or an unreachable area give a result (0 % where nothing was cleaned) with the reason.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

from ..geometry.machines import Machine
from ..geometry.transforms import matrix_to_se2, se2_to_matrix, transform_points
from ..inspection.spots import collision_free_spots
from ..params import OnlineParams
from ..robots.kinematics import fk
from ..robots.models import RobotModel, ur10_mobile
from ..seeding import check_seed, int_seed, rng_for
from ..sim.render import intrinsics_from_fov, mavac_T_opencv, render_rgbd
from ..sim.world import SimWorld
from ..validate import check_bool, check_instance
from .approach import find_approach
from .clustering import areas_from_nodes
from .detection import detect_dust, match_nodes
from .filters import FILTERS, filter_nodes
from .heaps import heaps_for_trial
from .misses import (CAUSE_DTYPE, CAUSES, HeapEvents, cause_counts, in_frustum, mark_blobs, miss_causes,
                     near_frustum)
from .motion import Motion, plan_arm_motion
from .perturbation import decoy_positions, localisation_error, machine_motion, noisy_images, true_base_pose
from .replay import Replay, ReplayRecorder
from .scene import build_cell
from .timing import TrialTimes, base_path_length
from .vacuum import vacuum_area

#: Ours: render clipping planes, m (the Kinect body around the camera origin is nearer than
#: ``NEAR``; the depth filter, not the far plane, bounds detection).
NEAR, FAR = 0.05, 5.0
#: Ours: only heaps whose sphere comes within this distance (m) of the view frustum enter the
#: world to be rendered (the others cannot show in the image; the slack covers any difference
#: between the renderer's projection and ``K``).
VIEW_MARGIN = 0.05


@dataclass
class TrialResult:
    """Outcome of :func:`run_trial`.

    Attributes
    ----------
    machine : str
    seed : int
    heaps : (n, 3) float
        True heap positions, m.
    cleaned : (n,) bool
    causes : (n,) str
        Cause of each miss (:data:`mavac.cleaning.misses.CAUSES`), ``""`` where cleaned.
    detected : int
        Nodes with a position (HSV blob with depth), over all images.
    true_positives : int
        Of those, nodes within ``match_radius`` of a true heap.
    recalled : int
        Heaps matched by at least one node.
    times : TrialTimes
    peak_forces : list of float, N
        Peak machine contact force of every vacuuming move.
    filtered : dict
        Nodes dropped per filter.
    areas, areas_cleaned : int
    guards : int
        Poses visited (``guards + poses_skipped`` is the plan's number of poses).
    replanned : int
        Guard and fold-home motions solved only by the re-plan with the larger budget.
    guards_unreachable : int
        Guard motions that failed even with the larger budget (the pose is skipped).
    fold_failures : int
        Fold-home motions that failed even with the larger budget.
    folds_retraced : int
        Of those, folds done by retracing the joint path executed since the arm left home.
    poses_skipped : int
        Poses never inspected from: unreachable guards, and the poses left when the arm could
        neither fold nor retrace (the trial stops there: the base cannot drive).
    reason : str
        Why nothing could be done (no heaps, empty plan), else ``""``.
    warnings : list of str
    wall_s : float
        Wall time of the trial, s (non-deterministic, like ``times.planning_wall_s`` and
        ``rrt_approach_seconds``).
    rrt_approach_seconds : list of float
        Wall time of every RRT-Connect approach plan, s.
    replay : mavac.cleaning.replay.Replay or None
        The robot's motion and each heap's removal time on the simulated clock (None when
        nothing ran: no heaps, or an empty plan); :meth:`to_html` plays it.
    seen_by : (n,) int or None
        Per heap, the first pose of the plan (a row of ``plan.poses``) whose detection found it
        (a node matched to it), -1 if none did (scoring only: the match uses the true positions).
    transit_contacts : list of float, N
        Peak robot-machine normal force of every tracked motion (guard, approach, fold home)
        during which the arm touched the machine; vacuuming contact is in ``peak_forces``.
    spots_blocked : int
        Drives that could not stop at their spot because the robot would collide with the
        machine there (only under a perturbation); their poses are skipped.
    """

    machine: str
    seed: int
    heaps: np.ndarray
    cleaned: np.ndarray
    causes: np.ndarray
    detected: int = 0
    true_positives: int = 0
    recalled: int = 0
    times: TrialTimes = field(default_factory=TrialTimes)
    peak_forces: list = field(default_factory=list)
    filtered: dict = field(default_factory=lambda: {name: 0 for name in FILTERS})
    areas: int = 0
    areas_cleaned: int = 0
    guards: int = 0
    replanned: int = 0
    guards_unreachable: int = 0
    fold_failures: int = 0
    folds_retraced: int = 0
    poses_skipped: int = 0
    reason: str = ""
    warnings: list = field(default_factory=list)
    wall_s: float = 0.0
    rrt_approach_seconds: list = field(default_factory=list)
    replay: Replay | None = None
    seen_by: np.ndarray | None = None
    transit_contacts: list = field(default_factory=list)
    spots_blocked: int = 0

    @property
    def n_heaps(self) -> int:
        return int(len(self.heaps))

    @property
    def n_cleaned(self) -> int:
        return int(np.count_nonzero(self.cleaned))

    @property
    def cleaning_pct(self) -> float:
        """Cleaned heaps in per cent (0 when there are none)."""
        return 100.0 * self.n_cleaned / self.n_heaps if self.n_heaps else 0.0

    @property
    def precision(self) -> float:
        """Detected nodes that are real heaps (NaN when nothing was detected)."""
        return self.true_positives / self.detected if self.detected else float("nan")

    @property
    def recall(self) -> float:
        """Heaps detected at least once (NaN when there are no heaps)."""
        return self.recalled / self.n_heaps if self.n_heaps else float("nan")

    def miss_counts(self) -> dict:
        return cause_counts(self.causes)

    def summary(self) -> str:
        """A few lines a person can read: heaps cleaned of all and in per cent, the cause of
        every miss with its count, the simulated time (base, arm, vacuum) and the wall time, s;
        then the reason nothing could be done, if any, and the warnings."""
        t = self.times
        misses = ", ".join(f"{cause} {n}" for cause, n in self.miss_counts().items() if n) or "none"
        lines = [f"{self.machine}, seed {self.seed}: {self.n_cleaned} of {self.n_heaps} heaps cleaned "
                 f"({self.cleaning_pct:.1f} %)",
                 f"  misses: {misses}",
                 f"  simulated time {t.sim_time_s:.1f} s (base {t.base_s:.1f}, arm {t.arm_s:.1f}, vacuum "
                 f"{t.vacuum_s:.1f}); wall time {self.wall_s:.1f} s"]
        if self.reason:
            lines.append(f"  reason: {self.reason}")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def heap_table(self):
        """One row per heap: ``heap`` (index), ``x``, ``y``, ``z`` (true position, m),
        ``cleaned`` (bool), ``cause`` (:data:`mavac.cleaning.misses.CAUSES`, ``""`` where
        cleaned) and ``seen_by_pose`` (the first pose of the plan whose detection found the
        heap, -1 if none did; a heap vacuumed beside another can be cleaned unseen).

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        heaps = np.asarray(self.heaps, dtype=float).reshape(-1, 3)
        return pd.DataFrame({"heap": np.arange(len(heaps)), "x": heaps[:, 0], "y": heaps[:, 1], "z": heaps[:, 2],
                             "cleaned": np.asarray(self.cleaned, dtype=bool),
                             "cause": np.asarray(self.causes).astype(str),
                             "seen_by_pose": np.full(len(heaps), -1) if self.seen_by is None else self.seen_by})

    def to_html(self, path, machine, *, robot=None):
        """Write the trial's meshcat replay (:func:`mavac.viz.scenes.trial_replay_html`): the
        robot through its poses, heaps vanishing as they are vacuumed, misses coloured by cause.

        Parameters
        ----------
        path : str or Path
            The HTML file.
        machine : Machine
            The machine the trial ran on.
        robot : RobotModel, optional
            The trial's robot (default: the UR10 on its mobile base).

        Returns
        -------
        Path
        """
        from ..viz.scenes import trial_replay_html

        check_instance("machine", machine, Machine)
        if self.replay is None:
            raise ValueError(f"this trial has nothing to replay ({self.reason or 'no replay recorded'})")
        if machine.name != self.machine:
            raise ValueError(f"machine must be the trial's machine {self.machine!r}, got {machine.name!r}")
        return trial_replay_html(self, machine, path, robot=robot)

    def row(self) -> dict:
        """One trial's row: the Table 2 columns (``data/results/mavac_table2.csv``), then
        ``guards``, ``replanned``, ``guards_unreachable``, ``fold_failures``, ``folds_retraced``
        and ``poses_skipped`` (failed motions are counted, never hidden), the motions that touched
        the machine and their largest force (N), the spots the base could not stop at, then the
        simulated and wall time, s."""
        return dict(machine=self.machine, trial=None, seed=self.seed, heaps=self.n_heaps, cleaned=self.n_cleaned,
                    uncleaned=self.n_heaps - self.n_cleaned, cleaning_pct=round(self.cleaning_pct, 3),
                    detected=self.detected, precision=round(self.precision, 4), recall=round(self.recall, 4),
                    guards=self.guards, replanned=self.replanned, guards_unreachable=self.guards_unreachable,
                    fold_failures=self.fold_failures, folds_retraced=self.folds_retraced,
                    poses_skipped=self.poses_skipped, transit_contacts=len(self.transit_contacts),
                    transit_peak_force=round(max(self.transit_contacts, default=0.0), 1),
                    spots_blocked=self.spots_blocked,
                    sim_time_s=round(self.times.sim_time_s, 3),
                    wall_s=round(self.wall_s, 2))


class _Run:
    """State of a trial in progress (cell, heaps' events, vacuumed nodes, counters, and the joint
    path executed since the arm left home)."""

    def __init__(self, cell, machine: Machine, params: OnlineParams, seed: int, result: TrialResult, camera):
        self.cell, self.machine, self.params, self.seed, self.result = cell, machine, params, seed, result
        self.events = HeapEvents.empty(result.n_heaps)
        self.vacuumed = np.zeros((0, 3))
        self.matched = np.zeros(result.n_heaps, dtype=bool)
        self.since_home: list[np.ndarray] = []  # tracked joint paths since the arm left home
        d = params.detection
        self.fov_y = float(np.degrees(2.0 * camera.theta_b))  # the FOV pyramid's height
        self.K = intrinsics_from_fov(d.width, d.height, self.fov_y)
        self.recorder = ReplayRecorder(matrix_to_se2(cell.world_T_base), cell.q_cmd, result.n_heaps)
        self.plan_T_moved = machine_motion(machine.mesh, params.perturbation, seed)
        self.drives = self.images = 0  # indices of the localisation and image-noise draws

    def execute(self, plan, progress: bool = False) -> None:
        """Algorithm 1, line 1-3 and the loop: every pose of T in order, folding and driving
        between spots; stops (counting the skipped poses) only when the arm cannot fold.
        ``progress``: a tqdm bar over the poses, with the heaps cleaned so far."""
        n = self.result.n_heaps
        with tqdm(total=len(plan.poses), desc="guard poses", unit="pose", disable=not progress, leave=False) as bar:
            reached = True
            for i, pose in enumerate(plan.poses):
                if i == 0 or plan.pose_spot[i] != plan.pose_spot[i - 1]:
                    if i > 0 and not self.fold_home(i):
                        self.skip(plan.poses[i:], f"arm could not fold home before pose {i}")
                        return
                    reached = self.drive_to(pose[:3])
                if reached:
                    self.inspect_and_clean(i, pose)
                else:
                    self.skip(pose, f"pose {i}: the base cannot stop at its spot (the machine is in the way)")
                bar.set_postfix_str(f"{int(np.count_nonzero(self.cell.dust.cleaned))} of {n} heaps cleaned",
                                    refresh=False)
                bar.update()

    def plan(self, q_goal, stage: str, index: int) -> Motion:
        """RRT-Connect from the commanded configuration to ``q_goal``; if it fails, once more
        with ``rrt_retry_factor`` times the budget (each attempt its own seed)."""
        a = self.params.approach
        factors = (1,) if a.rrt_retry_factor == 1 else (1, a.rrt_retry_factor)
        for attempt, factor in enumerate(factors):
            motion = plan_arm_motion(self.cell.robot, self.cell.checker, self.cell.q_cmd, q_goal, a,
                                     seed=int_seed(self.seed, stage, index, attempt), budget_factor=factor)
            self.result.times.planning_wall_s += motion.seconds
            if motion.solved:
                self.result.replanned += attempt
                break
        return motion

    def track(self, path) -> None:
        """Follow a joint path (its first row is the commanded configuration) and record it."""
        path = np.asarray(path, dtype=float)
        seconds = self.cell.track(path[1:], self.params)
        self.result.times.arm_s += seconds
        self.recorder.arm_path(path, seconds)
        self.since_home.append(path)

    def fold_home(self, i: int) -> bool:
        """Fold the arm home before driving: plan (with the re-plan), else retrace the path
        executed since home. False only if neither is possible (the arm never teleports)."""
        cell, r = self.cell, self.result
        motion = self.plan(cell.robot.q_home, "fold motion", i)
        if not motion.solved:
            r.fold_failures += 1
            r.warnings.append(f"arm home before pose {i}: RRT-Connect failed ({motion.reason}), retracing")
            back = self.retrace()
            if back is None:
                return False
            motion = Motion(back, True, "retraced", 0.0)
            r.folds_retraced += 1
        self.track(motion.path)
        self.since_home = []
        return True

    def retrace(self) -> np.ndarray | None:
        """(k, nq) the joint path executed since home, reversed (from the commanded
        configuration to home), or None if there is none or it is no longer collision-free."""
        if not self.since_home:
            return None
        back = np.vstack([p[::-1] for p in self.since_home[::-1]])
        back = back[np.r_[True, np.any(np.diff(back, axis=0) != 0.0, axis=1)]]  # paths share ends
        if len(back) < 2 or np.any(self.cell.checker.in_collision(back)):
            return None
        return back

    def drive_to(self, spot) -> bool:
        """Drive the base (arm folded) to ``spot`` (x, y, theta), along the shortest path around
        the machine. False, with the base left where it was, when the robot would collide with
        the machine where it really lands (the offline test of a spot,
        :func:`mavac.inspection.spots.collision_free_spots`): its safety scanners stop it."""
        cell, perturbation = self.cell, self.params.perturbation
        believed = se2_to_matrix(*spot)
        truth = true_base_pose(believed, self.plan_T_moved, localisation_error(perturbation, self.seed, self.drives))
        self.drives += 1
        if not np.array_equal(truth, believed) and not collision_free_spots(cell.robot, self.machine.mesh,
                                                                            [matrix_to_se2(truth)])[0]:
            self.result.spots_blocked += 1
            return False
        length = base_path_length(cell.world_T_base[:2, 3], spot[:2], self.machine.footprint,
                                  self.params.base_clearance)
        self.result.times.base_s += length / self.params.base_speed
        shown = spot if perturbation.is_null else matrix_to_se2(truth)  # the replay shows the truth
        self.recorder.base_drive(shown, length / self.params.base_speed)
        cell.move_base(believed, true_world_T_base=truth)
        return True

    def skip(self, poses, why: str) -> None:
        """Count ``poses`` (rows of T) as skipped; heaps in their planned view frustums are marked
        so that a miss there has its cause."""
        d, robot = self.params.detection, self.cell.robot
        for pose in np.atleast_2d(poses):
            planned = se2_to_matrix(*pose[:3]) @ fk(robot, pose[3:], robot.camera_frame)
            world_T_camera = self.cell.truth_T_belief @ planned @ mavac_T_opencv()
            seen = in_frustum(self.cell.dust.positions, world_T_camera, self.K, d.width, d.height, NEAR, FAR)
            self.events.mark("in_skipped_view", np.flatnonzero(seen))
        self.result.poses_skipped += len(np.atleast_2d(poses))
        self.result.warnings.append(f"{why}: {len(np.atleast_2d(poses))} pose(s) skipped")

    def look(self):
        """RGB-D image (with the perturbation's noise) from the camera where the arm really is;
        marks frustum/image ground truth. Returns rgb, depth, world_T_camera as the robot
        estimates it, and (h, w) the heap index drawn at each pixel (-1: none; scoring only)."""
        d, cell = self.params.detection, self.cell
        world_T_camera = cell.sim.world_T_link(cell.robot.camera_frame) @ mavac_T_opencv()
        shown = near_frustum(cell.dust.positions, world_T_camera, self.K, d.width, d.height, NEAR, FAR,
                             cell.dust.radius + VIEW_MARGIN)
        with cell.dust.in_view(cell.world, shown) as bodies:
            rgb, depth, seg = render_rgbd(cell.world.client, world_T_camera, width=d.width, height=d.height,
                                          fov_y_deg=self.fov_y, near=NEAR, far=FAR)
        present = np.flatnonzero(cell.dust.present)
        self.events.mark("in_frustum", present[in_frustum(cell.dust.positions[present], world_T_camera, self.K,
                                                          d.width, d.height, NEAR, FAR)])
        ids, inverse = np.unique(seg, return_inverse=True)
        heap_of_id = cell.dust.index_of_bodies(ids, bodies)
        self.events.mark("in_image", heap_of_id)
        rgb, depth = noisy_images(rgb, depth, self.params.perturbation, self.seed, self.images)
        self.images += 1
        return (rgb, depth, np.linalg.solve(cell.truth_T_belief, world_T_camera),
                heap_of_id[inverse].reshape(np.shape(seg)))

    def inspect_and_clean(self, i: int, pose) -> None:
        """Algorithm 1, lines 3-16 at pose ``i`` (a row of T: spot, then guard configuration)."""
        motion = self.plan(pose[3:], "guard motion", i)
        if not motion.solved:
            self.result.guards_unreachable += 1
            self.skip(pose, f"guard {i}: RRT-Connect failed ({motion.reason})")
            return
        self.track(motion.path)
        self.result.guards += 1
        rgb, depth, world_T_camera, seg_heaps = self.look()
        det = detect_dust(rgb, depth, self.K, world_T_camera, self.params.detection)
        located = np.all(np.isfinite(det.nodes), axis=1)
        heap_of = match_nodes(transform_points(self.cell.truth_T_belief, det.nodes), self.cell.dust.positions,
                              self.params.detection.match_radius)  # scoring, in the true frame
        mark_blobs(self.events, det.blobs, seg_heaps, heap_of)
        self.result.detected += int(located.sum())
        self.result.true_positives += int(np.count_nonzero(heap_of[located] >= 0))
        found = heap_of[heap_of >= 0]
        self.matched[found] = True
        self.result.seen_by[found[self.result.seen_by[found] < 0]] = i
        shoulder = self.cell.world_T_link(SHOULDER_LINK)[:3, 3]
        world_T_guard_tool = self.cell.world_T_tool()
        why = filter_nodes(det.nodes, det.depth, shoulder=shoulder, vacuumed=self.vacuumed,
                           params=self.params.detection, tip=world_T_guard_tool[:3, 3])
        for name in FILTERS:
            self.result.filtered[name] += int(np.count_nonzero(why == name))
        kept = np.flatnonzero(why == "")
        a = self.params.approach
        areas = areas_from_nodes(det.nodes[kept], eps=a.cluster_eps, min_samples=a.cluster_min_samples,
                                 node_order=a.node_order, area_order=a.area_order)
        for k, area in enumerate(areas):
            self.clean_area((i, k), det.nodes[kept][area], heap_of[kept][area], world_T_guard_tool)

    def clean_area(self, where, nodes, heaps, world_T_guard_tool) -> None:
        """Approach (eq. 5), vacuum, return; records the heaps' fate. ``where`` is (pose, area)."""
        cell, p = self.cell, self.params
        self.result.areas += 1
        approach = find_approach(cell.robot, cell.checker, cell.world_T_base, nodes, world_T_guard_tool, cell.q_cmd,
                                 p.approach, rng=rng_for(self.seed, "approach", *where),
                                 seed=int_seed(self.seed, "approach motion", *where))
        self.result.times.planning_wall_s += approach.planning_seconds
        self.result.rrt_approach_seconds += [a[2] for a in approach.attempts if a[1] != "no approach found"]
        if not approach.success:
            self.events.mark("no_approach" if approach.reason == "no approach found" else "planner_failed", heaps)
            return
        self.track(approach.motion.path)
        order = np.r_[approach.node:len(nodes), 0:approach.node]  # start at the approached node
        self.events.mark("attempted", heaps)
        # The vacuum moves end back at the approach configuration (Algorithm 1, line 13), so the
        # recorded paths stay one chain from home.
        log = vacuum_area(cell, approach.world_T_approach, nodes[order], p.vacuum)
        self.vacuumed = np.vstack([self.vacuumed, nodes])
        self.result.times.vacuum_s += log.seconds
        self.recorder.vacuuming(log.samples, log.sucked, log.sucked_at, log.seconds)
        self.result.peak_forces += log.peak_forces
        self.result.areas_cleaned += int(len(log.sucked) > 0)
        cell.q_cmd = np.array(approach.q, dtype=float)


#: link whose origin is the centre of the arm's reachable sphere (UR10 shoulder)
SHOULDER_LINK = "shoulder_link"


def _empty_result(name: str, seed: int, heaps, reason: str) -> TrialResult:
    n = len(heaps)
    causes = np.full(n, CAUSES[0], dtype=CAUSE_DTYPE)
    return TrialResult(name, seed, np.asarray(heaps).reshape(-1, 3), np.zeros(n, dtype=bool), causes, reason=reason,
                       seen_by=np.full(n, -1, dtype=np.int64))


def run_trial(machine: Machine, plan, *, robot=None, params: OnlineParams | None = None, seed: int = 0,
              progress: bool = False) -> TrialResult:
    """One online cleaning trial (Algorithm 1) in pybullet.

    Parameters
    ----------
    machine : Machine
    plan : mavac.inspection.inspection_plan.InspectionPlan
        Offline plan of ``machine`` (spots, guards, NoS guards in execution order).
    robot : RobotModel, optional
        The plan's robot (default :func:`mavac.robots.models.ur10_mobile`).
    params : OnlineParams, optional
    seed : int, in [0, 2**31 - 1]
        Heap layout, orientation samples, IK restarts and RRT-Connect seeds (checked once here;
        every stream is spawned from it by :mod:`mavac.seeding`).
    progress : bool
        A tqdm bar over the plan's poses (guards and NoS guards visited, heaps cleaned so far).

    Returns
    -------
    TrialResult
        No pybullet client stays connected, also when this raises.

    Raises
    ------
    mavac.planning.rrt.PlanningTimeout
        If a planner's wall-time safety net fires (the result would depend on the load).
    """
    from ..inspection.inspection_plan import InspectionPlan

    t0 = time.perf_counter()
    check_instance("machine", machine, Machine)
    robot = ur10_mobile() if robot is None else check_instance("robot", robot, RobotModel)
    params = OnlineParams() if params is None else check_instance("params", params, OnlineParams)
    seed = check_seed(seed)
    progress = check_bool("progress", progress)
    check_instance("plan", plan, InspectionPlan)
    if robot.name != plan.robot_name:  # the guards are joint configurations of the plan's robot
        raise ValueError(f"robot {robot.name!r} is not the plan's robot {plan.robot_name!r}; plan for it with "
                         f"plan_inspection(machine, robot=...)")
    heaps = heaps_for_trial(machine, params.dust, seed)
    if not len(heaps):
        return _empty_result(machine.name, seed, heaps, "no heaps: the machine has no upward-facing surface")
    if len(plan.poses) == 0:
        return _empty_result(machine.name, seed, heaps, "empty plan: no guard pose to inspect from")
    result = _empty_result(machine.name, seed, heaps, "")
    with SimWorld(time_step=params.time_step, seed=seed) as world:
        cell = build_cell(world, machine, robot, heaps, params, se2_to_matrix(*plan.poses[0, :3]),
                          decoys=decoy_positions(machine.mesh, params.perturbation.decoys, seed))
        run = _Run(cell, machine, params, seed, result, plan.params.camera)
        run.execute(plan, progress)
        result.cleaned = cell.dust.cleaned.copy()
        result.transit_contacts = list(cell.transit_contacts)
        result.replay = run.recorder.replay()
    _score(result, run)
    result.wall_s = time.perf_counter() - t0
    return result


def _score(result: TrialResult, run: _Run) -> None:
    """Recall, the cause of each miss, and the reason when nothing was detected."""
    result.recalled = int(np.count_nonzero(run.matched))
    result.causes = miss_causes(run.events, result.cleaned)
    if result.detected == 0:
        result.reason = "no dust detected from any guard pose"

"""Systematic cleaning, the baseline MAVAC names but does not run ("a comparison with systematic
coverage ... would be valuable", "challenging due to the lack of established baselines").

From the offline plan's spots, in the plan's order, the tool vacuums every surface dust can rest
on, whether dust lies there or not:

1. **Raster.** The faces within 60 deg of horizontal (where :func:`mavac.geometry.machines.dust_heaps`
   puts heaps) are cut by vertical planes ``line_spacing`` apart with the package's plane slicing
   (:func:`mavac.scrubbing.toolpath.slice_curves`, Kabir's Sec. VI), across the surface's long
   horizontal axis; the lines are resampled every ``waypoint_spacing`` and ordered back and forth
   (:func:`mavac.scrubbing.toolpath.boustrophedon`).
2. **Reach.** A spot and a tool axis reach a waypoint when the tool reaches it along the axis
   and the configuration ``delta`` back along the axis is collision-free: the test
   :mod:`mavac.cleaning.approach` applies to a node (eq. 5). The axes are straight down and
   ``n_orientations - 1`` tilted by eq. 5's ``alpha``: the online loop's orientation freedom.
3. **Passes.** Each line is cut into the fewest runs of consecutive waypoints that one spot and
   one axis reach (:func:`runs_of_line`). At each spot (the arm folded before the base drives,
   as in Algorithm 1) the arm plans to ``delta`` back from a pass's first waypoint
   (RRT-Connect, with the online loop's re-plan), moves in onto it, follows the waypoints at the
   vacuuming speed and backs out at the last one, all under the impedance control and suction
   of :mod:`mavac.cleaning.vacuum`.

No camera and no detection: the heaps only score. Motion bookkeeping (folding, retracing, the
replay) is the online trial's (:mod:`mavac.cleaning.trial`), so both loops are timed alike.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..geometry.machines import DUST_MIN_NORMAL_Z, Machine
from ..geometry.transforms import se2_to_matrix
from ..params import OnlineParams, SystematicParams
from ..robots.collision import CollisionChecker
from ..robots.kinematics import fk, ik, ik_axis
from ..robots.models import RobotModel, TOOL_SPHERE_RADIUS, ur10_mobile
from ..scrubbing.toolpath import boustrophedon, resample_polyline, slice_curves
from ..seeding import check_seed, rng_for
from ..sim.world import SimWorld
from ..validate import check_instance
from .approach import IK_RESTARTS
from .heaps import heaps_for_trial
from .replay import Replay
from .scene import build_cell
from .timing import TrialTimes
from .trial import TrialResult, _empty_result, _Run
from .vacuum import VacuumLog, linear_move, path_move

#: Ours: the tool's first axis over the raster, straight down: dust rests on faces within 60 deg
#: of horizontal, and a vertical tube reaches into concavities from above (:func:`tool_axes`
#: adds eq. 5's tilts)
TOOL_AXIS = np.array([0.0, 0.0, -1.0])


def line_spacing(params: SystematicParams, online: OnlineParams) -> float:
    """Distance between raster lines, m: ``params.line_spacing``, else the width the suction
    sweeps, ``2 sqrt(r_s**2 - rho**2)`` (``rho`` the tool sphere's radius)."""
    if params.line_spacing is not None:
        return float(params.line_spacing)
    r_s = online.vacuum.suction_radius
    if r_s <= TOOL_SPHERE_RADIUS:
        raise ValueError(f"suction_radius must exceed the tool sphere's radius {TOOL_SPHERE_RADIUS} m to sweep a "
                         f"width, got {r_s}; give SystematicParams.line_spacing")
    return 2.0 * float(np.sqrt(r_s**2 - TOOL_SPHERE_RADIUS**2))


def _area_covariance_xy(mesh) -> np.ndarray:
    """(2, 2) covariance of the horizontal position of a point spread uniformly over the mesh's
    area (exact per triangle: its second moment is (a a^T + b b^T + c c^T + s s^T) / 12 times its
    area, with s = a + b + c)."""
    tri = np.asarray(mesh.triangles)[:, :, :2]
    area = np.asarray(mesh.area_faces)
    s = tri.sum(axis=1)
    second = np.einsum("t,tvi,tvj->ij", area, tri, tri) + np.einsum("t,ti,tj->ij", area, s, s)
    mean = (area @ s) / (3.0 * area.sum())
    return second / (12.0 * area.sum()) - np.outer(mean, mean)


def raster_lines(machine: Machine, spacing: float, waypoint_spacing: float) -> list[np.ndarray]:
    """Boustrophedon raster over the faces dust can rest on.

    Parameters
    ----------
    machine : Machine
    spacing, waypoint_spacing : float, metres
        Between lines, and between waypoints along a line.

    Returns
    -------
    list of (k, 3) float, metres
        Waypoints of each line on the surface, in visiting order ([] for a machine with no such
        face).
    """
    mesh = machine.mesh
    upward = np.flatnonzero(np.asarray(mesh.face_normals)[:, 2] >= DUST_MIN_NORMAL_Z)
    if not len(upward):
        return []
    resting = mesh.submesh([upward], append=True)
    long_axis = np.linalg.eigh(_area_covariance_xy(resting))[1][:, -1]
    along = np.r_[long_axis, 0.0]
    across = np.r_[-long_axis[1], long_axis[0], 0.0]  # horizontal plane normal: lines run along the long axis
    lines = boustrophedon(slice_curves(resting, across, spacing), along)
    return [resample_polyline(line, waypoint_spacing) for line in lines if len(line) >= 2]


def tool_axes(alpha: float, n: int) -> np.ndarray:
    """(m, 3) tool axes to try: straight down, then ``n - 1`` tilted by ``alpha`` (rad) at equal
    azimuths (the orientation freedom eq. 5 gives the online loop: ``n_orientations`` within
    ``alpha``); only straight down when ``alpha`` is 0 or ``n`` is 1."""
    if alpha == 0.0 or n == 1:
        return TOOL_AXIS[None].copy()
    a = 2.0 * np.pi * np.arange(n - 1) / (n - 1)
    tilted = np.column_stack([np.sin(alpha) * np.cos(a), np.sin(alpha) * np.sin(a), np.full(n - 1, -np.cos(alpha))])
    return np.vstack([TOOL_AXIS, tilted])


def reach_matrix(robot, checker: CollisionChecker, spots, waypoints, axes, delta: float, *, rng):
    """Which spot and tool axis pairs vacuum each waypoint: the tool reaches the waypoint along
    the axis and the configuration ``delta`` back along it is collision-free (eq. 5's test of an
    approach).

    Parameters
    ----------
    robot : RobotModel
    checker : CollisionChecker
        Machine and floor with the approach margin (its base is moved here).
    spots : (s, 3) float
        SE(2) base poses in visiting order.
    waypoints : (n, 3) float, metres
    axes : (m, 3) float
        Unit tool axes (:func:`tool_axes`).
    delta : float, metres
    rng : numpy.random.Generator
        IK restarts (:data:`mavac.cleaning.approach.IK_RESTARTS` per target, as the online
        loop's approach IK).

    Returns
    -------
    reach : (n, s * m) bool
        Column ``spot * m + axis``.
    q_back : (n, s * m, nq) float, rad
        The configuration ``delta`` back from each waypoint (meaningful where ``reach``).
    """
    n, m = len(waypoints), len(axes)
    spots = np.asarray(spots, dtype=float).reshape(-1, 3)
    reach = np.zeros((n, len(spots) * m), dtype=bool)
    q_back = np.zeros((n, len(spots) * m, robot.nq))
    for s, pose in enumerate(spots):
        world_T_base = se2_to_matrix(*pose)
        base_T_world = np.linalg.inv(world_T_base)
        checker.set_base(world_T_base)
        at = waypoints @ base_T_world[:3, :3].T + base_T_world[:3, 3]
        for j, a in enumerate(axes):
            down = np.tile(base_T_world[:3, :3] @ a, (n, 1))
            on = ik_axis(robot, at, down, rng=rng, n_restarts=IK_RESTARTS)
            ok = on.success.copy()
            back = ik_axis(robot, at[ok] - delta * down[ok], down[ok], q0=on.q[ok], n_restarts=0)
            ok[ok] = back.success
            ok[ok] = ~checker.in_collision(back.q[back.success])
            q_back[on.success, s * m + j] = back.q
            reach[:, s * m + j] = ok
    return reach, q_back


@dataclass(frozen=True)
class RasterPass:
    """One pass of the raster: consecutive waypoints of a line, vacuumed from one spot with one
    tool axis.

    Attributes
    ----------
    spot : int
        Index into the plan's spots.
    waypoints : (k, 3) float, metres
    q_start : (nq,) float, rad
        The configuration ``delta`` back along the tool axis from the first waypoint.
    q_end : (nq,) float, rad or None
        The configuration ``delta`` back from the last waypoint with the orientation held from
        the start (:func:`held_passes`; None before).
    """

    spot: int
    waypoints: np.ndarray
    q_start: np.ndarray
    q_end: np.ndarray | None = None


def runs_of_line(reach) -> list[tuple[int, int, int]]:
    """The fewest runs that cover a line's reachable waypoints, each run consecutive waypoints
    that one column of ``reach`` reaches: from the first uncovered waypoint, the column reaching
    furthest (the lowest column on a tie), which is optimal for covering a line by intervals.

    Parameters
    ----------
    reach : (k, c) bool
        The line's rows of :func:`reach_matrix`.

    Returns
    -------
    list of (start, stop, column)
        Waypoints ``start:stop`` by ``column``, in order.
    """
    k = len(reach)
    # run[i, c]: consecutive waypoints from i that column c reaches
    run = np.zeros((k + 1, reach.shape[1]), dtype=int)
    for i in range(k - 1, -1, -1):
        run[i] = np.where(reach[i], run[i + 1] + 1, 0)
    out, i = [], 0
    while i < k:
        c = int(np.argmax(run[i]))
        if run[i, c] == 0:
            i += 1
            continue
        out.append((i, i + int(run[i, c]), c))
        i += int(run[i, c])
    return out


def passes_from_raster(lines, reach, q_back, n_axes: int) -> list[RasterPass]:
    """Each line's fewest runs (:func:`runs_of_line`) as passes, grouped by spot (in spot order),
    each spot's in raster order.

    Parameters
    ----------
    lines : list of (k_i, 3) float
        :func:`raster_lines`.
    reach, q_back : (sum k_i, c) bool and (sum k_i, c, nq) float
        :func:`reach_matrix` on the lines' waypoints, stacked in order.
    n_axes : int
        Tool axes per spot (a column is ``spot * n_axes + axis``).
    """
    passes, first = [], 0
    for line in lines:
        for a, b, c in runs_of_line(reach[first:first + len(line)]):
            passes.append(RasterPass(c // n_axes, line[a:b], q_back[first + a, c]))
        first += len(line)
    return sorted(passes, key=lambda p: p.spot)  # stable: raster order within a spot


def held_passes(robot, checker: CollisionChecker, spots, passes: list[RasterPass], *, rng) -> list[RasterPass]:
    """The passes as they run: the tool holds its starting orientation (the free rotation about
    the axis included), so each pass is cut after its last waypoint from which the arm backs
    out ``delta`` with that orientation (full-pose IK seeded at the start, clear of the machine
    with the approach margin); that configuration is its ``q_end``, where the next plan starts.

    Parameters
    ----------
    robot, checker, spots
        As :func:`reach_matrix`.
    passes : list of RasterPass
        :func:`passes_from_raster`, grouped by spot.
    rng : numpy.random.Generator
        IK restarts.
    """
    out = []
    for p in passes:
        world_T_base = se2_to_matrix(*spots[p.spot])
        base_T_world = np.linalg.inv(world_T_base)
        checker.set_base(world_T_base)
        base_T_start = fk(robot, p.q_start)
        W = p.waypoints @ base_T_world[:3, :3].T + base_T_world[:3, 3]
        targets = np.tile(base_T_start, (len(W), 1, 1))
        targets[:, :3, 3] = W + (base_T_start[:3, 3] - W[0])
        sol = ik(robot, targets, q0=np.tile(p.q_start, (len(W), 1)), rng=rng, n_restarts=IK_RESTARTS)
        ok = sol.success.copy()
        ok[ok] = ~checker.in_collision(sol.q[ok])
        ok[0] = True  # the start is q_start itself, checked by the reach test
        last = int(np.flatnonzero(ok)[-1])
        out.append(RasterPass(p.spot, p.waypoints[:last + 1], p.q_start, p.q_start if last == 0 else sol.q[last]))
    return out


def sweep_pass(cell, raster_pass: RasterPass, params: OnlineParams) -> VacuumLog:
    """Vacuum one pass: move in from ``delta`` back of its first waypoint, follow its waypoints at the
    vacuuming speed, back out ``delta`` from its last, the orientation held from the start (as the
    online loop holds its approach orientation)."""
    log = VacuumLog()
    cell.sim.enable_torque_control()
    above = cell.world_T_base @ fk(cell.robot, raster_pass.q_start)
    start, end, lifted = above.copy(), above.copy(), above.copy()
    W = raster_pass.waypoints
    start[:3, 3], end[:3, 3] = W[0], W[-1]
    lifted[:3, 3] = W[-1] + (above[:3, 3] - W[0])
    linear_move(cell, above, start, params.vacuum, log)
    if len(W) > 1:
        path_move(cell, start, W, params.vacuum, log)
    linear_move(cell, end, lifted, params.vacuum, log)
    return log


@dataclass
class SystematicResult:
    """Outcome of :func:`run_systematic`.

    Attributes
    ----------
    machine : str
    seed : int
    heaps : (n, 3) float, metres
    cleaned : (n,) bool
    times : TrialTimes
        Simulated seconds: base travel, arm motion (planned moves), vacuuming (the passes).
    waypoints : int
        Raster waypoints on the surfaces dust can rest on.
    waypoints_reachable : int
        Of those, reached from some spot and axis (the rest are never vacuumed).
    waypoints_in_passes : int
        Of those, in a pass once each pass is cut where it can no longer back out with the
        orientation it holds (:func:`held_passes`).
    passes : int
    passes_run : int
    passes_unplanned : int
        Passes RRT-Connect found no path to, even with the re-plan (skipped).
    passes_skipped : int
        Passes left when the arm could neither fold nor retrace before driving.
    fold_failures, folds_retraced, replanned : int
        As in :class:`mavac.cleaning.trial.TrialResult`.
    replay : Replay or None
    warnings : list of str
    wall_s : float
        Wall time, s (not deterministic).
    """

    machine: str
    seed: int
    heaps: np.ndarray
    cleaned: np.ndarray
    times: TrialTimes = field(default_factory=TrialTimes)
    waypoints: int = 0
    waypoints_reachable: int = 0
    waypoints_in_passes: int = 0
    passes: int = 0
    passes_run: int = 0
    passes_unplanned: int = 0
    passes_skipped: int = 0
    fold_failures: int = 0
    folds_retraced: int = 0
    replanned: int = 0
    replay: Replay | None = None
    warnings: list = field(default_factory=list)
    wall_s: float = 0.0

    # scored as an online trial is, from ``heaps`` and ``cleaned``
    n_heaps = TrialResult.n_heaps
    n_cleaned = TrialResult.n_cleaned
    cleaning_pct = TrialResult.cleaning_pct

    def row(self) -> dict:
        """One run's row: heaps, cleaned, the raster's counts and the simulated time, s."""
        t = self.times
        return dict(machine=self.machine, seed=self.seed, heaps=self.n_heaps, cleaned=self.n_cleaned,
                    cleaning_pct=round(self.cleaning_pct, 3), waypoints=self.waypoints,
                    waypoints_reachable=self.waypoints_reachable, waypoints_in_passes=self.waypoints_in_passes,
                    passes=self.passes, passes_run=self.passes_run,
                    passes_unplanned=self.passes_unplanned, passes_skipped=self.passes_skipped,
                    fold_failures=self.fold_failures, base_s=round(t.base_s, 3), arm_s=round(t.arm_s, 3),
                    vacuum_s=round(t.vacuum_s, 3), sim_time_s=round(t.sim_time_s, 3))


def _sweep_spots(run: _Run, spots, passes: list[RasterPass], result: SystematicResult) -> None:
    """Every spot with passes, in order: fold and drive (not before the first), then its passes."""
    cell, first = run.cell, True
    for s in sorted({p.spot for p in passes}):
        mine = [(k, p) for k, p in enumerate(passes) if p.spot == s]
        if not first and not run.fold_home(s):
            result.passes_skipped = sum(p.spot >= s for p in passes)
            result.warnings.append(f"arm could not fold home before spot {s}: {result.passes_skipped} pass(es) skipped")
            return
        first = False
        if not run.drive_to(spots[s]):  # only under a perturbation: the machine is where the base would stop
            result.passes_skipped += len(mine)
            result.warnings.append(f"spot {s}: the base cannot stop there: {len(mine)} pass(es) skipped")
            continue
        for k, p in mine:
            motion = run.plan(p.q_start, "raster motion", k)
            if not motion.solved:
                result.passes_unplanned += 1
                result.warnings.append(f"pass {k}: RRT-Connect failed ({motion.reason})")
                continue
            run.track(motion.path)
            log = sweep_pass(cell, p, run.params)
            run.result.times.vacuum_s += log.seconds
            run.recorder.vacuuming(log.samples, log.sucked, log.sucked_at, log.seconds)
            cell.q_cmd = np.array(p.q_end, dtype=float)
            result.passes_run += 1


def spots_of_poses(plan) -> np.ndarray:
    """(s, 3) float: the SE(2) base poses the online loop stops at for ``plan``'s poses, in
    their order (a plan cut to its first poses keeps only their spots)."""
    first = np.sort(np.unique(plan.pose_spot, return_index=True)[1])
    return np.asarray(plan.poses, dtype=float)[first, :3]


def run_systematic(machine: Machine, plan, *, robot=None, params: OnlineParams | None = None,
                   systematic: SystematicParams | None = None, seed: int = 0) -> SystematicResult:
    """Systematic cleaning of ``machine`` from the spots of ``plan``, in pybullet.

    Parameters
    ----------
    machine : Machine
    plan : mavac.inspection.inspection_plan.InspectionPlan
        The base stops where the online loop would for its poses (:func:`spots_of_poses`), in
        order; its guards are not used.
    robot : RobotModel, optional
        The plan's robot (default :func:`mavac.robots.models.ur10_mobile`).
    params : OnlineParams, optional
        Dust, approach (``delta``, RRT-Connect), vacuum (impedance, speed, suction) and timing,
        as for :func:`mavac.cleaning.trial.run_trial`.
    systematic : SystematicParams, optional
    seed : int, in [0, 2**31 - 1]
        Heap layout and RRT-Connect seeds.

    Returns
    -------
    SystematicResult
        No pybullet client stays connected, also when this raises.
    """
    from ..inspection.inspection_plan import InspectionPlan

    t0 = time.perf_counter()
    check_instance("machine", machine, Machine)
    robot = ur10_mobile() if robot is None else check_instance("robot", robot, RobotModel)
    params = OnlineParams() if params is None else check_instance("params", params, OnlineParams)
    systematic = SystematicParams() if systematic is None else check_instance("systematic", systematic,
                                                                              SystematicParams)
    seed = check_seed(seed)
    check_instance("plan", plan, InspectionPlan)
    if robot.name != plan.robot_name:
        raise ValueError(f"robot {robot.name!r} is not the plan's robot {plan.robot_name!r}")
    heaps = heaps_for_trial(machine, params.dust, seed)
    lines = raster_lines(machine, line_spacing(systematic, params), systematic.waypoint_spacing)
    result = SystematicResult(machine.name, seed, heaps, np.zeros(len(heaps), dtype=bool))
    if not lines or not len(plan.poses):
        result.warnings.append("nothing to sweep: no surface dust can rest on" if not lines else "empty plan: no pose, so no spot")
        return result
    spots = spots_of_poses(plan)
    checker = CollisionChecker(robot, machine.mesh, margin=params.approach.collision_margin, floor=True)
    axes = tool_axes(params.approach.alpha, params.approach.n_orientations)
    reach, q_back = reach_matrix(robot, checker, spots, np.vstack(lines), axes, params.approach.delta,
                                 rng=rng_for(seed, "raster reach"))
    passes = held_passes(robot, checker, spots, passes_from_raster(lines, reach, q_back, len(axes)),
                         rng=rng_for(seed, "raster hold"))
    result.waypoints, result.waypoints_reachable = len(reach), int(reach.any(axis=1).sum())
    result.passes, result.waypoints_in_passes = len(passes), sum(len(p.waypoints) for p in passes)
    _execute(machine, plan, spots, robot, params, seed, passes, result)
    result.wall_s = time.perf_counter() - t0
    return result


def _execute(machine, plan, spots, robot, params, seed, passes, result: SystematicResult) -> None:
    """Run the passes in pybullet; fills ``result``'s cleaned heaps, times, counts and replay."""
    if not passes:
        result.warnings.append("no raster waypoint is reachable from the plan's spots")
        return
    scratch = _empty_result(machine.name, seed, result.heaps, "")  # the online loop's motion bookkeeping
    with SimWorld(time_step=params.time_step, seed=seed) as world:
        cell = build_cell(world, machine, robot, result.heaps, params, se2_to_matrix(*spots[passes[0].spot]))
        run = _Run(cell, machine, params, seed, scratch, plan.params.camera)
        _sweep_spots(run, spots, passes, result)
        result.cleaned = cell.dust.cleaned.copy()
        result.replay = run.recorder.replay()
    result.times = scratch.times
    result.fold_failures, result.folds_retraced = scratch.fold_failures, scratch.folds_retraced
    result.replanned = scratch.replanned
    result.warnings += scratch.warnings

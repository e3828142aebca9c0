"""One call from a machine mesh to an ordered inspection pose set T (MAVAC offline computation).

``plan_inspection(machine)`` runs the paper's offline pipeline (Fig. 2):

1. surface elements S (points + outward normals, the machine's floor contact removed);
2. candidate spots on rings around the footprint, collision-free; accessible sets (visible AND
   reachable); greedy spot selection with ``P_s``;
3. per spot, guard candidates (normal at ``L_d``, collision-free IK, FOV + HPR), greedy guard
   selection with ``P_g`` and eq. 3; elements seen at earlier spots no longer count as new;
4. coverage C and overlap O (eq. 1-2);
5. non-observed surfaces: DBSCAN clusters, ray fans, gateways, NoS guards kept only if OMPL
   RRT-Connect finds a path from the spot's home configuration;
6. the pose set T: spots in a short tour (nearest neighbour + 2-opt on the floor), the guards
   of each spot in a short joint-space order from the home configuration.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..params import InspectionParams
from .coverage import cover_counts, coverage_overlap
from .diagnose import LOW_COVERAGE
from .spots import SpotSelection

POSE_KINDS = ("guard", "nos")


def short_open_path(dist, start: int = 0) -> np.ndarray:
    """A short open path through all nodes from ``start``: nearest neighbour, then 2-opt.

    Parameters
    ----------
    dist : (k, k) float
        Symmetric distances.
    start : int
        First node (kept first).

    Returns
    -------
    (k,) int
        Visiting order, deterministic (ties by lowest index).
    """
    d = np.asarray(dist, dtype=float)
    k = len(d)
    if d.shape != (k, k):
        raise ValueError(f"dist must be square, got {d.shape}")
    if k == 0:
        return np.zeros(0, dtype=np.int64)
    if not 0 <= start < k:
        raise ValueError(f"start must be in [0, {k - 1}], got {start}")
    order = [start]
    left = np.ones(k, dtype=bool)
    left[start] = False
    while left.any():
        cand = np.flatnonzero(left)
        nxt = int(cand[np.argmin(d[order[-1], cand])])
        order.append(nxt)
        left[nxt] = False
    p = np.array(order)
    improved = True
    while improved:
        improved = False
        for i in range(1, k - 1):
            for j in range(i + 1, k):
                before = d[p[i - 1], p[i]] + (d[p[j], p[j + 1]] if j + 1 < k else 0.0)
                after = d[p[i - 1], p[j]] + (d[p[i], p[j + 1]] if j + 1 < k else 0.0)
                if after < before - 1e-12:
                    p[i:j + 1] = p[i:j + 1][::-1].copy()
                    improved = True
    return p


@dataclass
class InspectionPlan:
    """Result of :func:`plan_inspection`.

    Attributes
    ----------
    machine_name, robot_name : str
    params : InspectionParams
    points, normals : (n, 3) float
        Surface elements S (world frame, m) and outward normals.
    spots : (k, 3) float
        Selected SE(2) base poses ``(x, y, theta)`` in tour order.
    poses : (h, 3 + nq) float
        The pose set T, in execution order: ``[x, y, theta, q_1 .. q_nq]`` per row
        (the paper's ``Gm = [m_b^T, q^T]^T``).
    pose_spot : (h,) int
        Index into ``spots`` of each pose.
    pose_kind : (h,) str
        ``"guard"`` or ``"nos"`` (NoS guard).
    pose_target : (h,) int
        Element of S the guard was placed on (-1 for NoS guards).
    world_T_camera : (h, 4, 4) float
    maneuverability : (h,) float
        I_m of each configuration.
    visible : (h, n) bool
        Elements each pose observes.
    spot_selection : SpotSelection or None
        Candidates, accessible sets and the greedy choice (None if no candidate exists).
    nos_clusters : list of mavac.inspection.nos.NoSCluster
        Clusters of the elements the guards left unobserved, with ray fans and gateways.
    nos_attempts : list of dict
        Per cluster with a gateway: ``cluster``, ``spot``, ``n_rays``, ``ik``, ``solved``,
        ``reason``, ``seconds``.
    C, O : float
        Coverage and overlap of T (eq. 1-2), fractions of |S|.
    C_guards, O_guards : float
        Same, regular guards only (without NoS guards).
    timings : dict
        Wall time per stage, s.
    warnings : list of str
    """

    machine_name: str
    robot_name: str
    params: InspectionParams
    points: np.ndarray
    normals: np.ndarray
    spots: np.ndarray
    poses: np.ndarray
    pose_spot: np.ndarray
    pose_kind: np.ndarray
    pose_target: np.ndarray
    world_T_camera: np.ndarray
    maneuverability: np.ndarray
    visible: np.ndarray
    spot_selection: SpotSelection | None
    nos_clusters: list = field(default_factory=list)
    nos_attempts: list = field(default_factory=list)
    C: float = 0.0
    O: float = 0.0
    C_guards: float = 0.0
    O_guards: float = 0.0
    timings: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    mesh: object = field(default=None, repr=False)

    @property
    def n_spots(self) -> int:
        return int(len(self.spots))

    @property
    def n_guards(self) -> int:
        """Regular guards (NoS guards excluded)."""
        return int(np.count_nonzero(self.pose_kind == "guard"))

    @property
    def n_nos_guards(self) -> int:
        return int(np.count_nonzero(self.pose_kind == "nos"))

    @property
    def visibility(self) -> str:
        """Visibility method behind C and O: ``"raycast"``, ``"hpr"``, or both named per stage."""
        spot, guard = self.params.spot.visibility, self.params.guard.visibility
        return guard if spot == guard else f"spots {spot}, guards {guard}"

    def summary(self) -> str:
        """A few lines a person can read; every coverage names its visibility method."""
        lines = [f"{self.machine_name}: C = {self.C:.3f}, O = {self.O:.3f} ({self.visibility} visibility) over "
                 f"|S| = {len(self.points)} surface elements ({self.params.surface_spacing:g} m apart); "
                 f"{self.n_spots} spots, {self.n_guards} guards, {self.n_nos_guards} NoS guards ({self.robot_name})",
                 f"  guards only: C = {self.C_guards:.3f}, O = {self.O_guards:.3f} ({self.visibility} visibility)"]
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    @property
    def observed(self) -> np.ndarray:
        """(n,) bool: elements seen by at least one pose of T."""
        return cover_counts(self.visible) > 0 if len(self.visible) else np.zeros(len(self.points), bool)

    def to_dict(self, timings: bool = False) -> dict:
        """Plain-JSON description: parameters, spots, T with poses and joint configurations.

        Wall times (``timings`` and the RRT-Connect seconds of ``nos_attempts``) are left out
        unless asked for, so the same seed gives the same file.
        """
        attempts = [{k: (v.item() if isinstance(v, np.generic) else v) for k, v in a.items()
                     if timings or k != "seconds"} for a in self.nos_attempts]
        out = {
            "machine": self.machine_name,
            "robot": self.robot_name,
            "params": dataclasses.asdict(self.params),
            "n_elements": int(len(self.points)),
            "visibility": self.visibility,
            "C": self.C, "O": self.O, "C_guards": self.C_guards, "O_guards": self.O_guards,
            "spots": [{"x": float(x), "y": float(y), "theta": float(t)} for x, y, t in self.spots],
            "poses": [
                {
                    "spot": int(self.pose_spot[i]),
                    "kind": str(self.pose_kind[i]),
                    "base": [float(v) for v in self.poses[i, :3]],
                    "q": [float(v) for v in self.poses[i, 3:]],
                    "world_T_camera": np.round(self.world_T_camera[i], 9).tolist(),
                    "target": int(self.pose_target[i]),
                    "maneuverability": float(self.maneuverability[i]),
                    "n_visible": int(self.visible[i].sum()),
                }
                for i in range(len(self.poses))
            ],
            "nos_attempts": attempts,
            "warnings": list(self.warnings),
        }
        if timings:
            out["timings"] = {k: float(v) for k, v in self.timings.items()}
        return out

    def to_json(self, path, timings: bool = False):
        """Write :meth:`to_dict` atomically as JSON."""
        from ..io import write_json

        return write_json(self.to_dict(timings=timings), path)

    def to_html(self, path, robot=None):
        """Static meshcat HTML that frames the machine: observed (green) / unobserved (red)
        elements, spots, camera poses, the robot animated through T, a colour legend; the
        guard rays and gateways are layers hidden by default (see
        :func:`mavac.viz.scenes.inspection_plan_html`)."""
        from ..viz.scenes import inspection_plan_html

        return inspection_plan_html(self, path, robot=robot)


def _surface(mesh, spacing: float, seed: int):
    """S on the machine, without the faces standing on the floor (not exposed)."""
    from ..geometry.surface import sample_surface

    s = sample_surface(mesh, spacing, seed=seed)
    on_floor = (s.points[:, 2] <= 1e-6) & (s.normals[:, 2] < -0.99)
    return s.subset(~on_floor)


def _as_machine(mesh_or_machine):
    import trimesh

    from ..geometry.machines import Machine, machine_from_mesh

    if isinstance(mesh_or_machine, Machine):
        return mesh_or_machine
    if isinstance(mesh_or_machine, trimesh.Trimesh):
        return machine_from_mesh(mesh_or_machine)
    raise ValueError(f"mesh_or_machine must be a mavac Machine or a trimesh.Trimesh, got {type(mesh_or_machine).__name__}")


@dataclass
class OfflineContext:
    """Everything of the offline pipeline that does not depend on ``P_s``, ``P_g``, ``k1``, ``k2``
    or the NoS parameters: S, candidate spots and their accessible sets, scenes, checker, and a
    cache of guard candidates and their visibility per candidate spot (so parameter sweeps reuse
    IK and HPR results). Built by :func:`prepare_offline`.

    Attributes
    ----------
    machine : Machine
    robot : RobotModel (with a ``camera_frame``)
    params : InspectionParams
    points, normals : (n, 3) float
    candidates : (m, 3) float
        Collision-free candidate spots.
    accessible : (m, n) bool
    clear : (n,) bool
        Elements whose normal segment to their guard point is free.
    targets : (k,) int
        Guard targets: one representative per small cluster of S.
    timings : dict
    """

    machine: object
    robot: object
    params: InspectionParams
    points: np.ndarray
    normals: np.ndarray
    candidates: np.ndarray
    accessible: np.ndarray
    clear: np.ndarray
    targets: np.ndarray
    scene: object = field(repr=False, default=None)
    vis_scene: object = field(repr=False, default=None)
    checker: object = field(repr=False, default=None)
    timings: dict = field(default_factory=dict)
    _guards: dict = field(default_factory=dict, repr=False)
    _visibility: dict = field(default_factory=dict, repr=False)

    def guard_candidates(self, row: int):
        """Feasible guard candidates of candidate spot ``row`` (computed once, then cached).

        IK restarts draw from a generator seeded by ``(seed, row)``, so the result does not
        depend on which other spots were planned before.
        """
        from . import guards as G
        from .spots import se2_matrices

        if row not in self._guards:
            acc = self.accessible[row, self.targets] & self.clear[self.targets]
            rng = np.random.default_rng([self.params.seed, 1, row])
            T = se2_matrices(self.candidates[row:row + 1])[0]
            self._guards[row] = G.guard_candidates(self.robot, self.checker, T, self.points, self.normals,
                                                   self.targets[acc], self.params.camera, rng)
        return self._guards[row]

    def select_guards(self, row: int, guard_params, covered):
        """Greedy guard selection at candidate spot ``row``, visibility results cached."""
        from . import guards as G

        cache = self._visibility.setdefault((row, guard_params.visibility, guard_params.hpr_input), {})
        return G.select_guards(self.guard_candidates(row), self.points, self.normals, self.params.camera,
                               guard_params, covered, self.vis_scene, cache)


def prepare_offline(mesh_or_machine, robot=None, params: InspectionParams | None = None,
                    rmap=None) -> OfflineContext:
    """Stages of the offline pipeline that do not depend on the selection thresholds.

    Parameters
    ----------
    mesh_or_machine : Machine or trimesh.Trimesh
    robot : RobotModel, optional
        Default :func:`mavac.robots.models.ur10_mobile`.
    params : InspectionParams, optional
    rmap : ReachabilityMap, optional
        Default: built or loaded from the disk cache for ``robot`` and ``params.reach``.
    """
    from ..robots.collision import CollisionChecker
    from ..robots.models import ur10_mobile
    from ..vision.visibility import VisibilityScene
    from . import guards as G
    from . import spots as SP
    from .nos import raycasting_scene
    from .reachability import reachability_map

    params = InspectionParams() if params is None else params
    if not isinstance(params, InspectionParams):
        raise ValueError(f"params must be an InspectionParams, got {type(params).__name__}")
    machine = _as_machine(mesh_or_machine)
    mesh = machine.mesh
    robot = ur10_mobile() if robot is None else robot
    if robot.camera_frame is None:
        raise ValueError(f"robot {robot.name} has no camera_frame; MAVAC guards need a camera on the arm")
    cam = params.camera
    timings = {}

    t0 = time.perf_counter()
    surf = _surface(mesh, params.surface_spacing, params.seed)
    P, N = surf.points, surf.normals
    timings["surface"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    rmap = reachability_map(robot, params.reach) if rmap is None else rmap
    timings["reachability_map"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    cands = SP.candidate_spots(machine.footprint, params.spot, np.random.default_rng([params.seed, 0]))
    cands = cands[SP.collision_free_spots(robot, mesh, cands, margin=params.guard.collision_margin)]
    vis_scene = VisibilityScene(mesh)
    if len(cands):
        spot_vis = SP.spot_visibility(P, N, cands, params.spot.view_heights, params.spot.visibility,
                                      vis_scene, cam.hpr_radius_factor)
    else:
        spot_vis = np.zeros((0, len(P)), dtype=bool)
    acc = SP.accessible_sets(rmap, cands, P, N, spot_vis, cam)
    timings["accessible_sets"] = time.perf_counter() - t0

    scene = raycasting_scene(mesh)
    clear = SP.guard_clearance(scene, P, N, cam.L_d)
    checker = CollisionChecker(robot, mesh, margin=params.guard.collision_margin, floor=True)
    targets = G.guard_targets(P, N, params.guard.guard_spacing)
    return OfflineContext(machine, robot, params, P, N, cands, acc, clear, targets, scene, vis_scene,
                          checker, timings)


def _empty_plan(ctx, sel, timings, message) -> InspectionPlan:
    warnings.warn(message, stacklevel=3)
    n, nq = len(ctx.points), ctx.robot.nq
    return InspectionPlan(ctx.machine.name, ctx.robot.name, ctx.params, ctx.points, ctx.normals,
                          np.zeros((0, 3)), np.zeros((0, 3 + nq)), np.zeros(0, np.int64), np.zeros(0, dtype="<U5"),
                          np.zeros(0, np.int64), np.zeros((0, 4, 4)), np.zeros(0), np.zeros((0, n), bool),
                          sel, timings=timings, warnings=[message], mesh=ctx.machine.mesh)


def plan_from_context(ctx: OfflineContext, params: InspectionParams | None = None,
                      progress: bool = False) -> InspectionPlan:
    """Spot and guard selection, NoS guards and the ordered pose set T on a prepared context.

    Parameters
    ----------
    ctx : OfflineContext
        From :func:`prepare_offline`.
    params : InspectionParams, optional
        Only ``spot.P_s``, ``guard`` (``P_g``, ``k1``, ``k2``, visibility) and ``nos`` are read;
        the rest must equal ``ctx.params`` (else ``ValueError``). Default ``ctx.params``.
    progress : bool
        tqdm progress over the spots.
    """
    from tqdm.auto import tqdm

    from ..robots.kinematics import fk, maneuverability
    from . import guards as G
    from . import spots as SP
    from .nos import nos_clusters, spot_along_direction

    params = ctx.params if params is None else params
    if not isinstance(params, InspectionParams):
        raise ValueError(f"params must be an InspectionParams, got {type(params).__name__}")
    g0 = ctx.params.guard
    geometry = dataclasses.replace(params, spot=dataclasses.replace(params.spot, P_s=ctx.params.spot.P_s),
                                   guard=dataclasses.replace(params.guard, P_g=g0.P_g, k1=g0.k1, k2=g0.k2,
                                                             visibility=g0.visibility, hpr_input=g0.hpr_input),
                                   nos=ctx.params.nos)
    if geometry != ctx.params:
        raise ValueError("params differ from the context's in more than spot.P_s, guard selection and nos: "
                         "prepare a new context with prepare_offline(...)")
    timings = dict(ctx.timings)
    P, N, cam = ctx.points, ctx.normals, params.camera

    t0 = time.perf_counter()
    sel = SP.select_spots(ctx.accessible, ctx.candidates, params.spot.P_s)
    timings["spot_selection"] = time.perf_counter() - t0
    if len(sel.greedy.selected) == 0:
        return _empty_plan(ctx, sel, timings,
                           f"no spot can access any surface element of {ctx.machine.name!r} "
                           f"({len(ctx.candidates)} collision-free candidate spots): empty plan, C = 0")

    # spots in a short tour on the floor, starting with the first one selected
    spots = sel.spots
    tour = short_open_path(np.linalg.norm(spots[:, None, :2] - spots[None, :, :2], axis=2), 0)
    spots = spots[tour]
    rows = sel.greedy.selected[tour]
    world_T_bases = SP.se2_matrices(spots)

    t0 = time.perf_counter()
    covered = np.zeros(len(P), dtype=bool)
    per_spot = []
    for k in tqdm(range(len(spots)), desc="guards", disable=not progress, leave=False):
        s_k = ctx.select_guards(int(rows[k]), params.guard, covered)
        covered = s_k.greedy.covered
        per_spot.append(s_k)
    timings["guards"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    nos_per_spot = [[] for _ in spots]
    clusters, attempts = [], []
    if params.nos.enabled:
        from ..planning.rrt import plan_rrt_connect

        pn = params.nos
        clusters = nos_clusters(ctx.machine.mesh, P, N, covered, pn.eps_factor * params.surface_spacing,
                                pn.min_samples, pn.n_rays,
                                pn.ray_length, pn.origin_offset, scene=ctx.scene)
        robot, checker = ctx.robot, ctx.checker
        for c in clusters:
            gw = c.best_gateway
            if gw is None:
                continue
            k = spot_along_direction(spots[:, :2], c.origin, gw.direction)
            rng = np.random.default_rng([params.seed, 2, c.label])
            # the gateway's rays closest to its exit direction, best first: the camera sits L_d
            # out along the first one that has a collision-free IK solution
            rays = gw.ray_directions[np.argsort(-(gw.ray_directions @ gw.direction), kind="stable")[:pn.max_ray_tries]]
            ok, q, _ = G.camera_configurations(robot, checker, world_T_bases[k], c.origin + cam.L_d * rays, -rays, rng)
            rec = {"cluster": int(c.label), "n_elements": int(len(c.members)), "spot": int(k),
                   "n_rays": gw.n_rays, "ik": bool(ok.any()), "solved": False, "reason": "no collision-free IK",
                   "seconds": 0.0}
            if ok.any():
                q_goal = q[int(np.argmax(ok))]
                checker.set_base(world_T_bases[k])
                res = plan_rrt_connect(lambda qq: not bool(checker.in_collision(qq)), robot.q_home, q_goal,
                                       robot.q_lower, robot.q_upper, time_limit=pn.rrt_time_limit,
                                       seed=int(rng.integers(2**31 - 1)), resolution=pn.rrt_resolution,
                                       max_iterations=pn.rrt_max_iterations)
                rec.update(solved=bool(res.solved), reason=res.reason, seconds=float(res.seconds))
                if res.solved:
                    T = world_T_bases[k] @ fk(robot, q_goal, robot.camera_frame)
                    vis = G.guard_visibility(T[None], P, N, cam, params.guard, ctx.vis_scene)[0]
                    nos_per_spot[k].append((q_goal, T, vis))
            attempts.append(rec)
    timings["nos"] = time.perf_counter() - t0

    # T: per spot, guards then NoS guards, in a short joint-space order from the home configuration
    out = {key: [] for key in ("rows", "spot", "kind", "target", "cam", "im", "vis")}
    for k in range(len(spots)):
        g = per_spot[k].guards
        extra = nos_per_spot[k]
        qs = [g.q[i] for i in range(len(g))] + [e[0] for e in extra]
        if not qs:
            continue
        Ts = [g.world_T_camera[i] for i in range(len(g))] + [e[1] for e in extra]
        vs = [per_spot[k].visible[i] for i in range(len(g))] + [e[2] for e in extra]
        kinds = ["guard"] * len(g) + ["nos"] * len(extra)
        tg = g.target.tolist() + [-1] * len(extra)
        Q = np.vstack([ctx.robot.q_home] + qs)
        order = short_open_path(np.linalg.norm(Q[:, None] - Q[None], axis=2), 0)[1:] - 1
        im = np.asarray(maneuverability(ctx.robot, np.asarray(qs)), dtype=float).reshape(-1)
        for i in order:
            out["rows"].append(np.concatenate([spots[k], qs[i]]))
            out["spot"].append(k)
            out["kind"].append(kinds[i])
            out["target"].append(tg[i])
            out["cam"].append(Ts[i])
            out["im"].append(im[i])
            out["vis"].append(vs[i])
    n, nq = len(P), ctx.robot.nq
    visible = np.array(out["vis"], dtype=bool).reshape(-1, n)
    kinds = np.array(out["kind"], dtype="<U5")
    C, O = coverage_overlap(visible, n)
    Cg, Og = coverage_overlap(visible[kinds == "guard"], n)
    return InspectionPlan(
        ctx.machine.name, ctx.robot.name, params, P, N, spots,
        np.array(out["rows"], dtype=float).reshape(-1, 3 + nq), np.array(out["spot"], dtype=np.int64), kinds,
        np.array(out["target"], dtype=np.int64), np.array(out["cam"], dtype=float).reshape(-1, 4, 4),
        np.array(out["im"], dtype=float), visible, sel, clusters, attempts, C, O, Cg, Og, timings, [],
        ctx.machine.mesh,
    )


def plan_inspection(mesh_or_machine, robot=None, params: InspectionParams | None = None, rmap=None,
                    progress: bool = False) -> InspectionPlan:
    """MAVAC offline computation: spots, guards, NoS guards and the ordered pose set T.

    Parameters
    ----------
    mesh_or_machine : mavac.geometry.machines.Machine or trimesh.Trimesh
        The machine (metres, z up, standing on the floor z = 0). A bare mesh gets the convex hull
        of its floor shadow as footprint.
    robot : RobotModel, optional
        Mobile manipulator with a camera frame; default :func:`mavac.robots.models.ur10_mobile`.
    params : InspectionParams, optional
        Paper defaults (P_s = 0.02, P_g = 0.15, k1 = k2 = 1).
    rmap : ReachabilityMap, optional
        Reuse a map (default: built or loaded from the disk cache for ``robot``/``params.reach``).
    progress : bool
        tqdm progress over the spots.

    Returns
    -------
    InspectionPlan
        Empty (no spots, C = 0, with a warning) when no candidate spot can access anything.

    Warns
    -----
    UserWarning
        When C is below :data:`mavac.inspection.diagnose.LOW_COVERAGE`, with how many elements
        are too high, too far or occluded (also in ``plan.warnings``).
    """
    ctx = prepare_offline(mesh_or_machine, robot=robot, params=params, rmap=rmap)
    plan = plan_from_context(ctx, progress=progress)
    warn_low_coverage(ctx, plan, rmap=rmap)
    return plan


def warn_low_coverage(ctx: OfflineContext, plan: InspectionPlan, rmap=None) -> None:
    """Append (and warn) the low-coverage message of :mod:`mavac.inspection.diagnose`, if any."""
    from .diagnose import coverage_message, unobserved_causes

    if plan.C >= LOW_COVERAGE:
        return
    message = coverage_message(plan.C, unobserved_causes(ctx, plan, rmap=rmap), plan.visibility)
    plan.warnings.append(message)
    warnings.warn(message, stacklevel=3)

"""One call from a machine mesh to an ordered inspection pose set T (MAVAC offline computation).

``plan_inspection(machine)`` runs the paper's offline pipeline (Fig. 2):

1. surface elements S (points + outward normals, the machine's floor contact removed);
2. candidate spots on rings around the footprint, collision-free; accessible sets (visible AND
   reachable); greedy spot selection with ``P_s``;
3. per spot, guard candidates (on the normal at the guard stand-off, collision-free IK, FOV +
   ``params.visibility``: HPR or ray casting), greedy guard
   selection with ``P_g`` and eq. 3; elements seen at earlier spots no longer count as new;
4. coverage C and overlap O (eq. 1-2);
5. non-observed surfaces: DBSCAN clusters, ray fans, gateways, NoS guards kept only if OMPL
   RRT-Connect finds a path from the spot's home configuration (:func:`mavac.inspection.nos.nos_guards`);
6. the pose set T: spots in a short tour (nearest neighbour + 2-opt on the floor), the guards
   of each spot in a short joint-space order from the home configuration (:class:`PoseSet`).

Stages 1-2 up to the accessible sets do not depend on the selection thresholds and are kept in
an :class:`OfflineContext` (:func:`prepare_offline`), so sweeps over ``P_s`` and ``P_g`` reuse them
(:func:`plan_from_context`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import trimesh
from tqdm.auto import tqdm

from ..geometry.machines import Machine, machine_from_mesh, on_floor
from ..geometry.surface import buried, sample_surface
from ..geometry.transforms import compose, se2_matrices
from ..io import write_json
from ..params import InspectionParams
from ..planning.tour import short_open_path
from ..robots.collision import CollisionChecker
from ..robots.kinematics import fk, maneuverability
from ..robots.models import ur10_mobile
from ..seeding import rng_for
from ..validate import check_positive, check_size
from ..vision.visibility import VisibilityScene
from ..viz.scenes import inspection_plan_html
from . import guards as G
from . import spots as SP
from .coverage import cover_counts, coverage_overlap
from .nos import nos_guards, raycasting_scene
from .reachability import reachability_map
from .spots import SpotSelection
from .unobserved import LOW_COVERAGE, coverage_message, unobserved_causes

POSE_KINDS = ("guard", "nos")


@dataclass(frozen=True)
class PoseSet:
    """The ordered pose set T, one row per pose (the paper's ``Gm = [m_b^T, q^T]^T``).

    Attributes
    ----------
    poses : (h, 3 + nq) float
        ``[x, y, theta, q_1 .. q_nq]`` per row, in execution order.
    spot : (h,) int
        Index into the plan's spots of each pose.
    kind : (h,) str
        ``"guard"`` or ``"nos"`` (NoS guard).
    target : (h,) int
        Element of S the guard was placed on (-1 for NoS guards).
    world_T_camera : (h, 4, 4) float
    maneuverability : (h,) float
        I_m of each configuration.
    visible : (h, n) bool
        Elements each pose observes.
    """

    poses: np.ndarray
    spot: np.ndarray
    kind: np.ndarray
    target: np.ndarray
    world_T_camera: np.ndarray
    maneuverability: np.ndarray
    visible: np.ndarray

    def __len__(self) -> int:
        return int(len(self.poses))

    def head(self, n: int) -> PoseSet:
        """The first ``n`` poses (all when ``n >= len(self)``)."""
        return PoseSet(*(getattr(self, f.name)[:n] for f in dataclasses.fields(self)))

    @classmethod
    def from_rows(cls, rows, n_elements: int, nq: int) -> PoseSet:
        """From ``(pose, spot, kind, target, world_T_camera, maneuverability, visible)`` tuples."""
        cols = list(zip(*rows)) if rows else [[]] * 7
        return cls(np.array(cols[0], dtype=float).reshape(-1, 3 + nq), np.array(cols[1], dtype=np.int64),
                   np.array(cols[2], dtype="<U5"), np.array(cols[3], dtype=np.int64),
                   np.array(cols[4], dtype=float).reshape(-1, 4, 4), np.array(cols[5], dtype=float),
                   np.array(cols[6], dtype=bool).reshape(-1, n_elements))


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
    pose_set : PoseSet
        The pose set T in execution order; its columns are also attributes of the plan:
        ``poses`` (h, 3 + nq), ``pose_spot`` (h,), ``pose_kind`` (h,), ``pose_target`` (h,),
        ``world_T_camera`` (h, 4, 4), ``maneuverability`` (h,), ``visible`` (h, n).
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
    pose_set: PoseSet
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
    def poses(self) -> np.ndarray:
        """(h, 3 + nq) float: ``[x, y, theta, q]`` per pose of T."""
        return self.pose_set.poses

    @property
    def pose_spot(self) -> np.ndarray:
        """(h,) int: index into ``spots`` of each pose."""
        return self.pose_set.spot

    @property
    def pose_kind(self) -> np.ndarray:
        """(h,) str: ``"guard"`` or ``"nos"``."""
        return self.pose_set.kind

    @property
    def pose_target(self) -> np.ndarray:
        """(h,) int: element a guard looks at (-1 for NoS guards)."""
        return self.pose_set.target

    @property
    def world_T_camera(self) -> np.ndarray:
        """(h, 4, 4) float: camera pose of each pose."""
        return self.pose_set.world_T_camera

    @property
    def maneuverability(self) -> np.ndarray:
        """(h,) float: I_m of each configuration."""
        return self.pose_set.maneuverability

    @property
    def visible(self) -> np.ndarray:
        """(h, n) bool: elements each pose observes."""
        return self.pose_set.visible

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
        """Visibility method behind C and O, ``"raycast"`` or ``"hpr"`` (``params.visibility.method``)."""
        return self.params.visibility.method

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
        return write_json(self.to_dict(timings=timings), path)

    @classmethod
    def from_dict(cls, doc: dict, machine: Machine, *, robot=None) -> InspectionPlan:
        """The plan :meth:`to_dict` wrote, rebuilt on its machine (:func:`plan_from_dict`)."""
        return plan_from_dict(doc, machine, robot=robot)

    def to_html(self, path, robot=None):
        """Static meshcat HTML that frames the machine: observed (green) / unobserved (red)
        elements, spots, camera poses, the robot animated through T, a colour legend; the
        guard rays and gateways are layers hidden by default (see
        :func:`mavac.viz.scenes.inspection_plan_html`)."""
        return inspection_plan_html(self, path, robot=robot)


@contextlib.contextmanager
def _timed(timings: dict, stage: str):
    """Record the wall time of a block as ``timings[stage]``, s."""
    t0 = time.perf_counter()
    yield
    timings[stage] = time.perf_counter() - t0


#: How far a camera pose recomputed from a plan file's joints may lie from the file's, m (the
#: file rounds it to 1e-9; a different robot or frame is off by centimetres)
PLAN_FILE_ATOL = 1e-6


def _plan_rows(doc: dict, nq: int) -> dict:
    """The arrays of a plan file's document; ValueError when it is not one :meth:`InspectionPlan.to_dict` wrote."""
    try:
        rows = doc["poses"]
        out = dict(base=np.array([r["base"] for r in rows], dtype=float).reshape(-1, 3),
                   q=np.array([r["q"] for r in rows], dtype=float).reshape(-1, nq),
                   spot=np.array([r["spot"] for r in rows], dtype=np.int64),
                   kind=np.array([r["kind"] for r in rows], dtype="<U5"),
                   target=np.array([r["target"] for r in rows], dtype=np.int64),
                   world_T_camera=np.array([r["world_T_camera"] for r in rows], dtype=float).reshape(-1, 4, 4),
                   maneuverability=np.array([r["maneuverability"] for r in rows], dtype=float),
                   spots=np.array([[s["x"], s["y"], s["theta"]] for s in doc["spots"]], dtype=float).reshape(-1, 3))
        out.update({k: doc[k] for k in ("machine", "robot", "params", "n_elements", "C", "nos_attempts", "warnings")})
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"plan: not an inspection plan written by InspectionPlan.to_dict or 'mavac inspect' "
                         f"({type(exc).__name__}: {exc})") from None
    if not set(out["kind"]) <= set(POSE_KINDS) or not np.isin(out["spot"], np.arange(len(out["spots"]))).all():
        raise ValueError("plan: its poses name a kind other than guard/nos or a spot it does not list")
    return out


def plan_from_dict(doc: dict, machine: Machine, *, robot=None) -> InspectionPlan:
    """Rebuild a plan from :meth:`InspectionPlan.to_dict` on the machine it was made for.

    S is sampled again from the plan's parameters, each pose's camera comes from forward
    kinematics of its base pose and joints, and what it sees from ``params.visibility``: the
    file keeps neither S nor the cover sets. The rebuilt plan must reproduce the file.

    Parameters
    ----------
    doc : dict
        The plan's document (e.g. ``json.load`` of the file ``mavac inspect`` wrote).
    machine : Machine
        The machine, loaded and placed as when the plan was made (same unit and up axis).
    robot : RobotModel, optional
        The plan's robot; default :func:`mavac.robots.models.ur10_mobile`.

    Returns
    -------
    InspectionPlan
        Without the spot selection, NoS clusters and timings (not in the file).

    Raises
    ------
    ValueError
        When the document is not a plan, names another robot, or does not reproduce its element
        count, camera poses or coverage C on ``machine`` (another mesh, unit or up axis).
    """
    if not isinstance(machine, Machine):
        raise ValueError(f"machine must be a mavac Machine, got {type(machine).__name__}")
    robot = ur10_mobile() if robot is None else robot
    f = _plan_rows(doc, robot.nq)
    if f["robot"] != robot.name:
        raise ValueError(f"plan: made for robot {f['robot']!r}, not {robot.name!r}")
    params = InspectionParams.from_dict(f["params"])
    surf = surface_elements(machine.mesh, params.surface_spacing, params.seed)
    P, N = surf.points, surf.normals
    if len(P) != f["n_elements"]:
        raise ValueError(f"plan: {f['n_elements']} surface elements in the file, {len(P)} on machine "
                         f"{machine.name!r}: the plan was made for another mesh, unit or up axis")
    T = compose(se2_matrices(f["base"]), fk(robot, f["q"], robot.camera_frame)) if len(f["q"]) else f["world_T_camera"]
    if not np.allclose(T, f["world_T_camera"], rtol=0.0, atol=PLAN_FILE_ATOL):
        raise ValueError(f"plan: its joints do not give its camera poses on robot {robot.name!r}")
    vis = G.guard_visibility(T, P, N, params.camera, params.visibility, VisibilityScene(machine.mesh))
    poses = PoseSet(np.hstack([f["base"], f["q"]]), f["spot"], f["kind"], f["target"], T, f["maneuverability"], vis)
    C, O = coverage_overlap(vis, len(P))
    Cg, Og = coverage_overlap(vis[poses.kind == "guard"], len(P))
    if not np.isclose(C, f["C"], rtol=0.0, atol=1e-9):
        raise ValueError(f"plan: coverage C = {f['C']:.4f} in the file, {C:.4f} on machine {machine.name!r}: "
                         "the plan was made for another mesh, unit or up axis")
    return InspectionPlan(f["machine"], robot.name, params, P, N, f["spots"], poses, None, [], list(f["nos_attempts"]),
                          C, O, Cg, Og, {}, list(f["warnings"]), machine.mesh)


#: Most surface elements an inspection plan takes: 40 times the test bench's 2,310 at 5 cm; every
#: element is a guard target and a visibility test per view, so more would run for hours.
MAX_SURFACE_ELEMENTS = 100_000


def surface_elements(mesh, spacing: float, seed: int):
    """S on the machine: the exposed part of its surface, sampled about ``spacing`` apart.

    Samples the whole mesh (:func:`mavac.geometry.surface.sample_surface`), then drops the
    points on faces standing on the floor and the points buried inside another body of the mesh
    (:func:`mavac.geometry.surface.buried`: overlapping bodies written into one mesh instead of
    a boolean union; only closed bodies bury points). Neither is exposed, so neither counts in
    the coverage C. The number of buried points dropped is given in a warning.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The machine, metres, standing on z = 0.
    spacing : float, metres
        Distance between neighbouring elements (> 0).
    seed : int
        Seed of the sampling.

    Returns
    -------
    mavac.geometry.surface.SurfacePoints
        ``n`` elements: points (n, 3) m, outward unit normals (n, 3), faces (n,).

    Raises
    ------
    ValueError
        Before sampling, when ``spacing`` would give more than :data:`MAX_SURFACE_ELEMENTS`.
    """
    check_positive("surface_spacing", spacing)
    check_size("surface_spacing", spacing, float(mesh.area) / spacing**2, MAX_SURFACE_ELEMENTS, "surface elements")
    s = sample_surface(mesh, spacing, seed=seed)
    s = s.subset(~on_floor(s.points[:, 2], s.normals[:, 2]))
    inside = buried(mesh, s)
    if inside.any():
        warnings.warn(f"{int(inside.sum())} of {len(s)} surface elements lie inside another body of the mesh "
                      "(overlapping bodies, not a boolean union) and were dropped: they are not on the "
                      "machine's outer surface", stacklevel=2)
    return s.subset(~inside)


def _as_machine(mesh_or_machine):
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
        Visible AND reachable elements per candidate (``params.spot``'s visibility).
    clear : (n,) bool
        Elements whose normal segment to their guard point is free.
    targets : (k,) int
        Guard targets: one representative per small cluster of S.
    timings : dict
    reachable : (m, n) bool
        Elements whose inspecting camera pose is in the reachability map from each candidate.
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
    reachable: np.ndarray | None = field(default=None, repr=False)
    _guards: dict = field(default_factory=dict, repr=False)
    _visibility: dict = field(default_factory=dict, repr=False)

    def accessible_with(self, visibility) -> np.ndarray:
        """Accessible sets (m, n) bool of the candidates under another :class:`~mavac.params.Visibility`,
        e.g. Table 1 with HPR and with ray casting from one context."""
        return self.reachable & _spot_visibility(self.points, self.normals, self.candidates, self.params.spot,
                                                 visibility, self.vis_scene)

    def guard_candidates(self, row: int):
        """Feasible guard candidates of candidate spot ``row`` (computed once, then cached).

        IK restarts draw from a generator seeded by ``(seed, row)``, so the result does not
        depend on which other spots were planned before.
        """
        if row not in self._guards:
            acc = self.accessible[row, self.targets] & self.clear[self.targets]
            rng = rng_for(self.params.seed, "guard candidates", row)
            T = se2_matrices(self.candidates[row:row + 1])[0]
            self._guards[row] = G.guard_candidates(self.robot, self.checker, T, self.points, self.normals,
                                                   self.targets[acc], self.params.camera, rng,
                                                   standoff=self.params.guard_standoff)
        return self._guards[row]

    def select_guards(self, row: int, guard_params, covered, *, maneuverability=None):
        """Greedy guard selection at candidate spot ``row``, visibility results cached.

        ``maneuverability``, a function of the configurations ``(g, nq) -> (g,)``, replaces the
        candidates' I_m in eq. 3 (e.g. one factor of it); default: their I_m.
        """
        cache = self._visibility.setdefault(row, {})  # one visibility per context
        cands = self.guard_candidates(row)
        if maneuverability is not None and len(cands):
            cands = dataclasses.replace(cands, maneuverability=np.asarray(maneuverability(cands.q), dtype=float))
        return G.select_guards(cands, self.points, self.normals, self.params.camera, guard_params,
                               visibility=self.params.visibility, covered=covered, vis_scene=self.vis_scene,
                               cache=cache)


def _accessible_candidates(machine, robot, rmap, points, normals, params: InspectionParams, vis_scene):
    """Collision-free candidate spots (m, 3), their reachable sets and accessible sets (m, n) bool."""
    cands = SP.candidate_spots(machine.footprint, params.spot, rng_for(params.seed, "spot candidates"))
    cands = cands[SP.collision_free_spots(robot, machine.mesh, cands, margin=params.guard.collision_margin)]
    reach = SP.reachable_sets(rmap, cands, points, normals, params.guard_standoff)
    return cands, reach, reach & _spot_visibility(points, normals, cands, params.spot, params.visibility, vis_scene)


def _spot_visibility(points, normals, cands, spot_params, visibility, vis_scene) -> np.ndarray:
    if not len(cands):
        return np.zeros((0, len(points)), dtype=bool)
    return SP.spot_visibility(points, normals, cands, spot_params, visibility, vis_scene=vis_scene)


def prepare_offline(mesh_or_machine, *, robot=None, params: InspectionParams | None = None,
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
    params = InspectionParams() if params is None else params
    if not isinstance(params, InspectionParams):
        raise ValueError(f"params must be an InspectionParams, got {type(params).__name__}")
    machine = _as_machine(mesh_or_machine)
    robot = ur10_mobile() if robot is None else robot
    if robot.camera_frame is None:
        raise ValueError(f"robot {robot.name} has no camera_frame; MAVAC guards need a camera on the arm")
    timings = {}
    with _timed(timings, "surface"):
        surf = surface_elements(machine.mesh, params.surface_spacing, params.seed)
    P, N = surf.points, surf.normals
    with _timed(timings, "reachability_map"):
        rmap = reachability_map(robot, params.reach) if rmap is None else rmap
    vis_scene = VisibilityScene(machine.mesh)
    with _timed(timings, "accessible_sets"):
        cands, reach, acc = _accessible_candidates(machine, robot, rmap, P, N, params, vis_scene)
    scene = raycasting_scene(machine.mesh)
    clear = SP.guard_clearance(scene, P, N, params.guard_standoff)
    checker = CollisionChecker(robot, machine.mesh, margin=params.guard.collision_margin, floor=True)
    targets = G.guard_targets(P, N, params.guard.guard_spacing)
    return OfflineContext(machine, robot, params, P, N, cands, acc, clear, targets, scene, vis_scene,
                          checker, timings, reachable=reach)


def _empty_plan(ctx, sel, timings, message) -> InspectionPlan:
    warnings.warn(message, stacklevel=3)
    poses = PoseSet.from_rows([], len(ctx.points), ctx.robot.nq)
    return InspectionPlan(ctx.machine.name, ctx.robot.name, ctx.params, ctx.points, ctx.normals,
                          np.zeros((0, 3)), poses, sel, timings=timings, warnings=[message], mesh=ctx.machine.mesh)


def _sweep_params(ctx: OfflineContext, params: InspectionParams | None) -> InspectionParams:
    """``params`` for :func:`plan_from_context`: only the selection thresholds and NoS may differ."""
    params = ctx.params if params is None else params
    if not isinstance(params, InspectionParams):
        raise ValueError(f"params must be an InspectionParams, got {type(params).__name__}")
    g0 = ctx.params.guard
    geometry = dataclasses.replace(params, spot=dataclasses.replace(params.spot, P_s=ctx.params.spot.P_s),
                                   guard=dataclasses.replace(params.guard, P_g=g0.P_g, k1=g0.k1, k2=g0.k2),
                                   nos=ctx.params.nos)
    if geometry != ctx.params:
        raise ValueError("params differ from the context's in more than spot.P_s, guard selection and nos: "
                         "prepare a new context with prepare_offline(...)")
    return params


def spot_tour(selection: SpotSelection) -> tuple[np.ndarray, np.ndarray]:
    """The selected spots in a short tour on the floor, starting with the first one selected.

    Returns
    -------
    spots : (k, 3) float
    rows : (k,) int
        Their rows in ``selection.candidates``.
    """
    spots = selection.spots
    tour = short_open_path(np.linalg.norm(spots[:, None, :2] - spots[None, :, :2], axis=2), 0)
    return spots[tour], selection.greedy.selected[tour]


def guards_at_spots(ctx: OfflineContext, rows, guard_params, progress: bool = False, *,
                    maneuverability=None) -> list:
    """Greedy guard selection at each spot, in tour order (MAVAC, "Guard selection").

    Elements seen by the guards of earlier spots are carried over as covered: they no longer
    count as new for the guards of later spots. ``maneuverability`` optionally replaces I_m in
    eq. 3 (see :meth:`OfflineContext.select_guards`).

    Returns
    -------
    list of mavac.inspection.guards.GuardSelection, one per row
    """
    covered = np.zeros(len(ctx.points), dtype=bool)
    selections = []
    for row in tqdm(rows, desc="guards", disable=not progress, leave=False):
        selection = ctx.select_guards(int(row), guard_params, covered, maneuverability=maneuverability)
        covered = selection.greedy.covered
        selections.append(selection)
    return selections


def _spot_poses(robot, k: int, spot, selection, nos) -> list:
    """Rows of T at spot ``k``: its guards then its NoS guards, in a short joint-space order
    from the home configuration."""
    g = selection.guards
    qs = [g.q[i] for i in range(len(g))] + [e.q for e in nos]
    if not qs:
        return []
    Ts = [g.world_T_camera[i] for i in range(len(g))] + [e.world_T_camera for e in nos]
    vs = [selection.visible[i] for i in range(len(g))] + [e.visible for e in nos]
    kinds = ["guard"] * len(g) + ["nos"] * len(nos)
    targets = g.target.tolist() + [-1] * len(nos)
    Q = np.vstack([robot.q_home] + qs)
    order = short_open_path(np.linalg.norm(Q[:, None] - Q[None], axis=2), 0)[1:] - 1
    im = np.asarray(maneuverability(robot, np.asarray(qs)), dtype=float).reshape(-1)
    return [(np.concatenate([spot, qs[i]]), k, kinds[i], targets[i], Ts[i], im[i], vs[i]) for i in order]


def pose_set(robot, spots, selections, nos, n_elements: int) -> PoseSet:
    """The pose set T: per spot in tour order, guards and NoS guards (:func:`_spot_poses`)."""
    rows = []
    for k, selection in enumerate(selections):
        rows += _spot_poses(robot, k, spots[k], selection, [e for e in nos if e.spot == k])
    return PoseSet.from_rows(rows, n_elements, robot.nq)


def plan_from_context(ctx: OfflineContext, params: InspectionParams | None = None, *,
                      progress: bool = False) -> InspectionPlan:
    """Spot and guard selection, NoS guards and the ordered pose set T on a prepared context.

    Parameters
    ----------
    ctx : OfflineContext
        From :func:`prepare_offline`.
    params : InspectionParams, optional
        Only ``spot.P_s``, ``guard`` (``P_g``, ``k1``, ``k2``) and ``nos`` are read;
        the rest must equal ``ctx.params`` (else ``ValueError``). Default ``ctx.params``.
    progress : bool
        tqdm progress over the spots.
    """
    params = _sweep_params(ctx, params)
    timings, n = dict(ctx.timings), len(ctx.points)
    with _timed(timings, "spot_selection"):
        sel = SP.select_spots(ctx.accessible, ctx.candidates, params.spot.P_s)
    if len(sel.greedy.selected) == 0:
        return _empty_plan(ctx, sel, timings,
                           f"no spot can access any surface element of {ctx.machine.name!r} "
                           f"({len(ctx.candidates)} collision-free candidate spots): empty plan, C = 0")
    spots, rows = spot_tour(sel)
    with _timed(timings, "guards"):
        selections = guards_at_spots(ctx, rows, params.guard, progress=progress)
    with _timed(timings, "nos"):
        clusters, nos, attempts = nos_guards(ctx, spots, selections[-1].greedy.covered, params)
    poses = pose_set(ctx.robot, spots, selections, nos, n)
    C, O = coverage_overlap(poses.visible, n)
    Cg, Og = coverage_overlap(poses.visible[poses.kind == "guard"], n)
    return InspectionPlan(ctx.machine.name, ctx.robot.name, params, ctx.points, ctx.normals, spots, poses, sel,
                          clusters, attempts, C, O, Cg, Og, timings, [], ctx.machine.mesh)


def plan_inspection(mesh_or_machine, *, robot=None, params: InspectionParams | None = None, rmap=None,
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
        Paper defaults (P_s = 0.02, P_g = 0.15, k1 = k2 = 1), with exact ray casting (and a
        back-face test) for visibility; ``InspectionParams().with_visibility("hpr")`` selects the
        paper's hidden point removal (``params.visibility``, one choice for every stage).
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
        When C is below :data:`mavac.inspection.unobserved.LOW_COVERAGE`, with how many elements
        are too high, too far or occluded (also in ``plan.warnings``).
    """
    ctx = prepare_offline(mesh_or_machine, robot=robot, params=params, rmap=rmap)
    plan = plan_from_context(ctx, progress=progress)
    warn_low_coverage(ctx, plan, rmap=rmap)
    return plan


def warn_low_coverage(ctx: OfflineContext, plan: InspectionPlan, rmap=None) -> None:
    """Append (and warn) the low-coverage message of :mod:`mavac.inspection.unobserved`, if any."""
    if plan.C >= LOW_COVERAGE:
        return
    message = coverage_message(plan.C, unobserved_causes(ctx, plan, rmap=rmap), plan.visibility)
    plan.warnings.append(message)
    warnings.warn(message, stacklevel=3)

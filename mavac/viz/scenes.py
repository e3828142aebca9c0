"""Self-contained HTML views of an inspection plan (MAVAC) and a reach study, each framed, with a
legend and the robot animated, plus the animation and colour helpers that the setup-plan view
(:mod:`mavac.setups.viewer`) shares.

Every page opens on a camera aimed at the scene, keeps dense line layers (guard rays, gateway
rays) hidden until ticked in the controls, names its colours in an overlay, and says which
visibility method produced any coverage it shows.
"""

from __future__ import annotations

import math

import matplotlib
import numpy as np

from ..geometry.transforms import se2_matrices
from ..robots.models import load_robot
from . import meshcat_scene as ms

GREEN, RED, GREY = (0.1, 0.7, 0.2), (0.9, 0.1, 0.1), (0.75, 0.75, 0.78)
BLUE, ORANGE, LIGHT_GREEN = (0.1, 0.3, 0.9), (1.0, 0.5, 0.0), (0.1, 0.8, 0.1)
#: the setup-plan page's table: a wood brown, apart from the part's grey and the setup colours
WOOD = (0.62, 0.47, 0.30)
#: frames (at :data:`FPS`) per arm motion, per metre of base travel, and held at each pose; an arm
#: motion gets a key every :data:`ARM_KEY_STEP` frames (three.js interpolates between keys)
ARM_FRAMES, BASE_FRAMES_PER_M, HOLD_FRAMES, FPS, ARM_KEY_STEP = 15, 12, 10, 30, 3


class Keys:
    """Animation keys: frame numbers with a base pose and an arm configuration each."""
    def __init__(self, base, q):
        self.t, self.base, self.q = [0], [np.asarray(base, float)], [np.asarray(q, float)]

    def hold(self, frames: int):
        self.add(self.base[-1], self.q[-1], frames)

    def add(self, base, q, frames: int):
        self.t.append(self.t[-1] + max(1, int(frames)))
        self.base.append(np.asarray(base, float))
        self.q.append(np.asarray(q, float))

    def arm_to(self, q):
        q0 = self.q[-1]
        steps = max(1, ARM_FRAMES // ARM_KEY_STEP)
        for s in range(1, steps + 1):
            self.add(self.base[-1], q0 + (np.asarray(q, float) - q0) * s / steps, ARM_FRAMES / steps)

    def base_to(self, base):
        a, b = self.base[-1], np.asarray(base, float).copy()
        b[2] = a[2] + math.remainder(b[2] - a[2], 2 * math.pi)  # turn the short way round
        self.add(b, self.q[-1], max(ARM_FRAMES // 2, BASE_FRAMES_PER_M * float(np.linalg.norm(b[:2] - a[:2]))))

    def arrays(self):
        return np.array(self.t), np.array(self.base), np.array(self.q)


def pose_set_motion(spots, pose_spot, q, q_home):
    """Animation keys of the robot going through T: base moves (arm at home), then arm moves.

    As MAVAC's Algorithm 1 (moveMobileBase, then moveArm). Between two poses at the same spot only
    the arm moves; before the base leaves a spot the arm returns home.

    Parameters
    ----------
    spots : (k, 3) float
        SE(2) spots.
    pose_spot : (h,) int
        Spot of each pose, in execution order.
    q : (h, nq) float
        Arm configuration of each pose.
    q_home : (nq,) float

    Returns
    -------
    times : (f,) int
        Frame number of each key.
    bases : (f, 3) float
        SE(2) base pose per key.
    qs : (f, nq) float
        Arm configuration per key.
    """
    q_home = np.asarray(q_home, float)
    spots = np.asarray(spots, float).reshape(-1, 3)
    keys = Keys(spots[pose_spot[0]] if len(pose_spot) else spots[0], q_home)
    for s, qi in zip(pose_spot, np.asarray(q, float)):
        if not np.allclose(spots[s], keys.base[-1]):
            if not np.allclose(keys.q[-1], q_home):
                keys.arm_to(q_home)
            keys.base_to(spots[s])
        keys.arm_to(qi)
        keys.hold(HOLD_FRAMES)
    return keys.arrays()


def robot_tracks(robot, name: str, world_T_bases, qs) -> dict:
    tracks = {f"{name}/{k}": v for k, v in ms.robot_node_transforms(robot, qs).items()}
    tracks[name] = np.asarray(world_T_bases, float)
    return tracks


def frame_box(lo, hi, points=()):
    pts = [np.asarray(lo, float), np.asarray(hi, float)] + [np.asarray(p, float).reshape(-1, 3) for p in points]
    allp = np.vstack(pts)
    return allp.min(axis=0), allp.max(axis=0)


#: Ours: an inspection page draws at most this many camera triads (a plan has ~110 poses, too
#: many triads to read)
MAX_TRIADS = 30


def _camera_triads(vis, plan) -> int:
    """Small triads at up to :data:`MAX_TRIADS` camera poses, spread evenly along the ordered pose
    set T (first and last included); returns how many were drawn."""
    h = len(plan.world_T_camera)
    chosen = np.unique(np.round(np.linspace(0, h - 1, min(h, MAX_TRIADS))).astype(int))
    for i in chosen:
        ms.add_triad(vis, f"cameras/{plan.pose_kind[i]}_{i}", plan.world_T_camera[i], length=0.08)
    return len(chosen)


def inspection_plan_html(plan, path, robot=None):
    """Meshcat page of an :class:`~mavac.inspection.inspection_plan.InspectionPlan`.

    Shows the machine, observed (green) and unobserved (red) elements of S, the spots (large RGB
    triads) and camera poses (small triads at up to :data:`MAX_TRIADS` of them; NoS guards also as
    orange dots), and the robot going through T (base moves, then arm moves); guard rays (blue)
    and the best gateways' rays (light green) are hidden layers. The legend gives C and O with the
    visibility method.
    """
    robot = load_robot(plan.robot_name) if robot is None else robot
    spots = np.asarray(plan.spots, float).reshape(-1, 3)
    world_T_spots = se2_matrices(spots) if len(spots) else np.zeros((0, 4, 4))
    with ms.scene() as vis:
        if plan.mesh is not None:
            ms.add_mesh(vis, "machine", plan.mesh, color=GREY, opacity=0.8)
        colors = np.where(plan.observed[:, None], [GREEN], [RED])
        ms.add_points(vis, "surface", plan.points, colors, size=0.02)
        for i, T in enumerate(world_T_spots):
            ms.add_triad(vis, f"spots/{i}", T, length=0.3)
        drawn = _camera_triads(vis, plan)
        guard = plan.pose_kind == "guard"
        if guard.any():
            ms.add_lines(vis, "guard_rays", plan.world_T_camera[guard, :3, 3],
                         plan.points[plan.pose_target[guard]], color=BLUE)
            ms.set_visible(vis, "guard_rays", False)
        nos = plan.pose_kind == "nos"
        if nos.any():
            ms.add_points(vis, "nos_cameras", plan.world_T_camera[nos, :3, 3], ORANGE, size=0.06)
        for c in plan.nos_clusters:
            g = c.best_gateway
            if g is not None:
                ends = g.origin + 0.5 * g.ray_directions
                ms.add_lines(vis, f"gateways/{c.label}", np.broadcast_to(g.origin, ends.shape), ends,
                             color=LIGHT_GREEN)
        if plan.nos_clusters:
            ms.set_visible(vis, "gateways", False)
        if len(spots):
            ms.add_robot(vis, "robot", robot, robot.q_home, world_T_base=world_T_spots[0])
            times, bases, qs = pose_set_motion(spots, plan.pose_spot, plan.poses[:, 3:], robot.q_home)
            ms.animate(vis, robot_tracks(robot, "robot", se2_matrices(bases), qs), times=times, fps=FPS)
        lo, hi = plan.mesh.bounds if plan.mesh is not None else (plan.points.min(0), plan.points.max(0))
        lo, hi = frame_box(lo, hi, [np.column_stack([spots[:, :2], np.zeros(len(spots))])])
        ms.frame_camera(vis, lo, np.maximum(hi, [hi[0], hi[1], 1.2]))
        legend = ms.legend_html(
            [(GREEN, f"observed surface element ({int(plan.observed.sum())})"),
             (RED, f"unobserved surface element ({int((~plan.observed).sum())})"),
             (GREY, "machine"), (ORANGE, "NoS guard camera"),
             (BLUE, "guard ray: camera to its target (hidden layer)"),
             (LIGHT_GREEN, "best gateway rays of a NoS cluster (hidden layer)")],
            title=f"{plan.machine_name}: C = {plan.C:.2f}, O = {plan.O:.2f} ({plan.visibility} visibility)",
            notes=[f"{plan.n_spots} spots (large RGB triads), {plan.n_guards} guards + {plan.n_nos_guards} NoS "
                   f"guards; small triads at {drawn} of the {len(plan.world_T_camera)} cameras, evenly along T "
                   "(x = optical axis)",
                   "the robot plays the pose set T: base moves, then arm; replay under Animations",
                   "hidden layers: tick guard_rays / gateways under Scene in the controls"])
        return ms.save_html(vis, path, legend=legend)


def _per_face_mesh(mesh, face_rgb):
    """Vertices unshared per face so each face carries its own colour: (3f, 3), (f, 3), (3f, 3)."""
    v = np.asarray(mesh.vertices)[np.asarray(mesh.faces)].reshape(-1, 3)
    return v, np.arange(len(v)).reshape(-1, 3), np.repeat(np.asarray(face_rgb, float), 3, axis=0)


def add_colored_mesh(vis, name, mesh, face_rgb, world_T_mesh=None):
    import meshcat.geometry as g

    v, f, c = _per_face_mesh(mesh, face_rgb)
    vis[name].set_object(g.TriangularMeshGeometry(v, f.astype(np.uint32), color=c),
                         g.MeshLambertMaterial(vertexColors=True))
    if world_T_mesh is not None:
        vis[name].set_transform(np.asarray(world_T_mesh, float))


def _setup_palette(reserved, margin: float = 0.3, apart: float = 0.2) -> np.ndarray:
    """matplotlib's tab10 then Dark2, without the colours within ``margin`` (RGB distance) of a
    ``reserved`` one and those within ``apart`` of a colour already kept: (m, 3)."""
    kept = []
    for c in [c[:3] for name in ("tab10", "Dark2") for c in matplotlib.colormaps[name].colors]:
        near = [np.linalg.norm(np.subtract(c, r)) for r in list(reserved) + kept]
        if min(near[:len(reserved)]) > margin and min(near[len(reserved):], default=1.0) > apart:
            kept.append(c)
    return np.array(kept)


#: colours the setup-plan page gives other meanings: unreached stain, clean surface, table
SETUP_RESERVED = (RED, GREY, WOOD)
#: setup colours: 11 qualitative ones, none close to :data:`SETUP_RESERVED` nor to each other
SETUP_PALETTE = _setup_palette(SETUP_RESERVED)


def setup_colors(k: int) -> np.ndarray:
    """(k, 3) RGB of setups 1..k: :data:`SETUP_PALETTE`, cycled."""
    return SETUP_PALETTE[np.arange(k) % len(SETUP_PALETTE)].reshape(-1, 3)


#: the reach page's colour bar: the score's quantity and unit (I_m = w / w_max * J_l, a product of
#: two ratios), then how to read it
REACH_COLORBAR_TITLE = ("best score: maneuverability index I_m of a camera pose that sees the element "
                        "(dimensionless; MAVAC eq. 4)")
REACH_COLORBAR_GUIDE = "higher = better reach (farther from singularities and joint limits); grey = not reached and seen"


def reach_study_html(study, path, robot=None, cmap: str = "viridis"):
    """Meshcat heat map of a :class:`~mavac.inspection.reach_study.ReachStudy`: each surface element
    coloured by its best reach-and-visibility score (grey: not reached), with a colour bar; the
    robot shown at the spot that serves most elements, in its best configuration for the best
    element."""

    robot = load_robot(study.robot_name) if robot is None else robot
    score = np.asarray(study.score, float)
    top = float(score.max()) if score.max() > 0 else 1.0
    colors = np.asarray(matplotlib.colormaps[cmap](np.clip(score / top, 0, 1)))[:, :3]
    colors[score <= 0] = (0.55, 0.55, 0.55)
    with ms.scene() as vis:
        ms.add_mesh(vis, "machine", study.mesh, color=(0.85, 0.85, 0.87))
        # one dot per element, as wide as the sampling, lifted off the surface so it is not buried
        ms.add_points(vis, "score", study.points + 0.005 * study.normals, colors,
                      size=float(study.params.surface_spacing))
        cands = np.asarray(study.candidates, float).reshape(-1, 3)
        for i, T in enumerate(se2_matrices(cands) if len(cands) else []):
            ms.add_triad(vis, f"spots/{i}", T, length=0.15)
        ms.set_visible(vis, "spots", False)
        if (score > 0).any():
            best = int(np.argmax(score))
            s = int(study.best_spot[best])
            ms.add_robot(vis, "robot", robot, study.best_q[best], world_T_base=se2_matrices(cands[s:s + 1])[0])
        lo, hi = frame_box(*study.mesh.bounds, [np.column_stack([cands[:, :2], np.zeros(len(cands))])])
        ms.frame_camera(vis, lo, np.maximum(hi, [hi[0], hi[1], 1.2]))
        legend = ms.legend_html(
            [((0.55, 0.55, 0.55), f"not reached and seen from any spot ({int((score <= 0).sum())} elements)")],
            title=(f"{study.machine_name}: reach study, {100 * study.reach_fraction:.0f} % of |S| reached and seen "
                   f"({study.visibility} visibility)"),
            colorbar=(cmap, 0.0, round(top, 3), REACH_COLORBAR_TITLE),
            notes=[REACH_COLORBAR_GUIDE, "robot: at the spot and configuration with the highest score",
                   f"{len(cands)} candidate spots: hidden layer 'spots' in the controls"])
        return ms.save_html(vis, path, legend=legend)


#: Ours: a trial's replay plays this many times faster than simulated time (a 450 s trial in 45 s)
REPLAY_SPEEDUP = 10.0
#: Ours: a page with the robot frames at least this height, m (the UR10 on its base, arm raised)
ROBOT_HEIGHT = 1.5
#: Ours: heaps drawn as spheres of this radius, m (the suction radius' order, visible from 3 m)
HEAP_RADIUS = 0.02


def cause_colors(causes) -> dict:
    """Miss cause -> RGB: matplotlib's tab10 without its green, which marks cleaned heaps."""
    cmap = matplotlib.colormaps["tab10"]
    palette = [cmap(i)[:3] for i in (3, 1, 4, 5, 6, 7, 8, 9, 0)]
    return {cause: palette[i % len(palette)] for i, cause in enumerate(causes)}


def _replay_keys(replay, robot, speedup: float):
    """Frames (at :data:`FPS`) of the replay's keys, one key per frame (the last one wins), and
    the robot's node tracks at them."""
    frames = np.round(np.asarray(replay.times) * FPS / speedup).astype(np.int64)
    last = np.r_[frames[1:] != frames[:-1], True]
    keep = np.flatnonzero(last)
    tracks = robot_tracks(robot, "robot", se2_matrices(replay.bases[keep]), replay.qs[keep])
    return frames[keep], tracks


def trial_replay_html(result, machine, path, *, robot=None, speedup: float = REPLAY_SPEEDUP):
    """Meshcat replay of a cleaning trial (:class:`~mavac.cleaning.trial.TrialResult`).

    The robot drives through its pose set as the trial executed it; each cleaned heap (green)
    vanishes when it is vacuumed; missed heaps stay, coloured by their cause, with a legend.

    Parameters
    ----------
    result : TrialResult
        With its :attr:`~mavac.cleaning.trial.TrialResult.replay`.
    machine : mavac.geometry.machines.Machine
        The trial's machine.
    path : str or Path
        The HTML file (written atomically).
    robot : RobotModel, optional
        The trial's robot (default: the UR10 on its mobile base).
    speedup : float, > 0
        Replay speed over simulated time.
    """
    from ..cleaning.misses import CAUSES
    from ..robots.models import ur10_mobile

    robot = ur10_mobile() if robot is None else robot
    replay, colors = result.replay, cause_colors(CAUSES)
    with ms.scene() as vis:
        ms.add_mesh(vis, "machine", machine.mesh, color=GREY, opacity=0.85)
        fate = [GREEN if c else colors[str(cause)] for c, cause in zip(result.cleaned, result.causes)]
        ms.add_spheres(vis, "heaps", result.heaps, fate, radius=HEAP_RADIUS)
        ms.add_robot(vis, "robot", robot, replay.qs[0], world_T_base=se2_matrices(replay.bases[:1])[0])
        frames, tracks = _replay_keys(replay, robot, speedup)
        gone = np.flatnonzero(np.isfinite(replay.cleaned_at))
        hide = {f"heaps/{i}": max(1, int(round(replay.cleaned_at[i] * FPS / speedup))) for i in gone}
        ms.animate(vis, tracks, times=frames, fps=FPS, hide_at=hide)
        lo, hi = frame_box(*machine.mesh.bounds, [np.column_stack([replay.bases[:, :2], np.zeros(len(replay.bases))])])
        ms.frame_camera(vis, lo, np.maximum(hi, [hi[0], hi[1], ROBOT_HEIGHT]))
        misses = result.miss_counts()
        entries = [(GREEN, f"cleaned heap, vanishes when vacuumed ({result.n_cleaned})")]
        entries += [(colors[c], f"missed: {c} ({n})") for c, n in misses.items() if n]
        legend = ms.legend_html(entries, title=f"{result.machine}, seed {result.seed}: {result.cleaning_pct:.1f} % "
                                               f"of {result.n_heaps} heaps cleaned (simulated)",
                                notes=[f"replay at {speedup:g}x: {replay.duration:.0f} s of simulated time "
                                       f"in {replay.duration / speedup:.0f} s; replay under Animations"])
        return ms.save_html(vis, path, legend=legend)

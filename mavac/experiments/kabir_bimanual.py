"""Notebook 11: Kabir et al.'s physical experiments (Sec. IX-C) in the SIMULATED two-arm cell.

:func:`learn_on_coupon` runs the GPR learner (Sec. VIII) against the cell on a single-patch
test coupon; :func:`run_part` plans the setups of the bowl or the hull, executes them with both
arms in pybullet (hold, move, scrub, look, re-plan) and returns everything the notebook
tabulates (Table VII, ``kabir_execution.csv``) and draws (Figs. 10-13, the meshcat replay).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
import trimesh

from ..geometry.parts import Part, load_part, stain_from_field
from ..geometry.transforms import look_at
from ..paper import paper_scalar
from ..params import BimanualCellParams, GPRParams, LissajousParams, ScrubModel, ToolpathParams
from ..scrubbing.bimanual import (Execution, StainState, _approach, execute_setup, perceive, plan_cell_setups,
                                  plan_params_for_cell, residue_faces, schedule_for_pass, setup_configurations)
from ..scrubbing.gpr import learn_parameters
from ..scrubbing.toolpath import PassPath
from ..setups.held import HeldSetups
from ..setups.reach import base_T_part
from ..sim.bimanual import brake, open_cell, run_schedule, snapshot, stain_overlay, world_T_part
from ..sim.cell import HOLDER_SEED, cell_robots, holder_ik
from ..sim.wear import lissajous_from_vector, stain_opacity
from ..sim.world import SimWorld

PARTS = ("bowl", "hull")
#: Fast mode: stained faces of the coarse run (ours: a few seconds of scrubbing).
FAST_STAIN_FACES = 300
#: Kabir Sec. IX-C: C_p^th and P_th of the learner per part.
THRESHOLDS = {"bowl": (0.60, 0.10), "hull": (0.90, 0.30)}
#: Kabir Sec. IX-C: the operating parameters the paper found (v, f_n, kappa, f_x, A_x).
PAPER_PARAMS = {"bowl": (0.3, 10.0, 5000.0, 7.0, 30.0), "hull": (0.1, 20.0, 5000.0, 6.0, 35.0)}


# ---------------------------------------------------------------- the GPR learner on a coupon


def coupon_part(seed: int = 0) -> Part:
    """Single-patch test coupon (ours): an 80 x 80 x 10 mm plate, its top a 40 x 40 grid of
    triangles (2 mm cells, < 10 mm^2 as the paper's parts), stained on a 24 x 50 mm strip
    narrower than the 30 mm pad, thickness 0.6-1.0 layers from ``seed``."""
    n, size, thick = 40, 0.08, 0.01
    g = np.linspace(-size / 2, size / 2, n + 1)
    X, Y = np.meshgrid(g, g, indexing="ij")
    top = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, thick)])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * [size / 2, size / 2, 1]
    V = np.vstack([top, corners])
    m = len(top)
    F = np.vstack([faces, [[m, m + 2, m + 1], [m, m + 3, m + 2]]])
    mesh = trimesh.Trimesh(V, F, process=False)
    ctr = mesh.triangles_center
    stain = np.flatnonzero((np.abs(ctr[:, 0]) < 0.025) & (np.abs(ctr[:, 1]) < 0.012) & (ctr[:, 2] > thick / 2))
    rng = np.random.default_rng(seed)
    return Part("coupon", mesh, stain, np.ones(len(stain), dtype=np.int64), rng.uniform(0.6, 1.0, len(stain)),
                "single-patch test coupon of the GPR learner (ours)")


class CouponCell:
    """``experiment(x, rng) -> C_p``: one SIMULATED scrubbing stroke over the coupon in the cell.

    The holding arm presents the coupon at the centre of the setup space; the cleaning arm
    makes one 60 mm stroke along the stain strip with the operation vector ``x = (v, f_n,
    kappa, f_x, A_x)`` (:func:`mavac.sim.wear.lissajous_from_vector`); the stain camera and
    K-means measure C_p. Use as a context manager (the pybullet client is closed on exit).
    """

    def __init__(self, cell: BimanualCellParams = BimanualCellParams(), toolpath: ToolpathParams = ToolpathParams(),
                 *, seed: int = 0):
        self.params, self.toolpath, self.seed = cell, toolpath, seed
        self.part = coupon_part(seed)
        self.cleaner, self.holder = cell_robots(cell, toolpath)
        self.world = None
        self._memo = {}

    def __enter__(self):
        T = base_T_part(np.array([[0.15, 0.15, 0.0]]), self.params.space)
        q = holder_ik(self.holder, T, self.params).q[0]
        self.world = SimWorld(time_step=self.params.time_step, seed=self.seed)
        try:
            self.cell = open_cell(self.world, self.cleaner, self.holder, self.part.mesh, q, params=self.params,
                                  pad_width=self.toolpath.tool_width_m)
            self.world.step(200)
            Tp = world_T_part(self.cell)
            xs = np.linspace(-0.03, 0.03, 13)
            seg = (Tp @ np.column_stack([xs, np.zeros_like(xs), np.full_like(xs, 0.01), np.ones_like(xs)]).T).T[:, :3]
            self.stroke = PassPath(1, np.arange(len(self.part.stain_faces)), [seg], [np.tile(Tp[:3, 2], (len(xs), 1))])
            self.q_start = None
        except BaseException:
            self.world.close()
            raise
        return self

    def __exit__(self, *exc):
        self.world.close()

    def __call__(self, x, rng: np.random.Generator | None = None) -> float:
        """C_p of one stroke at ``x``. Its process and pixel noise come from the seed and ``x``
        (not from ``rng``), so learners with other thresholds share the runs at the same point."""
        key = tuple(np.round(np.asarray(x, float), 9).tolist())
        if key not in self._memo:
            noise = np.random.default_rng([self.seed, *np.frombuffer(np.asarray(key).tobytes(), np.uint32)])
            self._memo[key] = self._stroke(np.asarray(key), noise)
        return self._memo[key]

    def _stroke(self, x, rng: np.random.Generator) -> float:
        lis = lissajous_from_vector(np.asarray(x, float)[None])
        rng_state = np.random.default_rng(self.seed)
        state = StainState.from_part(self.part, rng_state, image_size=64)
        sched = schedule_for_pass(self.stroke, lis, self.toolpath, self.world.time_step)
        if self.q_start is None:
            _approach(self.cell, sched, self.toolpath.lift_height_m, lis)
            self.q_start = self.cell.cleaner.q()
        self.cell.cleaner.reset_q(self.q_start)
        brake(self.cell.cleaner, self.q_start)
        log = run_schedule(self.cell, sched, stiffness=lis.kappa_x)
        before = state.thickness.copy()
        state.scrub(log.removal, rng)
        self.cell.cleaner.reset_q(self.q_start)
        brake(self.cell.cleaner, self.q_start)
        self.world.step(50)
        return float(perceive(state, before, self.part.stain_faces, rng)["C_p"])


def learn_on_coupon(part: str, experiment: CouponCell, *, budget: int, seed: int = 0):
    """GPR learner (Sec. VIII) with the paper's thresholds for ``part``, on the coupon in the cell
    (``experiment``, an open :class:`CouponCell`).

    Returns
    -------
    (GPRResult, LissajousParams)
        The learner's outcome and the parameters the run uses: the learned ones when the learner
        found a feasible point, else the paper's values for that part (the result says which).
    """
    cp_th, p_th = THRESHOLDS[part]
    params = GPRParams(Cp_th=cp_th, P_th=p_th, max_experiments=budget, seed=seed)
    result = learn_parameters(experiment, params, rng=np.random.default_rng(seed))
    x = PAPER_PARAMS[part] if not result.feasible else [result.chosen[k] for k in ("v", "f_n", "kappa", "f_x", "A_x")]
    return result, lissajous_from_vector(np.asarray(x, float)[None])


# ---------------------------------------------------------------- a whole part


@dataclass
class PartRun:
    """Everything one part's SIMULATED run produced."""

    name: str
    plans: list
    execution: Execution
    state: StainState
    rounds: int
    stain_removed: float
    unseen_faces: int
    lissajous: LissajousParams
    seconds: float
    notes: list = field(default_factory=list)


def part_for_run(name: str, *, fast: bool, seed: int = 0) -> Part:
    """The part (paper scale) or, fast, the same mesh with a FAST_STAIN_FACES-face stain needing one pass."""
    part = load_part(name, seed=seed)
    if not fast:
        return part
    stain, _, intensity = stain_from_field(part.mesh, FAST_STAIN_FACES, np.random.default_rng(seed), pass_range=(1, 1))
    return Part(name, part.mesh, stain, np.ones(len(stain), dtype=np.int64), intensity, f"fast mode: {FAST_STAIN_FACES} stain faces")


def run_part(name: str, *, fast: bool, lissajous: LissajousParams | None = None, seed: int = 0,
             cell: BimanualCellParams = BimanualCellParams(), toolpath: ToolpathParams = ToolpathParams(),
             snapshots: bool = True) -> PartRun:
    """Plan and execute a part in the cell; re-plan the residue up to ``cell.max_rounds`` times.

    Fast mode: a FAST_STAIN_FACES-face stain, one hierarchical-sampling level, the first setup only, no
    re-planning. ``lissajous`` defaults to the paper's parameters for the part.
    """
    t0 = time.perf_counter()
    part = part_for_run(name, fast=fast, seed=seed)
    lissajous = lissajous_from_vector(np.asarray(PAPER_PARAMS[name], float)[None]) if lissajous is None else lissajous
    if fast:
        cell = replace(cell, max_rounds=0, sampling=replace(cell.sampling, max_levels=1))
    cleaner, holder = cell_robots(cell, toolpath)
    rng = np.random.default_rng(seed)
    state = StainState.from_part(part, rng, image_size=cell.image_size)
    out = Execution()
    out.stain_images.append(perceive(state, state.initial, part.stain_faces, rng)["image"])
    plans, rounds, current, notes, unseen = [], 0, part, [], 0
    with SimWorld(time_step=cell.time_step, seed=seed) as world:
        sim = open_cell(world, cleaner, holder, part.mesh, HOLDER_SEED, params=cell, pad_width=toolpath.tool_width_m)
        shot = _snapshot_fn() if snapshots else None
        while True:
            plan = plan_cell_setups(current, cleaner, holder, cell, plan_params_for_cell(cell))
            plans.append(plan)
            if len(plan.setups) == 0:
                notes.append(f"round {rounds}: the planner found no setup for the {len(current.stain_faces)} faces left")
                break
            setups = plan.setups[:1] if fast else plan.setups
            qs = setup_configurations(HeldSetups(cleaner, holder, part.mesh, cell), setups, sim.holder.q())
            for j, (q, patches) in enumerate(zip(qs, plan.patches)):
                execute_setup(sim, current, patches, q, state, lissajous, toolpath, rng, out,
                              label=f"round {rounds} setup {j + 1}", snapshot=shot, seed=seed + j)
            last = state.images[-1]
            left, unseen = residue_faces(state, last["mask"], part.stain_faces)
            if last["residue_fraction"] <= cell.clean_residue or rounds >= cell.max_rounds or len(left) == 0:
                break
            rounds += 1
            current = Part(name, part.mesh, left, np.ones(len(left), dtype=np.int64), np.ones(len(left)),
                           f"residue after round {rounds - 1}")
    removed = float(1.0 - state.thickness[part.stain_faces].sum() / state.initial[part.stain_faces].sum())
    return PartRun(name, plans, out, state, rounds, removed, unseen, lissajous, time.perf_counter() - t0, notes)


def _snapshot_fn():
    """pybullet camera snapshot of the cell with the current stain drawn on the part."""
    def shoot(sim, state):
        T = world_T_part(sim)
        target = T[:3, 3] + np.array([0.0, 0.0, 0.06])
        ids = stain_overlay(sim, stain_opacity(state.thickness))
        try:
            return snapshot(sim, look_at(target + np.array([0.0, -0.75, 0.5]), target))
        finally:
            for body in ids:
                sim.world.remove_body(body)
    return shoot


# ---------------------------------------------------------------- tables


def table7(runs: dict) -> pd.DataFrame:
    """Kabir Table VII, ours beside the paper's: solution size, node expansions, n_rfc, average
    setup time (SIMULATED holding-arm motion of the first round's setups), planning time."""
    rows = []
    for name, run in runs.items():
        plan = run.plans[0]
        k = len(plan.setups)
        times = run.execution.setup_times[:k]
        row = dict(part=name, solution_size=k, node_expansion=plan.node_expansions, n_rfc=plan.n_rfc,
                   avg_setup_time=float(np.mean(times)) if times else float("nan"), planning_time=plan.seconds)
        for q in ("solution_size", "node_expansion", "n_rfc", "avg_setup_time", "planning_time"):
            row[f"{q}_paper"] = paper_scalar("kabir", "Table VII", q, f"part={name}")
        rows.append(row)
    cols = ["part"] + [c for q in ("solution_size", "node_expansion", "n_rfc", "avg_setup_time", "planning_time")
                       for c in (f"{q}_paper", q)]
    return pd.DataFrame(rows)[cols].rename(columns={q: f"{q}_ours" for q in
                                                    ("solution_size", "node_expansion", "n_rfc", "avg_setup_time",
                                                     "planning_time")})


def execution_table(runs: dict) -> pd.DataFrame:
    """``kabir_execution.csv``: one row per part, round, setup and pass (SIMULATED)."""
    frames = []
    for name, run in runs.items():
        df = pd.DataFrame(run.execution.rows)
        df.insert(0, "part", name)
        frames.append(df)
    df = pd.concat(frames, ignore_index=True).rename(columns={"pass_": "pass"})
    return df[["part", "setup", "pass", "path_length_m", "contact_s", "mean_normal_force_n", "residue_fraction",
               "C_p", "f_n_n", "sliding_m"]]


def summary_table(runs: dict) -> pd.DataFrame:
    """Per part: stain removed, re-plan rounds, force tracking error, learned parameters (SIMULATED)."""
    rows = []
    for name, run in runs.items():
        forces = np.concatenate(run.execution.forces) if run.execution.forces else np.zeros(0)
        mean = float(forces.mean()) if forces.size else float("nan")
        rows.append(dict(part=name, stain_removed=run.stain_removed, replan_rounds=run.rounds,
                         setups_executed=len(run.execution.setup_times), passes=len(run.execution.rows),
                         f_n_commanded=run.lissajous.f_n, mean_contact_force=mean,
                         force_error=abs(mean - run.lissajous.f_n) / run.lissajous.f_n,
                         residue_final=run.execution.rows[-1]["residue_fraction"] if run.execution.rows else np.nan,
                         faces_unseen=run.unseen_faces, wall_s=run.seconds))
    return pd.DataFrame(rows)


# ---------------------------------------------------------------- figures and replay


def plot_before_after(axes, run: PartRun, title: str) -> None:
    """Figs. 10 / 12: the stain camera's image of the part before and after cleaning (SIMULATED)."""
    for ax, img, label in zip(axes, (run.execution.stain_images[0], run.execution.stain_images[-1]),
                              ("(a) before cleaning", "(b) after cleaning")):
        ax.imshow(img)
        ax.set_title(f"{title} {label}", fontsize=9)
        ax.axis("off")


def plot_snapshots(fig, run: PartRun, ncols: int = 4) -> None:
    """Figs. 11 / 13: pybullet camera snapshots of each setup before cleaning and after each pass."""
    shots = run.execution.snapshots
    nrows = max(1, int(np.ceil(len(shots) / ncols)))
    for i, (label, img) in enumerate(shots):
        ax = fig.add_subplot(nrows, ncols, i + 1)
        ax.imshow(img)
        ax.set_title(label, fontsize=8)
        ax.axis("off")


def replay_tracks(run: PartRun, cleaner, holder, cell: BimanualCellParams, *, max_keys: int = 400):
    """Keyframes of the whole run: ``(times (k,) int frames at 30 fps, q_cleaner (k, 7),
    q_holder (k, 7), world_T_part (k, 4, 4))``, at most ``max_keys`` evenly spaced samples."""
    import pinocchio as pin

    from ..sim.cell import flange_T_part

    qc = np.concatenate([c for c, _, _ in run.execution.tracks])
    qh = np.concatenate([h for _, h, _ in run.execution.tracks])
    t = np.cumsum(np.concatenate([np.full(len(c), dt) for c, _, dt in run.execution.tracks]))
    keep = np.unique(np.linspace(0, len(t) - 1, min(max_keys, len(t))).astype(int))
    frames = np.maximum.accumulate(np.round(t[keep] * 30).astype(int))
    frames = frames + np.arange(len(frames))  # strictly increasing
    model, data = holder.model, holder.model.createData()
    fid = model.getFrameId("flange")
    parts = []
    for q in qh[keep]:
        pin.framesForwardKinematics(model, data, q)
        parts.append(cell.world_T_holder @ data.oMf[fid].homogeneous @ flange_T_part(cell))
    return frames, qc[keep], qh[keep], np.array(parts)


def replay_html(run: PartRun, path, *, cell: BimanualCellParams = BimanualCellParams(),
                toolpath: ToolpathParams = ToolpathParams()):
    """One meshcat HTML replaying the cell: both arms, the part and its tool paths, animated.

    The meshcat server is shut down on exit (also on error or interrupt).
    """
    from ..viz import meshcat_scene as ms
    from ..viz.scenes import robot_tracks

    cleaner, holder = cell_robots(cell, toolpath)
    frames, qc, qh, parts = replay_tracks(run, cleaner, holder, cell)
    with ms.scene() as vis:
        ms.add_robot(vis, "cleaner", cleaner, qc[0], world_T_base=cell.world_T_cleaner)
        ms.add_robot(vis, "holder", holder, qh[0], world_T_base=cell.world_T_holder)
        ms.add_mesh(vis, "part", run.state.mesh, color=(0.85, 0.85, 0.8), world_T_mesh=parts[0])
        stained = run.state.mesh.submesh([np.flatnonzero(run.state.initial > 0)], append=True)
        ms.add_mesh(vis, "part/stain", stained, color=(0.45, 0.3, 0.15))
        for i, (T, pts) in enumerate(run.execution.paths):
            ms.add_lines(vis, f"paths/{i}", pts[:-1], pts[1:], color=(0.9, 0.1, 0.1))
        tracks = {**robot_tracks(cleaner, "cleaner", np.repeat(cell.world_T_cleaner[None], len(qc), 0), qc),
                  **robot_tracks(holder, "holder", np.repeat(cell.world_T_holder[None], len(qh), 0), qh),
                  "part": parts}
        ms.animate(vis, tracks, times=frames, fps=30)
        ms.frame_camera(vis, [-0.3, -0.6, 0.0], [1.5, 0.6, 1.0])
        legend = ms.legend_html([((0.9, 0.1, 0.1), "tool path (contact)"), ((0.45, 0.3, 0.15), "stain (initial)")],
                                title=f"{run.name}: SIMULATED two-arm cell replay")
        return ms.save_html(vis, path, legend=legend)

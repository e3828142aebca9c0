"""Kabir et al.'s whole execution loop in the SIMULATED two-arm cell (Sec. VI-IX, IX-C), the
twin of :func:`mavac.cleaning.trial.run_trial`.

plan (setup planner, the holding arm's feasibility: :mod:`mavac.scrubbing.holding`) -> for each
setup: the holding arm moves the part there, the cleaning arm scrubs each pass under force
control with the Lissajous overlay, the camera looks after each pass
(:func:`mavac.scrubbing.scrub.execute_setup`) -> after the plan, re-plan the residue's patches
for at most ``max_rounds`` rounds. Everything measured here is SIMULATED.

Any part goes through it: :func:`run_part` takes a :class:`mavac.geometry.parts.Part`, its first
plan (:func:`cell_plan`) and one frozen :class:`PartRunParams`. The paper's parts, their operating
parameters and fast mode are in :mod:`mavac.experiments.kabir_bimanual`.

Random streams (:mod:`mavac.seeding`): ``"kabir stain"`` (hardness, process and pixel noise),
``"kabir setup motion"`` per round and setup (OMPL's seed).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..geometry.parts import Part
from ..geometry.transforms import look_at
from ..io import json_safe, write_json
from ..params import BimanualCellParams, LissajousParams, ToolpathParams
from ..seeding import check_seed, int_seed, rng_for
from ..setups.setup_plan import SetupPlan
from ..sim.world import SimWorld
from ..validate import check_bool, check_instance, check_int
from .cell import HOLDER_SEED, cell_robots
from .holding import HeldSetups, check_payload, plan_cell_setups, plan_params_for_cell, setup_configurations
from .residue import StainState, perceive, residue_faces
from .scene import SetupMotionError, check_held_start, open_cell, snapshot, stain_overlay, world_T_part
from .scrub import ApproachError, Execution, execute_setup
from .wear import stain_opacity, vector_from_lissajous

#: The operation vector's quantities, in the order of ``lissajous_from_vector``.
OPERATION = ("v", "f_n", "kappa", "f_x", "A_x")


@dataclass(frozen=True)
class PartRunParams:
    """Everything :func:`run_part` runs with, in one frozen bundle.

    Attributes
    ----------
    lissajous : LissajousParams
        The operating parameters (v, f_n, kappa and the Lissajous force). Required: Kabir et al.
        report them only for their bowl and hull
        (:func:`mavac.experiments.kabir_bimanual.paper_lissajous`), or learn them on the coupon.
    cell : BimanualCellParams
        The cell: placement, gains, time step, re-planning rounds (``max_rounds``);
        ``cell.part_mass`` must be within the holding arm's payload.
    toolpath : ToolpathParams
        Pad width (= slicing spacing), speeds, lift height.
    max_setups : int or None
        Execute only the first ``max_setups`` setups of each round's plan (None: all; ours, for
        a quick look at a part, as fast mode does with 1).
    """

    lissajous: LissajousParams
    cell: BimanualCellParams = BimanualCellParams()
    toolpath: ToolpathParams = ToolpathParams()
    max_setups: int | None = None

    def __post_init__(self):
        check_cell_inputs(self.cell, self.lissajous, self.toolpath)
        if self.max_setups is not None:
            check_int("max_setups", self.max_setups, 1)


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
    clean_residue: float = BimanualCellParams.clean_residue

    @property
    def status(self) -> str:
        """``"clean"`` (the camera's residue at most ``clean_residue``), ``"residue left"``, or
        ``"no setup"`` (the planner found none, or the holding arm could reach none: see ``notes``)."""
        if not self.execution.setups:
            return "no setup"
        last = self.state.images[-1]["residue_fraction"] if self.state.images else 1.0
        return "clean" if last <= self.clean_residue else "residue left"

    def setup_records(self) -> list[dict]:
        """One dict per executed setup: its pose, its passes' contact measures, stain removed."""
        ex = self.execution
        # the stain after each pass, the initial one first: a setup's passes run from first_row
        stain = [self.state.initial.sum()] + [t.sum() for _, t in ex.stain_states]
        ends = [s["first_row"] for s in ex.setups[1:]] + [len(ex.rows)]
        return [dict(label=s["label"], base_T_part=s["world_T_part"], q_holder=s["q_holder"], patches=s["patches"],
                     passes=[{("pass" if k == "pass_" else k): v for k, v in row.items() if k != "setup"}
                             for row in ex.rows[s["first_row"]:end]],
                     stain_removed=float((stain[s["first_row"]] - stain[end]) / stain[0]))
                for s, end in zip(ex.setups, ends)]

    def to_dict(self) -> dict:
        """The run as JSON-ready data (NaN as None): status, operating parameters, setups, notes."""
        rows = self.execution.rows
        return json_safe(dict(
            part=self.name, simulated=True, status=self.status, rounds=self.rounds, stain_removed=self.stain_removed,
            unseen_faces=self.unseen_faces, operation=dict(zip(OPERATION, vector_from_lissajous(self.lissajous))),
            failed_passes=sum(r["failed"] for r in rows), wall_s=self.seconds,
            frame="base_T_part: the part frame in the cleaning arm's base frame (metres)",
            setups=self.setup_records(), notes=self.notes))

    def row(self) -> dict:
        """The run in one row (SIMULATED): its status and size, the stain removed, and over ALL
        its passes the least duty, the force errors over all commanded steps and over contact
        steps (step-weighted means of :meth:`mavac.scrubbing.scrub.ScrubLog.row`'s), the integral's
        saturated share, the contact steps no plan allows, failed passes and the deepest wear."""
        rows = self.execution.rows
        col = {k: np.array([r[k] for r in rows], dtype=float) for k in _ROW_MEASURES}
        cmd, on = col["commanded_steps"], col["contact_steps"]
        return dict(part=self.name, status=self.status, stain_removed=self.stain_removed, replan_rounds=self.rounds,
                    setups_executed=len(self.execution.setup_times), passes=len(rows), f_n_commanded=self.lissajous.f_n,
                    duty_min=_finite(col["duty"], np.min),
                    duty=on.sum() / cmd.sum() if rows else np.nan,
                    force_error_all=_weighted(col["force_error_all"], cmd),
                    force_rms_all=np.sqrt(_weighted(col["force_rms_all"] ** 2, cmd)),
                    force_error_contact=_weighted(col["force_error_contact"], on),
                    force_rms_contact=np.sqrt(_weighted(col["force_rms_contact"] ** 2, on)),
                    integral_saturated_share=col["integral_saturated_steps"].sum() / cmd.sum() if rows else np.nan,
                    **{k: int(col[k].sum()) for k in _CONTACT_STEPS}, failed_passes=int(col["failed"].sum()),
                    wear_depth_max_mm=_finite(col["wear_depth_max_mm"], np.max),
                    residue_final=rows[-1]["residue_fraction"] if rows else np.nan, faces_unseen=self.unseen_faces,
                    wall_s=self.seconds)

    def summary(self) -> str:
        """A few lines a person can read (every number SIMULATED)."""
        r = self.row()
        lines = [f"{self.name}: {self.status}, {100 * self.stain_removed:.1f} % of the stain removed in "
                 f"{len(self.execution.setups)} setups, {r['passes']} passes, {self.rounds} re-planning rounds "
                 f"(SIMULATED; {self.seconds:.0f} s wall)"]
        if r["passes"]:
            err = np.nanmean([row["force_error_all"] for row in self.execution.rows])
            other = r["nonpad_part_steps"] + r["arm_arm_steps"] + r["arm_floor_steps"]
            lines.append(f"  pad on the part {100 * r['duty_min']:.0f} % of commanded contact at worst; force error "
                         f"over commanded steps {100 * err:+.1f} % (mean of passes); {other} steps of other contact, "
                         f"{r['failed_passes']} failed passes")
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_json(self, path):
        """Write :meth:`to_dict` atomically."""
        return write_json(self.to_dict(), path)

    def to_html(self, path, *, cell: BimanualCellParams = BimanualCellParams(),
                toolpath: ToolpathParams = ToolpathParams()):
        """Meshcat replay of the run (:func:`mavac.scrubbing.replay.replay_html`): both arms,
        the part, the tool paths, the stain fading as it is removed."""
        from .replay import replay_html

        return replay_html(self, path, cell=cell, toolpath=toolpath)


#: the contact steps no plan allows, summed over a run's passes by :meth:`PartRun.row`
_CONTACT_STEPS = ("nonpad_part_steps", "arm_arm_steps", "arm_floor_steps", "pad_touch_outside_steps")
#: the per-pass measures :meth:`PartRun.row` reads
_ROW_MEASURES = ("commanded_steps", "contact_steps", "duty", "force_error_all", "force_rms_all", "force_error_contact",
                 "force_rms_contact", "integral_saturated_steps", "failed", "wear_depth_max_mm", *_CONTACT_STEPS)


def _finite(values: np.ndarray, reduce) -> float:
    """``reduce`` over the finite ``values`` (NaN when there is none)."""
    ok = np.isfinite(values)
    return float(reduce(values[ok])) if ok.any() else float("nan")


def _weighted(values, weights) -> float:
    """Mean of per-pass ``values`` weighted by their step counts (NaN passes left out)."""
    v, w = np.asarray(values, float), np.asarray(weights, float)
    ok = np.isfinite(v) & (w > 0)
    return float((v[ok] * w[ok]).sum() / w[ok].sum()) if ok.any() else float("nan")


def check_cell_inputs(cell: BimanualCellParams, lissajous: LissajousParams, toolpath: ToolpathParams) -> None:
    """Parameter objects of a cell run (each error names the parameter)."""
    check_instance("cell", cell, BimanualCellParams)
    check_instance("lissajous", lissajous, LissajousParams)
    check_instance("toolpath", toolpath, ToolpathParams)


def cell_plan(part: Part, params: PartRunParams, *, robots=None) -> SetupPlan:
    """Kabir's setup plan of ``part`` for the cell (:func:`mavac.scrubbing.holding.plan_cell_setups`:
    the paper's DFBnB planner over the cell's setup square, setups the holding arm cannot present
    dropped): the ``plan`` :func:`run_part` starts from, and each re-planning round's.
    ``robots``: the cell's ``(cleaner, holder)`` if built already (:func:`mavac.scrubbing.cell.cell_robots`)."""
    cleaner, holder = cell_robots(params.cell, params.toolpath) if robots is None else robots
    return plan_cell_setups(part, cleaner, holder, params.cell, plan_params_for_cell(params.cell))


def run_part(part: Part, plan: SetupPlan, *, params: PartRunParams, seed: int = 0, snapshots: bool = True) -> PartRun:
    """Execute ``plan`` on ``part`` in the cell, then re-plan the residue the camera sees up to
    ``params.cell.max_rounds`` times: the twin of :func:`mavac.cleaning.trial.run_trial`.

    Parameters
    ----------
    part : Part
        Any part in its part frame, metres: a paper part
        (:func:`mavac.experiments.kabir_bimanual.paper_part`) or a user's
        (:func:`mavac.geometry.stain_marking.mark_stain`).
    plan : SetupPlan
        The first round's plan of this part (:func:`cell_plan`).
    params : PartRunParams
    seed : int, >= 0
        The stain's hardness, process and pixel noise, and the setup motions.
    snapshots : bool
        Take pybullet camera snapshots before and after each pass.

    Returns
    -------
    PartRun (SIMULATED)
    """
    t0 = time.perf_counter()
    check_instance("part", part, Part)
    check_instance("plan", plan, SetupPlan)
    check_instance("params", params, PartRunParams)
    if plan.part_name != part.name:
        raise ValueError(f"plan is for part {plan.part_name!r}, not {part.name!r}: plan it with cell_plan(part, params)")
    seed, snapshots = check_seed(seed), check_bool("snapshots", snapshots)
    check_payload(params.cell)
    rng = rng_for(seed, "kabir stain")
    state = StainState.from_part(part, rng, image_size=params.cell.image_size)
    out = Execution()
    out.stain_images.append(perceive(state, state.initial, part.stain_faces, rng)["image"])
    robots = cell_robots(params.cell, params.toolpath)
    with SimWorld(time_step=params.cell.time_step, seed=seed) as world:
        sim = open_cell(world, *robots, part.mesh, HOLDER_SEED, params=params.cell,
                        pad_width=params.toolpath.tool_width_m)
        check_held_start(sim, part.mesh)
        rounds = _Rounds(part, params, robots, state, out, rng, seed, _snapshot_fn() if snapshots else None)
        rounds.run(sim, plan)
    removed = float(1.0 - state.thickness[part.stain_faces].sum() / state.initial[part.stain_faces].sum())
    return PartRun(part.name, rounds.plans, out, state, rounds.round, removed, rounds.unseen, params.lissajous,
                   time.perf_counter() - t0, rounds.notes, params.cell.clean_residue)


@dataclass
class _Rounds:
    """The re-planning rounds of :func:`run_part`: execute a plan, look, plan the residue."""

    part: Part
    params: PartRunParams
    robots: tuple
    state: StainState
    out: Execution
    rng: np.random.Generator
    seed: int
    shot: object
    plans: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    round: int = 0
    unseen: int = 0

    def run(self, sim, plan: SetupPlan) -> None:
        """Execute ``plan``, then re-plan what the camera still sees until done (the notes say why)."""
        current = self.part
        while True:
            self.plans.append(plan)
            if len(plan.setups) == 0:
                self.notes.append(f"round {self.round}: the planner found no setup for the "
                                  f"{len(current.stain_faces)} faces left")
                return
            if not self.execute(sim, current, plan):  # nothing scrubbed, nothing new to look at
                return
            current = self.residue(current)
            if current is None:
                return
            plan = cell_plan(current, self.params, robots=self.robots)

    def execute(self, sim, current: Part, plan: SetupPlan) -> bool:
        """Every setup of ``plan`` (the first ``max_setups``); whether any pass ran."""
        p = self.params
        setups = plan.setups[: p.max_setups]
        qs = setup_configurations(HeldSetups(*self.robots, self.part.mesh, p.cell), setups, sim.holder.q())
        passes_before = len(self.out.rows)
        for j, (q, patches) in enumerate(zip(qs, plan.patches)):
            label = f"round {self.round} setup {j + 1}"
            try:
                execute_setup(sim, current, patches, q, self.state, p.lissajous, p.toolpath, self.rng, self.out,
                              label=label, snapshot=self.shot,
                              seed=int_seed(self.seed, "kabir setup motion", self.round, j))
            except SetupMotionError as exc:  # raised before the setup touches anything
                self.notes.append(f"{label} skipped: {exc}")
            except ApproachError as exc:  # the part presented, released again, nothing scrubbed
                self.notes.append(f"{label} presented but not scrubbed: {exc}")
        return len(self.out.rows) > passes_before

    def residue(self, current: Part) -> Part | None:
        """The part with the stain the camera still sees, for the next round; None when done."""
        last = self.state.images[-1]
        left, self.unseen = residue_faces(self.state, last["mask"], self.part.stain_faces)
        if last["residue_fraction"] <= self.params.cell.clean_residue or self.round >= self.params.cell.max_rounds \
                or len(left) == 0:
            return None
        if np.isin(current.stain_faces, left).all():  # re-planning would repeat this round
            self.notes.append(f"round {self.round}: no progress, the camera still sees all "
                              f"{len(current.stain_faces)} faces of this round stained; re-planning stopped")
            return None
        self.round += 1
        return Part(self.part.name, self.part.mesh, left, np.ones(len(left), dtype=np.int64), np.ones(len(left)),
                    f"residue after round {self.round - 1}")


def _snapshot_fn():
    """pybullet camera snapshot of the cell with the current stain drawn on the part, looking
    at the stain from the side it faces (:func:`snapshot_view`)."""
    def shoot(sim, state):
        world_T_camera = snapshot_view(state.mesh, np.flatnonzero(state.initial > 0), world_T_part(sim))
        ids = stain_overlay(sim, stain_opacity(state.thickness))
        try:
            return snapshot(sim, world_T_camera)
        finally:
            for body in ids:
                sim.world.remove_body(body)
    return shoot


#: Distance of the snapshot camera from the stain's centre, m (ours: a 20 cm part and the pad
#: fill pybullet's 40 deg view).
SNAPSHOT_DISTANCE = 0.5
#: Upward lean of the snapshot camera's line of sight, added to the stain's mean normal (ours: a
#: view a little from above, as the paper's photographs are taken).
SNAPSHOT_LIFT = np.array([0.0, 0.0, 0.5])


def snapshot_view(mesh, faces, world_T_part) -> np.ndarray:
    """Camera pose (OpenCV convention) looking at the centre of ``faces`` along their
    area-weighted mean normal, lifted by :data:`SNAPSHOT_LIFT`; from -y when the normals cancel.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Part frame, metres.
    faces : (k,) int
        The stain.
    world_T_part : (4, 4) float
    """
    R, t = world_T_part[:3, :3], world_T_part[:3, 3]
    target = R @ mesh.triangles_center[faces].mean(axis=0) + t
    normal = R @ (mesh.area_faces[faces, None] * mesh.face_normals[faces]).sum(axis=0)
    length = np.linalg.norm(normal)
    direction = (normal / length if length > 1e-9 else np.array([0.0, -1.0, 0.0])) + SNAPSHOT_LIFT
    return look_at(target + SNAPSHOT_DISTANCE * direction / np.linalg.norm(direction), target)

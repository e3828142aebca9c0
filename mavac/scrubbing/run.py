"""Kabir et al.'s whole execution loop in the SIMULATED two-arm cell (Sec. VI-IX, IX-C), the
twin of :func:`mavac.cleaning.trial.run_trial`.

plan (setup planner, the holding arm's feasibility: :mod:`mavac.scrubbing.holding`) -> for each
setup: the holding arm moves the part there, the cleaning arm scrubs each pass under force
control with the Lissajous overlay, the camera looks after each pass
(:func:`mavac.scrubbing.scrub.execute_setup`) -> after the plan, re-plan the residue's patches
for at most ``max_rounds`` rounds. Everything measured here is SIMULATED.

Random streams (:mod:`mavac.seeding`): ``"kabir stain"`` (hardness, process and pixel noise),
``"kabir fast stain"`` (the fast-mode stain), ``"kabir setup motion"`` per round and setup
(OMPL's seed).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..geometry.parts import PART_NAMES, Part, load_part, stain_from_field
from ..geometry.transforms import look_at
from ..io import json_safe, write_json
from ..paper import paper_scalar
from ..params import BimanualCellParams, LissajousParams, ToolpathParams
from ..seeding import check_seed, int_seed, rng_for
from ..sim.world import SimWorld
from ..validate import ParameterTypeError, check_bool, check_instance
from .cell import HOLDER_SEED, cell_robots
from .holding import HeldSetups, check_payload, plan_cell_setups, plan_params_for_cell, setup_configurations
from .residue import StainState, perceive, residue_faces
from .scene import SetupMotionError, check_held_start, open_cell, snapshot, stain_overlay, world_T_part
from .scrub import ApproachError, Execution, execute_setup
from .wear import lissajous_from_vector, stain_opacity, vector_from_lissajous

#: Fast mode: stained faces of the coarse run (ours: a few seconds of scrubbing).
FAST_STAIN_FACES = 300
#: The operation vector's quantities, in the order of ``lissajous_from_vector``.
OPERATION = ("v", "f_n", "kappa", "f_x", "A_x")


def paper_operation(part: str) -> tuple[float, ...]:
    """The operation vector ``(v, f_n [N], kappa [N/m], f_x [Hz], A_x [N])`` Kabir et al. found
    for ``part`` ("bowl" or "hull", Sec. IX-C), read from ``data/paper_values.csv``."""
    return tuple(paper_scalar("kabir", "Sec. IX-C GPR", q, f"part={part}") for q in OPERATION)


def paper_lissajous(part: str) -> LissajousParams:
    """:func:`paper_operation` as LissajousParams."""
    return lissajous_from_vector(np.asarray(paper_operation(part), float)[None])


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

    def summary(self) -> str:
        """A few lines a person can read (every number SIMULATED)."""
        rows = self.execution.rows
        lines = [f"{self.name}: {self.status}, {100 * self.stain_removed:.1f} % of the stain removed in "
                 f"{len(self.execution.setups)} setups, {len(rows)} passes, {self.rounds} re-planning rounds "
                 f"(SIMULATED; {self.seconds:.0f} s wall)"]
        if rows:
            duty = min(r["duty"] for r in rows)
            err = np.nanmean([r["force_error_all"] for r in rows])
            other = sum(r["nonpad_part_steps"] + r["arm_arm_steps"] + r["arm_floor_steps"] for r in rows)
            lines.append(f"  pad on the part {100 * duty:.0f} % of commanded contact at worst; force error over "
                         f"commanded steps {100 * err:+.1f} % (mean of passes); {other} steps of other contact, "
                         f"{sum(r['failed'] for r in rows)} failed passes")
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


def part_for_run(name: str, *, fast: bool, seed: int = 0) -> Part:
    """The part (paper scale) or, fast, the same mesh with a FAST_STAIN_FACES-face stain needing one pass."""
    part = load_part(name, seed=seed)
    if not fast:
        return part
    rng = rng_for(seed, "kabir fast stain")
    stain, _, intensity = stain_from_field(part.mesh, FAST_STAIN_FACES, rng, pass_range=(1, 1))
    return Part(name, part.mesh, stain, np.ones(len(stain), dtype=np.int64), intensity,
                f"fast mode: {FAST_STAIN_FACES} stain faces")


def check_cell_inputs(cell: BimanualCellParams, lissajous: LissajousParams, toolpath: ToolpathParams) -> None:
    """Parameter objects of a cell run (each error names the parameter)."""
    check_instance("cell", cell, BimanualCellParams)
    check_instance("lissajous", lissajous, LissajousParams)
    check_instance("toolpath", toolpath, ToolpathParams)


def run_part(part: str | Part, *, fast: bool, lissajous: LissajousParams | None = None, seed: int = 0,
             cell: BimanualCellParams = BimanualCellParams(), toolpath: ToolpathParams = ToolpathParams(),
             snapshots: bool = True) -> PartRun:
    """Plan and execute a part in the cell; re-plan the residue up to ``cell.max_rounds`` times.

    Parameters
    ----------
    part : str or Part
        A paper part of :func:`mavac.geometry.parts.load_part` ("bowl", "hull"), or any part
        (:func:`mavac.geometry.stain_marking.mark_stain`) in its part frame, metres.
    fast : bool
        One hierarchical-sampling level, the first setup only, no re-planning; a paper part
        also gets a FAST_STAIN_FACES-face stain (a user's part keeps its own).
    lissajous : LissajousParams, optional
        Default: the paper's parameters for a paper part (:func:`paper_lissajous`). Required for
        a user's part (the paper gives none for it; ``paper_lissajous("hull")`` is one choice).
    seed : int, >= 0
    cell, toolpath : BimanualCellParams, ToolpathParams
        ``cell.part_mass`` is the part's mass, kg; it must be within the holding arm's payload.
    snapshots : bool
        Take pybullet camera snapshots before and after each pass.
    """
    t0 = time.perf_counter()
    fast = check_bool("fast", fast)
    seed = check_seed(seed)
    part, lissajous = _part_and_operation(part, lissajous, fast=fast, seed=seed)
    check_cell_inputs(cell, lissajous, toolpath)
    check_payload(cell)
    if fast:
        cell = replace(cell, max_rounds=0, sampling=replace(cell.sampling, max_levels=1))
    cleaner, holder = cell_robots(cell, toolpath)
    rng = rng_for(seed, "kabir stain")
    state = StainState.from_part(part, rng, image_size=cell.image_size)
    out = Execution()
    out.stain_images.append(perceive(state, state.initial, part.stain_faces, rng)["image"])
    plans, rounds, current, notes, unseen = [], 0, part, [], 0
    with SimWorld(time_step=cell.time_step, seed=seed) as world:
        sim = open_cell(world, cleaner, holder, part.mesh, HOLDER_SEED, params=cell, pad_width=toolpath.tool_width_m)
        check_held_start(sim, part.mesh)
        shot = _snapshot_fn() if snapshots else None
        while True:
            plan = plan_cell_setups(current, cleaner, holder, cell, plan_params_for_cell(cell))
            plans.append(plan)
            if len(plan.setups) == 0:
                notes.append(f"round {rounds}: the planner found no setup for the {len(current.stain_faces)} faces left")
                break
            setups = plan.setups[:1] if fast else plan.setups
            qs = setup_configurations(HeldSetups(cleaner, holder, part.mesh, cell), setups, sim.holder.q())
            passes_before = len(out.rows)
            for j, (q, patches) in enumerate(zip(qs, plan.patches)):
                try:
                    execute_setup(sim, current, patches, q, state, lissajous, toolpath, rng, out,
                                  label=f"round {rounds} setup {j + 1}", snapshot=shot,
                                  seed=int_seed(seed, "kabir setup motion", rounds, j))
                except SetupMotionError as exc:  # raised before the setup touches anything
                    notes.append(f"round {rounds} setup {j + 1} skipped: {exc}")
                except ApproachError as exc:  # the part presented, released again, nothing scrubbed
                    notes.append(f"round {rounds} setup {j + 1} presented but not scrubbed: {exc}")
            if len(out.rows) == passes_before:  # nothing scrubbed, nothing new to look at
                break
            last = state.images[-1]
            left, unseen = residue_faces(state, last["mask"], part.stain_faces)
            if last["residue_fraction"] <= cell.clean_residue or rounds >= cell.max_rounds or len(left) == 0:
                break
            if np.isin(current.stain_faces, left).all():  # re-planning would repeat this round
                notes.append(f"round {rounds}: no progress, the camera still sees all {len(current.stain_faces)} "
                             "faces of this round stained; re-planning stopped")
                break
            rounds += 1
            current = Part(part.name, part.mesh, left, np.ones(len(left), dtype=np.int64), np.ones(len(left)),
                           f"residue after round {rounds - 1}")
    removed = float(1.0 - state.thickness[part.stain_faces].sum() / state.initial[part.stain_faces].sum())
    return PartRun(part.name, plans, out, state, rounds, removed, unseen, lissajous, time.perf_counter() - t0, notes,
                   cell.clean_residue)


def _part_and_operation(part, lissajous, *, fast: bool, seed: int) -> tuple[Part, LissajousParams]:
    """The part to run and its operating parameters (a paper part by name, or a user's Part)."""
    if isinstance(part, Part):
        if lissajous is None:
            raise ValueError("lissajous is required for a user's part (Kabir et al. give operating parameters only "
                             "for the bowl and the hull): e.g. lissajous=paper_lissajous('hull')")
        return part, lissajous
    if not isinstance(part, str):
        raise ParameterTypeError(f"part must be a part name (str) or a Part, got {part!r} ({type(part).__name__})")
    if part not in PART_NAMES:
        raise ValueError(f"part must be one of {PART_NAMES} or a Part, got {part!r}")
    return part_for_run(part, fast=fast, seed=seed), paper_lissajous(part) if lissajous is None else lissajous


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

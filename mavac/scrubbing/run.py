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
from ..paper import paper_scalar
from ..params import BimanualCellParams, LissajousParams, ToolpathParams
from ..seeding import check_seed, int_seed, rng_for
from ..sim.world import SimWorld
from ..validate import ParameterTypeError, check_bool, check_instance
from .cell import HOLDER_SEED, cell_robots
from .holding import HeldSetups, plan_cell_setups, plan_params_for_cell, setup_configurations
from .residue import StainState, perceive, residue_faces
from .scene import open_cell, snapshot, stain_overlay, world_T_part
from .scrub import Execution, execute_setup
from .wear import lissajous_from_vector, stain_opacity

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


def run_part(name: str, *, fast: bool, lissajous: LissajousParams | None = None, seed: int = 0,
             cell: BimanualCellParams = BimanualCellParams(), toolpath: ToolpathParams = ToolpathParams(),
             snapshots: bool = True) -> PartRun:
    """Plan and execute a part in the cell; re-plan the residue up to ``cell.max_rounds`` times.

    Parameters
    ----------
    name : str
        A part of :func:`mavac.geometry.parts.load_part` ("bowl", "hull").
    fast : bool
        A FAST_STAIN_FACES-face stain, one hierarchical-sampling level, the first setup only,
        no re-planning.
    lissajous : LissajousParams, optional
        Default: the paper's parameters for the part (:func:`paper_lissajous`).
    seed : int, >= 0
    cell, toolpath : BimanualCellParams, ToolpathParams
    snapshots : bool
        Take pybullet camera snapshots before and after each pass.
    """
    t0 = time.perf_counter()
    if not isinstance(name, str):
        raise ParameterTypeError(f"name must be a part name (str), got {name!r} ({type(name).__name__})")
    if name not in PART_NAMES:
        raise ValueError(f"name must be one of {PART_NAMES}, got {name!r}")
    fast = check_bool("fast", fast)
    seed = check_seed(seed)
    lissajous = paper_lissajous(name) if lissajous is None else lissajous
    check_cell_inputs(cell, lissajous, toolpath)
    part = part_for_run(name, fast=fast, seed=seed)
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
                              label=f"round {rounds} setup {j + 1}", snapshot=shot,
                              seed=int_seed(seed, "kabir setup motion", rounds, j))
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

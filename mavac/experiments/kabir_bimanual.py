"""Notebook 11: Kabir et al.'s physical experiments (Sec. IX-C) in the SIMULATED two-arm cell:
the tables and figures.

The cell and its loop live in :mod:`mavac.scrubbing` (:func:`mavac.scrubbing.run.run_part`,
:class:`mavac.scrubbing.coupon.CouponCell`) and take any part. Here are the paper's: its bowl
and hull (:func:`paper_part`), their operating parameters (:func:`paper_lissajous`) and fast
mode (:func:`run_paper_part`). :func:`learn_on_coupon` runs the GPR learner (Sec. VIII) with the
paper's thresholds on the coupon; :func:`cell_for_parts` places the cell's setup square by the
paper's narrowing; the rest tabulates (Table VII, ``kabir_execution.csv``) and draws
(Figs. 10-13) what :func:`mavac.scrubbing.run.run_part` returned.

Random streams (:mod:`mavac.seeding`): ``"kabir fast stain"`` (the fast-mode stain).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from ..geometry.parts import Part, load_part, stain_from_field
from ..paper import paper_scalar
from ..params import BimanualCellParams, GPRParams, LissajousParams, ToolpathParams
from ..scrubbing.cell_space import narrowed_cell_space
from ..scrubbing.coupon import CouponCell, calibrated_preston
from ..scrubbing.gpr import learn_parameters
from ..scrubbing.lissajous import vector_excursions
from ..scrubbing.run import OPERATION, PartRun, PartRunParams, cell_plan, run_part
from ..scrubbing.wear import lissajous_from_vector
from ..seeding import check_seed, rng_for
from ..validate import check_bool, check_instance

PARTS = ("bowl", "hull")
#: Fast mode: stained faces of the coarse run (ours: a few seconds of scrubbing).
FAST_STAIN_FACES = 300


def paper_operation(part: str) -> tuple[float, ...]:
    """The operation vector ``(v, f_n [N], kappa [N/m], f_x [Hz], A_x [N])`` Kabir et al. found
    for ``part`` ("bowl" or "hull", Sec. IX-C), read from ``data/paper_values.csv``."""
    if part not in PARTS:
        raise ValueError(f"part must be one of {PARTS} (Kabir et al. give operating parameters for no other), "
                         f"got {part!r}")
    return tuple(paper_scalar("kabir", "Sec. IX-C GPR", q, f"part={part}") for q in OPERATION)


def paper_lissajous(part: str) -> LissajousParams:
    """:func:`paper_operation` as LissajousParams."""
    return lissajous_from_vector(np.asarray(paper_operation(part), float)[None])


def paper_part(name: str, *, fast: bool, seed: int = 0) -> Part:
    """A paper part (:func:`mavac.geometry.parts.load_part`) or, fast, the same mesh with a
    :data:`FAST_STAIN_FACES`-face stain needing one pass."""
    part = load_part(name, seed=seed)
    if not fast:
        return part
    stain, _, intensity = stain_from_field(part.mesh, FAST_STAIN_FACES, rng_for(seed, "kabir fast stain"),
                                           pass_range=(1, 1))
    return Part(name, part.mesh, stain, np.ones(len(stain), dtype=np.int64), intensity,
                f"fast mode: {FAST_STAIN_FACES} stain faces")


def run_params(lissajous: LissajousParams, *, fast: bool, cell: BimanualCellParams = BimanualCellParams(),
               toolpath: ToolpathParams = ToolpathParams()) -> PartRunParams:
    """The run's parameters; fast mode: one hierarchical-sampling level, the first setup only, no
    re-planning (same code paths)."""
    if check_bool("fast", fast):
        check_instance("cell", cell, BimanualCellParams)
        cell = replace(cell, max_rounds=0, sampling=replace(cell.sampling, max_levels=1))
    return PartRunParams(lissajous, cell, toolpath, max_setups=1 if fast else None)


def run_paper_part(part: str, *, fast: bool, lissajous: LissajousParams | None = None, seed: int = 0,
                   cell: BimanualCellParams = BimanualCellParams(), toolpath: ToolpathParams = ToolpathParams(),
                   snapshots: bool = True) -> PartRun:
    """:func:`mavac.scrubbing.run.run_part` on the paper's ``part`` ("bowl" or "hull",
    :func:`paper_part`), with ``lissajous`` or, by default, the paper's operating parameters for it
    (:func:`paper_lissajous`)."""
    check_instance("part", part, str)
    if part not in PARTS:
        raise ValueError(f"part must be one of {PARTS} (Kabir et al.'s parts), got {part!r}")
    params = run_params(paper_lissajous(part) if lissajous is None else lissajous, fast=fast, cell=cell,
                        toolpath=toolpath)
    stained = paper_part(part, fast=fast, seed=check_seed(seed))
    return run_part(stained, cell_plan(stained, params), params=params, seed=seed, snapshots=snapshots)


def paper_thresholds(part: str) -> tuple[float, float]:
    """Kabir Sec. IX-C: the learner's ``(C_p^th, P_th)`` for ``part``, from ``data/paper_values.csv``."""
    return tuple(paper_scalar("kabir", "Sec. IX-C GPR", q, f"part={part}") for q in ("Cp_th", "P_th"))


def cell_for_parts(cell: BimanualCellParams, toolpath: ToolpathParams, *, fast: bool, seed: int = 0):
    """``cell`` with its setup square placed by the paper's narrowing (Sec. IV-A) over the stains
    of :data:`PARTS` as :func:`mavac.scrubbing.run.run_part` scrubs them
    (:func:`mavac.scrubbing.cell_space.narrowed_cell_space`), and the narrowing's table."""
    parts = {p: paper_part(p, fast=fast, seed=seed) for p in PARTS}
    space, info = narrowed_cell_space(parts, cell, toolpath)
    return replace(cell, space=space), info


# ---------------------------------------------------------------- the GPR learner on a coupon


def learn_on_coupon(part: str, experiment: CouponCell, *, budget: int, seed: int = 0):
    """GPR learner (Sec. VIII) with the paper's thresholds for ``part``, on the coupon in the cell
    (``experiment``, an open :class:`CouponCell`).

    The learner's feasibility rule also refuses every point whose oscillation would swing the
    pad more than one pad width off its path (the cell's path-deviation cap,
    :func:`mavac.scrubbing.lissajous.vector_excursions`): such points are never run.

    Returns
    -------
    (GPRResult, LissajousParams)
        The learner's outcome and the parameters the run uses: the learned ones when the learner
        found a feasible point, else the paper's values for that part (the result says which).
    """
    cp_th, p_th = paper_thresholds(part)
    params = GPRParams(Cp_th=cp_th, P_th=p_th, max_experiments=budget, seed=seed)
    cap = experiment.toolpath.tool_width_m  # the cell's path-deviation cap: one pad width
    result = learn_parameters(experiment, params, rng=rng_for(seed, "coupon gpr"),
                              admissible=lambda X: vector_excursions(X) <= cap)
    x = paper_operation(part) if not result.feasible else [result.chosen[k] for k in OPERATION]
    return result, lissajous_from_vector(np.asarray(x, float)[None])


def preston_table(coupon: CouponCell, points: dict, *, factors=(0.5, 1.0, 2.0)) -> pd.DataFrame:
    """C_p of one coupon stroke at each operation point for the cell's Preston constant times
    ``factors`` (its sensitivity), and the constant each part's paper threshold would calibrate
    on this coupon (:func:`mavac.scrubbing.coupon.calibrated_preston`).

    Parameters
    ----------
    coupon : CouponCell
        Open.
    points : dict (part, parameters) -> (5,) float
        Operation vectors, e.g. ``("bowl", "paper") -> paper_operation("bowl")``.
    factors : sequence of float
        Multiples of ``coupon.params.preston``.
    """
    rows = []
    for (part, source), x in points.items():
        cp_th = paper_thresholds(part)[0]
        coupon(x)  # the stroke, run once
        held = coupon.held_contact(coupon.stroke_row(x))  # else C_p is 0 whatever the constant
        row = dict(part=part, parameters=source, held_contact=held, Cp_th=cp_th,
                   preston_for_Cp_th=calibrated_preston(coupon, x, cp_th) if held else float("nan"))
        row.update({f"C_p_x{f:g}": coupon.c_p_at(x, f * coupon.params.preston) for f in factors})
        rows.append(row)
    return pd.DataFrame(rows)


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


#: Columns of ``kabir_execution.csv``: the pass, then every contact measure of
#: :meth:`mavac.scrubbing.scrub.ScrubLog.row`, then what the camera saw.
EXECUTION_COLUMNS = ["part", "parameters", "setup", "pass", "path_length_m", "commanded_steps", "contact_steps",
                     "duty", "contact_s", "f_n_n", "mean_force_all_n", "force_error_all", "force_rms_all",
                     "mean_force_contact_n", "force_error_contact", "force_rms_contact", "integral_saturated_steps",
                     "integral_saturated_share", "nonpad_part_steps", "nonpad_part_peak_n", "arm_arm_steps",
                     "arm_arm_peak_n", "arm_floor_steps", "arm_floor_peak_n", "pad_touch_outside_steps", "failed",
                     "max_deviation_mm", "wear_depth_max_mm", "sliding_m", "residue_fraction", "C_p"]


def execution_table(runs: dict) -> pd.DataFrame:
    """``kabir_execution.csv``: one row per part, parameter set, round, setup and pass (SIMULATED).

    ``runs`` maps ``(part, parameters)`` (e.g. ``("hull", "learned")``) to a PartRun.
    """
    frames = []
    for (name, source), run in runs.items():
        df = pd.DataFrame(run.execution.rows)
        df.insert(0, "parameters", source)
        df.insert(0, "part", name)
        frames.append(df)
    df = pd.concat(frames, ignore_index=True).rename(columns={"pass_": "pass"})
    return df[EXECUTION_COLUMNS]


def summary_table(runs: dict) -> pd.DataFrame:
    """Per part and parameter set (keys of ``runs`` as in :func:`execution_table`), the run's
    :meth:`mavac.scrubbing.run.PartRun.row` (SIMULATED)."""
    return pd.DataFrame([dict(part=name, parameters=source, **{k: v for k, v in run.row().items() if k != "part"})
                         for (name, source), run in runs.items()])


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

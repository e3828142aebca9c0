"""Kabir et al.'s whole execution loop in the simulated two-arm cell (Sec. VI-IX, IX-C).

plan (setup planner, the holding arm's feasibility) -> for each setup: the holding arm moves
the part there (collision-free, timed) -> tool path of each pass (``toolpath_for_setup`` at
the part pose the simulation reports) -> the cleaning arm scrubs it under force control with
the Lissajous overlay (:func:`mavac.sim.bimanual.run_schedule`) -> stain removed by the
Preston law from the MEASURED contact (pressure x sliding per face, hardness and process noise
from the seed) -> stain image, K-means, C_p and residue after the pass -> after the plan,
re-plan the residue's patches for a bounded number of rounds. Everything measured here is
SIMULATED.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ..geometry.parts import Part
from ..params import (BimanualCellParams, LissajousParams, ReachParams, ScrubModel, SetupPlanParams,
                      ToolpathParams)
from ..robots.kinematics import ik_axis
from ..setups.held import HeldSetups
from ..setups.plan import SetupPlan, plan_setups
from ..setups.reach import base_T_part
from ..sim.bimanual import (REPLAY_EVERY, Cell, Schedule, check_force_limits, move_cleaner, move_holder, run_schedule,
                            world_T_part)
from ..sim.cell import CLEANER_PARK, holder_ik
from ..sim.wear import render_stain_states, stain_hardness, stain_opacity
from ..validate import check_instance
from ..vision.stain import cleaning_performance, face_index_image, stain_masks_kmeans, view_of_faces
from .lissajous import overlay_path
from .toolpath import PassPath, reachable_from_robot, toolpath_for_setup


def plan_params_for_cell(cell: BimanualCellParams, *, ik_restarts: int = 2, **changes) -> SetupPlanParams:
    """Setup-planner parameters for the cell: its setup space and sampling, the cleaning arm's
    pad as the reach test's tool, ``ik_restarts`` DLS restarts (ours: 2 gave the same bowl
    plan as 12 in a quarter of the time)."""
    return SetupPlanParams(space=cell.space, sampling=cell.sampling,
                           reach=ReachParams(tool_length=cell.tool_length, ik_restarts=ik_restarts), **changes)


def plan_cell_setups(part: Part, cleaner, holder, cell: BimanualCellParams, plan_params: SetupPlanParams) -> SetupPlan:
    """Kabir's setup planner for the cleaning arm, dropping setups the holding arm cannot present."""
    return plan_setups(part, robot=cleaner, params=plan_params, feasible=HeldSetups(cleaner, holder, part.mesh, cell))


# ---------------------------------------------------------------- schedules


def _free_move(points, R0, R1, speed, dt):
    """Samples of a repositioning polyline at ``speed`` with the tool frame slerped R0 -> R1."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(2, int(np.ceil(s[-1] / (speed * dt))) + 1)
    st = np.linspace(0.0, s[-1], n)
    pos = np.column_stack([np.interp(st, s, points[:, k]) for k in range(3)])
    rot = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([R0, R1])))(st / max(s[-1], 1e-12)).as_matrix()
    return pos, rot


def schedule_for_pass(pp: PassPath, lissajous: LissajousParams, toolpath: ToolpathParams, dt: float) -> Schedule:
    """One pass as a time-sampled schedule: each contact segment with the Lissajous overlay
    (tool frame forces), each repositioning move (lift, move, lower) in free motion.

    Raises ``ValueError`` naming ``toolpath`` when the pass has no contact segment.
    """
    if not pp.segments:
        raise ValueError(f"toolpath: pass {pp.pass_number} has no contact segment (nothing reachable to clean)")
    overlays = [overlay_path(seg, nrm, lissajous, dt=dt) for seg, nrm in zip(pp.segments, pp.normals)]
    entry = len(pp.repositions) == len(pp.segments)  # the first move comes from the previous pass
    parts = []
    for i, ov in enumerate(overlays):
        j = i if entry else i - 1
        if j >= 0:
            R0 = overlays[i - 1].rotations[-1] if i > 0 else ov.rotations[0]
            pos, rot = _free_move(pp.repositions[j], R0, ov.rotations[0], toolpath.reposition_speed_m_s, dt)
            parts.append((pos, rot, np.zeros((len(pos), 3)), np.zeros(len(pos), dtype=bool)))
        f_tool = np.einsum("nji,nj->ni", ov.rotations, ov.forces)
        parts.append((ov.nominal, ov.rotations, f_tool, np.ones(len(ov.t), dtype=bool)))
    return Schedule(*(np.concatenate([p[k] for p in parts]) for k in range(4)))


# ---------------------------------------------------------------- stain state and perception


@dataclass
class StainState:
    """SIMULATED stain on a part: thickness per face (layers), hardness, and the camera view.

    Attributes
    ----------
    mesh : trimesh.Trimesh
    initial, thickness : (F,) float
    hardness : (F,) float
    face_index : (H, W) int
        :func:`mavac.vision.stain.face_index_image` of the view framing the stain.
    """

    mesh: object
    initial: np.ndarray
    thickness: np.ndarray
    hardness: np.ndarray
    face_index: np.ndarray
    images: list = field(default_factory=list)

    @classmethod
    def from_part(cls, part: Part, rng: np.random.Generator, *, image_size: int, model: ScrubModel = ScrubModel()):
        F = len(part.mesh.faces)
        s = np.zeros(F)
        s[part.stain_faces] = part.intensity
        view = view_of_faces(part.mesh, part.stain_faces)
        return cls(part.mesh, s.copy(), s, stain_hardness(F, rng, model),
                   face_index_image(part.mesh, view, (image_size, image_size)))

    def scrub(self, removal, rng: np.random.Generator, model: ScrubModel = ScrubModel()) -> None:
        """Apply one pass's measured removal with process noise (log-normal per pass and face)."""
        eps = rng.lognormal(0.0, model.batch_noise) * rng.lognormal(0.0, model.face_noise, len(removal))
        self.thickness = np.clip(self.thickness - removal * eps / self.hardness, 0.0, 1.0)


def perceive(state: StainState, before, faces, rng: np.random.Generator, *, model: ScrubModel = ScrubModel(),
             noise_std: float = 0.02) -> dict:
    """Camera images of the initial, before-pass and current stain, one K-means for all three,
    C_p of the pass over its patches' pixels and the residue fraction of the whole stain.

    Returns
    -------
    dict: ``C_p``, ``residue_fraction``, ``image`` (current, (H, W, 3) uint8), ``mask`` (current
    stain mask), ``region`` (pixels of the initially stained faces).
    """
    fi = state.face_index
    on = fi >= 0
    idx = np.where(on, fi, 0)
    images = render_stain_states(state.mesh, (state.initial, before, state.thickness), fi, model=model,
                                 noise_std=noise_std, rng=rng)
    m0, mb, ma = stain_masks_kmeans(images, int(rng.integers(2**31 - 1)), region_mask=on)
    region = on & (state.initial[idx] > 0)
    pass_region = on & np.isin(idx, faces) & (before[idx] > 0)
    cp = cleaning_performance(mb, ma, pass_region) if pass_region.any() else float("nan")
    residue = float((ma & region).sum() / max((m0 & region).sum(), 1))
    return {"C_p": cp, "residue_fraction": residue, "image": images[2], "mask": ma, "region": region}


def residue_faces(state: StainState, mask, stain_faces) -> tuple[np.ndarray, int]:
    """Stain faces the camera still sees stained (most of their pixels in ``mask``), and how
    many stain faces the camera does not see at all."""
    fi = state.face_index
    on = fi >= 0
    counts = np.bincount(fi[on], minlength=len(state.initial))
    stained = np.bincount(fi[on & mask], minlength=len(state.initial))
    faces = np.asarray(stain_faces)
    seen = counts[faces] > 0
    dirty = seen & (stained[faces] * 2 > counts[faces])
    return faces[dirty], int((~seen).sum())


# ---------------------------------------------------------------- executing a plan


@dataclass
class Execution:
    """What one part's run produced (SIMULATED).

    Attributes
    ----------
    rows : list of dict
        One per (round, setup, pass): the columns of ``kabir_execution.csv``.
    setup_times : list of float
        Holding-arm motion time of each setup, s (first round first).
    forces : list of (k,) float
        Measured normal force at every contact step of each pass, N.
    snapshots : list of (str, (H, W, 3) uint8)
        pybullet camera snapshots (label, image).
    stain_images : list of (H, W, 3) uint8
        Stain camera images: initial, then after each pass.
    tracks : list of (q_cleaner (k, 7), q_holder (k, 7), dt)
        Replay samples for the meshcat animation, ``dt`` s apart.
    paths : list of (world_T_part, (k, 3) contact path points)
    """

    rows: list = field(default_factory=list)
    setup_times: list = field(default_factory=list)
    forces: list = field(default_factory=list)
    snapshots: list = field(default_factory=list)
    stain_images: list = field(default_factory=list)
    tracks: list = field(default_factory=list)
    paths: list = field(default_factory=list)


def execute_setup(cell: Cell, part: Part, patches, q_holder, state: StainState, lissajous: LissajousParams,
                  toolpath: ToolpathParams, rng: np.random.Generator, out: Execution, *, label: str,
                  snapshot=None, seed: int = 0) -> None:
    """Move the part to a setup, scrub every pass of its tool path, look after each pass."""
    out.setup_times.append(move_holder(cell, q_holder, seed=seed))
    _keep(out, cell, "holder", 8)
    T = world_T_part(cell)
    tp = toolpath_for_setup(part, T, np.asarray(patches), toolpath, reachable=reachable_from_robot(cell.cleaner_model))
    if snapshot is not None:
        out.snapshots.append((f"{label} before cleaning", snapshot(cell, state)))
    first = True
    for pp in tp.passes:
        if not pp.segments:
            continue
        sched = schedule_for_pass(pp, lissajous, toolpath, cell.world.time_step)
        if first:
            _approach(cell, sched, toolpath.lift_height_m, lissajous)
            _keep(out, cell, "cleaner", 8)
            first = False
        log = run_schedule(cell, sched, stiffness=lissajous.kappa_x)
        out.tracks.append((log.q_samples, np.repeat(cell.holder.q()[None], len(log.q_samples), 0),
                           REPLAY_EVERY * cell.world.time_step))
        before = state.thickness.copy()
        state.scrub(log.removal, rng)
        seen = perceive(state, before, part.stain_faces[pp.patch_ids], rng)
        state.images.append(seen)
        out.forces.append(log.normal_force[log.in_contact & log.commanded_contact])
        out.paths.append((T, np.vstack(pp.segments)))
        out.rows.append(dict(setup=label, pass_=pp.pass_number, path_length_m=pp.path_length_m,
                             contact_s=log.contact_s, mean_normal_force_n=log.mean_contact_force,
                             f_n_n=lissajous.f_n, sliding_m=log.sliding_m,
                             residue_fraction=seen["residue_fraction"], C_p=seen["C_p"]))
        out.stain_images.append(seen["image"])
        if snapshot is not None:
            out.snapshots.append((f"{label} after pass {pp.pass_number}", snapshot(cell, state)))
    move_cleaner(cell, CLEANER_PARK)
    _keep(out, cell, "cleaner", 8)


def _keep(out: Execution, cell: Cell, arm: str, every: int) -> None:
    """Replay samples of the last joint motion of ``arm`` (the other arm stands still)."""
    q = cell.log[arm][-1].q
    other = np.repeat((cell.cleaner if arm == "holder" else cell.holder).q()[None], len(q), 0)
    pair = (other, q) if arm == "holder" else (q, other)
    out.tracks.append((*pair, every * cell.world.time_step))


def _approach(cell: Cell, sched: Schedule, lift: float, lissajous: LissajousParams) -> None:
    """Joint motion of the cleaning arm above the schedule's first point, pad along its axis
    (``lift`` m above it, or half that, or on it: the first the arm reaches); checks that the
    commanded forces stay within the joint torque limits there."""
    R = sched.rotations[0]
    for h in (lift, lift / 2, 0.0):
        start = sched.positions[0] - h * R[:, 2]
        res = ik_axis(cell.cleaner_model, start[None], R[:, 2][None], q0=cell.cleaner_model.q_home)
        if res.success[0]:
            break
    else:
        raise RuntimeError("the cleaning arm cannot reach the start of the tool path")
    peak = np.array([lissajous.A_x, lissajous.A_y, lissajous.f_n])
    check_force_limits(cell.cleaner_model, res.q[0], R, peak, name="lissajous (f_n, A_x, A_y)")
    move_cleaner(cell, res.q[0])


def setup_configurations(holder_feasible: HeldSetups, setups, q_prev=None) -> np.ndarray:
    """Holding-arm configurations of a plan's setups, each seeded from the previous one."""
    out = []
    for s in np.asarray(setups, float).reshape(-1, 3):
        T = base_T_part(s[None], holder_feasible.params.space)
        res = holder_ik(holder_feasible.holder, T, holder_feasible.params, q0=q_prev)
        if not res.success[0]:
            res = holder_ik(holder_feasible.holder, T, holder_feasible.params)
        q_prev = res.q[0]
        out.append(q_prev)
    return np.array(out)


def check_cell_inputs(cell: BimanualCellParams, lissajous: LissajousParams, toolpath: ToolpathParams) -> None:
    """Parameter objects of a cell run (each error names the parameter)."""
    check_instance("cell", cell, BimanualCellParams)
    check_instance("lissajous", lissajous, LissajousParams)
    check_instance("toolpath", toolpath, ToolpathParams)
    return None


def opacity_of(state: StainState) -> np.ndarray:
    """Stain opacity per face the camera would see (Beer-Lambert of the thickness)."""
    return stain_opacity(state.thickness)

"""Scrubbing one setup in the two-arm cell (Kabir et al. Sec. VI-VIII, IX-C), SIMULATED.

* :func:`schedule_for_pass` turns a pass of the tool path into a time-sampled
  :class:`Schedule`: the contact segments with the Lissajous overlay, the repositioning moves
  in free motion;
* :func:`run_schedule` makes the cleaning arm follow it in torque mode: Cartesian impedance
  with stiffness kappa in the tool plane, explicit force control (f_n plus an integral of the
  measured force error) along tool z, the Lissajous force as feed-forward, pinocchio gravity
  compensation (:class:`Gains`, from :class:`mavac.params.BimanualCellParams`). It logs the
  measured pad/part contact force and accumulates, per stain face, the Preston removal
  ``preston x pressure x sliding`` where the pad touches (pressure = measured normal force /
  pad area, sliding = measured relative pad/part velocity x dt);
* :func:`execute_setup` moves the part to a setup, scrubs every pass of its tool path and
  looks after each (:mod:`mavac.scrubbing.residue`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from scipy.spatial.transform import Rotation, Slerp

from ..geometry.parts import Part
from ..params import BimanualCellParams, LissajousParams, ToolpathParams
from ..robots.kinematics import ik_axis
from ..sim.control import gravity_torques
from ..sim.world import transforms_from_poses
from ..validate import check_array, check_instance
from .cell import CLEANER_PARK
from .lissajous import overlay_path
from .residue import StainState, perceive
from .scene import LOG_EVERY, TwoArmCell, move_cleaner, move_holder, world_T_part
from .toolpath import PassPath, reachable_from_robot, toolpath_for_setup
from .wear import ContactWear

#: Steps between the cleaning arm configurations kept for replays.
REPLAY_EVERY = 25


@dataclass(frozen=True)
class Schedule:
    """A time-sampled tool schedule for the cleaning arm, one sample per physics step.

    Attributes
    ----------
    positions : (m, 3) float, m
        Nominal pad-face positions (world).
    rotations : (m, 3, 3) float
        Nominal tool frames (z into the surface, x along travel).
    forces : (m, 3) float, N
        Commanded force in the tool frame: Lissajous ``(F_x, F_y)`` and ``f_n`` along z.
    contact : (m,) bool
        True where the pad should be in contact (force control along z); False for
        repositioning (stiffness along z, no force).
    """

    positions: np.ndarray
    rotations: np.ndarray
    forces: np.ndarray
    contact: np.ndarray

    def __post_init__(self):
        m = len(check_array("positions", self.positions, float))
        for name, shape in (("rotations", (m, 3, 3)), ("forces", (m, 3)), ("contact", (m,))):
            if np.shape(getattr(self, name)) != shape:
                raise ValueError(f"{name} must have shape {shape}, got {np.shape(getattr(self, name))}")
        if m == 0:
            raise ValueError("positions must hold at least one sample")
        if not np.any(self.contact):
            raise ValueError("contact: the tool path has no contact sample (nothing would be cleaned)")


@dataclass
class ScrubLog:
    """What the simulation measured while a schedule ran (SIMULATED).

    Attributes
    ----------
    t : (m,) float, s
    normal_force : (m,) float, N
        Measured pad/part contact normal force.
    in_contact : (m,) bool
        The pad touched the part.
    commanded_contact : (m,) bool
    pad_positions : (m, 3) float
        Measured pad-face positions (world).
    removal : (F,) float
        Preston removal accumulated per face of the part (stain layers at unit hardness).
    sliding_m : float
        Total measured pad/part sliding distance in contact, m.
    q_samples : (k, 7) float
        Cleaning arm configuration every :data:`REPLAY_EVERY` steps (for replays).
    """

    t: np.ndarray
    normal_force: np.ndarray
    in_contact: np.ndarray
    commanded_contact: np.ndarray
    pad_positions: np.ndarray
    removal: np.ndarray
    sliding_m: float
    q_samples: np.ndarray = field(default_factory=lambda: np.zeros((0, 7)))

    @property
    def contact_s(self) -> float:
        """Time with the pad touching the part, s."""
        dt = float(self.t[1] - self.t[0]) if len(self.t) > 1 else 0.0
        return float(self.in_contact.sum()) * dt

    @property
    def mean_contact_force(self) -> float:
        """Mean measured normal force over the steps in contact, N (nan without contact)."""
        sel = self.in_contact & self.commanded_contact
        return float(self.normal_force[sel].mean()) if sel.any() else float("nan")


def check_force_limits(cleaner_model, q, rotation, force_max, *, name: str = "force") -> None:
    """Refuse a commanded tool force whose static joint torques ``J^T F + g`` exceed the URDF's
    effort limits at configuration ``q`` (ValueError naming ``name``)."""
    model = cleaner_model.model
    data = model.createData()
    fid = model.getFrameId(cleaner_model.tool_frame)
    J = pin.computeFrameJacobian(model, data, np.asarray(q, float), fid, pin.LOCAL_WORLD_ALIGNED)[:3]
    F = np.asarray(rotation, float) @ np.asarray(force_max, float)
    tau = np.abs(J.T @ F) + np.abs(gravity_torques(model, q))
    limit = np.asarray(model.effortLimit, dtype=float)
    if np.any(tau > limit):
        j = int(np.argmax(tau / limit))
        raise ValueError(f"{name}: the commanded force {np.round(force_max, 2).tolist()} N needs {tau[j]:.0f} N m on "
                         f"joint {j + 1}, above its limit {limit[j]:.0f} N m")


def run_schedule(cell: TwoArmCell, schedule: Schedule, *, stiffness: float) -> ScrubLog:
    """The cleaning arm follows ``schedule`` in torque mode (see the module docstring).

    Parameters
    ----------
    cell : TwoArmCell
    schedule : Schedule
    stiffness : float, N/m
        kappa_x = kappa_y in the tool plane (also along z while repositioning).

    Returns
    -------
    ScrubLog (SIMULATED)
    """
    check_instance("schedule", schedule, Schedule)
    c = cell.cleaner
    robot = cell.cleaner_model.model
    data, gravity_data = robot.createData(), robot.createData()
    fid = robot.getFrameId(cell.cleaner_model.tool_frame)
    dt = cell.world.time_step
    gains = Gains.of(cell.params, stiffness)
    wear = ContactWear(cell.part_mesh, np.sqrt(cell.pad_area / np.pi), cell.params.preston)
    cell.holder.brake(cell.holder.q(), cell.params.brake_torque)
    c.enable_torque_control()
    m = len(schedule.positions)
    force, touch, pads = np.zeros(m), np.zeros(m, dtype=bool), np.zeros((m, 3))
    state = {"integral": 0.0, "sliding": 0.0}
    kept, contacts = [], []
    for i in range(m):
        q, dq = c.state()
        if i % REPLAY_EVERY == 0:
            kept.append(q)
        pin.computeJointJacobians(robot, data, q)
        pin.updateFramePlacements(robot, data)
        J = pin.getFrameJacobian(robot, data, fid, pin.LOCAL_WORLD_ALIGNED)
        T = data.oMf[fid]
        tau = _scrub_torques(robot, q, dq, J, T, schedule, i, gains, state, force[i - 1] if i else 0.0, dt)
        # gravity last, as the law's sum always had it; one pinocchio data for the whole loop
        c.apply_torques_unchecked(tau + np.array(pin.computeGeneralizedGravity(robot, gravity_data, q)))
        cell.world.step_once()
        summary = cell.world.contact_forces(c.body, cell.part, link_a=cell.pad_link)
        force[i], touch[i], pads[i] = summary.normal_force, summary.count > 0, T.translation
        if touch[i]:
            contacts.append(_contact_step(cell, summary, J @ dq, state, dt))
    _add_wear(wear, contacts)
    return ScrubLog(np.arange(1, m + 1) * dt, force, touch, np.asarray(schedule.contact, bool), pads,
                    wear.removal, state["sliding"], np.array(kept))


class Gains(NamedTuple):
    """Gains of the scrubbing law, from :class:`mavac.params.BimanualCellParams` and kappa.

    Attributes
    ----------
    k, d : float
        Tool-plane stiffness kappa (N/m) and damping ``2 zeta sqrt(kappa m)`` (N s/m), ``m`` the
        apparent mass; ``d`` also damps tool z under force control.
    kr, dr : float
        Rotational stiffness (N m/rad) and damping ``2 zeta sqrt(k_r I)`` (N m s/rad).
    ki : float
        Integral gain of the normal-force loop, 1/s.
    windup : float
        The force integral is clipped to ``+-windup x f_n`` (N).
    kn, dn : float
        Null-space posture stiffness (N m/rad) and damping (N m s/rad).
    """

    k: float
    d: float
    kr: float
    dr: float
    ki: float
    windup: float
    kn: float
    dn: float

    @classmethod
    def of(cls, params: BimanualCellParams, stiffness: float) -> Gains:
        """The gains for tool-plane stiffness ``stiffness`` (N/m) in the cell ``params``."""
        zeta = params.damping_ratio
        return cls(float(stiffness), 2 * zeta * np.sqrt(stiffness * params.apparent_mass), params.rot_stiffness,
                   2 * zeta * np.sqrt(params.rot_stiffness * params.wrist_inertia), params.force_gain,
                   params.force_integral_limit, params.null_stiffness, params.null_damping)


def _scrub_torques(robot, q, dq, J, T, schedule, i, g, state, f_measured, dt) -> np.ndarray:
    """Hybrid impedance/force law at sample ``i`` (tool-frame gains), plus a null-space pull
    towards the previous posture (the iiwa is redundant); the caller adds gravity."""
    R = schedule.rotations[i]
    e_t = R.T @ (schedule.positions[i] - T.translation)
    v = J @ dq
    v_t = R.T @ v[:3]
    f_cmd = schedule.forces[i]
    if schedule.contact[i]:
        state["integral"] = float(np.clip(state["integral"] + g.ki * (f_cmd[2] - f_measured) * dt,
                                          -g.windup * f_cmd[2], g.windup * f_cmd[2]))
        fz = f_cmd[2] + state["integral"] - g.d * v_t[2]
    else:
        state["integral"] = 0.0
        fz = g.k * e_t[2] - g.d * v_t[2]
    F_t = np.array([g.k * e_t[0] - g.d * v_t[0] + f_cmd[0], g.k * e_t[1] - g.d * v_t[1] + f_cmd[1], fz])
    moment = g.kr * pin.log3(R @ T.rotation.T) - g.dr * v[3:]
    # spin about the pad axis is free (a round pad): no stiffness or damping on link 7's tiny inertia
    moment -= R[:, 2] * (R[:, 2] @ moment)
    wrench = np.concatenate([R @ F_t, moment])
    J_pinv = np.linalg.pinv(J)
    null = np.eye(len(q)) - J.T @ J_pinv.T
    q_rest = state.setdefault("q_rest", q.copy())
    tau_null = null @ (g.kn * (q_rest - q) - g.dn * dq)
    return J.T @ wrench + tau_null


def _contact_step(cell, summary, pad_twist, state, dt) -> tuple:
    """This step's measured contact: adds its sliding (m) to ``state``; returns what the wear
    needs, ``(part position (3,), part xyzw quaternion (4,), contact centroid (3,), pressure
    (Pa), sliding (m))``, applied for all steps at once by :func:`_add_wear`."""
    lin, ang = cell.world.body_velocity(cell.part)
    position, quaternion = cell.world.body_position(cell.part)
    centre = summary.positions.mean(axis=0)
    v_part = lin + np.cross(ang, centre - position)
    v_rel = pad_twist[:3] - v_part
    n = summary.normals.mean(axis=0)
    n = n / max(np.linalg.norm(n), 1e-12)
    sliding = float(np.linalg.norm(v_rel - (v_rel @ n) * n)) * dt
    state["sliding"] += sliding
    return position, quaternion, centre, summary.normal_force / cell.pad_area, sliding


def _add_wear(wear: ContactWear, contacts: list) -> None:
    """Preston removal of the faces under the pad for every contact step (:func:`_contact_step`)."""
    if not contacts:
        return
    position, quaternion, centre, pressure, sliding = (np.array(c) for c in zip(*contacts))
    world_T_part = transforms_from_poses(position, quaternion)
    wear.add_steps(np.linalg.inv(world_T_part), centre, pressure, sliding)


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


# ---------------------------------------------------------------- one setup


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


def execute_setup(cell: TwoArmCell, part: Part, patches, q_holder, state: StainState, lissajous: LissajousParams,
                  toolpath: ToolpathParams, rng: np.random.Generator, out: Execution, *, label: str,
                  snapshot=None, seed: int = 0) -> None:
    """Move the part to a setup, scrub every pass of its tool path, look after each pass.

    Parameters
    ----------
    cell : TwoArmCell
    part : Part
        The part (or its residue) being cleaned.
    patches : (k,) int
        Patches this setup cleans (``SetupPlan.patches[j]``).
    q_holder : (7,) float, rad
        Holding arm configuration of the setup.
    state : StainState
        Updated in place: each pass's measured removal, then the camera's look.
    lissajous, toolpath : LissajousParams, ToolpathParams
    rng : numpy.random.Generator
        Process and pixel noise.
    out : Execution
        Appended to: setup time, rows, forces, tracks, images, snapshots.
    label : str
        Names the setup in rows and snapshots.
    snapshot : callable, optional
        ``snapshot(cell, state) -> (H, W, 3) uint8``, taken before and after each pass.
    seed : int
        OMPL seed of the setup motion.
    """
    out.setup_times.append(move_holder(cell, q_holder, seed=seed))
    _keep(out, cell, "holder")
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
            approach(cell, sched, toolpath.lift_height_m, lissajous)
            _keep(out, cell, "cleaner")
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
    _keep(out, cell, "cleaner")


def _keep(out: Execution, cell: TwoArmCell, arm: str) -> None:
    """Replay samples of the last joint motion of ``arm`` (the other arm stands still)."""
    q = cell.log[arm][-1].q
    other = np.repeat((cell.cleaner if arm == "holder" else cell.holder).q()[None], len(q), 0)
    pair = (other, q) if arm == "holder" else (q, other)
    out.tracks.append((*pair, LOG_EVERY * cell.world.time_step))


def approach(cell: TwoArmCell, sched: Schedule, lift: float, lissajous: LissajousParams) -> None:
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

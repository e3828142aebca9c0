"""Scrubbing one setup in the two-arm cell (Kabir et al. Sec. VI-VIII, IX-C), SIMULATED.

* :func:`schedule_for_pass` turns a pass of the tool path into a time-sampled
  :class:`Schedule`: a landing from the approach point (or the repositioning move from the
  previous pass), the contact segments with the Lissajous overlay ramped in, the repositioning
  moves in free motion; an oscillation wider than the pad is refused;
* :func:`run_schedule` makes the cleaning arm follow it in torque mode: Cartesian impedance
  with stiffness kappa in the tool plane and damping for the arm's real Cartesian inertia
  (:func:`mavac.sim.control.cartesian_damping`), explicit force control along tool z (f_n plus
  an integral of the error of the contact force measured along that axis, integrated only while
  the pad is on the part and restarted from 0 when it leaves), the Lissajous force as
  feed-forward, pinocchio gravity compensation (:class:`Gains`, from
  :class:`mavac.params.BimanualCellParams`). It logs every contact of
  both arms at every step (:meth:`ScrubLog.row`) and accumulates, per stain face under the
  pad, the Preston removal ``preston x pressure x sliding`` (pressure = measured normal force /
  pad area, sliding = measured relative pad/part velocity x dt);
* :func:`execute_setup` moves the part to a setup, fixes it as its exact mesh
  (:func:`mavac.scrubbing.scene.fix_part`), plans its tool path on the waypoints the pad reaches
  with nothing else touching (:class:`mavac.scrubbing.clearance.ToolClearance`), scrubs every
  pass and looks after each (:mod:`mavac.scrubbing.residue`).
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
from ..sim.control import cartesian_damping, gravity_torques
from ..sim.world import transforms_from_poses
from ..validate import check_array, check_instance
from .cell import CLEANER_PARK
from .clearance import ToolClearance
from .lissajous import check_excursion, excursion, overlay_path
from .residue import StainState, perceive
from .scene import LOG_EVERY, TwoArmCell, fix_part, move_cleaner, move_holder, release_part, world_T_part
from .toolpath import PassPath, toolpath_for_setup
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
    """What the simulation measured while a schedule ran, one entry per physics step (SIMULATED).

    Attributes
    ----------
    t : (m,) float, s
    normal_force : (m,) float, N
        Measured pad/part contact force along the tool axis (0 off the part): the contact
        normal forces summed as vectors and projected on tool z, what the iiwa's joint-torque
        estimate of the tool-frame force gives (friction left out). The force loop tracks it.
    in_contact : (m,) bool
        The pad touched the part.
    commanded_contact : (m,) bool
    commanded_force : (m,) float, N
        Commanded normal force f_n (0 while repositioning).
    saturated : (m,) bool
        The force integral sat at its clip.
    other : (m, 3) float, N
        Summed normal force of the contacts no plan allows: a cleaning-arm link other than the
        pad against the part, an arm against the other arm, an arm against the floor.
    other_count : (m, 3) int
        Their contact points.
    deviation : (m,) float, m
        Distance of the pad face from the nominal path in the tool plane.
    pad_positions : (m, 3) float
        Measured pad-face positions (world).
    removal : (F,) float
        Preston removal accumulated per face of the part (stain layers at unit hardness).
    sliding_m : float
        Total measured pad/part sliding distance in contact, m.
    wear_depth_m : float
        Deepest a face credited with wear lay below the surface under the pad, m.
    q_samples : (k, 7) float
        Cleaning arm configuration every :data:`REPLAY_EVERY` steps (for replays).
    """

    t: np.ndarray
    normal_force: np.ndarray
    in_contact: np.ndarray
    commanded_contact: np.ndarray
    commanded_force: np.ndarray
    saturated: np.ndarray
    other: np.ndarray
    other_count: np.ndarray
    deviation: np.ndarray
    pad_positions: np.ndarray
    removal: np.ndarray
    sliding_m: float
    wear_depth_m: float
    q_samples: np.ndarray = field(default_factory=lambda: np.zeros((0, 7)))

    @property
    def contact_s(self) -> float:
        """Time with the pad touching the part while contact was commanded, s."""
        dt = float(self.t[1] - self.t[0]) if len(self.t) > 1 else 0.0
        return float((self.in_contact & self.commanded_contact).sum()) * dt

    @property
    def mean_contact_force(self) -> float:
        """Mean measured tool-axis force over the commanded steps in contact, N (nan without contact)."""
        sel = self.in_contact & self.commanded_contact
        return float(self.normal_force[sel].mean()) if sel.any() else float("nan")

    def row(self) -> dict:
        """Every contact measure of the pass (the columns of ``kabir_execution.csv``).

        Force errors are relative to the mean commanded f_n: over ALL commanded steps (0 N
        counted while the pad is off the part) and over the steps in contact; ``failed`` marks a
        pass with any contact that is not the pad's.
        """
        cmd, touch = self.commanded_contact, self.in_contact
        on = cmd & touch
        f_n = float(self.commanded_force[cmd].mean())
        f_all = np.where(touch, self.normal_force, 0.0)[cmd]
        f_on = self.normal_force[on]
        steps = (self.other_count > 0).sum(axis=0)
        peak = self.other.max(axis=0, initial=0.0)
        error_all, rms_all = _force_error(f_all, self.commanded_force[cmd], f_n)
        error_on, rms_on = _force_error(f_on, self.commanded_force[on], f_n)
        return dict(commanded_steps=int(cmd.sum()), contact_steps=int(on.sum()), duty=float(on.sum() / cmd.sum()),
                    contact_s=self.contact_s, f_n_n=f_n, mean_force_all_n=float(f_all.mean()),
                    force_error_all=error_all, force_rms_all=rms_all,
                    mean_force_contact_n=self.mean_contact_force,
                    force_error_contact=error_on, force_rms_contact=rms_on,
                    integral_saturated_steps=int(self.saturated[cmd].sum()),
                    integral_saturated_share=float(self.saturated[cmd].mean()),
                    nonpad_part_steps=int(steps[0]), nonpad_part_peak_n=float(peak[0]),
                    arm_arm_steps=int(steps[1]), arm_arm_peak_n=float(peak[1]),
                    arm_floor_steps=int(steps[2]), arm_floor_peak_n=float(peak[2]),
                    pad_touch_outside_steps=int((touch & ~cmd).sum()), failed=bool(steps.sum() > 0),
                    max_deviation_mm=1e3 * float(self.deviation[cmd].max()),
                    wear_depth_max_mm=1e3 * self.wear_depth_m if np.isfinite(self.wear_depth_m) else np.nan,
                    sliding_m=self.sliding_m)


def _force_error(measured, commanded, f_n) -> tuple[float, float]:
    """``(mean error, RMS error)`` of measured against commanded forces, both over ``f_n``
    (NaN for no steps)."""
    if measured.size == 0:
        return float("nan"), float("nan")
    e = measured - commanded
    return float(e.mean() / f_n), float(np.sqrt(np.mean(e**2)) / f_n)


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
    """The cleaning arm follows ``schedule`` in torque mode (see the module docstring), every
    contact of the arms logged.

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
    cell.holder.brake(cell.holder.q(), cell.params.brake_torque)
    c.enable_torque_control()
    m = len(schedule.positions)
    log = _StepLog(m)
    state = {"integral": 0.0, "sliding": 0.0, "touch": False, "saturated": False, "mass_data": robot.createData()}
    kept, contacts = [], []
    state["twists"] = schedule_twists(schedule, dt)
    for i in range(m):
        q, dq = c.state()
        if i % REPLAY_EVERY == 0:
            kept.append(q)
        pin.computeJointJacobians(robot, data, q)
        pin.updateFramePlacements(robot, data)
        J = pin.getFrameJacobian(robot, data, fid, pin.LOCAL_WORLD_ALIGNED)
        T = data.oMf[fid]
        tau = _scrub_torques(robot, q, dq, J, T, schedule, i, gains, state, log.force[i - 1] if i else 0.0, dt)
        # gravity last, as the law's sum always had it; one pinocchio data for the whole loop
        c.apply_torques_unchecked(tau + np.array(pin.computeGeneralizedGravity(robot, gravity_data, q)))
        cell.world.step_once()
        pad = log.record(i, cell, state["saturated"], T.translation, schedule)
        # the loop integrates only while the pad presses on the part (its axial force > 0): a pad
        # pushed from behind (through a thin wall of the mesh) must not wind the integral up
        state["touch"] = pad is not None and log.force[i] > 0
        if pad is not None:
            contacts.append(_contact_step(cell, pad, J @ dq, schedule.rotations[i][:, 2], state, dt))
    wear = ContactWear(cell.part_mesh, np.sqrt(cell.pad_area / np.pi), cell.params.preston,
                       depth=cell.params.wear_depth)
    _add_wear(wear, contacts)
    return ScrubLog(np.arange(1, m + 1) * dt, log.force, log.touch, np.asarray(schedule.contact, bool),
                    np.where(schedule.contact, schedule.forces[:, 2], 0.0), log.saturated, log.other,
                    log.other_count, log.deviation, log.pads, wear.removal, state["sliding"], wear.deepest,
                    np.array(kept))


def schedule_twists(schedule: Schedule, dt: float) -> np.ndarray:
    """(m, 6) twist of the schedule's nominal pad frame (world-aligned linear m/s, angular
    rad/s), by finite differences over ``dt`` s (the last sample repeats the one before)."""
    m = len(schedule.positions)
    twists = np.zeros((m, 6))
    if m > 1:
        R = schedule.rotations
        twists[:-1, :3] = np.diff(schedule.positions, axis=0) / dt
        twists[:-1, 3:] = Rotation.from_matrix(R[1:] @ np.transpose(R[:-1], (0, 2, 1))).as_rotvec() / dt
        twists[-1] = twists[-2]
    return twists


class _StepLog:
    """Per-step arrays of :func:`run_schedule`, filled by :meth:`record`."""

    def __init__(self, m: int):
        self.force, self.touch, self.saturated = np.zeros(m), np.zeros(m, dtype=bool), np.zeros(m, dtype=bool)
        self.other, self.other_count = np.zeros((m, 3)), np.zeros((m, 3), dtype=int)
        self.deviation, self.pads = np.zeros(m), np.zeros((m, 3))

    def record(self, i: int, cell: TwoArmCell, saturated: bool, pad_position, schedule: Schedule):
        """Classify every contact of both arms at step ``i``; returns the pad/part contact
        ``(summed normal force (N), points on the part (k, 3), normals (k, 3))`` or None."""
        world = cell.world
        mine = world.contacts_of(cell.cleaner.body)
        theirs = world.contacts_of(cell.holder.body)
        parts = np.isin(mine.body_b, (cell.part, cell.scrubbed))
        pad = parts & (mine.link_a == cell.pad_link)
        masks = ((mine, parts & ~pad), (mine, mine.body_b == cell.holder.body),
                 (mine, mine.body_b == cell.floor))
        for k, (table, sel) in enumerate(masks):
            self.other[i, k], self.other_count[i, k] = table.normal_force[sel].sum(), int(sel.sum())
        on_floor = theirs.body_b == cell.floor
        self.other[i, 2] += theirs.normal_force[on_floor].sum()
        self.other_count[i, 2] += int(on_floor.sum())
        R = schedule.rotations[i]
        self.deviation[i] = float(np.linalg.norm((R.T @ (pad_position - schedule.positions[i]))[:2]))
        self.pads[i], self.saturated[i] = pad_position, saturated
        if not pad.any():
            return None
        normal, normals = mine.normal_force[pad], mine.normals[pad]
        # the reaction pushes the pad back, against its axis
        self.force[i], self.touch[i] = -float((normal @ normals) @ R[:, 2]), True
        return float(normal.sum()), mine.positions_b[pad], normals


class Gains(NamedTuple):
    """Gains of the scrubbing law, from :class:`mavac.params.BimanualCellParams` and kappa.

    Attributes
    ----------
    k : float
        Tool-plane stiffness kappa, N/m (also along tool z while repositioning).
    kr : float
        Rotational stiffness, N m/rad.
    zeta : float
        Damping ratio of every Cartesian axis (:func:`cartesian_damping`).
    ki : float
        Integral gain of the normal-force loop, 1/s.
    windup : float
        The force integral is clipped to ``+-windup x f_n`` (N).
    kn, dn : float
        Null-space posture stiffness (N m/rad) and damping (N m s/rad).
    """

    k: float
    kr: float
    zeta: float
    ki: float
    windup: float
    kn: float
    dn: float

    @classmethod
    def of(cls, params: BimanualCellParams, stiffness: float) -> Gains:
        """The gains for tool-plane stiffness ``stiffness`` (N/m) in the cell ``params``."""
        return cls(float(stiffness), params.rot_stiffness, params.damping_ratio, params.force_gain,
                   params.force_integral_limit, params.null_stiffness, params.null_damping)


def _scrub_torques(robot, q, dq, J, T, schedule, i, g, state, f_measured, dt) -> np.ndarray:
    """Hybrid impedance/force law at sample ``i`` (tool-frame gains), plus a null-space pull
    towards the previous posture (the iiwa is redundant); the caller adds gravity."""
    R = schedule.rotations[i]
    e_t = R.T @ (schedule.positions[i] - T.translation)
    v = J @ dq
    f_cmd = schedule.forces[i]
    state["saturated"] = False
    if schedule.contact[i] and state["touch"]:  # conditional integration: only on the part
        raw = state["integral"] + g.ki * (f_cmd[2] - f_measured) * dt
        state["integral"] = float(np.clip(raw, -g.windup * f_cmd[2], g.windup * f_cmd[2]))
        state["saturated"] = state["integral"] != raw
    else:  # off the part or repositioning: the integral restarts from 0
        state["integral"] = 0.0
    fz = f_cmd[2] + state["integral"] if schedule.contact[i] else g.k * e_t[2]
    F_t = np.array([g.k * e_t[0] + f_cmd[0], g.k * e_t[1] + f_cmd[1], fz])
    wrench = np.concatenate([R @ F_t, g.kr * pin.log3(R @ T.rotation.T)])
    D = cartesian_damping(robot, state["mass_data"], q, J, g.k, g.kr, g.zeta)
    wrench -= D @ (v - state["twists"][i])  # damping of the error to the schedule's own motion
    # spin about the pad axis is free (a round pad)
    wrench[3:] -= R[:, 2] * (R[:, 2] @ wrench[3:])
    J_pinv = np.linalg.pinv(J)
    null = np.eye(len(q)) - J.T @ J_pinv.T
    q_rest = state.setdefault("q_rest", q.copy())
    tau_null = null @ (g.kn * (q_rest - q) - g.dn * dq)
    return J.T @ wrench + tau_null


def _contact_step(cell, pad, pad_twist, axis, state, dt) -> tuple:
    """This step's measured pad contact ``pad`` (:meth:`_StepLog.record`): adds its sliding (m)
    to ``state``; returns what the wear needs, ``(part position (3,), part xyzw quaternion (4,),
    contact centroid on the part (3,), pad axis (3,), pressure (Pa), sliding (m))``, applied for
    all steps at once by :func:`_add_wear`."""
    force, points, normals = pad
    lin, ang = cell.world.body_velocity(cell.scrubbed)
    position, quaternion = cell.world.body_position(cell.scrubbed)
    centre = points.mean(axis=0)
    v_part = lin + np.cross(ang, centre - position)
    v_rel = pad_twist[:3] - v_part
    n = normals.mean(axis=0)
    n = n / max(np.linalg.norm(n), 1e-12)
    sliding = float(np.linalg.norm(v_rel - (v_rel @ n) * n)) * dt
    state["sliding"] += sliding
    return position, quaternion, centre, axis, force / cell.pad_area, sliding


def _add_wear(wear: ContactWear, contacts: list) -> None:
    """Preston removal of the faces under the pad for every contact step (:func:`_contact_step`)."""
    if not contacts:
        return
    position, quaternion, centre, axis, pressure, sliding = (np.array(c) for c in zip(*contacts))
    world_T_part = transforms_from_poses(position, quaternion)
    wear.add_steps(np.linalg.inv(world_T_part), centre, axis, pressure, sliding)


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


def schedule_for_pass(pp: PassPath, lissajous: LissajousParams, toolpath: ToolpathParams, dt: float, *,
                      ramp_periods: float = BimanualCellParams.lissajous_ramp_periods) -> Schedule:
    """One pass as a time-sampled schedule: each contact segment with the Lissajous overlay
    (tool frame forces, ramped in over ``ramp_periods`` periods of its y axis), each
    repositioning move (lift, move, lower) in free motion; a pass without a move into its
    first segment lands on it from its approach point, ``toolpath.lift_height_m`` above it
    along the pad axis.

    Raises ``ValueError`` naming ``toolpath`` when the pass has no contact segment, naming
    ``lissajous`` when the oscillation would swing the pad more than one pad width
    (``toolpath.tool_width_m``) off its path (:func:`mavac.scrubbing.lissajous.check_excursion`).
    """
    if not pp.segments:
        raise ValueError(f"toolpath: pass {pp.pass_number} has no contact segment (nothing reachable to clean)")
    check_excursion(lissajous, toolpath.tool_width_m)
    overlays = [overlay_path(seg, nrm, lissajous, dt=dt) for seg, nrm in zip(pp.segments, pp.normals)]
    entry = len(pp.repositions) == len(pp.segments)  # the first move comes from the previous pass
    ramp_s = ramp_periods / lissajous.f_y
    parts = []
    for i, ov in enumerate(overlays):
        R1 = ov.rotations[0]
        j = i if entry else i - 1
        if j >= 0 or i == 0:
            R0 = overlays[i - 1].rotations[-1] if i > 0 else R1
            move = pp.repositions[j] if j >= 0 else np.array([ov.nominal[0] - toolpath.lift_height_m * R1[:, 2],
                                                               ov.nominal[0]])
            pos, rot = _free_move(move, R0, R1, toolpath.reposition_speed_m_s, dt)
            parts.append((pos, rot, np.zeros((len(pos), 3)), np.zeros(len(pos), dtype=bool)))
        f_tool = np.einsum("nji,nj->ni", ov.rotations, ov.forces)
        if ramp_s > 0:
            f_tool[:, :2] *= np.clip(ov.t / ramp_s, 0.0, 1.0)[:, None]
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
        Measured contact force along the tool axis at every contact step of each pass, N.
    snapshots : list of (str, (H, W, 3) uint8)
        pybullet camera snapshots (label, image).
    stain_images : list of (H, W, 3) uint8
        Stain camera images: initial, then after each pass.
    tracks : list of (q_cleaner (k, 7), q_holder (k, 7), dt)
        Replay samples for the meshcat animation, ``dt`` s apart.
    paths : list of (world_T_part, (k, 3) contact path points)
    stain_states : list of (int, (F,) float)
        After each pass: how many of ``tracks`` it ends, and the stain thickness per face.
    setups : list of dict
        One per executed setup: ``label``, ``world_T_part`` (4, 4) as the part was met (world =
        the cleaning arm's base frame), ``q_holder`` (7,) rad, ``patches`` (int), ``first_row``
        (its first entry in ``rows`` and in ``stain_states``: one each per pass).
    """

    rows: list = field(default_factory=list)
    setup_times: list = field(default_factory=list)
    forces: list = field(default_factory=list)
    snapshots: list = field(default_factory=list)
    stain_images: list = field(default_factory=list)
    tracks: list = field(default_factory=list)
    paths: list = field(default_factory=list)
    stain_states: list = field(default_factory=list)
    setups: list = field(default_factory=list)


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
    fix_part(cell)
    T = world_T_part(cell)
    out.setups.append(dict(label=label, world_T_part=T, q_holder=np.asarray(q_holder, float).copy(),
                           patches=len(patches), first_row=len(out.rows)))
    clear = ToolClearance(cell.cleaner_model, part.mesh.copy().apply_transform(T), sweep=excursion(lissajous))
    tp = toolpath_for_setup(part, T, np.asarray(patches), toolpath, reachable=clear)
    if snapshot is not None:
        out.snapshots.append((f"{label} before cleaning", snapshot(cell, state)))
    first = True
    for pp in tp.passes:
        if not pp.segments:
            continue
        sched = schedule_for_pass(pp, lissajous, toolpath, cell.world.time_step,
                                  ramp_periods=cell.params.lissajous_ramp_periods)
        if first:
            try:
                approach(cell, sched, toolpath.lift_height_m, lissajous)
            except ApproachError:
                release_part(cell)  # the cleaning arm never left its park
                raise
            _keep(out, cell, "cleaner")
            first = False
        log = run_schedule(cell, sched, stiffness=lissajous.kappa_x)
        out.tracks.append((log.q_samples, np.repeat(cell.holder.q()[None], len(log.q_samples), 0),
                           REPLAY_EVERY * cell.world.time_step))
        before = state.thickness.copy()
        state.scrub(log.removal, rng)
        out.stain_states.append((len(out.tracks), state.thickness.copy()))
        seen = perceive(state, before, part.stain_faces[pp.patch_ids], rng)
        state.images.append(seen)
        out.forces.append(log.normal_force[log.in_contact & log.commanded_contact])
        out.paths.append((T, np.vstack(pp.segments)))
        out.rows.append(dict(setup=label, pass_=pp.pass_number, path_length_m=pp.path_length_m, **log.row(),
                             residue_fraction=seen["residue_fraction"], C_p=seen["C_p"]))
        out.stain_images.append(seen["image"])
        if snapshot is not None:
            out.snapshots.append((f"{label} after pass {pp.pass_number}", snapshot(cell, state)))
    move_cleaner(cell, CLEANER_PARK)
    _keep(out, cell, "cleaner")
    release_part(cell)


def _keep(out: Execution, cell: TwoArmCell, arm: str) -> None:
    """Replay samples of the last joint motion of ``arm`` (the other arm stands still)."""
    q = cell.log[arm][-1].q
    other = np.repeat((cell.cleaner if arm == "holder" else cell.holder).q()[None], len(q), 0)
    pair = (other, q) if arm == "holder" else (q, other)
    out.tracks.append((*pair, LOG_EVERY * cell.world.time_step))


class ApproachError(RuntimeError):
    """The cleaning arm cannot reach a pass's start with its pad along the pass's axis."""


def approach(cell: TwoArmCell, sched: Schedule, lift: float, lissajous: LissajousParams) -> None:
    """Joint motion of the cleaning arm above the schedule's first point, pad along its axis
    (``lift`` m above it, or half that, or on it: the first the arm reaches); checks that the
    commanded forces stay within the joint torque limits there; raises :class:`ApproachError`
    when it reaches none."""
    R = sched.rotations[0]
    for h in (lift, lift / 2, 0.0):
        start = sched.positions[0] - h * R[:, 2]
        res = ik_axis(cell.cleaner_model, start[None], R[:, 2][None], q0=cell.cleaner_model.q_home)
        if res.success[0]:
            break
    else:
        raise ApproachError(f"the cleaning arm cannot reach the start of the tool path at "
                            f"{np.round(sched.positions[0], 3)} m with its pad along {np.round(R[:, 2], 2)}")
    peak = np.array([lissajous.A_x, lissajous.A_y, lissajous.f_n])
    check_force_limits(cell.cleaner_model, res.q[0], R, peak, name="lissajous (f_n, A_x, A_y)")
    move_cleaner(cell, res.q[0])

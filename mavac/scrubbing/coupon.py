"""A single-patch test coupon in the two-arm cell: the black box of the GPR learner (Kabir et al.
Sec. VIII, run in the SIMULATED cell of Sec. IX-C).

:func:`coupon_part` is the coupon (ours); :class:`CouponCell` is ``experiment(x, rng) -> C_p``
for :func:`mavac.scrubbing.gpr.learn_parameters`: one scrubbing stroke over the coupon's stain
with the operation vector ``x``, measured by the stain camera and K-means.
"""

from __future__ import annotations

import numpy as np
import trimesh

from ..geometry.parts import Part
from ..params import BimanualCellParams, ToolpathParams
from ..seeding import check_seed, rng_for
from ..setups.reach import base_T_part
from ..sim.world import SimWorld
from ..validate import check_instance, check_int, check_positive, check_range
from .cell import cell_robots, holder_ik
from .residue import StainState, perceive
from .scene import fix_part, open_cell, world_T_part
from .scrub import approach, run_schedule, schedule_for_pass
from .toolpath import PassPath
from .wear import lissajous_from_vector

#: Ours: the setup ``(x, y, alpha)`` presenting the coupon, the centre of the cell's setup space.
COUPON_SETUP = (0.15, 0.15, 0.0)
#: Ours: the stroke, 60 mm along the strip in 13 waypoints, 10 mm above the coupon's base (its top).
STROKE_LENGTH, STROKE_POINTS, STROKE_HEIGHT = 0.06, 13, 0.01
#: Ours: physics steps to let the held coupon settle after loading, and after each stroke.
SETTLE_STEPS, RESET_STEPS = 200, 50
#: Ours: pixels of the stain camera's square image of the coupon.
COUPON_IMAGE = 64


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
    rng = rng_for(seed, "coupon stain")
    return Part("coupon", mesh, stain, np.ones(len(stain), dtype=np.int64), rng.uniform(0.6, 1.0, len(stain)),
                "single-patch test coupon of the GPR learner (ours)")


class CouponCell:
    """``experiment(x, rng) -> C_p``: one SIMULATED scrubbing stroke over the coupon in the cell.

    The holding arm presents the coupon at :data:`COUPON_SETUP`; the cleaning arm makes one
    60 mm stroke along the stain strip with the operation vector ``x = (v, f_n, kappa, f_x,
    A_x)`` (:func:`mavac.scrubbing.wear.lissajous_from_vector`); the stain camera and K-means
    measure C_p. A stroke in which the cell did not hold the commanded contact (pad on the coupon
    for less than ``cell.tracking_duty`` of the commanded steps, or a mean force over them more
    than ``cell.tracking_force_error`` x f_n off) is a failed experiment: C_p = 0. Each stroke's
    contact measures (:meth:`mavac.scrubbing.scrub.ScrubLog.row`) are kept in :attr:`strokes`.
    Use as a context manager (the pybullet client is closed on exit).

    Parameters
    ----------
    cell : BimanualCellParams
    toolpath : ToolpathParams
    seed : int, >= 0
        The coupon's stain, its hardness and each stroke's process and pixel noise.
    """

    def __init__(self, cell: BimanualCellParams = BimanualCellParams(), toolpath: ToolpathParams = ToolpathParams(),
                 *, seed: int = 0):
        self.params = check_instance("cell", cell, BimanualCellParams)
        self.toolpath = check_instance("toolpath", toolpath, ToolpathParams)
        self.seed = check_seed(seed)
        self.part = coupon_part(seed)
        self.cleaner, self.holder = cell_robots(cell, toolpath)
        self.world = None
        self._unit = {}
        self.strokes = {}

    def __enter__(self):
        T = base_T_part(np.array([COUPON_SETUP]), self.params.space)
        q = holder_ik(self.holder, T, self.params).q[0]
        self.world = SimWorld(time_step=self.params.time_step, seed=self.seed)
        try:
            self.cell = open_cell(self.world, self.cleaner, self.holder, self.part.mesh, q, params=self.params,
                                  pad_width=self.toolpath.tool_width_m)
            self.world.step(SETTLE_STEPS)
            fix_part(self.cell)
            Tp = world_T_part(self.cell)
            xs = np.linspace(-STROKE_LENGTH / 2, STROKE_LENGTH / 2, STROKE_POINTS)
            local = np.column_stack([xs, np.zeros_like(xs), np.full_like(xs, STROKE_HEIGHT), np.ones_like(xs)])
            seg = (Tp @ local.T).T[:, :3]
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
        return self.c_p_at(x, self.params.preston)

    def c_p_at(self, x, preston: float) -> float:
        """C_p of the stroke at ``x`` had the Preston constant been ``preston`` (stain layers
        per Pa per m): the simulated stroke is run once per ``x`` and its measured contact
        reused (removal is linear in the constant), the process and pixel noise are the same."""
        key = _key(x)
        if key not in self._unit:
            self._unit[key], self.strokes[key] = self._stroke(np.asarray(key))
        if not self.held_contact(self.strokes[key]):
            return 0.0
        words = np.frombuffer(np.asarray(key).tobytes(), np.uint32).tolist()
        rng = rng_for(self.seed, "coupon stroke", *words)
        state = StainState.from_part(self.part, rng_for(self.seed, "coupon hardness"), image_size=COUPON_IMAGE)
        before = state.thickness.copy()
        state.scrub(check_positive("preston", preston) * self._unit[key], rng)
        return float(perceive(state, before, self.part.stain_faces, rng)["C_p"])

    def stroke_row(self, x) -> dict:
        """Contact measures (:meth:`mavac.scrubbing.scrub.ScrubLog.row`) of the stroke run at
        operation vector ``x`` (5,); ValueError if none was."""
        row = self.strokes.get(_key(x))
        if row is None:
            raise ValueError(f"x: no stroke was run at {np.round(np.asarray(x, float), 4).tolist()}")
        return row

    def held_contact(self, row: dict) -> bool:
        """Whether a stroke's contact measures (:meth:`mavac.scrubbing.scrub.ScrubLog.row`) meet
        the cell's tracking rule (see the class docstring)."""
        cell = self.params
        return row["duty"] >= cell.tracking_duty and abs(row["force_error_all"]) <= cell.tracking_force_error

    def _stroke(self, x) -> tuple[np.ndarray, dict]:
        """Run the stroke at ``x``: per-face removal at a unit Preston constant, contact measures."""
        lis = lissajous_from_vector(np.asarray(x, float)[None])
        sched = schedule_for_pass(self.stroke, lis, self.toolpath, self.world.time_step,
                                  ramp_periods=self.params.lissajous_ramp_periods)
        cleaner, brake_torque = self.cell.cleaner, self.params.brake_torque
        if self.q_start is None:
            approach(self.cell, sched, self.toolpath.lift_height_m, lis)
            self.q_start = cleaner.q()
        cleaner.reset_q(self.q_start)
        cleaner.brake(self.q_start, brake_torque)
        log = run_schedule(self.cell, sched, stiffness=lis.kappa_x)
        cleaner.reset_q(self.q_start)
        cleaner.brake(self.q_start, brake_torque)
        self.world.step(RESET_STEPS)
        return log.removal / self.params.preston, log.row()


def _key(x) -> tuple:
    """Memo key of an operation vector (5,): its values rounded to 1e-9."""
    return tuple(np.round(np.asarray(x, float), 9).tolist())


def calibrated_preston(coupon: CouponCell, x, c_p_target: float, *, bounds=(1e-7, 1e-1), steps: int = 40) -> float:
    """The least Preston constant (stain layers per Pa per m) at which one coupon stroke at
    operation vector ``x`` reaches ``C_p >= c_p_target``: bisection in log over ``bounds``
    (C_p grows with the constant; the stroke itself is simulated once).

    Parameters
    ----------
    coupon : CouponCell
        Open (inside its ``with`` block).
    x : (5,) float
        Operation vector ``(v, f_n [N], kappa [N/m], f_x [Hz], A_x [N])``.
    c_p_target : float in (0, 1)
    bounds : (float, float)
        Search range of the constant, low < high, both > 0.
    steps : int, >= 1
        Bisection steps (40 halve the log range to 1e-12 of itself).

    Raises
    ------
    ValueError
        When the stroke at ``x`` did not hold contact (its C_p is 0 whatever the constant), or
        when even ``bounds[1]`` does not reach the target.
    """
    check_range("c_p_target", c_p_target, 0.0, 1.0, lo_open=True, hi_open=True)
    lo, hi = (check_positive(f"bounds[{k}]", float(b)) for k, b in enumerate(bounds))
    if not lo < hi:
        raise ValueError(f"bounds must be (low, high) with low < high, got {bounds}")
    steps = check_int("steps", steps, 1)
    if coupon.c_p_at(x, hi) < c_p_target:
        row = coupon.stroke_row(x)
        why = "the stroke did not hold contact" if not coupon.held_contact(row) else f"C_p stays below it at {hi:g}"
        raise ValueError(f"c_p_target: no Preston constant in {bounds} reaches C_p = {c_p_target} at x = "
                         f"{np.round(np.asarray(x, float), 4).tolist()} ({why})")
    a, b = np.log(lo), np.log(hi)
    for _ in range(steps):
        mid = 0.5 * (a + b)
        a, b = (a, mid) if coupon.c_p_at(x, float(np.exp(mid))) >= c_p_target else (mid, b)
    return float(np.exp(b))

"""Parameters as frozen dataclasses. Defaults are the papers' values; each field cites
where it comes from. Change them with ``dataclasses.replace``; every dataclass validates
itself on creation: :func:`mavac.validate.check_fields` checks each field's type and
finiteness from its annotation (``TypeError`` for a string, a boolean or ``None`` where a
number is meant, ``ValueError`` for NaN or infinity), then the legal values declared with the
field by :func:`mavac.validate.ranged` (``ValueError``), each error naming the field. A class
whose fields constrain each other checks that in its own ``__post_init__``.

One section per paper stage, each naming the modules that read it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .seeding import MAX_SEED
from .validate import CheckedFields, check_positive, check_range, ranged


# ---- MAVAC camera (read by mavac.vision.camera and mavac.vision.visibility) ----


#: Most experiments a GPR run or a random search may take: each is a simulated scrubbing run
#: (seconds), and 100 times the default budget is far beyond Kabir's tens (Sec. IX-C).
MAX_EXPERIMENTS = 10_000


@dataclass(frozen=True)
class CameraParams(CheckedFields):
    """Emulated camera of MAVAC ("Camera field of view (FOV)"): a rectangular pyramid along the
    camera x axis with half-angles ``theta_a`` (camera XY plane) and ``theta_b`` (XZ plane),
    cut at the reliable detection limit ``L_d`` (metres along x). What inside it is hidden is
    decided by :class:`Visibility`.
    """

    # The paper's camera is an Azure Kinect (MAVAC, Fig. 5) but it gives no angles. Azure
    # Kinect DK hardware spec: colour 16:9 = 90 x 59 deg, depth NFOV unbinned = 75 x 65 deg.
    # Dust is found in colour and located with depth, so the usable pyramid is their overlap,
    # 75 x 59 deg: theta_a = 75/2 deg (image width, camera y).
    theta_a: float = ranged(math.radians(37.5), gt=0.0, lt=math.pi / 2)
    # Overlap height 59 deg (colour limits it, depth has 65): theta_b = 59/2 deg (camera z).
    theta_b: float = ranged(math.radians(29.5), gt=0.0, lt=math.pi / 2)
    # MAVAC gives no number for the "reliable detection limit". 0.5 m: the colour camera
    # (1280 px over 90 deg) samples ~0.8 mm/px there, so a ~1 cm dust heap spans >10 px for
    # the HSV filter, and it is the NFOV depth minimum range (spec 0.5-3.86 m), so the guard
    # target (placed L_d along the normal) still gets depth.
    L_d: float = ranged(0.5, gt=0.0)


# ---- Kabir: Lissajous scrubbing, simulated scrub model, GPR (read by mavac/scrubbing/lissajous.py, mavac/scrubbing/wear.py, mavac/scrubbing/gpr.py) ----

# Order of the operation-parameter vector x used by the scrub model and the GPR learner
# (Kabir, Sec. VIII: tool speed, normal force, stiffness, frequency, amplitude).
OPERATION_PARAMS = ("v", "f_n", "kappa", "f_x", "A_x")


@dataclass(frozen=True)
class LissajousParams(CheckedFields):
    """Lissajous force oscillation overlaid on the nominal tool path (Kabir, Sec. VIII).

    Force in the tool XY plane: ``F_x = A_x sin(2 pi f_x t + phase)``,
    ``F_y = A_y sin(2 pi f_y_ratio f_x t)``; the impedance controller turns it into a
    displacement ``F / kappa``. The cleaning force ``f_n`` pushes along tool z.
    ``v`` is the paper's relative speed (fraction of the maximum joint velocity, v_max = 1);
    ours maps it to a tool speed ``v * tool_speed_at_vmax`` in m/s along the path.
    """

    # Kabir, Fig. 3 example: f_x = 6 Hz.
    f_x: float = ranged(6.0, gt=0.0)
    # Kabir, Fig. 3: kappa_x = kappa_y = 5000 N/m.
    kappa_x: float = ranged(5000.0, gt=0.0)
    kappa_y: float = ranged(5000.0, gt=0.0)
    # Kabir, Fig. 3: A_x = A_y = 30 N (Sec. VIII: A_y = A_x).
    A_x: float = ranged(30.0, ge=0.0)
    A_y: float = ranged(30.0, ge=0.0)
    # Kabir, Fig. 3: v = 0.3 (fraction of the maximum joint velocity v_max = 1).
    v: float = ranged(0.3, gt=0.0, le=1.0)
    # Kabir, Fig. 3: f_n = 10 N along tool z.
    f_n: float = ranged(10.0, ge=0.0)
    # Kabir, Sec. VIII: f_y = 0.4 f_x.
    f_y_ratio: float = ranged(0.4, gt=0.0)
    # Kabir, Sec. VIII: phase offset between x and y is pi/2.
    phase: float = ranged(math.pi / 2, ge=-2 * math.pi, le=2 * math.pi)
    # Ours (the paper gives no mapping): tool speed at v = 1. 0.1 m/s is a cautious contact
    # speed for a 7-DOF arm scrubbing with a sponge, so the paper's v = 0.3 -> 3 cm/s.
    tool_speed_at_vmax: float = ranged(0.1, gt=0.0)

    @property
    def f_y(self) -> float:
        """Oscillation frequency along tool y, Hz."""
        return self.f_y_ratio * self.f_x

    @property
    def tool_speed(self) -> float:
        """Nominal tool speed along the path, m/s (``v * tool_speed_at_vmax``)."""
        return self.v * self.tool_speed_at_vmax


#: Preston coefficient of the stain, stain layers removed per (Pa x m of sliding): one constant
#: for the cell's measured wear (BimanualCellParams.preston) and the analytic model
#: (ScrubModel.preston). No literature value exists for a stain counted in layers, so it was
#: calibrated once (mavac.scrubbing.coupon.calibrated_preston; tests/test_coupon.py re-runs it):
#: the least constant at which one coupon stroke in the default cell, at each part's paper
#: operating point (Kabir IX-C), meets that part's paper threshold C_p^th (bowl 0.6, hull 0.9),
#: as the paper's learner chose those points. The bowl binds (3.58e-4); the hull alone would
#: give 1.44e-4, at which the bowl's point reaches C_p 0.01 (the paper's stains differ: acrylic
#: paint on the bowl, mud on the hull). Notebook 11 reports C_p at half and twice the constant
#: (kabir_preston.csv).
PRESTON = 3.6e-4


@dataclass(frozen=True)
class ScrubModel(CheckedFields):
    """Constants of the SIMULATED scrubbing black box (``mavac.scrubbing.wear``), which stands in
    for Kabir's physical cleaning experiments (Sec. IX-C). None of them is in the paper:
    they are round, physically plausible values for a sponge tool on a 7-DOF arm in
    Cartesian impedance mode, chosen so that C_p depends on all five operation parameters.
    """

    # Preston coefficient: stain layers removed per (Pa x m of sliding); PRESTON, the cell's too.
    preston: float = ranged(PRESTON, gt=0.0)
    # Contact patch of the sponge: 20 mm x 20 mm (ours).
    contact_width: float = ranged(0.02, gt=0.0)
    contact_area: float = ranged(4.0e-4, gt=0.0)
    # Foam compression: the contact area grows as contact_area (1 + f_n / foam_force), so
    # pressure saturates at foam_force / contact_area (ours, 20 N for a kitchen sponge).
    foam_force: float = ranged(20.0, gt=0.0)
    # Coulomb friction sponge/part: the tool only slides when the oscillating force exceeds
    # mu * f_n (ours, wet sponge on plastic).
    friction: float = ranged(0.4, gt=0.0)
    # Apparent mass and damping ratio of tool + arm along the oscillation (ours); with
    # kappa = 5000 N/m the resonance is sqrt(kappa/m)/(2 pi) = 6.5 Hz.
    mass: float = ranged(3.0, gt=0.0)
    damping_ratio: float = ranged(0.3, gt=0.0)
    # The impedance controller's Cartesian path-deviation limit softly caps the oscillation
    # amplitude (ours, 10 mm).
    max_deviation: float = ranged(0.01, gt=0.0)
    # Tipping/chatter: contact fraction 1 / (1 + (A / (ratio f_n))^exponent); half the
    # contact is lost when the lateral force is 2.5 x the normal force (ours).
    tipping_ratio: float = ranged(2.5, gt=0.0)
    tipping_exponent: float = ranged(4.0, gt=0.0)
    # Process noise: per-face and per-experiment log-normal factors on the removal (ours).
    face_noise: float = ranged(0.10, ge=0.0)
    batch_noise: float = ranged(0.05, ge=0.0)
    # Stain hardness per face: log-normal spread (ours; layers of acrylic paint or mud dry
    # unevenly).
    hardness_sigma: float = ranged(0.3, ge=0.0)
    # Beer-Lambert optical depth, in stain layers: a face of thickness t shows the stain
    # colour with opacity (1 - exp(-t / depth)) / (1 - exp(-1 / depth)) (ours; a thin film
    # of paint is already dark).
    optical_depth: float = ranged(0.05, gt=0.0)


@dataclass(frozen=True)
class GPRParams(CheckedFields):
    """GPR-based operation-parameter learning (Kabir, Sec. VIII; adapted from their ref. [12]).

    Bounds are ``(lower, upper)`` per operation parameter. The paper selects them "based on
    the safety considerations and the robot capabilities" but gives no numbers: ours bracket
    the paper's chosen values (Sec. IX-C) by a factor of about 2-5 each way.
    """

    # Ours: v bounds (fraction of v_max), around the paper's 0.1 (hull) and 0.3 (bowl).
    v_bounds: tuple = ranged((0.05, 0.6), gt=0.0, le=1.0, length=2)
    # Ours: normal force bounds, N, around the paper's 10 N and 20 N.
    f_n_bounds: tuple = ranged((2.0, 40.0), gt=0.0, length=2)
    # Ours: stiffness bounds, N/m, around the paper's 5000 N/m.
    kappa_bounds: tuple = ranged((1000.0, 10000.0), gt=0.0, length=2)
    # Ours: oscillation frequency bounds, Hz, around the paper's 6-7 Hz.
    f_x_bounds: tuple = ranged((1.0, 12.0), gt=0.0, length=2)
    # Ours: oscillation amplitude bounds, N, around the paper's 30-35 N.
    A_x_bounds: tuple = ranged((5.0, 60.0), ge=0.0, length=2)
    # Kabir, Sec. IX-C: C_p^th = 0.60 for the bowl (0.90 for the hull).
    Cp_th: float = ranged(0.60, ge=0.0, le=1.0)
    # Kabir, Sec. IX-C: P_th = 0.10 for the bowl (0.30 for the hull).
    P_th: float = ranged(0.10, gt=0.0, lt=1.0)
    # Normalise inputs on log scales (all five are positive scale-like quantities). Ours.
    log_inputs: bool = True
    # Coarse uniform exploration (Sec. VIII): grid points per axis, cell-centred (2 -> 2^5 =
    # 32 points at 1/4 and 3/4 of each (log) range, plus the centre). Ours.
    grid_points: int = ranged(2, ge=2, le=5)
    # With 2 points per axis run the 2^(5-1) resolution-V half fraction (16 points + centre)
    # instead of the full 32 (ours; classic fractional factorial screening design).
    half_fraction: bool = True
    # Experiment budget (exploration included); the run stops there, feasible or not. Ours;
    # at most MAX_EXPERIMENTS.
    max_experiments: int = ranged(100, ge=1, le=MAX_EXPERIMENTS)
    # Candidate points per iteration (seeded Sobol, plus local ones around the incumbent). Ours.
    # At most 2^20: above, one GP prediction per iteration needs gigabytes.
    n_candidates: int = ranged(2048, ge=16, le=2**20)
    # Objective weight on speed; 1 - speed_weight goes to (low) force. Ours (equal weights).
    speed_weight: float = ranged(0.5, ge=0.0, le=1.0)
    # Convergence: stop when the best feasible objective improved by less than ``tol`` over
    # ``patience`` exploitation experiments, or the current answer is chosen again. Ours.
    tol: float = ranged(0.005, ge=0.0)
    patience: int = ranged(20, ge=1)
    seed: int = ranged(0, ge=0, le=MAX_SEED)

    def __post_init__(self):
        super().__post_init__()
        for name in OPERATION_PARAMS:
            lo, hi = getattr(self, f"{name}_bounds")
            if lo >= hi:
                raise ValueError(f"{name}_bounds: lower bound {lo} must be < upper bound {hi}")
        if self.log_inputs:  # the log scale needs a positive lower bound
            check_positive("A_x_bounds", self.A_x_bounds[0])

    @property
    def lower(self):
        """Lower bounds in ``OPERATION_PARAMS`` order."""
        return tuple(float(getattr(self, f"{n}_bounds")[0]) for n in OPERATION_PARAMS)

    @property
    def upper(self):
        """Upper bounds in ``OPERATION_PARAMS`` order."""
        return tuple(float(getattr(self, f"{n}_bounds")[1]) for n in OPERATION_PARAMS)


# ---- Kabir: setup space, reach test, candidate sampling (read by mavac/setups/reach.py, mavac/setups/sampling.py) ----


@dataclass(frozen=True)
class SetupSpaceParams(CheckedFields):
    """The part's setup space (x, y, alpha) and where it sits relative to the Puma 560 base.

    A setup (x, y, alpha) places the part frame (origin at the centre of the part's bounding-box
    bottom, z up) at ``base_T_part = Trans(origin_x + x, origin_y + y, table_z) Rz(alpha)`` in the
    robot base frame (the Puma's shoulder: z0 up through joint 1, the shoulder axis at z = 0).
    The paper gives the range, not the placement (Kabir, Sec. IX-A), and says how the range was
    found: a coarse sweep over a wide range, eliminating the setups that reach no patch
    (Sec. IV-A). The reproduced tables run that once over the four objects together and keep
    one 1 m square for all (:func:`mavac.setups.space.narrowed_square`, "for all the cases in
    Table II"). The defaults below are a generic square for a part of about a metre.
    """

    # Kabir, Sec. IX-A: "The narrowed down sampling region ... was [0, 1 m] x [0, 1 m] x [0, 2 pi]".
    x_min: float = 0.0
    x_max: float = 1.0
    y_min: float = 0.0
    y_max: float = 1.0
    alpha_min: float = 0.0
    alpha_max: float = 2.0 * math.pi
    # Kabir, Sec. IX-A1: "50 mm x 50 mm x 10 deg" (the paper counts alpha = 0 and 360 deg both,
    # 21 x 21 x 37 = 16,317; our grids keep one of them, 21 x 21 x 36).
    res_x: float = ranged(0.05, gt=0.0)
    res_y: float = ranged(0.05, gt=0.0)
    res_alpha: float = ranged(math.radians(10.0), gt=0.0)
    # Ours, a generic default kept from earlier versions: the square starts 0.30 m in front of
    # joint 1 and is centred on the robot sideways. The reproduced tables do not use it: they
    # place their square by the paper's procedure (mavac.setups.space.narrowed_square).
    origin_x: float = 0.30
    origin_y: float = -0.50
    # Ours: a work table 0.75 m high (a common table height; the paper gives none), with the
    # Puma's shoulder axis 0.672 m above the floor: the table top is 0.078 m above the shoulder.
    table_z: float = 0.75 - 0.672
    # Ours: a placement whose footprint comes within the robot's pedestal radius plus this
    # clearance of joint 1's axis is refused before the reach test (the part cannot stand where
    # the robot's column is; 0.05 m leaves room for the table's edge around the column). None
    # turns the test off. Applies to robots with a "pedestal" geometry (the Puma 560).
    pedestal_margin: float | None = ranged(0.05, ge=0.0)

    def __post_init__(self):
        super().__post_init__()
        if self.x_min > self.x_max:
            raise ValueError(f"x_min must be <= x_max, got {self.x_min} > {self.x_max}")
        if self.y_min > self.y_max:
            raise ValueError(f"y_min must be <= y_max, got {self.y_min} > {self.y_max}")
        check_range("alpha_max", self.alpha_max, self.alpha_min, self.alpha_min + 2.0 * math.pi)

    def at_resolution(self, resolution) -> SetupSpaceParams:
        """The same region on another grid: ``resolution`` is (x m, y m, alpha rad), each > 0."""
        res_x, res_y, res_alpha = (float(r) for r in resolution)
        return replace(self, res_x=res_x, res_y=res_y, res_alpha=res_alpha)


@dataclass(frozen=True)
class ReachParams(CheckedFields):
    """Reach test of a stain patch (Kabir, Sec. IV): all three vertices need an IK solution
    within joint limits with the tool axis along the patch normal, into the surface."""

    # Ours: the paper's Puma carries a cleaning tool of unstated length; 0.10 m from the flange
    # to the tool tip (a short scrubbing tool) makes the wrist centre sit back from the surface,
    # so the orientation constraint matters as it does for the paper's tool.
    tool_length: float = ranged(0.10, ge=0.0)
    # Kabir, Sec. IV: only IK is tested; arm-vs-part collision is an option (ours, off).
    check_collision: bool = False
    # Physics: the part rests on the table (the part frame's z = 0), so the tool cannot come
    # from below it. A patch whose tool, from the tip along the normal over the tool length
    # (at least 10 mm), would pass below the table top is unreachable; with check_collision
    # the table (a slab under the part) joins the collision model too.
    support_plane: bool = True
    # Clearance used by the optional collision check, m (ours).
    collision_margin: float = ranged(0.0, ge=0.0)
    # The collision check poses the tool this far above the patch along its normal, since at
    # the patch itself the tool tip touches the part by construction (ours, 10 mm).
    collision_standoff: float = ranged(0.01, ge=0.0)
    # Vertex targets per IK batch (memory bound; ~100 MB of float64 at 1e6). Ours.
    batch_size: int = ranged(1_000_000, ge=1)
    # Random restarts per target of the numerical (DLS) IK, for arms without a closed form
    # (the 7-DOF iiwa); the Puma's closed form ignores it. Ours: 12, the solver's default.
    ik_restarts: int = ranged(12, ge=0)


@dataclass(frozen=True)
class SamplingParams(CheckedFields):
    """Hierarchical / random sampling with gradient descent (Kabir, Sec. IV-A, IX-A2)."""

    # Level 1 of hierarchical sampling, points per axis. Kabir, Table III: level 1 costs
    # n_rfc = 36 without gradient descent, and Table V: "36 candidate setups ... uniformly
    # sampled": 36 = 3 x 3 x 4, x and y at both ends and the middle of their range, alpha at
    # 0, 90, 180 and 270 deg (ours: four distinct angles; 0 and 360 deg are one pose).
    coarse_points_x: int = ranged(3, ge=1)
    coarse_points_y: int = ranged(3, ge=1)
    coarse_points_alpha: int = ranged(4, ge=1)
    # Ours: at most 6 levels (two halvings of every axis, 250 x 250 x 60 deg) before giving up.
    max_levels: int = ranged(6, ge=1)
    # Gradient-descent step: the fine resolution of Kabir Sec. IX-A1 (50 mm, 50 mm, 10 deg),
    # the paper's Fig. 8 landscapes are sampled at 50 mm too. Ours (no step is given).
    gd_step_x: float = ranged(0.05, gt=0.0)
    gd_step_y: float = ranged(0.05, gt=0.0)
    gd_step_alpha: float = ranged(math.radians(10.0), gt=0.0)
    # Ours: random seeds drawn without replacement from the fine uniform grid, so the runs end
    # and reuse the baseline reach results; False draws from the continuous box.
    random_on_grid: bool = True
    # Seeds drawn at most when random_on_grid is False (ours).
    max_random_samples: int = ranged(20_000, ge=1)
    # Kabir, Sec. IX-A2: "repeating the experiment 100 times for each test case".
    repetitions: int = ranged(100, ge=1)


# ---- Kabir: tool paths and ICP (read by mavac/scrubbing/toolpath.py, mavac/vision/icp.py) ----


@dataclass(frozen=True)
class ToolpathParams(CheckedFields):
    """Plane-slicing tool paths and their execution time t^e = t^c + t^r (Kabir, Sec. III, VI)."""

    # Tool width = spacing of the cutting planes. Kabir, Sec. III: each patch has area
    # a_i <= a_m, the tool-tip area; Sec. IX gives patches < 1.5 cm^2 (synthetic) and
    # < 10 mm^2 (bowl, hull) but no tool size. Ours: a 30 mm sponge (a_m ~ 7 cm^2 >= both).
    tool_width_m: float = ranged(0.03, gt=0.0)
    # Ours (Kabir, Sec. VI samples the section curves but gives no spacing): 10 mm, a third of
    # the tool width, dense enough that IK failures and stain gaps split the path where they
    # happen and that the spline follows the surface curvature of the test parts.
    waypoint_spacing_m: float = ranged(0.01, gt=0.0)
    # Kabir, Sec. IX-C: v = 0.3 of the maximum joint velocity (bowl); mapped to m/s like
    # LissajousParams.tool_speed (0.3 x 0.1 m/s at v = 1) -> 0.03 m/s in contact.
    tool_speed_m_s: float = ranged(0.03, gt=0.0)
    # Ours (the paper gives none): lift 20 mm along the normal off the surface before a
    # repositioning move, clear of a sponge's compression and of small surface bumps.
    lift_height_m: float = ranged(0.02, gt=0.0)
    # Ours: repositioning is a free-space move, 0.1 m/s (tool_speed_at_vmax of LissajousParams,
    # i.e. v = 1), faster than scrubbing.
    reposition_speed_m_s: float = ranged(0.1, gt=0.0)


@dataclass(frozen=True)
class ICPParams(CheckedFields):
    """Registration of the part's CAD mesh to an RGB-D point cloud (Kabir, Sec. VII: "We used
    the iterative closest point (ICP) algorithm [25] to match the CAD model ... to its point
    cloud"). The paper gives no ICP settings; all values below are ours."""

    # Point-to-plane correspondences farther than this are ignored: 20 mm, ~10 % of the
    # bowl/hull size (Kabir, Sec. IX-C), wide enough for a few-degree initial error.
    max_correspondence_m: float = ranged(0.02, gt=0.0)
    # Open3D ICPConvergenceCriteria; 100 iterations is ample for point-to-plane.
    max_iterations: int = ranged(100, ge=1)
    relative_fitness: float = ranged(1e-7, gt=0.0)
    relative_rmse: float = ranged(1e-7, gt=0.0)
    # Points sampled on the CAD mesh (with its exact face normals) as the ICP target.
    model_points: int = ranged(20_000, ge=3)
    # A registration "succeeds" (basin of convergence) when both errors are below these:
    # 5 mm (a sixth of the 30 mm tool width) and 2 deg.
    success_translation_m: float = ranged(0.005, gt=0.0)
    success_rotation_rad: float = ranged(math.radians(2.0), gt=0.0, le=math.pi)


# ---- Kabir: setup planner, DFBnB + IESS (read by mavac/planning/setcover.py) ----


@dataclass(frozen=True)
class SetupPlannerParams(CheckedFields):
    """Depth-first branch-and-bound setup planner (Kabir, Sec. V, Algorithms 1-5).

    Cost of a plan (eq. 1): ``T(S) = sum_j (t_s + t_e(tau_j))``, each candidate setup having
    the fixed cost ``c_j = t_s + t_e_j``.
    """

    # Kabir, Sec. V-A: Algorithms 1-2 (2) or, Sec. V-B, Algorithms 3-4 with the IESS of
    # Algorithm 5 (4). Table V and the physical tests (Sec. IX-C) use Algorithm 2.
    algorithm: int = ranged(2, choices=(2, 4))
    # Kabir, eq. 2 T^lb = min over unused setups of c_j ("lb", exact) or eq. 7 T^b = max over
    # unused setups ("b", faster, optimal only with some probability); Table VI.
    bound: str = ranged("lb", choices=("lb", "b"))
    # Kabir, Sec. IX-A4: branch-guiding heuristic (sort S_u by cleaning rate), ON in the paper.
    guiding: bool = True
    # Kabir, Sec. IX-A4: branch-pruning heuristic (future-cost bound), ON in the paper.
    pruning: bool = True
    # Kabir, Sec. V-A: computational time bound T_max, s, of the whole call. The paper gives
    # no value. Ours: 60 s, so that no call hangs; None searches without a time bound.
    t_max: float | None = ranged(60.0, gt=0.0)
    # Ours: node limit of the search, deterministic where T_max is not (Tables V-VI are bounded
    # by it); None for none. 200,000 nodes are about ten seconds of search in Python.
    max_nodes: int | None = ranged(200_000, ge=1)
    # Cost of a setup in a plan. "fixed" (eq. 1 as printed): c_j = t_s + t_e over every patch
    # setup j reaches. "remaining" (Kabir, Sec. V-A, which recomputes cleaning rates on the
    # remaining patches as the plan grows): t_s + t_e of the patches not cleaned yet.
    cost_model: str = ranged("fixed", choices=("fixed", "remaining"))
    # Kabir, Sec. V-B2: T_decay in step 5 of Algorithm 4, s; "we set T_decay = 0".
    t_decay: float = ranged(0.0, ge=0.0)
    # Kabir, Sec. V-B2: T_decay "can be an exponential function of the number of nodes
    # expanded": T_decay(k) = t_decay * exp(t_decay_rate * k), 1/node. Ours: 0 (constant).
    t_decay_rate: float = ranged(0.0, ge=0.0)
    # Kabir, Algorithm 5: N_repeat. None applies Sec. IX-B: the smallest N_repeat reaching
    # probability iess_prob (eq. 5) for the worst q = ceil(m/2) (Fig. 9).
    n_repeat: int | None = ranged(None, ge=1)
    # Kabir, Sec. IX-B: "guarantees optimality with probability >= 0.90".
    iess_prob: float = ranged(0.9, gt=0.0, lt=1.0)
    # Kabir, Table VI: fixed setup time for all setups, 0, 60 or 3000 s; Table V's Hyperboloid
    # and Sine node counts match the 60 s rows.
    # Ours: at most 10^6 s (11.6 days), so that a plan's cost is a finite sum.
    setup_time: float = ranged(60.0, ge=0.0, le=1e6)
    # Seed of Algorithm 5's random draws (ours).
    seed: int = ranged(0, ge=0, le=MAX_SEED)
    # Ours: DFBnB searches the instance reduced by mavac.planning.reduction (same optimum, a
    # smaller tree). False is the paper's search over every candidate, whose nodes Tables V-VII
    # count.
    reduce: bool = True

    def __post_init__(self):
        super().__post_init__()
        if self.algorithm == 2 and self.t_decay > 0:
            raise ValueError("t_decay only enters step 5 of Algorithm 4; set algorithm=4")


#: Methods of the setup planner (:func:`mavac.planning.setcover.solve_setup_cover`); "auto" is
#: the proven optimum.
SETUP_COVER_METHODS = ("auto", "milp", "dfbnb", "both")


@dataclass(frozen=True)
class CertifyParams(CheckedFields):
    """Budgets of the certified set-cover solver (ours; :mod:`mavac.planning.certified`).

    Every budget counts nodes, never seconds, so a result does not depend on machine load.
    """

    # Ours: the bitset enumeration searches covers of up to this many setups; it proves the
    # optimum when the incumbent's size bound is no larger, else the integer program takes
    # over. 4 proves the Table II bowl (1,670 nodes) and Schwefel (50,401 nodes) instances.
    max_enumerated_size: int = ranged(4, ge=1)
    # Ours: nodes of the bitset enumeration before it hands over to the integer program.
    enumeration_nodes: int = ranged(500_000, ge=1)
    # Ours: branch-and-bound nodes given to HiGHS (each re-solves an LP: milliseconds on a few
    # hundred candidates, seconds on thousands); None for no limit.
    milp_nodes: int | None = ranged(10_000, ge=1)
    # Ours: a cover is optimal when no cover is cheaper by more than this fraction of its cost
    # (an integer program's optimum above ``(1 - rel_tol) T`` proves the incumbent ``T``; HiGHS'
    # own feasibility tolerance is 1e-7 absolute).
    rel_tol: float = ranged(1e-6, gt=0.0, lt=0.01)


# ---- MAVAC offline planning: reachability map, spots, guards, NoS (read by mavac/inspection) ----

#: Legal values of ``Visibility.method``: MAVAC's hidden point removal, and exact ray casting
#: against the mesh (ours for users). Tables list them in this order.
VISIBILITY_METHODS = ("hpr", "raycast")
#: Legal values of ``Visibility.hpr_input`` (see :mod:`mavac.vision.visibility`).
HPR_INPUTS = ("surface", "fov")


@dataclass(frozen=True)
class Visibility(CheckedFields):
    """How "the camera sees a surface element" is decided, for spots, guards and NoS guards
    (MAVAC, "Camera field of view (FOV)": FOV pyramid, then hidden point removal).

    ``method`` is ``"raycast"`` (exact: nothing of the mesh on the segment, and the element
    faces the viewpoint) or ``"hpr"`` (Katz, Tal and Basri 2007, with Open3D). HPR's
    spherical-flipping radius is ``radius`` (m) when given, else a factor times the farthest
    point distance ``max_i |s_i - viewpoint|``: ``radius_factor`` at guard views,
    ``spot_radius_factor`` at the farther spot viewpoints. Katz et al. need the radius to exceed
    that distance, so each factor must be > 1 (and an absolute radius is checked per viewpoint).

    Call :meth:`visible` (pairs of viewpoints and elements) or :meth:`visible_each` (element i
    from viewpoint i); both run :func:`mavac.vision.visibility.visible_points`.
    """

    method: str = ranged("raycast", choices=VISIBILITY_METHODS)
    # Ours: 10, the factor that misclassifies the fewest in-FOV pairs against ray casting over
    # guard poses at L_d = 0.5 m on the three machines (data/results/mavac_hpr_radius.csv,
    # notebook 03); the paper gives no radius.
    radius_factor: float = ranged(10.0, gt=1.0)
    # Ours: 30 at the spot viewpoints (0.5-3 m from the surface), chosen the same way
    # (data/results/mavac_hpr_radius_spots.csv, notebook 02); 10 hid ~1/4 of what a spot sees.
    spot_radius_factor: float = ranged(30.0, gt=1.0)
    # Absolute radius, m, for every viewpoint; None = the factors above. The authors' code uses
    # 10 (will-44/cleaning, script/class_fov_emulator.py, get_visible_point_pyramid).
    # At most 1,000 km: far beyond any machine, and spherical flipping overflows near 1e308.
    radius: float | None = ranged(None, gt=0.0, le=1e6)
    # Point set HPR runs on at guard views: "surface" = all of S (Fig. 3 shows HPR points outside
    # the pyramid), "fov" = only the points in the FOV (see mavac.vision.visibility).
    hpr_input: str = ranged("surface", choices=HPR_INPUTS)

    def at_spots(self) -> Visibility:
        """This visibility at spot viewpoints: ``spot_radius_factor`` replaces ``radius_factor``."""
        return replace(self, radius_factor=self.spot_radius_factor)

    def hpr_radius(self, max_distance: float) -> float:
        """HPR radius (m) for a viewpoint whose farthest point is ``max_distance`` (m) away."""
        if self.radius is None:
            return self.radius_factor * max_distance
        if not self.radius > max_distance:
            raise ValueError(f"radius = {self.radius!r} m must exceed the farthest point distance "
                             f"{max_distance:.3g} m (Katz et al. 2007); choose a larger radius")
        return self.radius

    def visible(self, points, normals, viewpoints, *, scene=None, candidates=None) -> np.ndarray:
        """(m, n) bool: element j seen from viewpoint i (see
        :func:`mavac.vision.visibility.visible_points` for the shapes and ``scene``)."""
        from .vision.visibility import visible_points

        return visible_points(self, points, normals, viewpoints, scene=scene, candidates=candidates)

    def visible_each(self, points, normals, viewpoints, *, scene=None) -> np.ndarray:
        """(n,) bool: element i seen from viewpoint i (:func:`mavac.vision.visibility.visible_each`)."""
        from .vision.visibility import visible_each

        return visible_each(self, points, normals, viewpoints, scene=scene)


@dataclass(frozen=True)
class ReachabilityMapParams(CheckedFields):
    """Reachability map of the arm on its base: voxels x sampled viewing-axis directions; the
    index of a voxel is the fraction of directions that are reachable (MAVAC, "Robot base
    placement", after Paus et al. and Porges et al.'s capability maps)."""

    # Ours: 5 cm voxels, the spacing of S (InspectionParams.surface_spacing), so neighbouring
    # guard points fall in different cells (the paper gives no resolution).
    voxel_size: float = ranged(0.05, gt=0.0)
    # Ours: axis directions on a Fibonacci sphere; 50 are ~29 deg apart.
    n_directions: int = ranged(50, ge=4)
    # Ours: forward-kinematics samples of the arm joints; each is rotated about joint 1's
    # vertical axis ``n_rotations`` times (exact copies when joint 1 turns a full circle).
    # 200k x 128 leaves < 10 % of the cells that batched IK reaches unmarked (UR10, 5 cm).
    n_samples: int = ranged(200_000, ge=1)
    n_rotations: int = ranged(128, ge=1)
    seed: int = ranged(0, ge=0, le=MAX_SEED)


@dataclass(frozen=True)
class SpotParams(CheckedFields):
    """Spot (mobile-base placement) selection (MAVAC, "Robot base placement")."""

    # MAVAC, Results: "we suggest to set P_s = 0.02" (Table 1 sweeps 0.01-0.30).
    P_s: float = ranged(0.02, ge=0.0, le=1.0)
    # Ours (the paper explores "different positions around the machine", after Paus et al.):
    # candidate base centres on rings at these distances from the machine footprint, m.
    # 0.45 m leaves 0.16 m between the 0.58 m-wide MiR200 (parked alongside) and the machine.
    ring_distances: tuple = ranged((0.45, 0.75), gt=0.0, nonempty=True)
    # Ours: spacing of candidate poses along a ring, m.
    ring_spacing: float = ranged(0.25, gt=0.0)
    # Ours: seeded jitter of the candidate poses (what varies between Table 1 trials besides
    # the surface sampling): uniform +- jitter_xy (m) and +- jitter_theta (rad).
    jitter_xy: float = ranged(0.05, ge=0.0)
    jitter_theta: float = ranged(0.15, ge=0.0, le=math.pi)
    # Ours: the base is parked alongside the machine (long side tangent to the ring), turned
    # by each of these offsets (rad).
    heading_offsets: tuple = ranged((0.0,), ge=-math.pi, le=math.pi, nonempty=True)
    # Ours: "visible from a spot" = visible from a viewpoint above the base at one of these
    # heights (m), a stand-in for where the arm can hold the camera.
    view_heights: tuple = ranged((0.8, 1.6), gt=0.0, nonempty=True)


@dataclass(frozen=True)
class GuardParams(CheckedFields):
    """Guard (arm inspection configuration) selection per spot (MAVAC, "Local exploration",
    "Guard selection", eq. 3: score = I_m^k1 x (N / |S|)^k2)."""

    # MAVAC, Results: "we suggest to set P_s = 0.02, P_g = 15" (per cent), i.e. 0.15.
    P_g: float = ranged(0.15, ge=0.0, le=1.0)
    # MAVAC, Results: "they are fixed to k1 = k2 = 1, to give the same weight to both".
    k1: float = ranged(1.0, ge=0.0, le=1.0)
    k2: float = ranged(1.0, ge=0.0, le=1.0)
    # Ours: one guard candidate per small cluster of surface elements of this size, m
    # (the paper assigns "a guard point to each surface").
    guard_spacing: float = ranged(0.10, gt=0.0)
    # Guard stand-off along the target's normal, m. None = CameraParams.L_d, the paper's text:
    # "The guard point is placed along this normal at a distance corresponding to the reliable
    # detection limit of the camera". The authors' code places it 0.4 m out instead (will-44/cleaning,
    # rubyrhod_ws/src/cleaning/script/offline.py, generate_pcd_guard).
    standoff: float | None = ranged(None, gt=0.0)
    # Ours: clearance to the machine for a guard configuration, m.
    collision_margin: float = ranged(0.01, ge=0.0)


@dataclass(frozen=True)
class NoSParams(CheckedFields):
    """Non-observed surfaces (MAVAC, "Non-observed surface (NoS)", Fig. 4): DBSCAN clusters,
    outward ray fans, gateways, NoS guards checked with RRT-Connect."""

    # Ours: DBSCAN radius as a multiple of the surface spacing (neighbouring elements of S are
    # ~0.85 spacing apart, so 1.5 links neighbours without bridging across edges and gaps),
    # and the minimum cluster size.
    eps_factor: float = ranged(1.5, gt=0.0)
    min_samples: int = ranged(3, ge=1)
    # Ours: rays per cluster (Fibonacci sphere) and the length a ray must travel free, m.
    n_rays: int = ranged(400, ge=4)
    ray_length: float = ranged(1.5, gt=0.0)
    # Ours: ray origins are lifted this far off the surface, m.
    origin_offset: float = ranged(0.01, ge=0.0)
    # Ours: the NoS camera is tried on up to this many rays of the best gateway, closest to its
    # mean exit direction first (the paper uses the mean direction; one ray may be unreachable).
    max_ray_tries: int = ranged(32, ge=1)
    # Ours: RRT-Connect iteration budget per NoS guard (MAVAC: RRT-Connect, Kuffner 2000). It,
    # not the clock, ends the search, so plans do not depend on the machine's speed; NoS guards
    # that our plans reach need a few hundred iterations, 10,000 take ~1.5 s on our machine.
    rrt_max_iterations: int = ranged(10_000, ge=1)
    # Ours: wall-time safety net per NoS guard, s. It never decides a result: when it fires before
    # the budget is spent, planning raises PlanningTimeout (300 s: ~15x what 10,000 iterations
    # take at the slowest rate we measured, 4-7 s per 3000 on a loaded 2-core machine).
    rrt_time_limit: float = ranged(300.0, gt=0.0)
    # Ours: collision-check resolution of RRT-Connect (fraction of the space extent).
    rrt_resolution: float = ranged(0.01, gt=0.0, le=1.0)
    enabled: bool = True


@dataclass(frozen=True)
class InspectionParams(CheckedFields):
    """Everything ``mavac.inspection.inspection_plan.plan_inspection`` needs (MAVAC offline computation)."""

    # Ours: surface discretisation S, m (MAVAC discretises the surface into a point cloud;
    # dust heaps are 10 cm apart, S is twice as fine).
    surface_spacing: float = ranged(0.05, gt=0.0)
    # Seed of the surface sampling, the spot jitter, IK restarts and RRT-Connect.
    seed: int = ranged(0, ge=0, le=MAX_SEED)
    camera: CameraParams = CameraParams()
    reach: ReachabilityMapParams = ReachabilityMapParams()
    spot: SpotParams = SpotParams()
    guard: GuardParams = GuardParams()
    nos: NoSParams = NoSParams()

    # Ours for users: exact ray casting ("raycast"); MAVAC's hidden point removal is
    # Visibility("hpr"), which the notebooks that reproduce the paper select. One choice for
    # spots, guards and NoS guards.
    visibility: Visibility = Visibility()

    @property
    def guard_standoff(self) -> float:
        """Distance of a guard camera from its target along the normal, m (``guard.standoff``,
        else the camera's ``L_d``)."""
        return self.camera.L_d if self.guard.standoff is None else self.guard.standoff

    def with_visibility(self, visibility: str | Visibility) -> InspectionParams:
        """The same parameters with another visibility: a :class:`Visibility`, or a method name
        (``"raycast"`` or ``"hpr"``) that replaces only ``visibility.method``."""
        if isinstance(visibility, str):
            visibility = replace(self.visibility, method=visibility)
        return replace(self, visibility=visibility)


# ---- MAVAC online execution, Algorithm 1 (read by mavac/cleaning) ----


@dataclass(frozen=True)
class DustParams(CheckedFields):
    """Green dust heaps of MAVAC's evaluation ("Experimental setup"), as pybullet visual bodies."""

    # MAVAC, Experimental setup: "green dust heaps are evenly distributed at intervals of 10 cm on
    # the surface, including within the concavities".
    spacing: float = ranged(0.10, gt=0.0)
    # Ours: a heap is a sphere of this radius centred on the surface (a 3 cm dome; the paper
    # gives no size).
    radius: float = ranged(0.015, gt=0.0)
    # Ours: pure green (the paper's heaps are green; the HSV filter looks for green).
    rgba: tuple = ranged((0.1, 0.8, 0.1, 1.0), ge=0.0, le=1.0, length=4)
    # Share of the 10 cm grid's heaps a trial keeps, drawn with its seed. The paper's 1 (every
    # heap); issue 34 compares adaptive with systematic cleaning at 1, 0.3 and 0.1.
    density: float = ranged(1.0, gt=0.0, le=1.0)


@dataclass(frozen=True)
class DetectionParams(CheckedFields):
    """Dust detection from one guard view: RGB-D render, HSV threshold, blobs, back-projection
    and the paper's filters (MAVAC, "Dust detection")."""

    # Ours: 320 x 236 px over the camera's 75 x 59 deg (CameraParams): ~4.3 mm/px at the 0.5 m
    # guard stand-off L_d, so a 3 cm heap spans ~7 px, and the TinyRenderer (CPU) stays fast.
    width: int = ranged(320, ge=8, le=2048)
    height: int = ranged(236, ge=8, le=2048)
    # MAVAC: "a simple HSV filter with fine-tuned parameters" (values not given). Ours, OpenCV
    # units (H in [0, 180)): green hue 35-85, saturation >= 80, value >= 40; our grey machine,
    # robot and floor have saturation ~0.
    hue_min: int = ranged(35, ge=0, le=179)
    hue_max: int = ranged(85, ge=0, le=179)
    saturation_min: int = ranged(80, ge=0, le=255)
    value_min: int = ranged(40, ge=0, le=255)
    # Ours: blobs smaller than this (px) are noise.
    min_blob_px: int = ranged(3, ge=1)
    # Depth validity, m: the sensor's operating range, Azure Kinect DK hardware specification
    # (learn.microsoft.com/azure/kinect-dk/hardware-specification, "Depth camera supported
    # operating modes"), WFOV 2x2 binned: 0.25-2.88 m (the NFOV modes start at 0.5 m, which
    # would blank a guard's own target at L_d). MAVAC uses L_d only offline (FOV pyramid, guard
    # stand-off); online it filters "dust particles that are beyond the robot's theoretically
    # reachable workspace or are incorrectly identified due to noise": no cut at L_d here.
    min_depth: float = ranged(0.25, gt=0.0)
    max_depth: float = ranged(2.88, gt=0.0)
    # "filters ... remove any dust particles that are beyond the robot's theoretically reachable
    # workspace": UR10 reach 1.3 m from the shoulder (UR10 datasheet) plus the 0.40 m tool tube
    # (mavac.robots.models.TOOL_TUBE_LENGTH).
    reach: float = ranged(1.7, gt=0.0)
    # Keep only nodes within this distance of the vacuum tip at the guard, m; None: no such
    # filter (the paper's text has none). Authors' code: 0.5 (will-44/cleaning,
    # rubyrhod_ws/src/cleaning/script/online.py, __main__: dust.filter_dust(dust_poses, dist=0.5);
    # script/dust.py, Dust.filter_dust keeps points whose norm in the vacuum_tcp frame is < dist).
    max_tip_distance: float | None = ranged(None, gt=0.0)
    # Ours, off by default: drop a node within duplicate_radius (half the heap spacing, m) of a
    # node already vacuumed in this trial. Neither the paper nor the authors' code has it, and
    # in our simulation a vacuumed heap is removed, so a node seen there again is dust the
    # vacuum missed: the paper lets another guard try it.
    duplicate: bool = False
    duplicate_radius: float = ranged(0.05, ge=0.0)
    # Ours, scoring only: a node matches a true heap within this distance, m (half the spacing).
    match_radius: float = ranged(0.05, gt=0.0)

    def __post_init__(self):
        super().__post_init__()
        if self.hue_max < self.hue_min:
            raise ValueError(f"hue_max must be >= hue_min, got {self.hue_max} < {self.hue_min}")
        if self.max_depth <= self.min_depth:
            raise ValueError(f"max_depth must be > min_depth, got {self.max_depth} <= {self.min_depth}")


@dataclass(frozen=True)
class ApproachParams(CheckedFields):
    """Areas and approach points (MAVAC, "Trajectory generation", eq. 5) and RRT-Connect."""

    # Ours: DBSCAN radius of an area, m (1.5 heap spacings links neighbouring heaps), and the
    # smallest area (1: a lone heap is an area too); the paper gives neither. Authors' code:
    # eps 0.1 m and 1 neighbour (will-44/cleaning, script/dust.py, Dust.dust_path:
    # clusterise_dbscan(dust_list, eps=0.1, neighbors=1)); pyclustering does not count the point
    # itself (script/open3d_tools.py, Open3dTool.clusterise_dbscan), scikit-learn does, so
    # min_samples 2: a node with no other node within eps is noise.
    cluster_eps: float = ranged(0.15, gt=0.0)
    cluster_min_samples: int = ranged(1, ge=1)
    # Order of an area's nodes: "tsp", the shortest closed tour (Algorithm 1, line 4,
    # detectClusterizeTspDust; closed, because the tool returns to the approach point), or
    # "path", ours before: nearest neighbour + 2-opt open path from the node nearest the centroid.
    node_order: str = ranged("tsp", choices=("tsp", "path"))
    # Order of the areas: "detection" (order of their first node in the image) or "tsp" (closed
    # tour over the area centroids from the first area). Authors' code: "tsp" over each cluster's
    # first node (script/dust.py, Dust.dust_path; solver script/robot.py,
    # Robot.generate_trajectory: fast_tsp). The paper's text does not say what its TSP orders.
    area_order: str = ranged("detection", choices=("detection", "tsp"))
    # eq. 5: the approach point is delta before the node, the tool within +- alpha of the guard's
    # orientation. The paper gives neither value. Ours: delta = 0.10 m (two tool-sphere
    # diameters), alpha = 15 deg. Authors' code: delta 0.05 m (script/online.py, __main__: the
    # planning TCP is "vacuum_safe_tcp", "the end of vacuum, and we add 5cm to set up an approche
    # point"), alpha 0 (the entry pose keeps the guard's TCP orientation exactly).
    delta: float = ranged(0.10, ge=0.0)
    alpha: float = ranged(math.radians(15.0), ge=0.0, le=math.pi)
    # eq. 5 writes d_z - delta. "tool": delta back along the tool axis (the tool z points into
    # the surface, so this is "above" the node as the tool sees it); "world": delta above the
    # node along world z (d_z - delta literally in world z would be inside the machine).
    approach_reading: str = ranged("tool", choices=("tool", "world"))
    # Ours: orientations sampled within +- alpha (the first is the guard's own; 1 with alpha 0).
    n_orientations: int = ranged(8, ge=1)
    # Ours: clearance of approach configurations and RRT-Connect paths to the machine, m.
    collision_margin: float = ranged(0.01, ge=0.0)
    # Ours: RRT-Connect budget per plan (iterations, not time: deterministic) and collision-check
    # resolution (fraction of the joint box diagonal).
    rrt_max_iterations: int = ranged(3000, ge=1)
    # Ours: wall-time safety net per plan, s. It never decides a result: when it fires before
    # the budget is spent, planning raises PlanningTimeout. 120 s is ~17x the slowest
    # 3000-iteration search we measured (4-7 s on a loaded 2-core machine), so it only fires on
    # a hang; a re-plan's cap grows with its budget (rrt_retry_factor).
    rrt_time_limit: float = ranged(120.0, gt=0.0)
    rrt_resolution: float = ranged(0.01, gt=0.0, le=1.0)
    # Ours: a guard or fold-home motion that fails within rrt_max_iterations is planned once more
    # with this many times the budget (and the cap) before it is counted as a failure, because a
    # failure within a budget may be a narrow passage rather than an impossible motion; the
    # re-plan costs time only where the first plan failed.
    rrt_retry_factor: int = ranged(10, ge=1)
    # Ours: the arm's joint speed and acceleration limits for planned motions (UR10: 2.09-3.14
    # rad/s per joint, datasheet; ours slower, as near a machine).
    max_joint_velocity: float = ranged(1.0, gt=0.0)
    max_joint_acceleration: float = ranged(2.0, gt=0.0)


@dataclass(frozen=True)
class VacuumParams(CheckedFields):
    """Dust collection under Cartesian impedance control (MAVAC, "Dust collecting")."""

    # MAVAC uses impedance control but gives no gains. Ours: 1000 N/m, so pressing the tool
    # sphere its full 2.5 cm radius into a surface costs 25 N; 30 N m/rad. Damping: ours, near
    # critical for the tool's apparent mass and stable at the 240 Hz physics step. Authors'
    # code: 100 N/m and 20 N m/rad (script/online.py, __main__:
    # arm.set_compliance([100, 100, 100, 20, 20, 20]), Doosan task compliance control).
    stiffness: float = ranged(1000.0, ge=0.0)
    rotational_stiffness: float = ranged(30.0, ge=0.0)
    damping: float = ranged(60.0, ge=0.0)
    rotational_damping: float = ranged(1.0, ge=0.0)
    # Ours: speed of the linear vacuuming moves, m/s. Authors' code: 0.02 (rubyrhod_ws/src/
    # utility/script/utility/doosan.py, Doosan.dsr_go_to_l: move_line velocity 20 mm/s).
    speed: float = ranged(0.10, gt=0.0)
    # "linear": MAVAC's text, "a linear movement to directly engage with the dust". "spiral":
    # authors' code, after the linear move into a node, a spiral of spiral_turns revolutions
    # out to spiral_radius in spiral_time (script/online.py, __main__:
    # arm.dsr_spiral(revolution=2, max_radius=10, time=5), max_radius in mm; doosan.py,
    # Doosan.dsr_spiral: Doosan move_spiral with taskAxis 2 (Z) and ref 0, the base frame as we
    # read Doosan's constants), at the last node of each area only (spiral_nodes "last";
    # "every": ours, at each node).
    pattern: str = ranged("linear", choices=("linear", "spiral"))
    spiral_radius: float = ranged(0.010, gt=0.0)
    spiral_turns: float = ranged(2.0, gt=0.0)
    spiral_time: float = ranged(5.0, gt=0.0)
    spiral_nodes: str = ranged("last", choices=("last", "every"))
    # Ours: a heap is sucked up when the tool sphere's centre passes within this distance of it,
    # m: the 2.5 cm sphere radius plus 2.5 cm of suction reach.
    suction_radius: float = ranged(0.05, ge=0.0)
    # Ours: after a linear move, hold the target until within this distance, m, or this long, s.
    settle_tol: float = ranged(0.005, gt=0.0)
    max_settle_time: float = ranged(0.5, ge=0.0)


@dataclass(frozen=True)
class SystematicParams(CheckedFields):
    """The systematic baseline of ``mavac.cleaning.systematic``: a boustrophedon raster over every
    surface dust can rest on, vacuumed from the plan's spots (MAVAC names no baseline: "the lack
    of established baselines")."""

    # Ours: raster lines this far apart, m. None: the width the suction sweeps, 2 sqrt(r_s^2 -
    # rho^2), with r_s the suction radius and rho the tool sphere's radius (the sphere's centre
    # rides rho above the surface the heaps lie on), so neighbouring lines leave no heap unswept.
    line_spacing: float | None = ranged(None, gt=0.0)
    # Ours: waypoints this far apart along a line, m: a fifth of the 10 cm heap spacing, so a
    # reach test between two waypoints decides at most a fifth of a heap's cell.
    waypoint_spacing: float = ranged(0.02, gt=0.0)


@dataclass(frozen=True)
class PerturbationParams(CheckedFields):
    """The world departing from what the offline plan and the robot assume
    (``mavac.cleaning.perturbation``). Every default is 0: the paper's trials, where the robot is
    where it believes, the machine where it was planned, and the camera noise-free. The sweeps of
    notebook 12 (MAVAC claims its plan survives machines "slightly rearranged" with "no
    additional scanning") set one field at a time."""

    # Base localisation error at each spot: a Gaussian offset in the base frame, sigma per
    # horizontal axis (m) and of the heading (deg); the robot plans at the spot it believes.
    base_position_sigma: float = ranged(0.0, ge=0.0, le=1.0)
    base_heading_sigma: float = ranged(0.0, ge=0.0, le=90.0)
    # The machine moved after planning: this far (m) in a horizontal direction drawn per trial,
    # and turned this much (deg, sign drawn per trial) about the vertical through its
    # footprint's centre. The robot's collision model and plan stay where the machine was.
    machine_shift: float = ranged(0.0, ge=0.0, le=5.0)
    machine_rotation: float = ranged(0.0, ge=0.0, le=180.0)
    # Per-pixel Gaussian noise on the depth image (sigma, m) and on each colour channel (sigma,
    # 8-bit levels); the renderer's images are otherwise exact.
    depth_noise: float = ranged(0.0, ge=0.0, le=1.0)
    colour_noise: float = ranged(0.0, ge=0.0, le=255.0)
    # Green-ish machine parts: this many static spheres of the dust's size and colour (inside the
    # detector's HSV box: the worst case), area-uniform on the whole machine surface. They are
    # detected, approached and vacuumed like dust and never go away.
    decoys: int = ranged(0, ge=0, le=10_000)

    @property
    def is_null(self) -> bool:
        """True when nothing is perturbed (the paper's trials)."""
        return self == PerturbationParams()


@dataclass(frozen=True)
class OnlineParams(CheckedFields):
    """Everything a MAVAC online trial needs (``mavac.cleaning.trial.run_trial``)."""

    dust: DustParams = DustParams()
    detection: DetectionParams = DetectionParams()
    approach: ApproachParams = ApproachParams()
    vacuum: VacuumParams = VacuumParams()
    # The world as it really is, against the plan's (default: unperturbed).
    perturbation: PerturbationParams = PerturbationParams()
    # MiR200 datasheet: maximum speed 1.1 m/s forward. Ours: base travel at that speed along
    # the shortest path around the machine (kinematic; no acceleration phases).
    base_speed: float = ranged(1.1, gt=0.0)
    # Ours: clearance kept between the base's footprint and the machine's on base paths, m.
    base_clearance: float = ranged(0.10, ge=0.0)
    # Physics step, s (pybullet's default, 240 Hz).
    time_step: float = ranged(1.0 / 240.0, gt=0.0, le=0.01)


# ---- Kabir: plan_setups, the user-facing setup planner (read by mavac/setups/setup_plan.py) ----



#: Gradient-descent variants of candidate sampling, Kabir Table I names ("a" spells alpha);
#: "none" is sampling without gradient descent (read by mavac.setups.sampling).
SAMPLING_VARIANTS = ("none", "C_XY", "CA_XY", "C_XY_a", "CA_XY_a", "C_XYa", "CA_XYa")


@dataclass(frozen=True)
class SetupPlanParams(CheckedFields):
    """Everything ``mavac.setups.setup_plan.plan_setups`` needs: setup space, reach test, candidate
    sampling, cost model and planner (Kabir, Sections III-V)."""

    space: SetupSpaceParams = field(default_factory=SetupSpaceParams)
    reach: ReachParams = field(default_factory=ReachParams)
    sampling: SamplingParams = field(default_factory=SamplingParams)
    # Kabir, Sec. IX-A2: "hierarchical uniform sampling with the CA_XY gradient descent variant
    # guarantees optimal solution" -> the default candidate generator. "uniform" is the
    # 16,317-setup baseline (IV-A1), "random" is IV-A3.
    sampling_method: str = ranged("hierarchical", choices=("uniform", "hierarchical", "random"))
    # Kabir, Table I / Sec. IX-A2: CA_XY worked best.
    variant: str = ranged("CA_XY", choices=SAMPLING_VARIANTS)
    # Seed of random sampling (ours).
    seed: int = ranged(0, ge=0, le=MAX_SEED)
    # Kabir, eq. 1 with t_e from a simple model (ours): t_e = sum(area x passes) / rate, rate =
    # 1e-3 m^2/s (a 20 mm wide tool sweeping 5 cm/s); the paper gives no rate for the Puma.
    cleaning_rate: float = ranged(1.0e-3, gt=0.0)
    # Setup planner. Ours: Algorithm 2, bound eq. 2, both heuristics on (the paper's setting),
    # with T_max = 10 s so the call always returns (the paper sets no T_max); setup time 60 s
    # (Kabir, Table VI middle value).
    planner: SetupPlannerParams = field(default_factory=lambda: SetupPlannerParams(t_max=10.0))
    # "auto" (the proven optimum: reduction, size bound, enumeration, integer program), "milp"
    # (HiGHS alone), "dfbnb" (the paper's search) or "both" (DFBnB's plan, the proven optimum as
    # certificate and gap). Ours: "auto", because a user wants the cheapest plan, proven.
    method: str = ranged("auto", choices=SETUP_COVER_METHODS)
    # Node budgets of the proof (ours; see CertifyParams).
    certify: CertifyParams = field(default_factory=CertifyParams)

    @classmethod
    def paper(cls, **changes) -> SetupPlanParams:
        """The paper's planner: DFBnB (Algorithm 2) over every candidate, its plan and node count,
        with the proven optimum beside it (method "both", no reduction)."""
        defaults = cls()
        return replace(defaults, method="both", planner=replace(defaults.planner, reduce=False), **changes)


# ---- Kabir bimanual cell: two iiwa arms in pybullet (read by mavac/scrubbing/cell.py, scene.py, scrub.py,
# holding.py, run.py) ----


def _cell_space() -> SetupSpaceParams:
    # Ours (the paper's cell is not dimensioned): the part centre moves over a 0.30 x 0.30 m
    # square between the arms (two steps of level-1 sampling's 150 mm grid), its bottom 0.35 m
    # above both bases; the holding arm presents it with its flange pointing up. The corner
    # here (0.45-0.75 m in front of the cleaning arm's base) is a default for a user's part;
    # notebook 11 places the square by the paper's narrowing over the bowl and the hull
    # (mavac.scrubbing.cell_space.narrowed_cell_space).
    return SetupSpaceParams(x_min=0.0, x_max=0.3, y_min=0.0, y_max=0.3, origin_x=0.45, origin_y=-0.15,
                            table_z=0.35)


def _cell_sampling() -> SamplingParams:
    # Level 1 of hierarchical sampling keeps the paper's 36 = 3 x 3 x 4 setups (Table III): on
    # the cell's 0.30 m square that is 150 mm x 150 mm x 90 deg; descent steps as for the Puma.
    return SamplingParams()


@dataclass(frozen=True)
class BimanualCellParams(CheckedFields):
    """The two-arm cell of Kabir Sec. IX-C in simulation: a holding iiwa and a cleaning iiwa.

    World frame = the cleaning arm's base frame (on the floor plate under joint 1, z up, x
    towards the other arm). The holding arm's base sits ``arm_separation`` m along x, turned
    by 180 deg so the arms face each other across the workspace. A setup ``(x, y, alpha)``
    puts the part frame at ``Trans(origin_x + x, origin_y + y, table_z) Rz(alpha)`` in the
    world (:func:`mavac.setups.reach.base_T_part` with ``space``), which the holding arm's
    flange must reach through the fixed grasp ``flange_T_part = Trans(0, 0, grasp_offset)``.
    """

    # Ours: 1.2 m between the bases, so a part 0.45-0.75 m from one base is 0.45-0.75 m from
    # the other, inside both arms' reach with the flange up (holder) and the pad down (cleaner).
    arm_separation: float = ranged(1.2, gt=0.0)
    # Ours: a 60 mm adapter between the holding flange and the part frame (part z = flange z).
    grasp_offset: float = ranged(0.06, gt=0.0)
    # Ours: a plastic bowl or a 3-D printed hull of ~20 cm weighs a few hundred grams.
    part_mass: float = ranged(0.3, gt=0.0)
    # Ours: 120 mm from the cleaning flange to the pad face (holder and 10 mm pad).
    tool_length: float = ranged(0.12, gt=0.0)
    space: SetupSpaceParams = field(default_factory=_cell_space)
    sampling: SamplingParams = field(default_factory=_cell_sampling)
    # 1 kHz, the fastest cycle of the iiwa's Fast Robot Interface (KUKA Sunrise.FRI: 1-100 ms),
    # which runs a torque-level loop such as this one. At 500 Hz the loop on the iiwa's light
    # wrist went unstable at learned gains (pad impacts above 1 kN, 14 m of sliding in a 4 s pass).
    time_step: float = ranged(0.001, gt=0.0, le=0.02)
    # Ours: setup and approach motions at 0.5 rad/s on the joint that moves most (the iiwa 7's
    # axis limits are 98-180 deg/s; a cautious half of the slowest).
    joint_speed: float = ranged(0.5, gt=0.0)
    # Ours: joint PD gains (N m/rad, N m s/rad) of the holding arm and of free motions, on top
    # of pinocchio's gravity compensation.
    kp: float = ranged(600.0, gt=0.0)
    kd: float = ranged(40.0, gt=0.0)
    # Ours: rotational stiffness (N m/rad) of the cleaning arm's Cartesian impedance;
    # translational stiffness in the tool plane is kappa of LissajousParams.
    rot_stiffness: float = ranged(150.0, gt=0.0)
    # Damping ratio of every Cartesian axis, for the arm's real Cartesian inertia at the pad
    # (factorization design, sim.control.cartesian_damping): 0.7, the default of KUKA Sunrise's
    # Cartesian impedance mode.
    damping_ratio: float = ranged(0.7, gt=0.0)
    # Ours: integral gain (1/s) of the explicit normal-force loop along tool z, tuned on the
    # coupon stroke (tests/test_scrub.py): 6/s left the mean contact force 36 % above f_n on
    # the bowl's parameters (pad bouncing off after landing), 100/s tracks it within ~1 %.
    force_gain: float = ranged(100.0, ge=0.0)
    # Ours: pybullet friction coefficient pad/part, the wet sponge on plastic of ScrubModel.friction.
    friction: float = ranged(0.4, gt=0.0)
    # Ours: contact stiffness (N/m) and damping (N s/m) of the foam pad: 10 N compresses it 1 mm.
    pad_stiffness: float = ranged(1.0e4, gt=0.0)
    pad_damping: float = ranged(200.0, gt=0.0)
    # Preston coefficient of the cell's measured wear, stain layers per (Pa x m of sliding):
    # PRESTON, the analytic ScrubModel's too.
    preston: float = ranged(PRESTON, gt=0.0)
    # Ours: re-plan rounds after the planned passes (Kabir Sec. IX-C iterates "until there is no
    # more stain left"; we bound it).
    max_rounds: int = ranged(3, ge=0, le=20)
    # Ours: stain image size (pixels) of the camera view that measures C_p.
    image_size: int = ranged(128, ge=16, le=1024)
    # Ours: the part counts as clean when the residue is below this fraction of its stained pixels.
    clean_residue: float = ranged(0.02, ge=0.0, le=1.0)
    # Ours: null-space posture stiffness (N m/rad) and damping (N m s/rad) of the redundant
    # iiwa while scrubbing: weak, so the pull towards the start posture never fights the task.
    null_stiffness: float = ranged(2.0, gt=0.0)
    null_damping: float = ranged(0.1, gt=0.0)
    # Ours: the normal-force integral is clipped to +-force_integral_limit x f_n. It integrates
    # only while the pad touches the part and restarts from 0 when contact is lost (conditional
    # integration, the standard anti-windup), so the clip is a last resort.
    force_integral_limit: float = ranged(2.0, gt=0.0)
    # Ours: a coupon stroke of the GPR learner counts as failed (C_p = 0, whatever it removed)
    # unless the pad stayed on the coupon for this share of the commanded contact steps and the
    # mean force over all of them stayed within this fraction of f_n: the cell must hold the
    # commanded contact before its cleaning is credited (the acceptance figures of the cell).
    tracking_duty: float = ranged(0.95, ge=0.0, le=1.0)
    tracking_force_error: float = ranged(0.10, gt=0.0)
    # Ours: the Lissajous force ramps in linearly over this many periods of its slower (y)
    # axis after each landing, so the pad settles under f_n before it is pushed sideways
    # (Kabir Sec. VIII overlays the oscillation on the path but says nothing of its start).
    lissajous_ramp_periods: float = ranged(1.0, ge=0.0)
    # Ours: wear goes only to faces within this distance (m), along the pad axis, of the real
    # surface under the pad (the contact points on the part's exact mesh); 2 mm is the pad's
    # compression at 20 N under pad_stiffness, the deepest the pad face reaches into the part.
    wear_depth: float = ranged(0.002, gt=0.0)
    # pybullet_data's kuka_iiwa/model.urdf: joint effort 300 N m, the motor force of a braked arm.
    brake_torque: float = ranged(300.0, gt=0.0)
    # Ours: the held part's rotational inertia is that of a sphere of this radius (m) and of
    # part_mass; setup motions are slow, so the value barely matters.
    part_inertia_radius: float = ranged(0.1, gt=0.0)
    # Ours: joint acceleration limit (rad/s^2) of setup and approach motions, cautious like
    # joint_speed.
    joint_acceleration: float = ranged(1.0, gt=0.0)
    # Ours: growth (m) of the box around the parked cleaning arm's link origins that the holding
    # arm and its part avoid (the origins miss the links' ~6 cm radius).
    park_margin: float = ranged(0.08, ge=0.0)
    # Ours: clearance (m) the held part keeps from both arms when a setup is tested (coal margin).
    part_clearance: float = ranged(0.005, ge=0.0)
    # Ours: RRT-Connect budget of a setup motion. The iteration budget stops the search; the
    # wall-clock cap (s) only turns a hang into an error (ENVIRONMENT: wall-clock limits make
    # results load-dependent).
    setup_rrt_iterations: int = ranged(5000, ge=1)
    setup_rrt_time_limit: float = ranged(60.0, gt=0.0)

    @property
    def world_T_cleaner(self):
        """(4, 4) pose of the cleaning arm's base (identity: the world frame)."""
        return np.eye(4)

    @property
    def world_T_holder(self):
        """(4, 4) pose of the holding arm's base: ``arm_separation`` along x, facing -x."""
        T = np.diag([-1.0, -1.0, 1.0, 1.0])
        T[0, 3] = self.arm_separation
        return T

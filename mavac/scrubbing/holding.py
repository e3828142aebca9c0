"""Setups a holding arm can present, and the setup plan of the two-arm cell (Kabir et al.
Sec. IX-C).

In the paper's cell one iiwa holds the part and changes setups, the other cleans. A setup
``(x, y, alpha)`` then exists only where the holding arm reaches the part pose with its
flange (full-pose IK through the fixed grasp) and the part, held there, leaves room for both
arms. :class:`HeldSetups` is that test as the ``feasible`` argument of
:func:`mavac.setups.setup_plan.plan_setups`: the planner drops every other candidate and says how
many and why. :func:`plan_cell_setups` plans with it; :func:`setup_configurations` gives the
holding arm's configuration of each planned setup.
"""

from __future__ import annotations

import numpy as np

from ..geometry.mesh import check_mesh
from ..geometry.parts import Part
from ..params import BimanualCellParams, ReachParams, SetupPlanParams
from ..setups.reach import base_T_part
from ..setups.setup_plan import SetupPlan, plan_setups
from ..validate import check_instance, check_points
from .cell import ArmClearance, holder_ik

#: Rated payload of the holding arm, kg: KUKA LBR iiwa 7 R800 datasheet (7 kg); the part and its
#: adapter must weigh no more.
HOLDER_PAYLOAD_KG = 7.0


def check_payload(params: BimanualCellParams) -> None:
    """ValueError when ``params.part_mass`` is over the holding arm's rated payload."""
    if params.part_mass > HOLDER_PAYLOAD_KG:
        raise ValueError(f"part_mass must be at most {HOLDER_PAYLOAD_KG:g} kg, the holding arm's rated payload "
                         f"(KUKA LBR iiwa 7 R800), got {params.part_mass:g} kg: the cell cannot hold this part")


class HeldSetups:
    """``feasible(setups (k, 3)) -> (k,) bool`` for a part held by the cell's holding arm.

    Parameters
    ----------
    cleaner, holder : RobotModel
        From :func:`mavac.scrubbing.cell.cell_robots`.
    part_mesh : trimesh.Trimesh
        Part frame, metres.
    params : BimanualCellParams

    Attributes
    ----------
    unreachable, collides : int
        Setups refused so far because the holding arm cannot reach the pose, or because the
        part at that pose hits an arm (too large to fit between them).
    """

    def __init__(self, cleaner, holder, part_mesh, params: BimanualCellParams = BimanualCellParams()):
        self.cleaner, self.holder = cleaner, holder
        self.part_mesh = check_mesh("part_mesh", part_mesh)
        self.params = check_instance("params", params, BimanualCellParams)
        self.unreachable = 0
        self.collides = 0
        self._clearance = None  # built on first use (setup_configurations never needs it)

    def holder_q(self, setups) -> tuple[np.ndarray, np.ndarray]:
        """Holding arm configurations ``(k, 7)`` for the setups and which exist ``(k,)``."""
        T = base_T_part(check_points("setups", setups, 3), self.params.space)
        res = holder_ik(self.holder, T, self.params)
        return res.q, res.success

    def __call__(self, setups) -> np.ndarray:
        setups = check_points("setups", setups, 3)
        q, ok = self.holder_q(setups)
        self.unreachable += int((~ok).sum())
        if ok.any():
            T = base_T_part(setups[ok], self.params.space)
            if self._clearance is None:
                self._clearance = ArmClearance(self.cleaner, self.holder, self.part_mesh, self.params)
            clear = self._clearance(T, q[ok])
            self.collides += int((~clear).sum())
            ok[np.flatnonzero(ok)[~clear]] = False
        return ok

    def summary(self) -> str:
        """What was refused and why, for the plan's warnings."""
        return (f"{self.unreachable} the holding arm cannot reach, {self.collides} where the part "
                "would hit an arm (too large to fit between them)")


def plan_params_for_cell(cell: BimanualCellParams, *, ik_restarts: int = 2, **changes) -> SetupPlanParams:
    """Setup-planner parameters for the cell: the paper's planner (DFBnB, whose nodes Table VII
    counts; :meth:`SetupPlanParams.paper`), the cell's setup space and sampling, the cleaning
    arm's pad as the reach test's tool, ``ik_restarts`` DLS restarts (ours: 2 gave the same bowl
    plan as 12 in a quarter of the time)."""
    return SetupPlanParams.paper(space=cell.space, sampling=cell.sampling,
                                 reach=ReachParams(tool_length=cell.tool_length, ik_restarts=ik_restarts), **changes)


def plan_cell_setups(part: Part, cleaner, holder, cell: BimanualCellParams, plan_params: SetupPlanParams) -> SetupPlan:
    """Kabir's setup planner for the cleaning arm, dropping setups the holding arm cannot present."""
    return plan_setups(part, robot=cleaner, params=plan_params, feasible=HeldSetups(cleaner, holder, part.mesh, cell))


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

"""Setups a holding arm can present (Kabir et al. Sec. IX-C, the two-arm cell).

In the paper's cell one iiwa holds the part and changes setups, the other cleans. A setup
``(x, y, alpha)`` then exists only where the holding arm reaches the part pose with its
flange (full-pose IK through the fixed grasp) and the part, held there, leaves room for both
arms. :class:`HeldSetups` is that test as the ``feasible`` argument of
:func:`mavac.setups.plan.plan_setups`: the planner drops every other candidate and says how
many and why.
"""

from __future__ import annotations

import numpy as np

from ..geometry.mesh import check_mesh
from ..params import BimanualCellParams
from ..sim.cell import holder_ik, part_clear_of_arms
from ..validate import check_instance, check_points
from .reach import base_T_part


class HeldSetups:
    """``feasible(setups (k, 3)) -> (k,) bool`` for a part held by the cell's holding arm.

    Parameters
    ----------
    cleaner, holder : RobotModel
        From :func:`mavac.sim.cell.cell_robots`.
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
            clear = part_clear_of_arms(self.cleaner, self.holder, self.part_mesh, T, q[ok], self.params)
            self.collides += int((~clear).sum())
            ok[np.flatnonzero(ok)[~clear]] = False
        return ok

    def summary(self) -> str:
        """What was refused and why, for the plan's warnings."""
        return (f"{self.unreachable} the holding arm cannot reach, {self.collides} where the part "
                "would hit an arm (too large to fit between them)")

"""Where the two-arm cell's setup square lies: Kabir et al.'s narrowing (Sec. IV-A), run with
the cell's two arms.

"Our sampling starts with a coarse resolution over a wide range of configuration space
parameters. We find a narrower feasible sampling range by eliminating setups that do not cover
any patch." The paper does not dimension its cell (Sec. IX-C), so the square is found the way
the package finds the Puma's (:mod:`mavac.setups.space`):

1. the wide region on the cleaning arm's side: every part placement from which its pad could
   reach a stain vertex (:func:`mavac.setups.space.wide_setup_space`), at the table height and
   fine resolution of ``cell.space``;
2. a coarse sweep of it for every part: a setup survives when the holding arm can present the
   part there (:class:`mavac.scrubbing.holding.HeldSetups`) and the cleaning arm's reach test
   reaches at least one of its patches (:func:`setups_reaching_a_patch`);
3. the square of ``cell.space``'s size keeping the largest share of the survivors, summed over
   the parts (:func:`mavac.setups.space.narrowed_square`).

Nothing here looks at how many setups a plan then needs.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from ..params import BimanualCellParams, SetupSpaceParams, ToolpathParams
from ..setups.reach import patch_reach, reach_targets
from ..setups.sampling import uniform_setups
from ..setups.space import WIDE_RESOLUTION, box_summary, narrowed_square, wide_setup_space
from ..validate import check_instance, check_int
from .cell import cell_robots
from .holding import HeldSetups, plan_params_for_cell

#: Patches tested together by :func:`setups_reaching_a_patch` (ours: a setup that reaches the
#: stain at all usually reaches some of the first few hundred of an evenly spread order).
PATCH_CHUNK = 200


def setups_reaching_a_patch(robot, part, setups, space: SetupSpaceParams, params, *,
                            chunk: int = PATCH_CHUNK) -> np.ndarray:
    """Which setups reach at least one patch (``patch_reach(...).any(axis=1)``), found with less
    work: the patches are tested ``chunk`` at a time in an order spread over the whole stain,
    and a setup leaves the test at the first chunk it reaches. The IK's restarts are drawn per
    batch, so at the margin of reach a setup may differ from one full call (1 of the bowl's
    1,322 presentable setups did in our run).

    Parameters
    ----------
    robot : RobotModel
        The cleaning arm (with its tool).
    part : Part
    setups : (k, 3) float
        ``(x [m], y [m], alpha [rad])`` in ``space``.
    space : SetupSpaceParams
    params : ReachParams
    chunk : int, >= 1

    Returns
    -------
    (k,) bool
        Setup j reaches at least one patch.
    """
    chunk = check_int("chunk", chunk, 1)
    n = len(part.patch_vertices)
    hit = np.zeros(len(setups), dtype=bool)
    stride = max(1, -(-n // chunk))  # chunk c holds patches c, c + stride, c + 2 stride, ...
    for c in range(stride):
        todo = np.flatnonzero(~hit)
        if len(todo) == 0:
            break
        rows = np.arange(c, n, stride)
        targets = reach_targets(part.patch_vertices[rows], part.patch_normals[rows])
        hit[todo] = patch_reach(robot, targets, setups[todo], space, params=params).any(axis=1)
    return hit


def narrowed_cell_space(parts, cell: BimanualCellParams, toolpath: ToolpathParams, *,
                        wide_resolution=WIDE_RESOLUTION) -> tuple[SetupSpaceParams, pd.DataFrame]:
    """The cell's setup square for ``parts`` by the narrowing (see the module docstring).

    Parameters
    ----------
    parts : dict name -> Part
        The parts the square must serve (their stains, part frame, metres).
    cell : BimanualCellParams
        Its ``space`` gives the square's size, table height, fine resolution and alpha range;
        its origin is what this finds.
    toolpath : ToolpathParams
        The pad (the cleaning arm's tool).
    wide_resolution : (3,) float
        Coarse ``(m, m, rad)`` of the wide sweep.

    Returns
    -------
    space : SetupSpaceParams
        ``cell.space`` moved to the square found.
    info : DataFrame
        One row per part: ``wide_setups``, ``held`` (the holding arm presents the part),
        ``reaching`` (and the cleaning arm reaches a patch), ``reaching_in_square`` and its
        ``share``, the square's corners ``x_lo, x_hi, y_lo, y_hi`` (cleaning arm base frame, m).
    """
    check_instance("cell", cell, BimanualCellParams)
    check_instance("toolpath", toolpath, ToolpathParams)
    if not parts:
        raise ValueError("parts must name at least one part")
    cleaner, holder = cell_robots(cell, toolpath)
    every = np.concatenate([p.patch_vertices.reshape(-1, 3) for p in parts.values()])
    wide = wide_setup_space(cleaner, every, base=cell.space, resolution=wide_resolution)
    wide_cell = dataclasses.replace(cell, space=wide)
    reach_params = plan_params_for_cell(cell).reach
    setups = uniform_setups(wide)
    reaching, rows = {}, []
    for name, part in parts.items():
        held = HeldSetups(cleaner, holder, part.mesh, wide_cell)(setups)
        hit = held.copy()
        hit[held] = setups_reaching_a_patch(cleaner, part, setups[held], wide, reach_params)
        reaching[name] = setups[hit, :2] + [wide.origin_x, wide.origin_y]
        rows.append(dict(part=name, wide_setups=len(setups), held=int(held.sum()), reaching=int(hit.sum())))
    size = cell.space.x_max - cell.space.x_min
    space, _ = narrowed_square(wide, reaching, size=size, fine=cell.space)
    box = box_summary(space)
    for row in rows:
        xy = reaching[row["part"]]
        inside = ((xy[:, 0] >= box["x_lo"] - 1e-9) & (xy[:, 0] <= box["x_hi"] + 1e-9)
                  & (xy[:, 1] >= box["y_lo"] - 1e-9) & (xy[:, 1] <= box["y_hi"] + 1e-9))
        row.update(reaching_in_square=int(inside.sum()), share=float(inside.mean()) if len(xy) else 0.0,
                   **{k: box[k] for k in ("x_lo", "x_hi", "y_lo", "y_hi")})
    return space, pd.DataFrame(rows)

"""The cell's setup square by the paper's narrowing (mavac.scrubbing.cell_space)."""

import dataclasses
import math

import numpy as np
import pytest

from mavac.geometry.parts import load_part
from mavac.params import BimanualCellParams, ToolpathParams
from mavac.scrubbing import cell_space as S
from mavac.scrubbing.cell import cell_robots
from mavac.scrubbing.coupon import coupon_part
from mavac.scrubbing.holding import plan_params_for_cell
from mavac.setups.reach import patch_reach, reach_targets_from_part
from mavac.setups.sampling import uniform_setups
from mavac.setups.space import wide_setup_space

CELL = BimanualCellParams()
COARSE = (0.2, 0.2, math.radians(90.0))


def test_setups_reaching_a_patch_is_the_full_reach_tests_any():
    """Chunked with early exit against the brute-force cover, on setups near and far."""
    cleaner, _ = cell_robots(CELL, ToolpathParams())
    part = load_part("bowl")
    rows = np.random.default_rng(0).choice(len(part.stain_faces), 60, replace=False)
    part = dataclasses.replace(part, stain_faces=part.stain_faces[rows], passes=part.passes[rows],
                               intensity=part.intensity[rows])
    wide = wide_setup_space(cleaner, part.patch_vertices, base=CELL.space, resolution=(0.15, 0.15, math.pi / 2))
    setups = uniform_setups(wide)
    params = plan_params_for_cell(CELL).reach
    brute = patch_reach(cleaner, reach_targets_from_part(part), setups, wide, params=params).any(axis=1)
    assert 0 < brute.sum() < len(setups)  # some setups reach the stain, some do not
    assert np.array_equal(S.setups_reaching_a_patch(cleaner, part, setups, wide, params, chunk=7), brute)


def test_the_square_keeps_the_cells_size_and_holds_setups_that_present_and_reach_the_part():
    parts = {"coupon": coupon_part()}
    space, info = S.narrowed_cell_space(parts, CELL, ToolpathParams(), wide_resolution=COARSE)
    row = info.iloc[0]
    assert row.wide_setups > row.held >= row.reaching > 0
    assert 0 < row.reaching_in_square <= row.reaching
    # the square has the cell's size, table height and fine grid; only its corner moved
    assert (space.x_max, space.y_max, space.table_z, space.res_x) == (CELL.space.x_max, CELL.space.y_max,
                                                                       CELL.space.table_z, CELL.space.res_x)
    assert (row.x_lo, row.y_lo) == (space.origin_x, space.origin_y)


def test_a_holding_arm_that_presents_nothing_leaves_no_square(monkeypatch):
    monkeypatch.setattr(S.HeldSetups, "__call__", lambda self, setups: np.zeros(len(setups), dtype=bool))
    with pytest.raises(ValueError, match="no setup of the wide sweep reaches any patch"):
        S.narrowed_cell_space({"coupon": coupon_part()}, CELL, ToolpathParams(), wide_resolution=COARSE)


def test_bad_inputs_name_the_parameter():
    with pytest.raises(ValueError, match="parts"):
        S.narrowed_cell_space({}, CELL, ToolpathParams())
    with pytest.raises(TypeError, match="cell"):
        S.narrowed_cell_space({"coupon": coupon_part()}, ToolpathParams(), ToolpathParams())
    with pytest.raises(ValueError, match="chunk"):
        S.setups_reaching_a_patch(None, coupon_part(), np.zeros((1, 3)), CELL.space, None, chunk=0)

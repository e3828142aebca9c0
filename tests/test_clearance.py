"""The cleaning arm's tool clearance (mavac.scrubbing.clearance)."""

import numpy as np
import pytest
import trimesh

from mavac.params import BimanualCellParams, ToolpathParams
from mavac.scrubbing.cell import cell_robots
from mavac.scrubbing.clearance import ToolClearance

DOWN = np.array([0.0, 0.0, -1.0])


@pytest.fixture(scope="module")
def cleaner():
    return cell_robots(BimanualCellParams(), ToolpathParams())[0]


def _step():
    """A 30 x 30 cm plate with its top at z = 0.35 m, 0.6 m in front of the arm, and a 5 cm wall
    rising from it at x = 0.65 m (an inside corner)."""
    plate = trimesh.creation.box((0.3, 0.3, 0.1))
    plate.apply_translation((0.6, 0.0, 0.3))
    wall = trimesh.creation.box((0.05, 0.3, 0.05))
    wall.apply_translation((0.675, 0.0, 0.375))
    return trimesh.util.concatenate([plate, wall])


def test_the_pad_on_open_ground_is_kept_and_only_the_holder_sinking_in_is_refused(cleaner):
    clear = ToolClearance(cleaner, _step(), sweep=0.0)
    on = np.array([0.55, 0.0, 0.35])
    assert clear(on[None], DOWN[None]).tolist() == [True]
    # the holder's rim is 10 mm above the pad face: 5 mm into the part it is still clear, 15 mm not
    assert not clear.holder_hits(on - [0, 0, 0.005], DOWN) and clear.holder_hits(on - [0, 0, 0.015], DOWN)


def test_an_inside_corner_refuses_the_holder_before_the_pad_and_the_swing_widens_it(cleaner):
    step = _step()
    # the pad (15 mm radius) fits 17 mm from the wall, its 20 mm holder does not; at 30 mm both fit
    near, far = np.array([[0.633, 0.0, 0.35], [0.62, 0.0, 0.35]])
    axes = np.array([DOWN, DOWN])
    assert ToolClearance(cleaner, step, sweep=0.0)(np.array([near, far]), axes).tolist() == [False, True]
    # swung 15 mm off its path, the holder reaches the wall from 30 mm too
    assert ToolClearance(cleaner, step, sweep=0.015)(far[None], DOWN[None]).tolist() == [False]


def test_a_waypoint_out_of_reach_is_refused(cleaner):
    clear = ToolClearance(cleaner, _step(), sweep=0.0)
    assert clear(np.array([[2.5, 0.0, 0.35]]), DOWN[None]).tolist() == [False]
    assert clear(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)


def test_bad_inputs_name_the_parameter(cleaner):
    with pytest.raises(ValueError, match="sweep"):
        ToolClearance(cleaner, _step(), sweep=-0.01)
    clear = ToolClearance(cleaner, _step(), sweep=0.0)
    with pytest.raises(ValueError, match="axes must have one row per position"):
        clear(np.zeros((2, 3)), DOWN[None])

"""The two-arm cell's replay page: the stain shells that fade as passes remove the stain."""

import numpy as np
import pytest
import trimesh

from mavac.scrubbing.replay import SHELL_STEP, STAIN_LEVELS, stain_shells


def _three_triangles() -> trimesh.Trimesh:
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [3, 0, 0], [2, 1, 0], [4, 0, 0], [5, 0, 0], [4, 1, 0]])
    return trimesh.Trimesh(v * 0.01, np.arange(9).reshape(3, 3), process=False)


def test_each_face_leaves_each_shell_at_the_end_of_the_pass_that_took_it_below_the_level():
    assert [level for level, _ in STAIN_LEVELS] == pytest.approx([0.02, 1 / 3, 2 / 3])
    initial = np.array([0.9, 0.5, 0.0])
    states = [np.array([0.5, 0.5, 0.0]), np.array([0.1, 0.2, 0.0]), np.array([0.0, 0.2, 0.0])]
    shells = stain_shells(_three_triangles(), initial, states, [10, 20, 30])
    got = {(level, int(len(mesh.faces)), frame) for level, mesh, _, frame in shells}
    # level 0.02: face 0 goes after pass 3, face 1 never; level 1/3: both after pass 2; 2/3: face 0 after pass 1
    assert got == {(0, 1, 30), (0, 1, 0), (1, 2, 20), (2, 1, 10)}


def test_shells_lie_along_the_normals_one_step_per_level():
    mesh = _three_triangles()
    shells = stain_shells(mesh, np.array([1.0, 0.0, 0.0]), [], [])
    assert [frame for *_, frame in shells] == [0, 0, 0]  # no pass: nothing fades
    for level, shell, color, _ in shells:
        assert np.allclose(shell.vertices, mesh.triangles[0] + [0, 0, SHELL_STEP * (level + 1)])
        assert color == STAIN_LEVELS[level][1]

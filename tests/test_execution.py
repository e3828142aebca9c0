"""Kabir's execution pipeline: per-setup tool paths and one scrubbing pass seen by the camera."""

import numpy as np
import pytest
import trimesh

from mavac.geometry.parts import part_from_mesh
from mavac.robots.models import puma560
from mavac.params import LissajousParams, ScrubModel, SetupSpaceParams, ToolpathParams
from mavac.scrubbing import execution as E
from mavac.scrubbing.toolpath import toolpath_for_setup
from mavac.setups.reach import base_T_part


@pytest.fixture(scope="module")
def part():
    """A 20 cm square bump stained at its top: the crest needs three passes, the flanks one."""
    n, size = 16, 0.2
    xs = np.linspace(-size / 2, size / 2, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    Z = 0.05 * np.exp(-(X**2 + Y**2) / 0.004)
    m = n + 1
    a = (np.arange(n)[:, None] * m + np.arange(n)[None, :]).ravel()
    F = np.vstack([np.column_stack([a, a + m, a + m + 1]), np.column_stack([a, a + m + 1, a + 1])])
    mesh = trimesh.Trimesh(np.column_stack([X.ravel(), Y.ravel(), Z.ravel()]), F, process=False)
    z = mesh.triangles_center[:, 2]
    faces = np.flatnonzero(z > 0.01)
    passes = np.where(z[faces] > 0.03, 3, 1)
    # thin stain on the flanks (one pass of the Fig. 3 parameters removes ~0.07 layer), thick at the crest
    return part_from_mesh(mesh, faces, passes, name="bump", intensity=np.where(passes == 3, 1.0, 0.05))


def test_toolpaths_for_plan_is_one_toolpath_per_setup(part):
    setups = np.array([[0.1, 0.5, 0.0], [0.2, 0.4, 1.0]])
    patches = [np.arange(0, len(part.stain_faces), 2), np.arange(1, len(part.stain_faces), 2)]
    space, params = SetupSpaceParams(), ToolpathParams()
    robot = puma560(tool_length=0.1)
    paths = E.toolpaths_for_plan(part, setups, patches, robot, params=params, space=space)
    assert len(paths) == 2
    for tp, T, p in zip(paths, base_T_part(setups, space), patches):
        np.testing.assert_array_equal(tp.world_T_part, T)
        assert len(tp.passes) == part.passes[p].max()
        alone = toolpath_for_setup(part, T, p, params)  # without IK: never shorter
        assert alone.path_length_m >= tp.path_length_m - 1e-12


def test_cover_from_patches():
    cover = E.cover_from_patches([[0, 2], [], [1]], 4)
    assert cover.tolist() == [[True, False, True, False], [False] * 4, [False, True, False, False]]


def test_perceive_scrub_pass_is_consistent_and_deterministic(part):
    a = E.perceive_scrub_pass(part, np.random.default_rng(3), image_size=(48, 48), n_clusters=4)
    b = E.perceive_scrub_pass(part, np.random.default_rng(3), image_size=(48, 48), n_clusters=4)
    assert np.array_equal(a.before, b.before) and a.cleaning_performance == b.cleaning_performance
    assert a.before.shape == a.after.shape == (48, 48, 3)
    # C_p is the drop of stain pixels over the stained region
    region = a.region.sum()
    expected = (a.mask_before[a.region].sum() - a.mask_after[a.region].sum()) / region
    assert a.cleaning_performance == pytest.approx(expected)
    assert 0.0 < a.cleaning_performance <= 1.0
    # the stained region is where the part needs passes; off the part everything is -1
    assert np.array_equal(a.region, a.passes_true > 0)
    assert np.all((a.passes_estimated == -1) == (a.passes_true == -1))
    # a pass with no normal force removes nothing: nothing cleaned
    idle = E.perceive_scrub_pass(part, np.random.default_rng(3), image_size=(48, 48),
                                 lissajous=LissajousParams(f_n=0.0))
    assert idle.cleaning_performance == pytest.approx(0.0, abs=0.02)


def test_scrub_experiment_holds_the_parts_stain(part):
    ex = E.scrub_experiment(part, np.random.default_rng(0), model=ScrubModel())
    assert np.count_nonzero(ex.face_stain) == len(part.stain_faces)
    np.testing.assert_allclose(ex.face_stain[part.stain_faces], part.intensity)
    assert ex.hardness.shape == (len(part.mesh.faces),) and np.all(ex.hardness > 0)

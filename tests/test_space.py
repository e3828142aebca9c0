"""Setup space by the paper's procedure (Kabir Sec. IV-A): wide coarse sweep, drop the setups that
reach nothing, box the rest; and the support plane of the reach test (issue 14)."""

import dataclasses
import math
import warnings

import numpy as np
import pytest
import trimesh

from mavac.geometry.parts import load_part, part_from_mesh
from mavac.params import ReachParams, SetupPlanParams, SetupSpaceParams
from mavac.robots.models import puma560
from mavac.setups.reach import PartReach, below_support, reach_bound, reach_targets, reach_targets_from_part
from mavac.setups.sampling import uniform_setups
from mavac.setups.setup_plan import plan_setups
from mavac.setups.space import part_radius, reaching_box, wide_setup_space

ROBOT = puma560(tool_length=0.10)


def test_wide_space_is_wide_enough_to_contain_every_reaching_setup():
    part = load_part("schwefel")
    wide = wide_setup_space(ROBOT, part.patch_vertices, resolution=(0.1, 0.1, math.radians(30)))
    b = reach_bound(ROBOT)
    r = part_radius(part.patch_vertices) + b.radius + b.tool_offset
    assert wide.origin_x == 0.0 and wide.x_max >= r and wide.origin_y <= -r and wide.origin_y + wide.y_max >= r
    # a ring of placements just outside the wide region reaches nothing
    far = np.array([[wide.x_max + 0.05, y, a] for y in np.linspace(0, wide.y_max, 7) for a in (0.0, 2.0)])
    assert not PartReach(ROBOT, reach_targets_from_part(part), wide)(far).any()


def test_reaching_box_is_the_bounding_box_of_the_setups_that_reach_something():
    wide = SetupSpaceParams(x_max=2.0, y_max=2.0, origin_x=0.0, origin_y=-1.0, res_x=0.5, res_y=0.5)
    setups = uniform_setups(wide, (0.5, 0.5, math.pi))
    cover = np.zeros((len(setups), 3), bool)
    hit = (np.isclose(setups[:, 0], 0.5) & np.isclose(setups[:, 1], 1.5)) | \
          (np.isclose(setups[:, 0], 1.5) & np.isclose(setups[:, 1], 0.5))
    cover[hit, 1] = True
    box = reaching_box(setups, cover, wide)
    assert (box.origin_x, box.x_max, box.origin_y, box.y_max) == (0.5, 1.0, -0.5, 1.0)
    assert box.x_min == 0.0 and box.y_min == 0.0 and box.res_x == SetupSpaceParams().res_x
    with pytest.raises(ValueError, match="cover"):
        reaching_box(setups, np.zeros_like(cover), wide)


def test_no_space_parameter_was_chosen_for_the_number_of_setups():
    import inspect

    from mavac import params

    text = inspect.getsource(params.SetupSpaceParams)
    assert "reaches most" not in text and "Lower tables" not in text


def test_synthetic_stain_is_one_contiguous_region_and_blobs_are_an_option():
    for name in ("sine", "schwefel", "concave_bowl", "hyperboloid"):
        part = load_part(name)
        stained = set(part.stain_faces.tolist())
        edges = [e for e in part.mesh.face_adjacency if e[0] in stained and e[1] in stained]
        labels = trimesh.graph.connected_component_labels(np.array(edges), node_count=len(part.mesh.faces))
        assert len(set(labels[part.stain_faces])) == 1, name
    several = load_part("sine", stain_blobs=(3, 3))
    assert not np.array_equal(several.stain_faces, load_part("sine").stain_faces)
    with pytest.raises(ValueError, match="stain_blobs"):
        load_part("bowl", stain_blobs=(1, 1))


def _plate(face_down: bool):
    box = trimesh.creation.box(extents=[0.3, 0.2, 0.02])
    box.apply_translation([0, 0, 0.01])  # resting on the table (part frame z = 0)
    sign = -1 if face_down else 1
    faces = np.flatnonzero(box.face_normals[:, 2] * sign > 0.9)
    return part_from_mesh(box, faces, np.ones(len(faces), int), name="plate")


def test_tool_from_below_the_table_is_refused():
    down, up = _plate(True), _plate(False)
    t_down = reach_targets(down.patch_vertices, down.patch_normals)
    assert below_support(t_down, 0.10).all()
    assert not below_support(reach_targets(up.patch_vertices, up.patch_normals), 0.10).any()
    # a table well above the shoulder: the arm could point the tool up at the plate's bottom
    space = dataclasses.replace(SetupSpaceParams(), res_x=0.1, res_y=0.1, res_alpha=math.radians(90),
                                table_z=0.4)
    setups = uniform_setups(space)
    assert not PartReach(ROBOT, t_down, space)(setups).any()
    # without the support plane the IK alone would accept it: the table is what refuses it
    off = PartReach(ROBOT, t_down, space, params=ReachParams(support_plane=False))(setups)
    assert off.any()


@pytest.mark.parametrize("collision", [False, True])
def test_stain_facing_the_table_gets_no_plan_and_the_plan_says_why(collision):
    params = dataclasses.replace(SetupPlanParams(), reach=ReachParams(check_collision=collision))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_setups(_plate(True), params=params)
    assert plan.status == "no_solution" and len(plan.setups) == 0
    assert set(plan.uncoverable_causes) == {"below_support"}
    assert any("table" in w for w in plan.warnings)

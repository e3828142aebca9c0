"""Setup space by the paper's procedure (Kabir Sec. IV-A): wide coarse sweep, drop the setups that
reach nothing, one 1 m square for all objects; no placement on the robot's pedestal; the
collision option of the reach test on a deep cavity; the support plane of the reach test."""

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
from mavac.setups.space import (PedestalClear, axis_distance, footprint, narrowed_square, part_radius, pedestal_radius,
                                 wide_setup_space)

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


def test_narrowed_square_keeps_the_largest_share_of_every_objects_reaching_setups():
    wide = SetupSpaceParams(x_max=2.0, y_max=2.0, origin_x=0.0, origin_y=-1.0, res_x=0.5, res_y=0.5)
    # object a reaches around (1.5, 0.4), object b at (1.5, -0.4) and far at (0, -1)
    a = np.array([[1.5, 0.4], [1.5, 0.4], [1.6, 0.3]])
    b = np.array([[1.5, -0.4], [0.0, -1.0]])
    space, scores = narrowed_square(wide, {"a": a, "b": b}, size=1.0, step=0.5)
    assert (space.origin_x, space.origin_y, space.x_max, space.y_max) == (1.0, -0.5, 1.0, 1.0)
    assert space.res_x == SetupSpaceParams().res_x and space.x_min == 0.0
    best = scores[np.lexsort((scores[:, 1], scores[:, 0]))]
    assert np.isclose(scores[:, 2].max(), 1.0 + 0.5)  # all of a, half of b
    assert len(best) == 9  # corners 0, 0.5, 1 m on each axis of the 2 m region
    with pytest.raises(ValueError, match="reaching"):
        narrowed_square(wide, {"a": np.zeros((0, 2))})
    with pytest.raises(ValueError, match="size"):
        narrowed_square(wide, {"a": a}, size=3.0)


def test_footprint_distance_to_the_robot_axis():
    square = trimesh.creation.box(extents=[0.4, 0.2, 0.1])
    hull = footprint(square.vertices)
    space = dataclasses.replace(SetupSpaceParams(), origin_x=0.0, origin_y=0.0)
    setups = np.array([[0.5, 0.0, 0.0], [0.5, 0.0, math.pi / 2], [0.05, 0.05, 0.3], [0.0, 0.5, 0.0]])
    d = axis_distance(hull, setups, space)
    assert np.allclose(d, [0.3, 0.4, 0.0, 0.4])
    assert pedestal_radius(ROBOT) == pytest.approx(0.10)


def test_no_placement_on_the_pedestal_reaches_anything():
    from mavac.experiments import kabir_setups as K

    part = load_part("concave_bowl")
    # a square reaching over the robot: many placements would stand on its pedestal
    space = SetupSpaceParams(x_max=2.0, y_max=2.0, origin_x=-1.0, origin_y=-1.0, res_x=0.25, res_y=0.25,
                             res_alpha=math.radians(90))
    b = K.baseline("concave_bowl", space, ReachParams(), n_jobs=1)
    clear = PedestalClear(part.mesh.vertices, space, pedestal_radius(ROBOT), space.pedestal_margin)
    on = ~clear(b.setups)
    assert on.sum() == b.removed > 0
    assert not b.cover[on].any()  # 0 placements inside the pedestal
    assert b.cover[~on].any() and K.table2({"bowl": b}).n_rfc.iloc[0] == len(b.setups)
    # the off-grid reach function refuses them too
    inside = np.array([[1.0, 1.0, 0.0], [1.1, 0.9, 0.3]])
    assert not clear(inside).any() and not b.reach(ReachParams())(inside).any()


def test_paper_grid_has_15876_distinct_setups():
    from mavac.setups.sampling import uniform_setups

    assert len(uniform_setups(SetupSpaceParams())) == 21 * 21 * 36 == 15_876


def _vase():
    # a bottle: 16 cm body, 5 cm neck 6 cm long, walls 8 mm, floor 10 mm; stained inside floor
    profile = np.array([(0, 0), (0.08, 0), (0.08, 0.30), (0.03, 0.33), (0.03, 0.36), (0.022, 0.36),
                        (0.022, 0.33), (0.072, 0.30), (0.072, 0.01), (0, 0.01)])
    mesh = trimesh.creation.revolve(profile, sections=32)
    floor = np.flatnonzero(np.abs(mesh.triangles_center[:, 2] - 0.01) < 1e-6)
    return part_from_mesh(mesh, floor, np.ones(len(floor), int), name="vase")


@pytest.mark.parametrize("collision", [False, True])
def test_patches_only_a_colliding_arm_reaches_are_refused(collision):
    vase = _vase()
    space = dataclasses.replace(SetupSpaceParams(), res_x=0.25, res_y=0.25, res_alpha=math.radians(90))
    params = dataclasses.replace(SetupPlanParams(), space=space, sampling_method="uniform",
                                 reach=ReachParams(check_collision=collision))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_setups(vase, params=params)
    n = len(vase.stain_faces)
    if not collision:  # the IK alone reaches the floor through the 4.4 cm neck
        assert plan.found and len(plan.uncoverable) == 0 and plan.collision_refused == 0
    else:
        assert len(plan.uncoverable) == n and plan.collision_refused == n
        assert any("passing through the part" in w for w in plan.warnings)
        assert plan.to_dict()["collision_refused"] == n


def test_no_space_parameter_was_chosen_for_the_number_of_setups():
    import inspect

    from mavac import params

    text = inspect.getsource(params.SetupSpaceParams)
    assert "reaches most" not in text and "Lower tables" not in text


def test_synthetic_stain_is_spread_over_the_part_in_several_regions():
    for name in ("sine", "schwefel", "concave_bowl", "hyperboloid"):
        for seed in (0, 1):
            part = load_part(name, seed=seed)
            stained = set(part.stain_faces.tolist())
            edges = [e for e in part.mesh.face_adjacency if e[0] in stained and e[1] in stained]
            labels = trimesh.graph.connected_component_labels(np.array(edges), node_count=len(part.mesh.faces))
            assert len(set(labels[part.stain_faces])) >= 2, (name, seed)
            assert 4000 <= len(part.stain_faces) <= 5000
    assert not np.array_equal(load_part("sine", seed=1).stain_faces, load_part("sine").stain_faces)
    assert np.array_equal(load_part("sine", seed=3).stain_faces, load_part("sine", seed=3).stain_faces)
    one = load_part("sine", stain_blobs=(1, 1))
    assert not np.array_equal(one.stain_faces, load_part("sine").stain_faces)
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


def test_at_resolution_keeps_the_region_and_changes_the_grid():
    from mavac.params import SetupSpaceParams

    base = SetupSpaceParams()
    coarse = base.at_resolution((0.1, 0.2, 0.5))
    assert (coarse.res_x, coarse.res_y, coarse.res_alpha) == (0.1, 0.2, 0.5)
    assert (coarse.x_min, coarse.x_max, coarse.y_min, coarse.y_max) == (base.x_min, base.x_max, base.y_min, base.y_max)
    with pytest.raises(ValueError, match="res_x"):
        base.at_resolution((0.0, 0.1, 0.1))

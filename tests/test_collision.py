import coal
import numpy as np
import pinocchio as pin
import pytest
import trimesh

from mavac.robots import kinematics as K
from mavac.robots.collision import CollisionChecker, pair_cost_key
from mavac.robots.models import iiwa7, puma560, se2_to_matrix, ur10_mobile


@pytest.fixture(scope="module")
def ur10():
    return ur10_mobile()


@pytest.fixture(scope="module")
def box_at_tool(ur10):
    """A 0.3 m box centred on the tool tip at the home configuration (base at the origin)."""
    tip = K.fk(ur10, ur10.q_home)[:3, 3]
    box = trimesh.creation.box((0.3, 0.3, 0.3))
    box.apply_translation(tip)
    return box


def test_home_is_free_without_obstacle(ur10):
    checker = CollisionChecker(ur10)
    assert checker.in_collision(ur10.q_home) is False
    assert CollisionChecker(puma560(0.2)).in_collision(puma560(0.2).q_home) is False


def test_tool_into_box_collides_and_moving_base_away_frees_it(ur10, box_at_tool):
    checker = CollisionChecker(ur10, box_at_tool)
    assert checker.in_collision(ur10.q_home)
    names = {n for pair in checker.colliding_pairs(ur10.q_home) for n in pair}
    assert "obstacle" in names and names & {"tool_tube", "tool_sphere", "camera_body"}
    checker.set_base(se2_to_matrix(-5.0, 0.0, 0.0))
    assert not checker.in_collision(ur10.q_home)
    far = CollisionChecker(ur10, box_at_tool, world_T_base=se2_to_matrix(0.0, 10.0, 1.0))
    assert not far.in_collision(ur10.q_home)


def test_margin_reports_near_misses(ur10):
    tip = K.fk(ur10, ur10.q_home)[:3, 3]
    box = trimesh.creation.box((0.2, 0.2, 0.2))
    box.apply_translation(tip + [0.0, 0.3, 0.0])  # beside the tool tip, ~0.15 m clear
    clear = CollisionChecker(ur10, box)
    padded = CollisionChecker(ur10, box, margin=0.5)
    assert not clear.in_collision(ur10.q_home)
    assert padded.in_collision(ur10.q_home)


def test_base_box_against_obstacle(ur10):
    """An obstacle overlapping the mobile base blocks every configuration."""
    box = trimesh.creation.box((0.4, 0.4, 0.2))
    box.apply_translation([0.3, 0.0, 0.1])
    checker = CollisionChecker(ur10, box)
    assert checker.in_collision(np.vstack([ur10.q_home, np.zeros(6)])).all()


def test_folded_arm_self_collides(ur10):
    checker = CollisionChecker(ur10)
    folded = np.array([0.0, -1.46, 2.9, 0.0, 0.0, 0.0])  # elbow folded onto the upper arm
    assert checker.in_collision(folded)
    pairs = checker.colliding_pairs(folded)
    assert any("upper_arm_link_0" in p for p in pairs)
    into_base = ur10.q_home.copy()
    into_base[1] = 0.4  # shoulder swung back and down: upper arm into the platform
    assert ("upper_arm_link_0", "mir200_base") in checker.colliding_pairs(into_base)


def test_floor(ur10):
    down = ur10.q_home.copy()
    down[1:3] = [-0.34, 1.0]  # arm lowered in front of the platform: the tool tip goes below z = 0
    assert K.fk(ur10, down)[2, 3] < -0.1
    assert not CollisionChecker(ur10).in_collision(down)
    assert CollisionChecker(ur10, floor=True).in_collision(down)
    assert not CollisionChecker(ur10, floor=True).in_collision(ur10.q_home)


def test_batched_matches_single(ur10, box_at_tool):
    checker = CollisionChecker(ur10, box_at_tool)
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (30, 6))
    batched = checker.in_collision(q)
    assert batched.shape == (30,) and batched.dtype == bool
    assert 0 < batched.sum() < 30
    assert [checker.in_collision(qi) for qi in q] == batched.tolist()
    assert [checker.is_free(qi) for qi in q] == (~batched).tolist()


def test_adjacent_links_are_not_paired(ur10):
    checker = CollisionChecker(ur10)
    gm, model = checker.geometry_model, ur10.model
    for cp in gm.collisionPairs:
        ja, jb = gm.geometryObjects[cp.first].parentJoint, gm.geometryObjects[cp.second].parentJoint
        assert ja != jb and model.parents[ja] != jb and model.parents[jb] != ja


def test_bad_inputs(ur10):
    with pytest.raises(ValueError, match="obstacle"):
        CollisionChecker(ur10, obstacle="box.stl")
    with pytest.raises(ValueError, match="margin"):
        CollisionChecker(ur10, margin=-0.1)
    with pytest.raises(ValueError, match="world_T_base"):
        CollisionChecker(ur10, world_T_base=np.ones((4, 4)))
    checker = CollisionChecker(ur10)
    with pytest.raises(ValueError, match="q"):
        checker.in_collision(np.zeros(3))
    with pytest.raises(ValueError, match="q contains NaN"):
        checker.in_collision(np.full(6, np.nan))


def test_ignored_pairs_are_not_tested_and_the_margin_survives(ur10, box_at_tool):
    folded = np.array([0.0, -1.46, 2.9, 0.0, 0.0, 0.0])
    checker = CollisionChecker(ur10, box_at_tool, margin=0.01)
    pairs = [p for p in checker.colliding_pairs(folded) if "obstacle" not in p]
    n = checker.n_pairs
    checker.ignore_pairs(pairs)
    assert checker.n_pairs == n - len(pairs)
    assert not any(p in checker.colliding_pairs(folded) for p in pairs)
    checker.ignore_pairs(pairs)  # already ignored: nothing to do
    assert checker.n_pairs == n - len(pairs)
    # robot-vs-obstacle pairs keep their margin after the rebuild
    tip = K.fk(ur10, ur10.q_home)[:3, 3]
    box = trimesh.creation.box((0.2, 0.2, 0.2))
    box.apply_translation(tip + [0.0, 0.3, 0.0])
    padded = CollisionChecker(ur10, box, margin=0.5)
    padded.ignore_pairs([("upper_arm_link_0", "mir200_base")])
    assert padded.in_collision(ur10.q_home)
    with pytest.raises(ValueError, match="pairs"):
        checker.ignore_pairs([("upper_arm_link_0", "no_such_link")])


def _all_pairs_reference(checker, q, obstacle) -> bool:
    """Every pair of the checker tested in one pinocchio call, none cached or skipped, on the
    meshes as pinocchio loads them (OBBRSS hierarchies) and an OBBRSS obstacle."""
    gm = checker.geometry_model.copy()
    for g, original in zip(gm.geometryObjects, checker.robot.collision_model.geometryObjects):
        g.geometry = original.geometry
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(len(obstacle.faces), len(obstacle.vertices))
    bvh.addVertices(np.asarray(obstacle.vertices, dtype=float))
    bvh.addTriangles(np.asarray(obstacle.faces, dtype=np.int64))
    bvh.endModel()
    gm.geometryObjects[gm.getGeometryId("obstacle")].geometry = bvh
    gdata = pin.GeometryData(gm)
    for k in range(len(gm.collisionPairs)):
        gdata.collisionRequests[k].security_margin = checker._gdata.collisionRequests[k].security_margin
    return pin.computeCollisions(checker.robot.model, checker.robot.model.createData(), gm, gdata, q, False)


@pytest.mark.parametrize("name, margin", [("ur10", 0.01), ("iiwa7", 0.0)])
def test_ordered_and_cached_pairs_answer_like_all_pairs(ur10, name, margin):
    """Base-fixed pairs cached per base pose, the cheapest-first order and the OBB hierarchies
    change no answer (the UR10 on its platform with a margin; the Kabir cell's iiwa without)."""
    robot = ur10 if name == "ur10" else iiwa7(0.1)
    tip = K.fk(robot, robot.q_home)[:3, 3]
    box = trimesh.creation.box((0.5, 0.5, 0.5))
    box.apply_translation(tip + [0.2, 0.0, -0.3])
    checker = CollisionChecker(robot, box, margin=margin, floor=True)
    qs = np.random.default_rng(1).uniform(robot.q_lower, robot.q_upper, (200, robot.nq))
    n_hits = []
    for world_T_base in (np.eye(4), se2_to_matrix(0.6, 0.0, 0.0), se2_to_matrix(-4.0, 1.0, 0.5)):
        checker.set_base(world_T_base)
        ref = np.array([_all_pairs_reference(checker, q, box) for q in qs])
        n_hits.append(int(ref.sum()))
        assert checker.in_collision(qs).tolist() == ref.tolist()
        assert [not checker.is_free(q) for q in qs] == ref.tolist()
    assert 0 < n_hits[0] < len(qs) and 0 < n_hits[2] < len(qs)
    if name == "ur10":
        assert n_hits[1] == len(qs)  # the platform against the box: a cached base-fixed pair


def test_base_fixed_pair_cache_follows_set_base_and_ignore_pairs(ur10):
    box = trimesh.creation.box((0.4, 0.4, 0.2))
    box.apply_translation([0.3, 0.0, 0.1])  # overlaps the platform at the origin
    checker = CollisionChecker(ur10, box)
    assert checker.in_collision(ur10.q_home)
    assert ("mir200_base", "obstacle") in checker.colliding_pairs(ur10.q_home)
    checker.set_base(se2_to_matrix(-5.0, 0.0, 0.0))
    assert checker.is_free(ur10.q_home) and checker.colliding_pairs(ur10.q_home) == []
    checker.set_base(np.eye(4))
    assert not checker.is_free(ur10.q_home)
    checker.ignore_pairs([("mir200_base", "obstacle"), ("base_link_0", "obstacle")])
    assert checker.is_free(ur10.q_home)


def test_pairs_are_tested_cheapest_first(ur10, box_at_tool):
    checker = CollisionChecker(ur10, box_at_tool, floor=True)
    objs = checker.geometry_model.geometryObjects
    keys = [pair_cost_key(objs[cp.first], objs[cp.second]) for cp in checker.geometry_model.collisionPairs]
    assert keys == sorted(keys)
    assert keys[0][0] == 0 and keys[-1][0] == 2  # primitive pairs first, mesh against mesh last


def test_meshes_are_tested_as_obb_hierarchies_and_the_robot_is_untouched(ur10, box_at_tool):
    checker = CollisionChecker(ur10, box_at_tool)
    kinds = {type(g.geometry).__name__ for g in checker.geometry_model.geometryObjects}
    assert "BVHModelOBB" in kinds and "BVHModelOBBRSS" not in kinds
    assert any(isinstance(g.geometry, coal.BVHModelOBBRSS) for g in ur10.collision_model.geometryObjects)

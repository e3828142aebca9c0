"""Kabir reach test: batched closed-form vs per-point DLS, all-three-vertices rule, placement."""

import functools

import numpy as np
import pytest
import trimesh

from mavac.geometry.parts import load_part
from mavac.params import ReachParams, SetupSpaceParams
from mavac.robots.kinematics import fk, ik_axis
from mavac.robots.models import puma560
from mavac.setups import reach as R
from mavac.setups.sampling import uniform_setups

SPACE = SetupSpaceParams()
PARAMS = ReachParams()


@functools.lru_cache(maxsize=1)
def robot():
    return puma560(tool_length=PARAMS.tool_length)


@functools.lru_cache(maxsize=1)
def bowl_sample():
    """300 patches of the concave bowl's stain (every 16th)."""
    part = load_part("concave_bowl")
    return part.patch_vertices[::16], part.patch_normals[::16]


def vertex_reach(targets, setups, method):
    """Per-target reachability by a direct ik_axis call, (k, t) bool."""
    T = R.base_T_part(setups, SPACE)
    pos = np.einsum("kij,tj->kti", T[:, :3, :3], targets.positions) + T[:, None, :3, 3]
    ax = np.einsum("kij,tj->kti", T[:, :3, :3], targets.axes)
    kw = {"rng": np.random.default_rng(0)} if method == "dls" else {}
    ok = ik_axis(robot(), pos.reshape(-1, 3), ax.reshape(-1, 3), method=method, **kw).success
    return ok.reshape(len(setups), -1)


def test_base_T_part_places_the_setup_square_in_front_of_the_robot():
    T = R.base_T_part(np.array([[0.0, 0.0, 0.0], [1.0, 1.0, np.pi / 2]]), SPACE)
    np.testing.assert_allclose(T[0, :3, 3], [SPACE.origin_x, SPACE.origin_y, SPACE.table_z])
    np.testing.assert_allclose(T[1, :3, 3], [SPACE.origin_x + 1, SPACE.origin_y + 1, SPACE.table_z])
    np.testing.assert_allclose(T[1, :3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-12)


def test_targets_are_distinct_vertex_normal_pairs():
    # two coplanar triangles share an edge (4 targets); folding one gives 6
    flat = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, 0]]], float)
    up = np.array([[0, 0, 1.0], [0, 0, 1.0]])
    t = R.reach_targets(flat, up)
    assert t.n_targets == 4 and t.n_patches == 2
    np.testing.assert_allclose(t.axes, np.tile([0, 0, -1.0], (4, 1)))
    np.testing.assert_allclose(t.positions[t.patch_targets], flat)
    tilted = np.array([[0, 0, 1.0], [0, 0.6, 0.8]])
    assert R.reach_targets(flat, tilted).n_targets == 6
    with pytest.raises(ValueError, match="patch_vertices"):
        R.reach_targets(np.zeros((2, 3)), up)
    with pytest.raises(ValueError, match="patch_normals"):
        R.reach_targets(flat, np.zeros((2, 3)))


def test_reach_bound_contains_every_configuration():
    rb = R.reach_bound(robot())
    rng = np.random.default_rng(0)
    q = rng.uniform(robot().q_lower, robot().q_upper, (2000, 6))
    T = fk(robot(), q)
    d = T[:, :3, 3] - rb.tool_offset * T[:, :3, 2] - rb.centre
    assert np.all(np.linalg.norm(d, axis=1) <= rb.radius + 1e-9)


def test_patch_reachable_iff_all_three_vertices_reachable():
    v, n = bowl_sample()
    targets = R.reach_targets(v, n)
    rng = np.random.default_rng(1)
    grid = uniform_setups(SPACE)
    setups = grid[rng.choice(len(grid), 12, replace=False)]
    cover = R.patch_reach(robot(), targets, setups, SPACE, params=PARAMS)
    per_vertex = vertex_reach(targets, setups, "closed_form")
    np.testing.assert_array_equal(cover, per_vertex[:, targets.patch_targets].all(axis=2))
    # the sample must exercise both outcomes and partially reachable patches
    some = per_vertex[:, targets.patch_targets].any(axis=2)
    assert cover.any() and (~cover).any() and (some & ~cover).any()


def test_batched_reach_agrees_with_per_point_dls():
    v, n = bowl_sample()
    targets = R.reach_targets(v[::3], n[::3])
    rng = np.random.default_rng(2)
    grid = uniform_setups(SPACE)
    setups = grid[rng.choice(len(grid), 3, replace=False)]
    closed = vertex_reach(targets, setups, "closed_form")
    dls = vertex_reach(targets, setups, "dls")
    # a DLS solution is a solution: the closed form (complete, 8 branches) must find one too
    assert not np.any(dls & ~closed)
    # and DLS with restarts finds almost every solution the closed form finds
    assert (dls == closed).mean() >= 0.95
    cover = R.patch_reach(robot(), targets, setups, SPACE, params=PARAMS)
    np.testing.assert_array_equal(cover, closed[:, targets.patch_targets].all(axis=2))


def test_batches_of_any_size_give_the_same_answer():
    v, n = bowl_sample()
    targets = R.reach_targets(v, n)
    setups = uniform_setups(SPACE, (0.5, 0.5, np.radians(120)))
    a = R.patch_reach(robot(), targets, setups, SPACE, params=PARAMS)
    b = R.patch_reach(robot(), targets, setups, SPACE, params=ReachParams(batch_size=1000))
    np.testing.assert_array_equal(a, b)
    assert R.patch_reach(robot(), targets, np.zeros((0, 3)), SPACE).shape == (0, len(v))


def test_counting_reach_counts_one_call_per_new_setup():
    v, n = bowl_sample()
    reach = R.CountingReach(R.PartReach(robot(), R.reach_targets(v, n), SPACE, params=PARAMS))
    s = uniform_setups(SPACE, (0.5, 0.5, np.radians(120)))[:5]
    a = reach(s)
    b = reach(s[::-1])
    assert reach.n_rfc == 5
    np.testing.assert_array_equal(a[::-1], b)


def test_shared_reach_asks_each_exact_setup_once_and_answers_like_the_test_alone():
    v, n = bowl_sample()
    live = R.PartReach(robot(), R.reach_targets(v, n), SPACE, params=PARAMS)
    asked = []

    def recording(setups):
        asked.extend(map(tuple, setups))
        return live(setups)

    shared = R.SharedReach(recording)
    s = uniform_setups(SPACE, (0.25, 0.25, np.radians(60)))
    first = shared(s[:40])
    again = shared(np.concatenate([s[30:60], s[30:35]]))  # 10 known, 20 new, 5 repeated in the call
    assert len(asked) == 60 and len(set(asked)) == 60
    near = s[:3].copy()
    near[:, 0] = np.nextafter(near[:, 0], 1.0)  # same setup_keys, other floats: asked, not remembered
    shared(near)
    assert len(asked) == 63
    alone = np.concatenate([live(row[None]) for row in s[:60]])
    np.testing.assert_array_equal(first, alone[:40])
    np.testing.assert_array_equal(again, np.concatenate([alone[30:60], alone[30:35]]))
    assert first.any() and not first.all()
    assert shared(np.zeros((0, 3))).shape == (0, len(v))


def test_collision_option_only_removes_patches():
    v, n = bowl_sample()
    part = load_part("concave_bowl")
    targets = R.reach_targets(v[::4], n[::4])
    setups = np.array([[0.2, 0.5, 0.0]])
    free = R.patch_reach(robot(), targets, setups, SPACE, params=PARAMS)
    checked = R.patch_reach(robot(), targets, setups, SPACE, params=ReachParams(check_collision=True),
                            part_mesh=part.mesh)
    assert not np.any(checked & ~free)
    with pytest.raises(ValueError, match="part_mesh"):
        R.patch_reach(robot(), targets, setups, SPACE, params=ReachParams(check_collision=True))


def test_part_reach_builds_its_collision_checker_once_and_answers_as_a_fresh_one(count_checker_builds):
    # issue 33: a checker (a coal hierarchy of the whole part) per reach call cost 60 s and 1 GB
    # of garbage per planning run on a 2 M-face part
    import pickle

    box = trimesh.creation.box((0.2, 0.2, 0.2)).subdivide().subdivide()
    box.apply_translation([0, 0, 0.1])
    stain = np.flatnonzero(box.face_normals[:, 2] > -0.5)  # top and sides
    targets = R.reach_targets(box.triangles[stain], box.face_normals[stain])
    params = ReachParams(check_collision=True)
    setups = np.array([[0.0, 0.25, 0.0], [0.25, 0.0, 1.571], [0.25, 0.5, 0.0]])
    fresh = [R.patch_reach(robot(), targets, s[None], SPACE, params=params, part_mesh=box) for s in setups]
    built = count_checker_builds(R)
    live = R.PartReach(robot(), targets, SPACE, params=params, part_mesh=box)
    answers = [live(s[None]) for s in setups]
    assert len(built) == 1
    for a, b in zip(answers, fresh):
        np.testing.assert_array_equal(a, b)
    free = R.patch_reach(robot(), targets, setups, SPACE, params=PARAMS)
    assert np.concatenate(fresh).any() and (free & ~np.concatenate(fresh)).any()  # the arm test matters
    again = pickle.loads(pickle.dumps(live))  # a worker's copy builds its own
    np.testing.assert_array_equal(again(setups[:1]), fresh[0])
    assert len(built) == 2


def test_reach_params_validate():
    with pytest.raises(ValueError, match="tool_length"):
        ReachParams(tool_length=-0.1)
    with pytest.raises(ValueError, match="batch_size"):
        ReachParams(batch_size=0)
    with pytest.raises(ValueError, match="setups"):
        R.base_T_part(np.zeros((2, 2)), SPACE)


def test_a_box_far_away_is_unreachable_and_a_near_one_is_not():
    box = trimesh.creation.box((0.2, 0.2, 0.2))
    box.apply_translation([0, 0, 0.1])
    top = np.flatnonzero(box.face_normals[:, 2] > 0.9)
    targets = R.reach_targets(box.triangles[top], box.face_normals[top])
    far = dict(origin_x=5.0)
    cover_far = R.patch_reach(robot(), targets, np.zeros((1, 3)), SetupSpaceParams(**far), params=PARAMS)
    cover_near = R.patch_reach(robot(), targets, np.array([[0.2, 0.5, 0.0]]), SPACE, params=PARAMS)
    assert not cover_far.any() and cover_near.all()


def test_every_vertex_slot_decides_inside_the_reach_bound():
    # Large random triangles across the workspace: patches whose only unreachable vertex is the
    # first, the second or the third, that vertex inside the exact reach sphere so that the IK,
    # not the prefilter, has to reject it.
    rng = np.random.default_rng(0)
    n = 600
    centres = rng.uniform([-0.6, -0.2, 0.0], [0.4, 1.2, 0.7], size=(n, 3))
    v = centres[:, None, :] + rng.normal(scale=0.12, size=(n, 3, 3))
    nrm = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    nrm *= np.sign(nrm[:, 2:3] + 1e-9)  # face up: the tool comes from above
    targets = R.reach_targets(v, nrm)
    setups = np.zeros((1, 3))
    per_vertex = vertex_reach(targets, setups, "closed_form")[0][targets.patch_targets]
    T = R.base_T_part(setups, SPACE)[0]
    pos = targets.positions @ T[:3, :3].T + T[:3, 3]
    ax = targets.axes @ T[:3, :3].T
    bound = R.reach_bound(robot())
    inside = (np.linalg.norm(pos - bound.tool_offset * ax - bound.centre, axis=1) <= bound.radius)
    inside = inside[targets.patch_targets].all(axis=1)
    for slot in range(3):
        only_this = inside & ~per_vertex[:, slot] & (per_vertex.sum(axis=1) == 2)
        assert only_this.sum() >= 5, f"the sample has too few patches lost at vertex slot {slot}"
    # the triangles cross the table top: only the IK decides here, not the support plane
    cover = R.patch_reach(robot(), targets, setups, SPACE, params=ReachParams(support_plane=False))
    np.testing.assert_array_equal(cover[0], per_vertex.all(axis=1))

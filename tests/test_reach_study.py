import dataclasses
import warnings

import numpy as np
import pytest
import trimesh

from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.machines import machine_from_mesh
from mavac.inspection.reach_study import reach_study
from mavac.inspection.spots import se2_matrices
from mavac.robots.collision import CollisionChecker
from mavac.robots.kinematics import fk
from mavac.robots.models import ur10_mobile


@pytest.fixture(scope="module")
def step_under_slab():
    # a low step (top z = 0.3) under a slab cantilevered 0.3 m above it: the camera 0.5 m up the
    # step's normal would sit inside the slab, so no pose sees that part of the step
    parts = [trimesh.creation.box(bounds=[[0, 0, 0], [0.6, 1.0, 0.3]]),
             trimesh.creation.box(bounds=[[0, 0.5, 0.3], [0.6, 1.0, 1.0]]),
             trimesh.creation.box(bounds=[[0, 0, 0.6], [0.6, 1.0, 0.7]])]
    return machine_from_mesh(trimesh.boolean.union(parts, engine="manifold"), name="step")


@pytest.fixture(scope="module")
def studies(step_under_slab):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {v: reach_study(step_under_slab, params=fast_params().with_visibility(v)) for v in ("raycast", "hpr")}


def test_scores_are_maneuverability_of_reached_and_seen_elements(studies):
    s = studies["raycast"]
    assert np.all((s.score >= 0) & (s.score <= 1))
    np.testing.assert_allclose(s.score, s.maneuverability * s.visible)
    assert np.all(s.reached[s.score > 0]) and np.all(s.visible[s.score > 0])
    assert np.all(s.best_spot[~s.reached] == -1) and np.isnan(s.best_q[~s.reached]).all()
    assert 0 < s.reach_fraction < 1


def test_best_configuration_holds_the_camera_on_the_normal_without_collision(studies, step_under_slab):
    s = studies["raycast"]
    robot = ur10_mobile()
    checker = CollisionChecker(robot, step_under_slab.mesh, margin=s.params.guard.collision_margin, floor=True)
    L_d = s.params.camera.L_d
    for i in np.flatnonzero(s.reached)[:: max(1, int(s.reached.sum()) // 15)]:
        T = se2_matrices(s.candidates[s.best_spot[i]:s.best_spot[i] + 1])[0] @ fk(robot, s.best_q[i], robot.camera_frame)
        np.testing.assert_allclose(T[:3, 3], s.points[i] + L_d * s.normals[i], atol=2e-3)
        assert T[:3, 0] @ -s.normals[i] > 0.999  # optical axis (camera x) looks back at the element
        checker.set_base(se2_matrices(s.candidates[s.best_spot[i]:s.best_spot[i] + 1])[0])
        assert not checker.in_collision(s.best_q[i])


def test_elements_under_the_slab_are_not_seen_and_score_zero(studies):
    s = studies["raycast"]
    under = (np.abs(s.points[:, 2] - 0.3) < 1e-6) & (s.points[:, 1] < 0.45) & (s.normals[:, 2] > 0.99)
    assert under.any()
    assert not s.visible[under].any() and np.all(s.score[under] == 0)


def test_visibility_method_only_changes_what_is_seen(studies):
    r, h = studies["raycast"], studies["hpr"]
    np.testing.assert_array_equal(r.reached, h.reached)  # same seeds, same IK
    np.testing.assert_allclose(r.maneuverability, h.maneuverability)
    assert r.visibility == "raycast" and h.visibility == "hpr"
    assert "(hpr visibility)" in h.summary()
    frame = h.to_frame()
    assert len(frame) == len(h.points) and {"score", "spot_x", "q6"} <= set(frame)


def test_bad_visibility_is_refused(step_under_slab):
    with pytest.raises(ValueError, match="method must be one of"):
        fast_params().with_visibility("exact")
    with pytest.raises(TypeError, match="visibility"):
        reach_study(step_under_slab, params=dataclasses.replace(fast_params(), visibility="hpr"))

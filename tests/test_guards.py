"""Guard targets, collision-free camera IK, FOV bound vs visibility, lazy greedy selection."""

import numpy as np
import pytest
import trimesh

from mavac.inspection import guards as G
from mavac.params import CameraParams, GuardParams, InspectionParams, Visibility


def test_guard_targets_one_per_cluster_never_across_an_edge():
    box = trimesh.creation.box(bounds=[[0, 0, 0], [1.0, 1.0, 1.0]])
    pts, fi = trimesh.sample.sample_surface_even(box, 2000, seed=0)
    nrm = box.face_normals[fi]
    idx = G.guard_targets(pts, nrm, 0.25)
    assert len(np.unique(idx)) == len(idx) and np.all(np.diff(idx) > 0)
    cells = {tuple(np.floor(p / 0.25).astype(int)) + (int(np.argmax(np.abs(n))), int(np.sign(n[np.argmax(np.abs(n))])))
             for p, n in zip(pts, nrm)}
    assert len(idx) == len(cells)  # one representative per (cell, face direction)
    assert G.guard_targets(np.zeros((0, 3)), np.zeros((0, 3)), 0.1).size == 0
    with pytest.raises(ValueError, match="spacing"):
        G.guard_targets(pts, nrm, 0.0)


@pytest.fixture(scope="module")
def setup():
    from mavac.robots.collision import CollisionChecker
    from mavac.robots.models import ur10_mobile

    robot = ur10_mobile()
    box = trimesh.creation.box(bounds=[[-0.6, 0.4, 0.0], [0.6, 1.2, 0.7]])
    checker = CollisionChecker(robot, box, margin=0.01, floor=True)
    pts, fi = trimesh.sample.sample_surface_even(box, 600, seed=1)
    keep = box.face_normals[fi][:, 2] > -0.5
    return robot, box, checker, pts[keep], box.face_normals[fi][keep]


def test_camera_configurations_hit_the_pose(setup):
    from mavac.robots.kinematics import fk

    robot, box, checker, pts, nrm = setup
    cam = CameraParams()
    front = np.flatnonzero(nrm[:, 1] < -0.9)[:10]
    pos, ax = pts[front] + cam.L_d * nrm[front], -nrm[front]
    T = np.eye(4)
    ok, q, n_ik = G.camera_configurations(robot, checker, T, pos, ax, np.random.default_rng(0))
    assert ok.any() and n_ik >= ok.sum()
    F = fk(robot, q[ok], robot.camera_frame)
    assert np.allclose(F[:, :3, 3], pos[ok], atol=1e-4)
    assert np.allclose(F[:, :3, 0], ax[ok], atol=1e-3)  # the optical axis is camera x
    assert not np.any(checker.in_collision(q[ok]))


def test_candidates_fov_bounds_visibility_and_lazy_equals_eager(setup):
    from mavac.vision.visibility import VisibilityScene

    robot, box, checker, pts, nrm = setup
    cam = CameraParams()
    params = GuardParams(P_g=0.1)
    targets = G.guard_targets(pts, nrm, 0.2)
    cand = G.guard_candidates(robot, checker, np.eye(4), pts, nrm, targets, cam, np.random.default_rng(0))
    assert len(cand) > 3 and cand.n_tried == len(targets)
    # the camera is L_d along the target normal, optical axis (camera x) back along it
    assert np.allclose(cand.world_T_camera[:, :3, 3], pts[cand.target] + cam.L_d * nrm[cand.target], atol=1e-4)
    assert np.allclose(cand.world_T_camera[:, :3, 0], -nrm[cand.target], atol=1e-3)
    scene = VisibilityScene(box)  # the default visibility is exact ray casting
    vis = G.guard_visibility(cand.world_T_camera, pts, nrm, cam, Visibility(), vis_scene=scene)
    assert np.all(vis <= cand.fov)  # FOV is an upper bound
    sel = G.select_guards(cand, pts, nrm, cam, params, vis_scene=scene)
    eager = G.greedy_select(vis, params.P_g, weights=cand.maneuverability, k1=params.k1, k2=params.k2)
    assert sel.greedy.selected.tolist() == eager.selected.tolist()
    assert np.array_equal(sel.visible, vis[eager.selected])
    assert sel.n_evaluated <= sel.n_candidates
    assert np.allclose(sel.guards.q, cand.q[eager.selected])


def test_raycast_option(setup):
    from mavac.vision.visibility import VisibilityScene

    robot, box, checker, pts, nrm = setup
    cam = CameraParams()
    targets = G.guard_targets(pts, nrm, 0.3)
    cand = G.guard_candidates(robot, checker, np.eye(4), pts, nrm, targets, cam, np.random.default_rng(0))
    sel = G.select_guards(cand, pts, nrm, cam, GuardParams(), visibility=Visibility("raycast"),
                          vis_scene=VisibilityScene(box))
    assert len(sel.greedy.selected) >= 1
    assert np.all(sel.visible <= sel.guards.fov)


def test_empty_candidates(setup):
    robot, box, checker, pts, nrm = setup
    cand = G.guard_candidates(robot, checker, np.eye(4), pts, nrm, np.zeros(0, int), CameraParams(),
                              np.random.default_rng(0))
    assert len(cand) == 0
    sel = G.select_guards(cand, pts, nrm, CameraParams(), GuardParams())
    assert len(sel.greedy.selected) == 0 and sel.visible.shape == (0, len(pts))


def test_covered_elements_do_not_count(setup):
    robot, box, checker, pts, nrm = setup
    cam = CameraParams()
    cand = G.guard_candidates(robot, checker, np.eye(4), pts, nrm, G.guard_targets(pts, nrm, 0.2), cam,
                              np.random.default_rng(0))
    sel = G.select_guards(cand, pts, nrm, cam, GuardParams(P_g=0.0), covered=np.ones(len(pts), bool))
    assert len(sel.greedy.selected) == 0


def _coplanar_in_view(pts, nrm, t, T, cam, shrink=0.9):
    """Elements on the target's face whose camera-frame (y, z) lie well inside the pyramid's
    far rectangle: the neighbourhood a guard looking squarely at its target must see."""
    from mavac.vision.camera import points_in_camera

    same_face = (np.abs((pts - pts[t]) @ nrm[t]) < 1e-9) & (nrm @ nrm[t] > 1 - 1e-9)
    pc = points_in_camera(pts, T)[0]
    lateral = ((np.abs(pc[:, 1]) <= shrink * cam.L_d * np.tan(cam.theta_a))
               & (np.abs(pc[:, 2]) <= shrink * cam.L_d * np.tan(cam.theta_b)))
    return np.flatnonzero(same_face & lateral)


def test_guard_sees_its_own_target_face(setup):
    """The guard stands L_d from its target, so the target's face lies on the far plane; the FK
    of the IK solution moves it by up to the IK tolerance, which must not cut the face off."""
    from mavac.vision.visibility import VisibilityScene

    robot, box, checker, pts, nrm = setup
    cam = CameraParams()
    cand = G.guard_candidates(robot, checker, np.eye(4), pts, nrm, G.guard_targets(pts, nrm, 0.2), cam,
                              np.random.default_rng(0))
    rows = np.arange(len(cand))
    assert len(cand) > 5
    assert cand.fov[rows, cand.target].all()
    for visibility, scene in ((Visibility("hpr"), None), (Visibility("raycast"), VisibilityScene(box))):
        vis = G.guard_visibility(cand.world_T_camera, pts, nrm, cam, visibility, vis_scene=scene)
        assert vis[rows, cand.target].all(), visibility.method
        for i in rows:
            face = _coplanar_in_view(pts, nrm, cand.target[i], cand.world_T_camera[i:i + 1], cam)
            assert cand.fov[i, face].all()
            if visibility.method == "raycast":  # exact visibility: the whole face in view is seen
                assert vis[i, face].all()


def test_standoff_moves_the_guard_camera(setup):
    """GuardParams.standoff (the authors' code: 0.4 m) places the camera that far from its
    target along the normal, independently of the pyramid depth L_d; None keeps L_d."""
    robot, box, checker, pts, nrm = setup
    cam = CameraParams(L_d=0.7)
    targets = G.guard_targets(pts, nrm, 0.2)
    near = G.guard_candidates(robot, checker, np.eye(4), pts, nrm, targets, cam, np.random.default_rng(0),
                              standoff=0.4)
    assert len(near) > 3
    dist = np.linalg.norm(near.world_T_camera[:, :3, 3] - pts[near.target], axis=1)
    np.testing.assert_allclose(dist, 0.4, atol=1e-4)
    assert np.allclose(near.world_T_camera[:, :3, 0], -nrm[near.target], atol=1e-3)
    assert near.fov[np.arange(len(near)), near.target].all()  # the target is well inside the 0.7 m pyramid
    assert InspectionParams(camera=cam, guard=GuardParams(standoff=0.4)).guard_standoff == 0.4
    assert InspectionParams(camera=cam).guard_standoff == 0.7  # None: the paper's L_d
    with pytest.raises(ValueError, match="standoff"):
        GuardParams(standoff=0.0)
    with pytest.raises(ValueError, match="standoff"):
        G.guard_candidates(robot, checker, np.eye(4), pts, nrm, targets, cam, np.random.default_rng(0),
                           standoff=-0.4)

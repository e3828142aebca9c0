import numpy as np
import pinocchio as pin
import pytest

from mavac.robots import kinematics as K
from mavac.robots.models import puma560, ur10_mobile


@pytest.fixture(scope="module")
def ur10():
    return ur10_mobile()


@pytest.fixture(scope="module")
def puma():
    return puma560(tool_length=0.1)


def _in_limits(robot, q):
    return np.all((q >= robot.q_lower - 1e-12) & (q <= robot.q_upper + 1e-12))


def _random_q(robot, rng, n):
    return rng.uniform(np.maximum(robot.q_lower, -np.pi), np.minimum(robot.q_upper, np.pi), (n, robot.nq))


@pytest.mark.parametrize("which", ["ur10", "puma"])
def test_batched_fk_and_jacobian_match_pinocchio(which, request):
    robot = request.getfixturevalue(which)
    q = _random_q(robot, np.random.default_rng(0), 20)
    data = robot.model.createData()
    frames = [robot.tool_frame] + ([robot.camera_frame] if robot.camera_frame else [])
    for frame in frames:
        T = K.fk(robot, q, frame)
        J = K.jacobian(robot, q, frame)
        fid = robot.model.getFrameId(frame)
        for i in range(len(q)):
            pin.framesForwardKinematics(robot.model, data, q[i])
            np.testing.assert_allclose(T[i], data.oMf[fid].homogeneous, atol=1e-12)
            Jp = pin.computeFrameJacobian(robot.model, data, q[i], fid, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(J[i], Jp, atol=1e-12)
    assert K.fk(robot, q[0]).shape == (4, 4)
    assert K.jacobian(robot, q[0]).shape == (6, robot.nq)


def test_puma_fk_matches_plain_dh(puma):
    """Independent plain-numpy standard-DH product, 1e-9 m."""
    from mavac.robots.models import PUMA560_DH

    q = _random_q(puma, np.random.default_rng(3), 200)
    T = K.fk(puma, q)
    for i in range(len(q)):
        A = np.eye(4)
        for qi, (a, d, alpha) in zip(q[i], PUMA560_DH):
            ct, st, ca, sa = np.cos(qi), np.sin(qi), np.cos(alpha), np.sin(alpha)
            A = A @ np.array(
                [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]]
            )
        A = A @ np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.1], [0, 0, 0, 1]])
        np.testing.assert_allclose(T[i], A, atol=1e-9)


@pytest.mark.parametrize("which", ["ur10", "puma"])
def test_ik_full_pose_round_trip(which, request):
    robot = request.getfixturevalue(which)
    rng = np.random.default_rng(4)
    targets = K.fk(robot, _random_q(robot, rng, 150))
    res = K.ik(robot, targets, rng=rng)
    assert res.q.shape == (150, 6)
    assert res.success.mean() >= 0.95
    assert _in_limits(robot, res.q)
    T = K.fk(robot, res.q[res.success])
    assert np.max(np.linalg.norm(T[:, :3, 3] - targets[res.success, :3, 3], axis=1)) < 1e-4
    R_err = T[:, :3, :3].transpose(0, 2, 1) @ targets[res.success, :3, :3]
    angle = np.arccos(np.clip((np.trace(R_err, axis1=1, axis2=2) - 1) / 2, -1, 1))
    assert angle.max() < 1e-3
    np.testing.assert_array_less(res.position_error[res.success], 1e-5)
    np.testing.assert_array_less(res.rotation_error[res.success], 1e-4)


@pytest.mark.parametrize("which", ["ur10", "puma"])
def test_ik_axis_dls_round_trip_frees_the_spin(which, request):
    robot = request.getfixturevalue(which)
    rng = np.random.default_rng(5)
    T = K.fk(robot, _random_q(robot, rng, 150))
    res = K.ik_axis(robot, T[:, :3, 3], T[:, :3, 2], method="dls", rng=rng)
    assert res.success.mean() >= 0.95
    assert _in_limits(robot, res.q)
    T2 = K.fk(robot, res.q[res.success])
    assert np.max(np.linalg.norm(T2[:, :3, 3] - T[res.success, :3, 3], axis=1)) < 1e-4
    cosang = np.einsum("ij,ij->i", T2[:, :3, 2], T[res.success, :3, 2])
    assert np.arccos(np.clip(cosang, -1, 1)).max() < 1e-3


def test_ik_result_reports_failure_for_unreachable_targets(ur10):
    res = K.ik_axis(ur10, [[5.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]], n_restarts=1, max_iter=30)
    assert not res.success[0]
    assert res.position_error[0] > 3.0
    assert _in_limits(ur10, res.q)


def test_puma_closed_form_round_trip(puma):
    rng = np.random.default_rng(6)
    q = rng.uniform(puma.q_lower, puma.q_upper, (20000, 6))
    T = K.fk(puma, q)
    res = K.ik_axis(puma, T[:, :3, 3], T[:, :3, 2])  # auto -> closed form
    assert res.success.mean() >= 0.999
    assert _in_limits(puma, res.q)
    T2 = K.fk(puma, res.q[res.success])  # generic FK, not the solver's own
    np.testing.assert_array_less(np.linalg.norm(T2[:, :3, 3] - T[res.success, :3, 3], axis=1), 1e-6)
    cross = np.linalg.norm(np.cross(T2[:, :3, 2], T[res.success, :3, 2]), axis=1)
    np.testing.assert_array_less(cross, 1e-6)
    assert np.all(np.einsum("ij,ij->i", T2[:, :3, 2], T[res.success, :3, 2]) > 0)


def test_puma_closed_form_seed_selects_the_generating_branch(puma):
    rng = np.random.default_rng(7)
    q = rng.uniform(puma.q_lower * 0.8, puma.q_upper * 0.8, (500, 6))
    q[:, 4] = np.sign(q[:, 4]) * np.maximum(np.abs(q[:, 4]), 0.2)  # away from the wrist singularity
    q[:, 5] = 0.0
    T = K.fk(puma, q)
    res = K.ik_axis(puma, T[:, :3, 3], T[:, :3, 2], q0=q)
    assert res.success.all()
    np.testing.assert_allclose(res.q, q, atol=1e-7)


def test_puma_closed_form_agrees_with_dls(puma):
    """Reachability of random (position, axis) targets: closed form vs numerical IK."""
    rng = np.random.default_rng(8)
    n = 300
    p = rng.uniform([-0.9, -0.9, -0.6], [0.9, 0.9, 0.9], (n, 3))
    a = rng.normal(size=(n, 3))
    cf = K.ik_axis(puma, p, a, method="closed_form")
    dls = K.ik_axis(puma, p, a, method="dls", rng=rng, n_restarts=10)
    assert 0.1 < cf.success.mean() < 0.9  # the sample mixes reachable and unreachable targets
    # the closed form enumerates every branch: whatever DLS reaches, it reaches too
    assert np.all(cf.success[dls.success])
    disagreement = np.mean(cf.success != dls.success)
    assert disagreement <= 0.05, disagreement


def test_closed_form_refused_for_other_robots(ur10):
    with pytest.raises(ValueError, match="closed_form"):
        K.ik_axis(ur10, [[0.8, 0.0, 0.8]], [[1.0, 0.0, 0.0]], method="closed_form")


def test_maneuverability_range_singularities_and_limits(ur10, puma):
    rng = np.random.default_rng(9)
    for robot in (ur10, puma):
        q = _random_q(robot, rng, 500)
        im = K.maneuverability(robot, q)
        assert im.shape == (500,)
        assert np.all((im >= 0) & (im <= 1))
        jl_max = 1.0 - np.exp(-K.JOINT_LIMIT_K / 4.0**robot.nq)  # every joint at mid-range
        assert np.all(K.joint_limit_penalty(robot, q) <= jl_max + 1e-15)
        np.testing.assert_allclose(im, K.manipulability_ratio(robot, q) * K.joint_limit_penalty(robot, q))
        assert K.maneuverability(robot, robot.q_home) > 0.2 * jl_max  # home is far from singular
    home = ur10.q_home
    wrist_singular = home.copy()
    wrist_singular[4] = 0.0  # joint 4 and 6 axes aligned
    elbow_straight = home.copy()
    elbow_straight[2] = 0.0
    at_limit = home.copy()
    at_limit[2] = ur10.q_upper[2]
    for q in (wrist_singular, elbow_straight, at_limit):
        assert K.maneuverability(ur10, q) < 1e-6
    near_limit = home.copy()
    near_limit[2] = ur10.q_upper[2] - 0.05
    assert K.maneuverability(ur10, near_limit) < 0.5 * K.maneuverability(ur10, home)
    # puma wrist singularity q5 = 0
    q = puma.q_home.copy()
    q[4] = 0.0
    assert K.maneuverability(puma, q) < 1e-6


def test_bad_inputs_raise(ur10):
    with pytest.raises(ValueError, match="q must have shape"):
        K.fk(ur10, np.zeros(5))
    with pytest.raises(ValueError, match="q contains NaN"):
        K.fk(ur10, np.full(6, np.nan))
    with pytest.raises(ValueError, match="frame"):
        K.fk(ur10, np.zeros(6), frame="nope")
    with pytest.raises(ValueError, match="base_T_target"):
        K.ik(ur10, np.zeros((2, 3, 4)))
    with pytest.raises(ValueError, match="base_T_target"):
        K.ik(ur10, np.full((4, 4), np.nan))
    with pytest.raises(ValueError, match="positions"):
        K.ik_axis(ur10, np.zeros((2, 2)), np.ones((2, 3)))
    with pytest.raises(ValueError, match="axes"):
        K.ik_axis(ur10, np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="same length"):
        K.ik_axis(ur10, np.zeros((2, 3)), np.ones((3, 3)))
    with pytest.raises(ValueError, match="q0"):
        K.ik_axis(ur10, np.zeros((2, 3)), np.ones((2, 3)), q0=np.zeros(4))
    with pytest.raises(ValueError, match="method"):
        K.ik_axis(ur10, np.zeros((1, 3)), np.ones((1, 3)), method="magic")
    with pytest.raises(ValueError, match="n_restarts"):
        K.ik(ur10, np.eye(4), n_restarts=-1)
    with pytest.raises(ValueError, match="k"):
        K.maneuverability(ur10, ur10.q_home, k=-1.0)
    with pytest.raises(ValueError, match="k"):
        K.joint_limit_penalty(ur10, ur10.q_home, k=0.0)


def test_pose_residual_matches_scipy_including_near_pi():
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(10)
    R = Rotation.random(600, random_state=11).as_matrix()
    rv = Rotation.random(600, random_state=12).as_rotvec()
    unit = rv / np.linalg.norm(rv, axis=1)[:, None]
    angles = np.concatenate([rng.uniform(0, np.pi, 300), rng.uniform(np.pi - 0.15, np.pi, 200), np.full(100, 1e-10)])
    rv = unit * angles[:, None]
    R_target = Rotation.from_rotvec(rv).as_matrix() @ R
    soa = lambda M: np.ascontiguousarray(M.transpose(2, 1, 0))  # noqa: E731
    out, ang = K._pose_residual(soa(R), soa(R_target))
    np.testing.assert_allclose(out.T, rv, atol=1e-9)
    np.testing.assert_allclose(ang, angles, atol=1e-9)


def test_ik_is_deterministic_and_uses_q0(ur10):
    T = K.fk(ur10, _random_q(ur10, np.random.default_rng(13), 40))
    a = K.ik(ur10, T, rng=np.random.default_rng(1))
    b = K.ik(ur10, T, rng=np.random.default_rng(1))
    np.testing.assert_array_equal(a.q, b.q)
    # seeded at a solution, the first Newton step already converges there
    c = K.ik(ur10, T[a.success], q0=a.q[a.success], n_restarts=0)
    assert c.success.all()
    np.testing.assert_allclose(c.q, a.q[a.success], atol=1e-6)


def test_ik_axis_can_aim_the_camera_optical_axis(ur10):
    rng = np.random.default_rng(14)
    T = K.fk(ur10, _random_q(ur10, rng, 60), frame="camera")
    res = K.ik_axis(ur10, T[:, :3, 3], T[:, :3, 0], frame="camera", frame_axis=0, rng=rng)
    assert res.success.mean() >= 0.95
    T2 = K.fk(ur10, res.q[res.success], frame="camera")
    np.testing.assert_allclose(T2[:, :3, 3], T[res.success, :3, 3], atol=1e-4)
    np.testing.assert_allclose(T2[:, :3, 0], T[res.success, :3, 0], atol=1e-3)
    with pytest.raises(ValueError, match="frame_axis"):
        K.ik_axis(ur10, T[:1, :3, 3], T[:1, :3, 0], frame_axis=3)


def test_joint_limit_penalty_is_eq4_with_simox_scale(ur10):
    """MAVAC eq. 4 written out for one configuration, with k = 50 (Simox, Vahrenkamp's library)."""
    q = ur10.q_home
    lo, hi = ur10.q_lower, ur10.q_upper
    expected = 1.0 - np.exp(-50.0 * np.prod((q - lo) * (hi - q) / (hi - lo) ** 2))
    assert K.JOINT_LIMIT_K == 50.0
    assert K.joint_limit_penalty(ur10, q) == pytest.approx(expected, rel=1e-12)
    # a large k saturates J_l near 1 away from the limits; it still vanishes at a limit
    assert K.joint_limit_penalty(ur10, q, k=3 * 4.0**6) > 0.5
    at_limit = q.copy()
    at_limit[2] = hi[2]
    assert K.joint_limit_penalty(ur10, at_limit, k=3 * 4.0**6) == 0.0

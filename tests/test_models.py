import numpy as np
import pinocchio as pin
import pytest

from mavac.robots.models import (
    MIR200_SIZE,
    PUMA560_DH,
    ROBOT_NAMES,
    TOOL_TUBE_LENGTH,
    RobotModel,
    load_robot,
    puma560,
    se2_to_matrix,
    ur10_mobile,
)


@pytest.fixture(scope="module")
def ur10():
    return ur10_mobile()


@pytest.fixture(scope="module")
def puma():
    return puma560(tool_length=0.15)


def _frame_pose(robot, q, frame):
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    return data.oMf[robot.model.getFrameId(frame)].homogeneous


def _dh_fk(q, dh, tool_length):
    """Plain standard-DH product A_1 ... A_6 Tz(tool_length), independent of pinocchio."""
    T = np.eye(4)
    for qi, (a, d, alpha) in zip(q, dh):
        ct, st, ca, sa = np.cos(qi), np.sin(qi), np.cos(alpha), np.sin(alpha)
        T = T @ np.array(
            [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]]
        )
    tool = np.eye(4)
    tool[2, 3] = tool_length
    return T @ tool


def test_robot_model_fields(ur10, puma):
    for robot in (ur10, puma):
        assert isinstance(robot, RobotModel)
        assert robot.nq == 6
        assert robot.q_home.shape == (6,)
        assert np.all(robot.q_lower < robot.q_upper)
        assert np.all((robot.q_home > robot.q_lower) & (robot.q_home < robot.q_upper))
        assert robot.model.existFrame(robot.tool_frame)
        assert robot.manipulability_max > 0
    assert ur10.camera_frame == "camera" and puma.camera_frame is None


def test_ur10_limits_are_the_urdf_limits(ur10):
    two_pi = 2 * np.pi
    np.testing.assert_allclose(ur10.q_upper, [two_pi, two_pi, np.pi, two_pi, two_pi, two_pi], atol=1e-9)
    np.testing.assert_allclose(ur10.q_lower, -ur10.q_upper)


def test_ur10_arm_mounted_on_top_centre_of_base_box(ur10):
    base_T_arm = _frame_pose(ur10, ur10.q_home, "base_link")
    expected = np.eye(4)
    expected[2, 3] = MIR200_SIZE[2]
    np.testing.assert_allclose(base_T_arm, expected, atol=1e-12)
    box = ur10.collision_model.geometryObjects[ur10.collision_model.getGeometryId("mir200_base")]
    assert box.parentJoint == 0
    np.testing.assert_allclose(2 * box.geometry.halfSide, MIR200_SIZE)
    np.testing.assert_allclose(box.placement.translation, [0, 0, MIR200_SIZE[2] / 2])


def test_ur10_tool_and_camera_frames(ur10):
    rng = np.random.default_rng(0)
    for q in rng.uniform(-np.pi, np.pi, (5, 6)):
        flange = _frame_pose(ur10, q, "tool0")
        tip = _frame_pose(ur10, q, "tool_tip")
        cam = _frame_pose(ur10, q, "camera")
        # tip: TOOL_TUBE_LENGTH along the flange z, same orientation
        np.testing.assert_allclose(tip[:3, 3], flange[:3, 3] + TOOL_TUBE_LENGTH * flange[:3, 2], atol=1e-12)
        np.testing.assert_allclose(tip[:3, :3], flange[:3, :3], atol=1e-12)
        # MAVAC convention: optical axis = camera x = tool z; right-handed camera frame
        np.testing.assert_allclose(cam[:3, 0], tip[:3, 2], atol=1e-12)
        assert np.linalg.det(cam[:3, :3]) == pytest.approx(1.0)
        # mounted near the flange, on top of the tube
        assert np.linalg.norm(cam[:3, 3] - flange[:3, 3]) < 0.15
    names = {g.name for g in ur10.collision_model.geometryObjects}
    assert {"tool_tube", "tool_sphere", "camera_body", "mir200_base"} <= names


def test_a_longer_tube_moves_only_the_tip_and_is_another_robot(ur10):
    import pickle

    long = ur10_mobile(tube_length=0.55)
    q = np.random.default_rng(1).uniform(-np.pi, np.pi, 6)
    flange = _frame_pose(long, q, "tool0")
    np.testing.assert_allclose(_frame_pose(long, q, "tool_tip")[:3, 3], flange[:3, 3] + 0.55 * flange[:3, 2], atol=1e-12)
    np.testing.assert_allclose(_frame_pose(long, q, "camera"), _frame_pose(ur10, q, "camera"), atol=1e-12)
    assert long.name == "ur10_mobile_tube550mm" and ur10_mobile(tube_length=TOOL_TUBE_LENGTH).name == ur10.name
    tube = {g.name: g for g in long.collision_model.geometryObjects}["tool_tube"]
    assert tube.geometry.halfLength == pytest.approx(0.275)
    back = pickle.loads(pickle.dumps(long))
    assert back.name == long.name and back.model.inertias[6].mass == pytest.approx(long.model.inertias[6].mass)
    with pytest.raises(ValueError, match=r"tube_length must be in \[0.1, 1.3\]"):
        ur10_mobile(tube_length=2.0)


def test_puma_matches_published_dh(puma):
    rng = np.random.default_rng(1)
    for q in rng.uniform(puma.q_lower, puma.q_upper, (50, 6)):
        np.testing.assert_allclose(_frame_pose(puma, q, "tool"), _dh_fk(q, PUMA560_DH, 0.15), atol=1e-9)


def test_puma_limits_are_corkes(puma):
    np.testing.assert_allclose(np.rad2deg(puma.q_lower), [-160, -45, -225, -110, -100, -266])
    np.testing.assert_allclose(np.rad2deg(puma.q_upper), [160, 225, 45, 170, 100, 266])


def test_puma_tool_geometry_follows_tool_length():
    short, long_ = puma560(0.0), puma560(0.3)
    assert not short.collision_model.existGeometryName("tool")
    assert long_.collision_model.existGeometryName("tool")


def test_se2_to_matrix():
    T = se2_to_matrix(1.0, -2.0, np.pi / 2)
    np.testing.assert_allclose(T @ [1, 0, 0, 1], [1.0, -1.0, 0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    with pytest.raises(ValueError, match="theta"):
        se2_to_matrix(0.0, 0.0, np.nan)


def test_load_robot():
    assert set(ROBOT_NAMES) == {"ur10_mobile", "puma560", "iiwa7"}
    assert load_robot("puma560", tool_length=0.1).name == "puma560"
    with pytest.raises(ValueError, match="name"):
        load_robot("kuka")
    with pytest.raises(ValueError, match="tool_length"):
        puma560(tool_length=-0.1)


def test_pickle_rebuilds_small_and_keeps_q_home(puma):
    import dataclasses
    import pickle

    robot = puma560(tool_length=0.15)
    robot.q_home = robot.q_home + 0.01
    blob = pickle.dumps(robot)
    assert len(blob) < 2000  # builder call, not the geometry
    back = pickle.loads(blob)
    np.testing.assert_array_equal(back.q_home, robot.q_home)
    assert back.manipulability_max == robot.manipulability_max
    np.testing.assert_allclose(_frame_pose(back, back.q_home, "tool"), _frame_pose(robot, robot.q_home, "tool"))
    # a hand-made variant pickles in full
    variant = dataclasses.replace(puma, q_home=np.zeros(6))
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(variant)).q_home, np.zeros(6))


def test_cached_chains_follow_the_model(puma):
    """A variant with a new model (e.g. an extra frame) must not reuse the old chains."""
    import dataclasses

    from mavac.robots import kinematics as K

    q = puma.q_home
    before = K.fk(puma, q)
    model = puma.model.copy()
    j6 = model.getJointId("joint6")
    model.frames[model.getFrameId("tool")].placement = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.5]))
    variant = dataclasses.replace(puma, model=model)  # shares puma._cache
    after = K.fk(variant, q)
    assert model.frames[model.getFrameId("tool")].parentJoint == j6
    np.testing.assert_allclose(after[:3, 3], before[:3, 3] + (0.5 - 0.15) * before[:3, 2], atol=1e-12)
    np.testing.assert_allclose(K.fk(puma, q), before)

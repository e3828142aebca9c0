"""The trial replay's recorder: keys on the simulated clock, base turns, heap removal times."""

import numpy as np
import pytest

from mavac.cleaning.replay import ReplayRecorder, path_times


def test_path_times_follow_the_largest_joint_step():
    path = np.array([[0.0, 0.0], [0.1, 0.3], [0.4, 0.3], [0.4, 0.3]])
    assert path_times(path, 6.0) == pytest.approx([0.0, 3.0, 6.0, 6.0])
    assert path_times(path[:1], 2.0) == pytest.approx([0.0])
    assert path_times(np.zeros((3, 2)), 2.0) == pytest.approx([0.0, 1.0, 2.0])  # no motion: evenly


def test_recorder_keeps_one_clock_over_arm_base_and_vacuum():
    rec = ReplayRecorder([0.0, 0.0, 3.0], [0.0, 0.0], n_heaps=4)
    rec.arm_path([[0.0, 0.0], [0.2, 0.0], [0.2, 0.4]], 3.0)
    rec.base_drive([1.0, 0.0, -3.0], 5.0)  # 3 rad to -3 rad: the short way, through pi
    rec.vacuuming([(0.0, np.array([0.2, 0.4])), (0.5, np.array([0.3, 0.4]))], [2, 0], [0.25, 0.75], 1.5)
    rec.vacuuming([], [2], [0.1], 1.0)  # heap 2 was already gone: its time stays
    r = rec.replay()
    assert r.times.tolist() == pytest.approx([0.0, 1.0, 3.0, 8.0, 8.0, 8.5, 10.5])
    assert r.duration == pytest.approx(10.5)
    assert r.bases[3, 2] == pytest.approx(2 * np.pi - 3.0) and r.bases[3, 0] == 1.0
    assert np.all(r.bases[4:, :2] == [1.0, 0.0])
    assert r.qs[2].tolist() == [0.2, 0.4] and r.qs[-1].tolist() == [0.3, 0.4]
    np.testing.assert_allclose(r.cleaned_at, [8.75, np.nan, 8.25, np.nan])
    assert r.qs.shape == (7, 2) and r.bases.shape == (7, 3)


def test_motion_totals_measure_an_arc_of_the_shoulder_pan_and_ignore_base_drives():
    from mavac.cleaning.replay import motion_totals
    from mavac.robots.kinematics import fk
    from mavac.robots.models import ur10_mobile

    robot = ur10_mobile()
    q0 = np.array(robot.q_home, dtype=float)
    q1 = q0.copy()
    q1[0] += 1.0  # joint 1 turns about the base's vertical axis: the tool draws an arc
    rec = ReplayRecorder([0.0, 0.0, 0.0], q0, n_heaps=0)
    rec.arm_path([q0, q1], 2.0)
    rec.base_drive([3.0, 1.0, 0.5], 4.0)  # the arm is still: nothing to count
    tool_m, joints_rad = motion_totals(rec.replay(), robot)
    radius = np.linalg.norm(fk(robot, q0)[:2, 3])  # the base's z axis is joint 1's
    assert joints_rad == pytest.approx(1.0)
    assert tool_m == pytest.approx(radius * 1.0, rel=1e-5)
    assert motion_totals(ReplayRecorder([0, 0, 0], q0, 0).replay(), robot) == (0.0, 0.0)

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

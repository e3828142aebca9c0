"""What a cleaning trial did, on the simulated clock: the robot's motion and when each heap went.

:func:`mavac.cleaning.trial.run_trial` records it with a :class:`ReplayRecorder` while the loop
runs, and keeps it as :attr:`TrialResult.replay <mavac.cleaning.trial.TrialResult>`;
:meth:`TrialResult.to_html <mavac.cleaning.trial.TrialResult.to_html>` plays it back as a meshcat
page. The clock is the trial's simulated time (base travel + arm motion + vacuuming, the sum
:attr:`TrialTimes.sim_time_s <mavac.cleaning.timing.TrialTimes.sim_time_s>` reports); images
and planning take no simulated time.

Keys are the executed joint paths' waypoints, the two ends of every base drive and samples of
the arm while it vacuums (:data:`mavac.cleaning.vacuum.REPLAY_SAMPLE_S`); a viewer interpolates
between them, so the replay shows where the robot went and in which order, not every physics
step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..robots.kinematics import fk

#: Ours: joint-space segments between replay keys are cut into steps of at most this much on
#: any joint (rad) before the tool is placed by forward kinematics (2 mm at the UR10's 1.3 m reach)
MOTION_STEP_RAD = 0.0015


@dataclass(frozen=True)
class Replay:
    """Keys of a trial's motion and the heaps' removal times.

    Attributes
    ----------
    times : (k,) float, s
        Simulated time of each key, non-decreasing (a base drive and the arm's first waypoint
        after it can share a time).
    bases : (k, 3) float
        SE(2) base pose (x, y in m; theta in rad) at each key.
    qs : (k, nq) float, rad
        Arm configuration at each key.
    cleaned_at : (n,) float, s
        When each heap was vacuumed; NaN for a heap never vacuumed.
    """

    times: np.ndarray
    bases: np.ndarray
    qs: np.ndarray
    cleaned_at: np.ndarray

    @property
    def duration(self) -> float:
        """Simulated time of the last key, s (0 for an empty replay)."""
        return float(self.times[-1]) if len(self.times) else 0.0


def path_times(path, duration: float) -> np.ndarray:
    """(k,) float, s: times of a joint path's waypoints when it takes ``duration`` s, spread in
    proportion to the largest joint step (the joint that limits each segment's speed).

    Parameters
    ----------
    path : (k, nq) float, rad
        Waypoints; the first is where the motion starts (time 0).
    duration : float, s
    """
    path = np.asarray(path, dtype=float)
    steps = np.abs(np.diff(path, axis=0)).max(axis=1) if len(path) > 1 else np.zeros(0)
    total = float(steps.sum())
    if total == 0.0:
        return np.linspace(0.0, float(duration), len(path))
    return float(duration) * np.r_[0.0, np.cumsum(steps)] / total


class ReplayRecorder:
    """Collects a :class:`Replay` while a trial runs (the trial's only mutable record of it).

    Parameters
    ----------
    base : (3,) float
        SE(2) base pose at the start.
    q : (nq,) float, rad
        Arm configuration at the start.
    n_heaps : int
    """

    def __init__(self, base, q, n_heaps: int):
        self.t = 0.0
        self.times, self.bases, self.qs = [0.0], [np.asarray(base, float)], [np.asarray(q, float)]
        self.cleaned_at = np.full(int(n_heaps), np.nan)

    def _key(self, t: float, base, q) -> None:
        self.times.append(float(t))
        self.bases.append(np.asarray(base, float))
        self.qs.append(np.asarray(q, float))

    def arm_path(self, path, duration: float) -> None:
        """A joint path (its first row is the configuration the arm starts from) that took
        ``duration`` s."""
        path = np.asarray(path, dtype=float)
        for t, q in zip(self.t + path_times(path, duration)[1:], path[1:]):
            self._key(t, self.bases[-1], q)
        self.t += float(duration)

    def base_drive(self, base, duration: float) -> None:
        """The base drove to ``base`` (SE(2)) in ``duration`` s, the arm folded; the replay
        turns it the short way round."""
        base = np.asarray(base, dtype=float).copy()
        last = self.bases[-1]
        base[2] = last[2] + np.remainder(base[2] - last[2] + np.pi, 2.0 * np.pi) - np.pi
        self.t += float(duration)
        self._key(self.t, base, self.qs[-1])

    def vacuuming(self, samples, sucked, sucked_at, duration: float) -> None:
        """One area's vacuuming: ``samples`` of (s since its start, q), the heaps ``sucked`` and
        when (s since its start), over ``duration`` s."""
        for s, q in samples:
            self._key(self.t + s, self.bases[-1], q)
        sucked = np.asarray(sucked, dtype=int)
        first = np.isnan(self.cleaned_at[sucked])  # a heap goes once
        self.cleaned_at[sucked[first]] = self.t + np.asarray(sucked_at, dtype=float)[first]
        self.t += float(duration)

    def replay(self) -> Replay:
        """The keys so far, ending at the clock's present (the last state held until then)."""
        if self.t > self.times[-1]:
            self._key(self.t, self.bases[-1], self.qs[-1])
        return Replay(np.asarray(self.times), np.vstack(self.bases), np.vstack(self.qs), self.cleaned_at.copy())


def motion_totals(replay: Replay, robot) -> tuple[float, float]:
    """How far the arm moved over a replay: the tool centre's path length and the joints' travel.

    Between two keys the arm is taken to move linearly in joint space (as a planned path's
    segments are; vacuuming is keyed every :data:`mavac.cleaning.vacuum.REPLAY_SAMPLE_S`), cut
    into steps of at most :data:`MOTION_STEP_RAD` on any joint. Base drives are not counted (the
    arm is folded; the base's travel is timed apart).

    Parameters
    ----------
    replay : Replay
    robot : RobotModel
        The trial's robot (its tool frame).

    Returns
    -------
    tool_path_m : float
        Length of the tool centre's path in the base frame, m.
    joint_travel_rad : float
        Sum over joints of the absolute angle travelled, rad.
    """
    qs = np.asarray(replay.qs, dtype=float)
    if len(qs) < 2:
        return 0.0, 0.0
    dq = np.diff(qs, axis=0)
    steps = np.maximum(1, np.ceil(np.abs(dq).max(axis=1) / MOTION_STEP_RAD).astype(int))
    s = np.concatenate([np.arange(n) / n for n in steps])
    seg = np.repeat(np.arange(len(dq)), steps)
    dense = np.vstack([qs[seg] + s[:, None] * dq[seg], qs[-1:]])
    tool = fk(robot, dense)[:, :3, 3]
    return float(np.linalg.norm(np.diff(tool, axis=0), axis=1).sum()), float(np.abs(dq).sum())

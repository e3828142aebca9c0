"""A MAVAC online trial end to end on a small machine: deterministic, never leaves a client
connected, and hard scenes give a result with a reason instead of an exception."""

import dataclasses
import re
import warnings

import numpy as np
import pytest
import trimesh

from mavac.cleaning import trial as T
from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.machines import machine_from_mesh
from mavac.inspection.inspection_plan import PoseSet, plan_inspection
from mavac.params import ApproachParams, DetectionParams, DustParams, OnlineParams

PARAMS = OnlineParams(dust=DustParams(spacing=0.2))


def _connected_clients() -> list[int]:
    import pybullet as p

    return [c for c in range(32) if p.isConnected(physicsClientId=c)]


@pytest.fixture(scope="module")
def box_plan():
    """A 1.0 x 0.6 x 0.6 m box and its fast-mode plan."""
    machine = machine_from_mesh(trimesh.creation.box(bounds=[[-0.5, -0.3, 0.0], [0.5, 0.3, 0.6]]), name="box")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return machine, plan_inspection(machine, params=fast_params())


@pytest.fixture(scope="module")
def small(box_plan):
    """The box and the first three poses of its plan."""
    machine, plan = box_plan
    return machine, dataclasses.replace(plan, pose_set=plan.pose_set.head(3))


def test_same_seed_same_row_and_no_client_left(small):
    machine, plan = small
    a = T.run_trial(machine, plan, params=PARAMS, seed=3)
    b = T.run_trial(machine, plan, params=PARAMS, seed=3)
    ra, rb = a.row(), b.row()
    ra.pop("wall_s"), rb.pop("wall_s")
    assert ra == rb
    assert a.causes.tolist() == b.causes.tolist()
    assert a.n_heaps > 0 and a.detected > 0 and a.precision == 1.0
    assert a.n_cleaned > 0 and a.times.vacuum_s > 0 and a.times.arm_s > 0
    assert (a.causes == "").sum() == a.n_cleaned
    assert _connected_clients() == []


def test_no_client_left_after_a_raise(small, monkeypatch):
    machine, plan = small

    def boom(*args, **kwargs):
        raise RuntimeError("detector crashed")

    monkeypatch.setattr(T, "detect_dust", boom)
    with pytest.raises(RuntimeError, match="detector crashed"):
        T.run_trial(machine, plan, params=PARAMS, seed=0)
    assert _connected_clients() == []


def test_machine_without_upward_surface_gives_zero_with_reason(small):
    _, plan = small
    spire = trimesh.creation.cone(radius=0.2, height=2.0, sections=8)
    result = T.run_trial(machine_from_mesh(spire, name="spire"), plan, params=PARAMS, seed=0)
    assert result.cleaning_pct == 0.0 and result.n_heaps == 0 and "no heaps" in result.reason


def test_empty_plan_and_no_detection_give_zero_with_reason(small):
    machine, plan = small
    empty = dataclasses.replace(plan, pose_set=PoseSet.from_rows([], len(plan.points), 6))
    r = T.run_trial(machine, empty, params=PARAMS, seed=0)
    assert r.cleaning_pct == 0.0 and "empty plan" in r.reason and set(r.causes) == {"never in view"}
    blue = dataclasses.replace(PARAMS, detection=DetectionParams(hue_min=100, hue_max=110))
    r = T.run_trial(machine, plan, params=blue, seed=0)
    assert r.cleaning_pct == 0.0 and r.detected == 0 and "no dust detected" in r.reason
    assert r.miss_counts()["filtered"] > 0


def test_unreachable_areas_are_counted_not_raised(small):
    machine, plan = small
    far = dataclasses.replace(PARAMS, approach=ApproachParams(delta=3.0, n_orientations=1))
    r = T.run_trial(machine, plan, params=far, seed=0)
    assert r.n_cleaned == 0 and r.areas > 0
    assert r.miss_counts()["no approach found"] > 0


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="machine"):
        T.run_trial("bench", None)
    with pytest.raises(ValueError, match="seed"):
        T.run_trial(machine_from_mesh(trimesh.creation.box(extents=[1, 1, 1]), name="b"), None, seed=-1)


class _Clock:
    """``time.perf_counter`` running ``rate`` times as fast as the real one."""

    def __init__(self, real, rate: float):
        self.real, self.rate, self.origin = real, rate, real()

    def __call__(self) -> float:
        return self.origin + self.rate * (self.real() - self.origin)


def _table_row(result) -> dict:
    row = result.row()
    row.pop("wall_s")
    return row | {"causes": result.causes.tolist()}


def test_same_row_on_a_slow_or_fast_clock(small, monkeypatch):
    # A loaded machine is a clock that runs fast. No wall-clock cap may change the row: a clock
    # 300x too slow or a huge cap give the same row; a clock 10,000x too fast or a 0.1 ms cap
    # give it too, or raise PlanningTimeout (the cap is a safety net, never a quiet failure).
    import time

    from mavac.planning.rrt import PlanningTimeout

    machine, plan = small
    real = time.perf_counter
    monkeypatch.setattr(time, "perf_counter", _Clock(real, 1 / 300))
    reference = _table_row(T.run_trial(machine, plan, params=PARAMS, seed=3))
    assert reference["cleaned"] > 0
    huge_cap, tiny_cap = (dataclasses.replace(PARAMS, approach=ApproachParams(rrt_time_limit=cap))
                          for cap in (1e6, 1e-4))
    for rate, params in ((1.0, huge_cap), (1e4, PARAMS), (1.0, tiny_cap)):
        monkeypatch.setattr(time, "perf_counter", _Clock(real, rate))
        try:
            assert _table_row(T.run_trial(machine, plan, params=params, seed=3)) == reference, (rate, params.approach)
        except PlanningTimeout as exc:
            assert "time_limit" in str(exc) and params is not huge_cap


@pytest.fixture(scope="module")
def two_spots(box_plan):
    """The box and four poses of its plan over two spots (two each)."""
    machine, plan = box_plan
    ps = plan.pose_set
    idx = np.r_[np.flatnonzero(ps.spot == ps.spot[0])[:2], np.flatnonzero(ps.spot != ps.spot[0])[:2]]
    sub = type(ps)(*(getattr(ps, f.name)[idx] for f in dataclasses.fields(ps)))
    assert len(set(sub.spot.tolist())) == 2
    return machine, dataclasses.replace(plan, pose_set=sub)


@pytest.fixture
def watched(monkeypatch):
    """Lists for the planner calls and the drives (the configuration when the base moves); fails
    the test on any ``reset_q`` after the cell is built (a teleport)."""
    calls, drives = [], []
    real_build, real_drive = T.build_cell, T._Run.drive_to

    def build(*args, **kwargs):
        cell = real_build(*args, **kwargs)

        def teleport(q):
            raise AssertionError("the arm was teleported (reset_q)")

        cell.sim.reset_q = teleport
        return cell

    def drive(self, spot):
        drives.append(self.cell.sim.q())
        return real_drive(self, spot)

    monkeypatch.setattr(T, "build_cell", build)
    monkeypatch.setattr(T._Run, "drive_to", drive)
    return calls, drives


def _failing_planner(monkeypatch, calls, fails):
    """``plan_arm_motion`` that fails (as RRT-Connect would) whenever ``fails(goal, factor)``;
    records (goal, budget factor, seed) of every call in ``calls``."""
    real = T.plan_arm_motion

    def planner(robot, checker, q_start, q_goal, params, *, seed, budget_factor=1):
        calls.append((np.array(q_goal), budget_factor, seed))
        if fails(np.asarray(q_goal), budget_factor):
            return T.Motion(None, False, "iteration budget exhausted", 0.0)
        return real(robot, checker, q_start, q_goal, params, seed=seed, budget_factor=budget_factor)

    monkeypatch.setattr(T, "plan_arm_motion", planner)


def test_failed_fold_is_replanned_then_retraced_never_teleported(two_spots, watched, monkeypatch):
    machine, plan = two_spots
    calls, drives = watched
    home = T.ur10_mobile().q_home
    _failing_planner(monkeypatch, calls, lambda goal, factor: np.allclose(goal, home))
    r = T.run_trial(machine, plan, params=PARAMS, seed=3)
    assert [f for g, f, _ in calls if np.allclose(g, home)] == [1, 10]  # re-planned with 10x the budget
    assert (r.fold_failures, r.folds_retraced, r.poses_skipped) == (1, 1, 0)
    assert r.guards == 4 and r.row()["fold_failures"] == 1 and r.row()["folds_retraced"] == 1
    assert len(drives) == 2
    np.testing.assert_allclose(drives[1], home, atol=0.05)  # folded by retracing, then driven


def test_fold_that_cannot_even_retrace_stops_and_counts(two_spots, watched, monkeypatch):
    machine, plan = two_spots
    calls, drives = watched
    home = T.ur10_mobile().q_home
    _failing_planner(monkeypatch, calls, lambda goal, factor: np.allclose(goal, home))
    monkeypatch.setattr(T._Run, "retrace", lambda self: None)
    r = T.run_trial(machine, plan, params=PARAMS, seed=3)
    assert (r.fold_failures, r.folds_retraced, r.poses_skipped, r.guards) == (1, 0, 2, 2)
    assert len(drives) == 1  # never drove with the arm out
    assert any("could not fold" in w for w in r.warnings)
    assert set(r.causes) <= set(T.CAUSES) | {""}


def test_unreachable_guards_are_counted_and_their_heaps_have_a_cause(two_spots, watched, monkeypatch):
    machine, plan = two_spots
    calls, _ = watched
    guards = plan.poses[:, 3:]
    _failing_planner(monkeypatch, calls, lambda goal, factor: any(np.allclose(goal, q) for q in guards))
    r = T.run_trial(machine, plan, params=PARAMS, seed=3)
    assert [f for _, f, _ in calls].count(10) == 4  # every guard re-planned once with 10x the budget
    assert (r.guards, r.guards_unreachable, r.poses_skipped, r.replanned) == (0, 4, 4, 0)
    assert r.n_cleaned == 0 and r.miss_counts()["guard not reached"] > 0
    assert r.row()["guards_unreachable"] == 4 and r.row()["poses_skipped"] == 4


def test_guard_solved_by_the_larger_budget_is_counted_and_no_two_plans_share_a_seed(two_spots, watched,
                                                                                      monkeypatch):
    from mavac.cleaning import approach as A

    machine, plan = two_spots
    calls, _ = watched
    second = plan.poses[1, 3:]
    _failing_planner(monkeypatch, calls, lambda goal, factor: factor == 1 and np.allclose(goal, second))
    seeds, real = [], A.plan_arm_motion

    def approach_planner(*args, seed, **kwargs):
        seeds.append(seed)
        return real(*args, seed=seed, **kwargs)

    monkeypatch.setattr(A, "plan_arm_motion", approach_planner)
    r = T.run_trial(machine, plan, params=PARAMS, seed=3)
    assert (r.replanned, r.guards_unreachable, r.guards) == (1, 0, 4)
    seeds += [s for *_, s in calls]
    assert len(seeds) > len(calls) and len(set(seeds)) == len(seeds)


def test_summary_and_heap_table_say_what_the_trial_stored(small):
    machine, plan = small
    r = T.run_trial(machine, plan, params=PARAMS, seed=3)
    table = r.heap_table()
    assert list(table.columns) == ["heap", "x", "y", "z", "cleaned", "cause", "seen_by_pose"]
    # the pose that first found a heap: one of the plan's, a heap it found counts as recalled
    seen = table["seen_by_pose"].to_numpy()
    assert ((seen >= -1) & (seen < len(plan.poses))).all() and np.count_nonzero(seen >= 0) == r.recalled > 0
    assert not set(table["cause"][seen >= 0]) & {"never in view", "guard not reached"}
    cameras = plan.world_T_camera[seen[seen >= 0], :3, 3]
    assert (np.linalg.norm(cameras - r.heaps[seen >= 0], axis=1) < T.FAR).all()
    assert len(table) == r.n_heaps and table["heap"].tolist() == list(range(r.n_heaps))
    assert np.array_equal(table[["x", "y", "z"]].to_numpy(), r.heaps)
    assert table["cleaned"].dtype == bool and table["cleaned"].tolist() == r.cleaned.tolist()
    assert (table["cause"] == "").tolist() == table["cleaned"].tolist()
    assert set(table["cause"]) <= {"", *T.CAUSES}
    text = r.summary()
    assert f"{r.n_cleaned} of {r.n_heaps} heaps cleaned ({r.cleaning_pct:.1f} %)" in text
    assert "misses: " in text and "simulated time" in text and "wall time" in text
    for cause, n in r.miss_counts().items():
        assert (f"{cause} {n}" in text) == (n > 0)


def test_summary_and_heap_table_of_a_trial_without_heaps(small):
    _, plan = small
    spire = trimesh.creation.cone(radius=0.2, height=2.0, sections=8)
    r = T.run_trial(machine_from_mesh(spire, name="spire"), plan, params=PARAMS, seed=0)
    assert r.heap_table().empty
    assert list(r.heap_table().columns) == ["heap", "x", "y", "z", "cleaned", "cause", "seen_by_pose"]
    text = r.summary()
    assert "0 of 0 heaps cleaned (0.0 %)" in text and "misses: none" in text and "reason: no heaps" in text


def test_replay_follows_the_trial_clock_its_spots_and_its_heaps(two_spots, tmp_path, monkeypatch):
    import mavac.viz.meshcat_scene as ms

    machine, plan = two_spots
    played, animate = {}, ms.animate
    monkeypatch.setattr(ms, "animate", lambda vis, tracks, **kw: (played.update(kw), animate(vis, tracks, **kw)))
    r = T.run_trial(machine, plan, params=PARAMS, seed=3)
    rp = r.replay
    assert np.all(np.diff(rp.times) >= 0) and rp.times[0] == 0.0
    assert rp.duration == pytest.approx(r.times.sim_time_s, abs=1e-9)
    spots = np.unique(plan.poses[:, :3], axis=0)
    assert all(np.any(np.all(np.isclose(b, spots), axis=1)) for b in np.unique(rp.bases, axis=0))
    assert len(np.unique(rp.bases, axis=0)) == len(spots) > 1  # the replay drives between both spots
    robot = T.ur10_mobile()
    lo, hi = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    assert np.all((rp.qs >= lo - 1e-6) & (rp.qs <= hi + 1e-6))
    assert np.isfinite(rp.cleaned_at).tolist() == r.cleaned.tolist()  # vacuumed = cleaned, heap by heap
    assert np.all((rp.cleaned_at[r.cleaned] > 0) & (rp.cleaned_at[r.cleaned] <= rp.duration))
    page = r.to_html(tmp_path / "replay.html", machine).read_text()
    assert sorted(played["hide_at"]) == sorted(f"heaps/{i}" for i in np.flatnonzero(r.cleaned))
    assert f"{r.cleaning_pct:.1f} % of {r.n_heaps} heaps cleaned" in page
    assert f"cleaned heap, vanishes when vacuumed ({r.n_cleaned})" in page
    for cause, n in r.miss_counts().items():
        assert (f"missed: {cause} ({n})" in page) == (n > 0)


def test_replay_is_refused_without_a_trial_or_for_another_machine(small, tmp_path):
    machine, plan = small
    spire = machine_from_mesh(trimesh.creation.cone(radius=0.2, height=2.0, sections=8), name="spire")
    empty = T.run_trial(spire, plan, params=PARAMS, seed=0)
    assert empty.replay is None
    with pytest.raises(ValueError, match="nothing to replay .no heaps"):
        empty.to_html(tmp_path / "x.html", spire)
    r = T.run_trial(machine, plan, params=PARAMS, seed=3)
    with pytest.raises(ValueError, match="machine must be the trial's machine 'box', got 'spire'"):
        r.to_html(tmp_path / "x.html", spire)
    with pytest.raises(TypeError, match="machine"):
        r.to_html(tmp_path / "x.html", "box")
    assert not list(tmp_path.iterdir())


def test_progress_shows_the_poses_visited_and_the_heaps_cleaned_and_changes_nothing(small, capsys):
    machine, plan = small
    quiet = T.run_trial(machine, plan, params=PARAMS, seed=3)
    assert "guard poses" not in capsys.readouterr().err
    shown = T.run_trial(machine, plan, params=PARAMS, seed=3, progress=True)
    err = capsys.readouterr().err
    assert f"/{len(plan.poses)} " in err and "guard poses" in err
    assert re.search(rf"\d+ of {shown.n_heaps} heaps cleaned", err), err
    assert _table_row(shown) == _table_row(quiet)
    with pytest.raises(TypeError, match="progress must be True or False"):
        T.run_trial(machine, plan, params=PARAMS, progress="yes")


def test_a_robot_other_than_the_plans_is_refused_before_the_simulation(small):
    from mavac.robots.models import puma560

    machine, plan = small
    with pytest.raises(ValueError, match="robot 'puma560' is not the plan's robot 'ur10_mobile'"):
        T.run_trial(machine, plan, robot=puma560())

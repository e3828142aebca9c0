"""A MAVAC online trial end to end on a small machine: deterministic, never leaves a client
connected, and hard scenes give a result with a reason instead of an exception."""

import dataclasses
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
def small():
    """A 1.0 x 0.6 x 0.6 m box and the first three poses of its fast-mode plan."""
    machine = machine_from_mesh(trimesh.creation.box(bounds=[[-0.5, -0.3, 0.0], [0.5, 0.3, 0.6]]), name="box")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_inspection(machine, params=fast_params())
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

"""Causes of unobserved surface (MAVAC plan) in mavac.inspection.unobserved."""

import dataclasses

import numpy as np
import pytest
import trimesh

from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.machines import machine_from_mesh
from mavac.inspection.inspection_plan import plan_from_context, plan_inspection, prepare_offline
from mavac.inspection.unobserved import LOW_COVERAGE, coverage_message, unobserved_causes


def test_a_tall_tower_is_reported_too_high():
    tower = machine_from_mesh(trimesh.creation.box(bounds=[[0, 0, 0], [0.4, 0.4, 4.0]]), name="tower")
    params = dataclasses.replace(fast_params(), nos=dataclasses.replace(fast_params().nos, enabled=False))
    assert params.visibility.method == "raycast"  # the default: the message names it
    with pytest.warns(UserWarning, match=r"coverage is low: C = 0\.\d\d \(raycast visibility\).*too high for the camera"):
        plan = plan_inspection(tower, params=params)
    assert plan.C < LOW_COVERAGE and any("too high" in w for w in plan.warnings)
    ctx = prepare_offline(tower, params=params)
    causes = unobserved_causes(ctx, plan_from_context(ctx))
    top = ctx.points[:, 2] > 3.0
    assert set(causes[top]) == {"too_high"}
    assert set(causes) <= {"observed", "too_high", "too_far", "occluded"}
    assert (causes == "observed").any()


def test_message_only_below_the_threshold():
    causes = np.array(["observed"] * 9 + ["occluded"])
    assert coverage_message(0.9, causes, "raycast") is None
    msg = coverage_message(0.5, causes, "raycast")
    assert "C = 0.50 (raycast visibility)" in msg and "1 of 10" in msg and "1 occluded" in msg

"""Notebook 12, Part 4: each step lifts the limits it names and nothing else, the paper and
ray-casting steps are Parts 1 and 3's trials, detection guards see at least what the paper's
do, and the summary follows from the runs."""

import dataclasses
import math
import warnings

import numpy as np
import pandas as pd
import pytest

from mavac.cleaning.misses import CAUSES
from mavac.experiments import beyond_improved as BI
from mavac.experiments import beyond_online as BO
from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.transforms import se2_to_matrix
from mavac.inspection.inspection_plan import plan_inspection
from mavac.geometry.machines import MILL_BACK, MILL_BODY_SIZE, MILL_SLAB
from mavac.params import CameraParams, DetectionParams, DustParams, OnlineParams
from mavac.robots.kinematics import fk
from mavac.robots.models import TOOL_SPHERE_RADIUS, TOOL_TUBE_LENGTH, ur10_mobile
from mavac.vision.camera import fov_mask


def test_a_heap_spans_the_pinhole_area_and_the_pyramid_far_corner_is_inside_the_fov():
    cam, det, dust = CameraParams(), DetectionParams(), DustParams()
    f = det.width / 2 / math.tan(cam.theta_a)
    # the heap's radius in pixels at 0.5 m, by projecting its rim
    rim = f * dust.radius / 0.5
    assert BI.heap_pixels(0.5, cam, det, dust) == pytest.approx(math.pi * rim**2)
    assert BI.heap_pixels(1.0, cam, det, dust) == pytest.approx(BI.heap_pixels(0.5, cam, det, dust) / 4)
    corner = cam.L_d * np.array([1.0, math.tan(cam.theta_a), math.tan(cam.theta_b)])
    assert np.linalg.norm(corner) == pytest.approx(BI.pyramid_far_distance(cam))
    inside = fov_mask(np.array([0.999 * corner, 1.01 * corner]), np.eye(4), cam)
    assert inside.tolist() == [True, False]


def test_detection_guards_only_drop_the_greedy_threshold_and_refuse_an_undetectable_pyramid():
    params = fast_params()
    out = BI.detection_guard_params(params, OnlineParams())
    assert out.guard.P_g == 0.0 and dataclasses.replace(out, guard=params.guard) == params
    far = dataclasses.replace(params, camera=dataclasses.replace(params.camera, L_d=5.0))
    with pytest.raises(ValueError, match="min_blob_px"):
        BI.detection_guard_params(far, OnlineParams())


def test_detection_guards_see_at_least_what_the_papers_see_with_more_guards(box_plan):
    machine = box_plan[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        paper = plan_inspection(machine, params=fast_params())
        detection = plan_inspection(machine, params=BI.detection_guard_params(fast_params(), OnlineParams()))
    n_guards = [np.count_nonzero(p.pose_set.kind == "guard") for p in (paper, detection)]
    assert n_guards[1] > n_guards[0]
    assert detection.C_guards >= paper.C_guards


def test_concave_approach_widens_eq5_only():
    a = OnlineParams().approach
    c = BI.concave_approach_params(a)
    assert (c.alpha, c.n_orientations) == (BI.CONCAVE_ALPHA, BI.CONCAVE_ORIENTATIONS)
    assert dataclasses.replace(c, alpha=a.alpha, n_orientations=a.n_orientations) == a
    assert BI.improved_params(BI.STEPS["concave_approach"], fast=True).approach == BI.concave_approach_params(
        BI.online_params("paper", fast=True).approach)
    assert BI.improved_params(("raycast", "detection_guards"), fast=True) == BI.online_params("paper", fast=True)
    reach = BI.online_params("paper", fast=True).detection.reach
    assert BI.improved_params(("long_tube",), fast=True).detection.reach == pytest.approx(
        reach + BI.enclosure_tube_length() - TOOL_TUBE_LENGTH)


def test_the_long_tube_reaches_the_enclosures_far_bottom_with_the_camera_outside():
    L, front = BI.enclosure_tube_length(), BI.camera_front(ur10_mobile())
    diagonal = np.hypot(MILL_BODY_SIZE[1] - MILL_BACK - TOOL_SPHERE_RADIUS,
                        MILL_BODY_SIZE[2] - 2 * MILL_SLAB - TOOL_SPHERE_RADIUS)
    assert L - 0.01 < front + diagonal <= L and L > TOOL_TUBE_LENGTH
    assert BI.improved_robot(("long_tube",)).name != ur10_mobile().name == BI.improved_robot(("raycast",)).name


def _tip_to_target(plan, robot) -> np.ndarray:
    guard = plan.pose_set.kind == "guard"
    rows, targets = plan.pose_set.poses[guard], plan.pose_set.target[guard]
    tips = [se2_to_matrix(*r[:3]) @ fk(robot, r[3:], robot.tool_frame) for r in rows]
    return np.linalg.norm(np.array([t[:3, 3] for t in tips]) - plan.points[targets], axis=1)


def test_long_tube_guards_stand_back_so_the_sphere_keeps_the_papers_distance_to_the_target(box_plan):
    machine, _ = box_plan
    long = ur10_mobile(tube_length=BI.enclosure_tube_length())
    params = BI.long_tube_inspection_params(fast_params(), BI.enclosure_tube_length())
    assert params.camera.L_d == pytest.approx(fast_params().camera.L_d + BI.enclosure_tube_length() - TOOL_TUBE_LENGTH)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        paper = plan_inspection(machine, params=fast_params())
        tube = plan_inspection(machine, robot=long, params=params)
    assert tube.robot_name == long.name and np.count_nonzero(tube.pose_set.kind == "guard")
    assert np.median(_tip_to_target(tube, long)) == pytest.approx(np.median(_tip_to_target(paper, ur10_mobile())),
                                                                   abs=0.01)


def test_a_longer_tube_hides_more_of_the_image():
    cam, det = CameraParams(), DetectionParams()
    short, long = (BI.tool_blind_spot(ur10_mobile(tube_length=L), cam, det) for L in (0.3, BI.enclosure_tube_length()))
    assert 0.0 < short < long < 0.5


def test_the_paper_and_raycast_steps_are_parts_1_and_3s_trials_and_every_step_round_trips():
    items = BI.improved_items(scenes=("test_bench",), seeds=(1,), fast=True)
    assert len(items) == len(BI.STEPS) == len(set(items))
    assert items[0] == BO.comparison_items(scenes=("test_bench",), densities=(1.0,), seeds=(1,), fast=True)[0]
    assert items[1] in BO.visibility_items(scenes=("test_bench",), seeds=(1,), fast=True)
    assert [BI.step_of(u) for u in items] == list(BI.STEPS)
    assert items[-1] == ("improved", "test_bench", BI.LIMITS, 1, True) and len(BI.LIMITS) == 4
    ladder = list(BI.STEPS.values())
    assert all(after[:-1] == before for before, after in zip(ladder, ladder[1:]))
    with pytest.raises(ValueError, match="step must be one of"):
        BI.improved_unit("test_bench", 1, "teleport")


@pytest.fixture
def on_the_box(monkeypatch, box_plan):
    machine, plan = box_plan
    params = OnlineParams(dust=DustParams(spacing=0.1))
    monkeypatch.setattr(BO, "load_machine", lambda scene: machine)
    plans = {(): plan}

    def improved_plan(scene, limits, *, fast):  # the box, for the step's robot and parameters
        if limits not in plans:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                full = plan_inspection(machine, robot=BI.improved_robot(limits),
                                       params=BI.improved_inspection_params(limits, fast=True))
            plans[limits] = dataclasses.replace(full, pose_set=full.pose_set.head(3))
        return plans[limits]

    monkeypatch.setattr(BI, "improved_plan", improved_plan)
    monkeypatch.setattr(BI, "_plan_of", lambda unit: improved_plan(unit[1], unit[2], fast=True))
    monkeypatch.setattr(BI, "online_params", lambda reading, *, fast: params)


def test_an_improved_run_counts_every_uncleaned_heap_under_one_cause(on_the_box):
    items = [BI.improved_unit("box", 2, "concave_approach", fast=True)]
    runs = BI.improved_runs(items)
    assert list(runs.columns) == BI.RUN_COLUMNS + list(CAUSES)
    row = runs.iloc[0]
    assert row.step == "concave_approach" and row.heaps > 0
    assert row[list(CAUSES)].sum() == row.heaps - row.cleaned
    # the long tube's plan runs only on the long-tube robot
    with pytest.raises(ValueError, match="is not the plan's robot"):
        BO.run_trial(BO.load_machine("box"), BI.improved_plan("box", BI.LIMITS, fast=True), seed=2)


def _runs() -> pd.DataFrame:
    rows = []
    for step, means in (("paper", (85.0, 75.0)), ("concave_approach", (97.0, 96.0))):
        for scene, mean in zip(("a", "b"), means):
            for seed, noise in zip((1, 2, 3), (-1.0, 0.0, 1.0)):
                rows.append(dict(step=step, scene=scene, seed=seed, C=0.8, guards=30, heaps=100,
                                 cleaned=int(mean + noise), cleaning_pct=mean + noise, sim_time_s=400.0,
                                 **{c: 0 for c in CAUSES}))
    return pd.DataFrame(rows, columns=BI.RUN_COLUMNS + list(CAUSES))


def test_summary_pools_both_scenes_and_meets_the_goal_only_on_every_scene():
    s = BI.improved_summary(_runs().iloc[::-1])
    assert s.step.tolist() == ["paper"] * 3 + ["concave_approach"] * 3
    assert s.scene.tolist()[2::3] == ["both", "both"]
    both = s[s.scene == "both"].set_index("step")
    assert both.cleaning_pct.tolist() == pytest.approx([80.0, 96.5]) and both.trials.tolist() == [6, 6]
    assert s.groupby("step").meets_goal.all().to_dict() == {"concave_approach": True, "paper": False}
    vs = BI.improved_vs_paper(s)
    assert vs.best_step.tolist() == ["concave_approach", "concave_approach"]
    assert dict(zip(vs.scene, vs.ours_best)) == {"a": 97.0, "b": 96.0}


def test_bad_steps_and_seeds_are_refused():
    with pytest.raises(ValueError, match="step must be one of"):
        BI.improved_items(steps=("paper", "teleport"))
    with pytest.raises((TypeError, ValueError), match="seeds"):
        BI.improved_items(seeds=None)

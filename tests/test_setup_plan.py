"""plan_setups end to end on small stains: coverage, uncoverable patches, certificate, errors."""

import dataclasses
import functools
from types import SimpleNamespace

import numpy as np
import pytest

from mavac.geometry.parts import load_part
from mavac.params import SetupPlannerParams, SetupPlanParams
from mavac.robots.models import puma560
from mavac.setups.setup_plan import plan_setups


@functools.lru_cache(maxsize=1)
def robot():
    return puma560(tool_length=SetupPlanParams().reach.tool_length)


def small_stain(name="concave_bowl", step=40, far_patch=False):
    """Every ``step``-th stain patch of a test object's one-region stain (optionally one patch
    10 m away)."""
    part = load_part(name, stain_blobs=(1, 1))
    v, n = part.patch_vertices[::step], part.patch_normals[::step]
    a, p = part.patch_areas[::step], part.passes[::step]
    if far_patch:
        v = np.concatenate([v, v[:1] + [10.0, 0.0, 0.0]])
        n, a, p = np.concatenate([n, n[:1]]), np.concatenate([a, a[:1]]), np.concatenate([p, p[:1]])
    return SimpleNamespace(name=f"{name}_small", patch_vertices=v, patch_normals=n, patch_areas=a, passes=p)


FAST = SetupPlanParams(planner=SetupPlannerParams(t_max=5.0))


def check_plan(plan, n):
    covered = np.zeros(n, bool)
    for new, reach in zip(plan.patches, plan.reachable):
        assert not covered[new].any()  # each patch is cleaned once
        assert set(new) <= set(reach)
        covered[new] = True
    assert np.array_equal(~covered, np.isin(np.arange(n), plan.uncoverable))
    assert len(plan.setups) == len(plan.patches) == len(plan.step_costs)
    assert np.isclose(plan.cost, plan.step_costs.sum())
    assert np.isclose(plan.cost, plan.setup_time_total + plan.execution_time_total)


def test_plan_covers_every_coverable_patch_with_a_certificate():
    part = small_stain()
    plan = plan_setups(part, robot=robot(), params=FAST)
    check_plan(plan, len(part.passes))
    assert plan.n_rfc > 0 and plan.nondominated <= plan.candidates
    assert len(plan.uncoverable) < len(part.passes)
    assert plan.certificate_cost is not None and plan.cost >= plan.certificate_cost - 1e-6
    if plan.status == "optimal":
        assert plan.certificate_gap == pytest.approx(0.0, abs=1e-9)
    assert "setup 1" in plan.summary()


def test_uncoverable_patches_are_listed_not_searched():
    part = small_stain(far_patch=True)
    # the far patch keeps hierarchical sampling refining: two levels bound the run
    params = dataclasses.replace(FAST, sampling=dataclasses.replace(FAST.sampling, max_levels=2))
    plan = plan_setups(part, robot=robot(), params=params)
    far = len(part.passes) - 1
    assert far in set(plan.uncoverable.tolist())
    check_plan(plan, len(part.passes))


def test_empty_stain_gives_an_empty_plan():
    empty = SimpleNamespace(name="empty", patch_vertices=np.zeros((0, 3, 3)), patch_normals=np.zeros((0, 3)),
                            patch_areas=np.zeros(0), passes=np.zeros(0, int))
    plan = plan_setups(empty, robot=robot())
    assert len(plan.setups) == 0 and plan.cost == 0.0 and plan.status == "empty" and plan.n_rfc == 0


def test_plan_is_deterministic_and_milp_matches_dfbnb_without_time_bound():
    part = small_stain(step=60)
    milp = plan_setups(part, robot=robot(), params=dataclasses.replace(FAST, method="milp"))
    again = plan_setups(part, robot=robot(), params=dataclasses.replace(FAST, method="milp"))
    np.testing.assert_array_equal(milp.setups, again.setups)
    assert milp.n_rfc == again.n_rfc
    both = plan_setups(part, robot=robot(), params=dataclasses.replace(
        FAST, method="both", planner=SetupPlannerParams(t_max=None)))
    assert both.status == "optimal"
    assert both.cost == pytest.approx(milp.cost)
    assert both.certificate_gap == pytest.approx(0.0, abs=1e-9)


def test_random_and_uniform_sampling_paths_run():
    part = small_stain(step=80)
    coarse = dataclasses.replace(FAST.space, res_x=0.25, res_y=0.25, res_alpha=np.radians(60))
    for method in ("uniform", "random"):
        params = dataclasses.replace(FAST, space=coarse, sampling_method=method, method="milp",
                                     sampling=dataclasses.replace(FAST.sampling, gd_step_x=0.25, gd_step_y=0.25,
                                                                  gd_step_alpha=np.radians(60)))
        plan = plan_setups(part, robot=robot(), params=params)
        check_plan(plan, len(part.passes))
        if method == "uniform":
            assert plan.n_rfc == 5 * 5 * 6  # alpha 0-300 deg: 360 deg is 0 deg again


def test_bad_parameters_raise_value_errors():
    with pytest.raises(ValueError, match="sampling_method"):
        SetupPlanParams(sampling_method="grid")
    with pytest.raises(ValueError, match="variant"):
        SetupPlanParams(variant="XY")
    with pytest.raises(ValueError, match="cleaning_rate"):
        SetupPlanParams(cleaning_rate=0.0)
    with pytest.raises(ValueError, match="setup_time"):
        SetupPlannerParams(setup_time=-1.0)
    with pytest.raises(ValueError, match="params"):
        plan_setups(small_stain(), robot=robot(), params=SetupPlannerParams())
    bad = small_stain()
    bad.passes = bad.passes[:-1]
    with pytest.raises(ValueError, match="same length"):
        plan_setups(bad, robot=robot())


def _shifted(part, offset, normal=None):
    v = part.patch_vertices + np.asarray(offset, float)
    n = part.patch_normals if normal is None else np.broadcast_to(normal, part.patch_normals.shape).copy()
    return SimpleNamespace(name="moved", patch_vertices=v, patch_normals=n, patch_areas=part.patch_areas,
                           passes=part.passes)


def test_unreachable_share_warns_with_its_cause():
    part = small_stain(far_patch=True)
    params = dataclasses.replace(FAST, sampling=dataclasses.replace(FAST.sampling, max_levels=2))
    with pytest.warns(UserWarning, match=r"of \d+ stain patches \(\d+ % of the stain area\) are unreachable .*"
                                         r"1 too far from the arm"):
        plan = plan_setups(part, robot=robot(), params=params)
    far = list(plan.uncoverable).index(len(part.passes) - 1)
    assert plan.uncoverable_causes[far] == "too_far"
    assert "unreachable" in plan.summary()


def test_no_solution_has_no_certificate_and_says_so():
    part = _shifted(small_stain(step=200), (0.0, 0.0, 5.0))  # 5 m above the table
    with pytest.warns(UserWarning, match="too high for the arm"):
        plan = plan_setups(part, robot=robot(), params=FAST)
    assert plan.status == "no_solution"
    assert plan.certificate_cost is None and plan.certificate_gap is None
    assert set(plan.uncoverable_causes) == {"too_high"}
    text = plan.summary()
    assert "NO SOLUTION" in text and "MILP optimum" not in text and "wrong units" in text


def test_causes_classify_each_left_out_patch():
    from mavac.params import SetupSpaceParams
    from mavac.setups.unreachable import unreachable_causes

    tri = np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.0, 0.01, 0.0]])
    space = SetupSpaceParams(origin_x=0.0, origin_y=0.0, table_z=-0.5)  # table 0.5 m under the shoulder
    grid = np.zeros((1, 3))
    # at the shoulder (inside the reach sphere, no IK), 3 m up, 3 m out, one the arm reaches, and
    # that one again facing down into the table
    v = np.stack([tri + [0, 0, 0.5], tri + [0, 0, 3.5], tri + [3.0, 0, 0.5], tri + [0.3, 0.0, 0.0],
                  tri + [0.3, 0.0, 0.0]])
    n = np.array([[0, 0, 1.0]] * 4 + [[0, 0, -1.0]])
    causes = unreachable_causes(robot(), v, n, space, grid=grid)
    assert causes.tolist() == ["facing_away", "too_high", "too_far", "missed_by_sampling", "below_support"]


def test_the_reach_sphere_test_of_left_out_patches_works_in_blocks():
    # issue 33: one (grid, patches, 3) block of 300 x 200k patches took 5 GB
    from mavac.params import SetupSpaceParams
    from mavac.setups.reach import reach_bound
    from mavac.setups.unreachable import diagnosis_grid, inside_reach_anywhere

    space = SetupSpaceParams()
    part = load_part("concave_bowl")
    bound = reach_bound(robot())
    rng = np.random.default_rng(3)
    wrist = part.patch_vertices[::7] * rng.uniform(1.0, 8.0, (1, 1, 1))  # some out of reach
    wrist = wrist * rng.uniform(0.5, 6.0, (len(wrist), 1, 1))
    grid = diagnosis_grid(space)
    whole = inside_reach_anywhere(wrist, grid, space, bound, chunk=len(wrist))
    assert whole.any() and not whole.all()
    for chunk in (1, 5, 64):
        np.testing.assert_array_equal(inside_reach_anywhere(wrist, grid, space, bound, chunk=chunk), whole)
    with pytest.raises(ValueError, match="chunk"):
        inside_reach_anywhere(wrist, grid, space, bound, chunk=0)


def test_patches_larger_than_the_tool_tip_warn():
    part = small_stain(step=200)
    part.patch_vertices = part.patch_vertices * 1.0
    big = SimpleNamespace(**{**vars(part), "patch_areas": np.full(len(part.passes), 4e-4)})
    with pytest.warns(UserWarning, match="larger than the tool tip"):
        plan = plan_setups(big, robot=robot(), params=FAST)
    assert any("tool tip" in w for w in plan.warnings)


def test_summary_says_when_dfbnb_stops_above_the_proven_optimum():
    part = small_stain(step=8)
    starved = dataclasses.replace(FAST, method="both",
                                  planner=SetupPlannerParams(t_max=None, max_nodes=5, guiding=False))
    plan = plan_setups(part, robot=robot(), params=starved)
    best = plan_setups(part, robot=robot(), params=FAST)
    assert best.status == "optimal" and best.certificate_cost == pytest.approx(best.cost)
    assert "proven optimal" in best.summary()
    assert plan.status == "node_limited" and plan.certificate_cost == pytest.approx(best.cost)
    assert best.cost < plan.cost
    line = plan.summary().splitlines()[1]
    assert line.startswith(f"  DFBnB stopped (node_limited) at {plan.cost:.1f} s") and f"{best.cost:.1f} s" in line
    assert "method 'auto' plans the optimum" in line


def test_paper_params_run_dfbnb_over_every_candidate_with_the_optimum_beside_it():
    paper = SetupPlanParams.paper(seed=3)
    assert paper.method == "both" and paper.planner.reduce is False and paper.seed == 3
    assert SetupPlanParams().method == "auto" and SetupPlanParams().planner.reduce is True

"""Notebook helpers of mavac.experiments.kabir_setups: Fig. 7 diagnosis, the reach-test setup, the
placed setup spaces and the determinism of notebook 08's planner tables."""

import dataclasses
import math

import numpy as np
import pandas as pd

from mavac.experiments import kabir_setups as K
from mavac.params import ReachParams, SamplingParams, SetupPlanParams, SetupSpaceParams
from mavac.setups.sampling import uniform_setups

SPACE = SetupSpaceParams(res_x=0.5, res_y=0.5, res_alpha=math.radians(120))
SAMPLING = dataclasses.replace(SamplingParams(), gd_step_x=0.5, gd_step_y=0.5, gd_step_alpha=math.radians(120))


def toy_baseline():
    """Patch 0 is reached only at x = 0, with patch 1; x = 0.5 reaches 1-5, x = 1 reaches 1-9:
    the absolute round always walks away from patch 0."""
    setups = uniform_setups(SPACE)
    cover = np.zeros((len(setups), 10), dtype=bool)
    for j, (x, _, _) in enumerate(setups):
        cover[j, {0.0: [0, 1], 0.5: [1, 2, 3, 4, 5], 1.0: list(range(1, 10))}[round(x, 1)]] = True
    return K.Baseline("toy", SPACE, setups, cover, np.ones(10), np.ones(10, dtype=int), 0)


def test_absolute_round_walks_away_from_a_rare_patch_and_exhausts_the_grid():
    b = toy_baseline()
    ca = K.exhaustion_diagnosis(b, SAMPLING, variant="CA_XY", seed=0)
    assert not ca["covers_target"] and ca["n_rfc"] == len(b.setups)  # every grid setup drawn
    # x = 0: 3 y values x 3 distinct alpha (0, 120, 240 deg)
    assert ca["missing_patches"] == 1 and ca["grid_setups_reaching_min"] == 9
    assert ca["seeds_reaching_missing"] == 9
    assert ca["kept_after_conservative"] == 9 and ca["kept_after_absolute"] == 0
    c = K.exhaustion_diagnosis(b, SAMPLING, variant="C_XY", seed=0)
    assert c["covers_target"] and c["missing_patches"] == 0 and c["kept_after_absolute"] is None


def test_contrast_setup_reaches_about_half_of_the_stain():
    b = toy_baseline()
    j = np.flatnonzero(np.all(b.setups == K.contrast_setup(b), axis=1))[0]
    assert b.cover[j].sum() == 5  # x = 0.5: half of the ten coverable patches


def _fast_planner_tables():
    """Notebook 08's Tables V and VI in fast mode (its settings, its calls)."""
    res = K.GRID_RESOLUTION["fast"]
    space = dataclasses.replace(SetupSpaceParams(), res_x=res[0], res_y=res[1], res_alpha=res[2])
    sampling = dataclasses.replace(SamplingParams(), gd_step_x=res[0], gd_step_y=res[1], gd_step_alpha=res[2])
    baselines, spaces = K.placed_baselines(K.PLANNER_OBJECTS, space, ReachParams(),
                                           wide_resolution=K.WIDE_RESOLUTIONS["fast"], n_jobs=1)
    instances = {name: K.planner_instance(baselines[name], ReachParams(), sampling) for name in K.PLANNER_OBJECTS}
    rate, nodes = SetupPlanParams().cleaning_rate, K.PLANNER_MAX_NODES["fast"]
    return (K.table5(instances, rate, nodes, setup_time=60.0),
            K.table6(instances, rate, nodes, setup_times=(0, 60, 3000)).drop(columns="seconds"), spaces)


def test_notebook08_planner_tables_are_the_same_twice_and_flag_their_rows():
    t5a, t6a, spaces = _fast_planner_tables()
    t5b, t6b, _ = _fast_planner_tables()
    pd.testing.assert_frame_equal(t5a, t5b)
    pd.testing.assert_frame_equal(t6a, t6b)
    for t in (t5a, t6a):
        assert {"timed_out", "node_limited", "finished"} <= set(t.columns)
        assert not t.timed_out.any() and (t.finished == ~t.node_limited).all()
        assert (t.nodes <= K.PLANNER_MAX_NODES["fast"]).all()
    assert set(t6a.cost_model) == {"fixed", "remaining"}
    # the placed boxes start on the table side of the robot and hold the setups that reach
    assert (spaces.x_lo >= 0).all() and (spaces.wide_reaching > 0).all()
    exact = t6a[(t6a.bound == "lb") & (t6a.algorithm == 2) & t6a.finished]
    assert len(exact) and np.allclose(exact.gap, 0.0)


def test_min_cover_size_equals_brute_force():
    from mavac.planning.setcover import brute_force_setup_cover

    rng = np.random.default_rng(8)
    sizes = set()
    for _ in range(200):
        m, n = int(rng.integers(1, 14)), int(rng.integers(1, 40))
        cover = rng.random((m, n)) < rng.uniform(0.05, 0.5)
        best = len(brute_force_setup_cover(cover, np.ones(m))[0]) if cover.any() else 0
        assert K.min_cover_size(cover) == best
        sizes.add(best)
    assert {1, 2, 3, 4} <= sizes  # every branch of min_cover_size ran


def test_min_cover_size_asks_the_milp_when_the_proof_runs_out_of_nodes(monkeypatch):
    from mavac.planning.certified import certified_cover
    from mavac.planning.setcover import brute_force_setup_cover

    calls = []

    def unproven(cover, costs):
        calls.append(len(cover))
        return dataclasses.replace(certified_cover(cover, costs), status="node_limited")

    monkeypatch.setattr(K, "certified_cover", unproven)
    rng = np.random.default_rng(8)
    for _ in range(200):
        m, n = int(rng.integers(1, 14)), int(rng.integers(1, 40))
        cover = rng.random((m, n)) < rng.uniform(0.05, 0.5)
        best = len(brute_force_setup_cover(cover, np.ones(m))[0]) if cover.any() else 0
        assert K.min_cover_size(cover) == best
    assert calls  # the proof was asked, and refused, at least once


def test_exhaustion_diagnosis_equals_the_seed_by_seed_descent():
    """The map-based diagnosis keeps exactly the seeds that gradient_descent, run seed by seed
    (the reference), keeps after each round, on a random grid whose CA runs exhaust it."""
    from mavac.setups.reach import CountingReach, lookup_reach
    from mavac.setups.sampling import gradient_descent, random_sampling, variant_plan

    rng = np.random.default_rng(4)
    setups = uniform_setups(SPACE)
    cover = rng.random((len(setups), 40)) < 0.15
    b = K.Baseline("random", SPACE, setups, cover, np.ones(40), np.ones(40, dtype=int), 0)
    for variant in ("CA_XY", "C_XYa", "CA_XY_a"):
        got = K.exhaustion_diagnosis(b, SAMPLING, variant=variant, seed=1)
        reach = CountingReach(lookup_reach(b.setups, b.cover))
        run = random_sampling(reach, b.space, SAMPLING, variant=variant, seed=1, target=b.coverable)
        missing = np.flatnonzero(b.coverable & ~run.cover.any(axis=0))
        assert got["n_rfc"] == run.n_rfc and got["missing_patches"] == len(missing)
        rounds, _ = variant_plan(variant)
        kept = dict.fromkeys(rounds, 0)
        for j in np.flatnonzero(b.cover[:, missing].any(axis=1)):
            g = gradient_descent(reach, b.setups[j], variant, b.space, SAMPLING, seed_cover=b.cover[j])
            for name, end in zip(rounds, g.round_ends):
                kept[name] += bool(reach(end[None])[0][missing][b.cover[j, missing]].all())
        assert got["kept_after_conservative"] == kept["conservative"]
        assert got["kept_after_absolute"] == kept.get("absolute")


class _AnalyticBaseline(K.Baseline):
    """A baseline whose reach test is a formula (a disc of reach around (0.5 m, 0.5 m) over
    patch points of a 1 m x 0.6 m part), so hierarchical levels off its grid have answers."""

    def reach(self, reach_params):
        from mavac.setups.reach import lookup_reach

        return lookup_reach(self.setups, self.cover, fallback=disc_reach)


def disc_reach(setups):
    pts = np.random.default_rng(0).uniform(-0.5, 0.5, (30, 2)) * [1.0, 0.6]
    c, s = np.cos(setups[:, 2:]), np.sin(setups[:, 2:])
    wx = setups[:, :1] + c * pts[:, 0] - s * pts[:, 1]
    wy = setups[:, 1:2] + s * pts[:, 0] + c * pts[:, 1]
    return (wx - 0.5) ** 2 + (wy - 0.5) ** 2 < 0.3**2


def test_table3_rows_are_the_runs_of_each_variant_alone():
    """Table III's variants share one reach test per object (SharedReach): each row is still
    the run of hierarchical_sampling with its own reach test, n_rfc included."""
    from mavac.setups.reach import CountingReach
    from mavac.setups.sampling import VARIANTS, hierarchical_sampling

    space = SetupSpaceParams(res_x=0.25, res_y=0.25, res_alpha=math.radians(60))
    sampling = dataclasses.replace(SamplingParams(), gd_step_x=0.25, gd_step_y=0.25,
                                   gd_step_alpha=math.radians(60), max_levels=5)
    setups = uniform_setups(space)
    b = _AnalyticBaseline("disc", space, setups, disc_reach(setups), np.ones(30), np.ones(30, dtype=int), 0)
    got = K.table3({"disc": b}, ReachParams(), sampling)
    assert list(got.variant) == list(VARIANTS)
    for row in got.itertuples():
        res = hierarchical_sampling(CountingReach(b.reach(None)), space, sampling, variant=row.variant,
                                    target=b.coverable)
        assert (row.setups, row.level, row.n_rfc, row.covers_target) == (
            K.min_cover_size(res.nondominated_cover), res.level, res.n_rfc, res.covers_target)
    assert got.level.max() >= 4  # levels off the 0.25 m x 60 deg grid were asked (0.125 m, 30 deg)

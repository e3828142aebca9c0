"""Candidate-setup sampling and gradient descent (Kabir Sec. IV) on a toy reach function."""

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from mavac.params import SamplingParams, SetupSpaceParams
from mavac.setups import sampling as S


def toy_reach(n=60, seed=0, radius=0.45, centre=(0.5, 0.5)):
    """Patches at random part-frame points; reachable when inside a disc around ``centre``
    after placing the part at (x, y) rotated by alpha (mimics a robot workspace)."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-0.5, 0.5, (n, 2)) * np.array([1.0, 0.6])
    c = np.asarray(centre)

    def reach(setups):
        setups = np.asarray(setups, float)
        ca, sa = np.cos(setups[:, 2]), np.sin(setups[:, 2])
        wx = setups[:, :1] + ca[:, None] * pts[:, 0] - sa[:, None] * pts[:, 1]
        wy = setups[:, 1:2] + sa[:, None] * pts[:, 0] + ca[:, None] * pts[:, 1]
        return (wx - c[0]) ** 2 + (wy - c[1]) ** 2 < radius**2

    return reach


SPACE = SetupSpaceParams()
COARSE_SPACE = dataclasses.replace(SPACE, res_x=0.1, res_y=0.1, res_alpha=math.radians(30))
SAMP = SamplingParams()
COARSE_SAMP = dataclasses.replace(SAMP, gd_step_x=0.1, gd_step_y=0.1, gd_step_alpha=math.radians(30))


def test_paper_grid_holds_each_pose_once():
    # the paper's 16,317 = 21 x 21 x 37 counts alpha = 0 and alpha = 360 deg both: one pose
    xs, ys, alphas = S.grid_axes(SPACE)
    assert (len(xs), len(ys), len(alphas)) == (21, 21, 36)
    grid = S.uniform_setups(SPACE)
    assert grid.shape == (15876, 3)
    assert grid[:, 0].min() == 0.0 and math.isclose(grid[:, 0].max(), 1.0)
    assert math.isclose(grid[:, 2].max(), 2 * math.pi - math.radians(10))
    assert len(set(S.setup_keys(grid))) == len(grid)


def _distinct_poses(grid):
    """Setups as poses: alpha modulo 2 pi, rounded."""
    a = np.mod(grid[:, 2], 2 * math.pi)
    a[np.isclose(a, 2 * math.pi)] = 0.0
    return {tuple(np.round([x, y, t], 9)) for x, y, t in zip(grid[:, 0], grid[:, 1], a)}


@pytest.mark.parametrize("res_alpha_deg", [10, 30, 90, 120])
def test_no_grid_has_duplicate_setups(res_alpha_deg):
    grid = S.uniform_setups(SPACE, (0.25, 0.5, math.radians(res_alpha_deg)))
    assert len(_distinct_poses(grid)) == len(grid)


def test_level_one_is_3_by_3_by_4_distinct_setups_and_levels_halve_one_axis_at_a_time():
    coarse = S.coarse_resolution(SPACE, SAMP)
    level1 = S.uniform_setups(SPACE, S.hierarchy_resolution(coarse, 1))
    assert len(level1) == 36 and len(_distinct_poses(level1)) == 36
    np.testing.assert_allclose(np.unique(level1[:, 2]), np.radians([0, 90, 180, 270]))
    np.testing.assert_allclose(np.unique(level1[:, 0]), [0.0, 0.5, 1.0])
    np.testing.assert_allclose(S.hierarchy_resolution(coarse, 2), coarse * [0.5, 1, 1])
    np.testing.assert_allclose(S.hierarchy_resolution(coarse, 3), coarse * [0.5, 0.5, 1])
    np.testing.assert_allclose(S.hierarchy_resolution(coarse, 4), coarse * 0.5)
    np.testing.assert_allclose(S.hierarchy_resolution(coarse, 5), coarse * [0.25, 0.5, 0.5])
    wide = dataclasses.replace(SPACE, x_max=2.6, y_max=1.3)  # the box's own size sets the step
    np.testing.assert_allclose(S.coarse_resolution(wide, SAMP)[:2], [1.3, 0.65])


def test_bad_inputs_raise_value_errors_naming_the_parameter():
    with pytest.raises(ValueError, match="res_x"):
        SetupSpaceParams(res_x=0.0)
    with pytest.raises(ValueError, match="res_alpha"):
        SetupSpaceParams(res_alpha=-1.0)
    with pytest.raises(ValueError, match="res_y"):
        S.uniform_setups(SPACE, (0.05, 0.0, 0.1))
    with pytest.raises(ValueError, match="coarse_points_x"):
        SamplingParams(coarse_points_x=0)
    with pytest.raises(ValueError, match="gd_step_alpha"):
        SamplingParams(gd_step_alpha=-0.1)
    with pytest.raises(ValueError, match="repetitions"):
        SamplingParams(repetitions=0)
    with pytest.raises(ValueError, match="variant"):
        S.hierarchical_sampling(toy_reach(), SPACE, SAMP, variant="XY")
    with pytest.raises(ValueError, match="scoring"):
        S.score(np.ones(3, bool), np.ones((1, 3), bool), "greedy")
    with pytest.raises(ValueError, match="x_min"):
        SetupSpaceParams(x_min=2.0)


def test_scores_follow_section_iv_b():
    p1 = np.array([1, 1, 0, 0], bool)
    p2 = np.array([[1, 1, 1, 0], [1, 0, 1, 1], [0, 0, 0, 0]], bool)
    np.testing.assert_array_equal(S.score(p1, p2, "absolute"), [3, 3, 0])
    # superset -> |P2|; otherwise |P1 & P2|
    np.testing.assert_array_equal(S.score(p1, p2, "conservative"), [3, 1, 0])


def test_counting_reach_counts_each_setup_once():
    calls = []
    base = toy_reach()

    def reach(s):
        calls.append(len(s))
        return base(s)

    counted = S.CountingReach(reach)
    grid = S.uniform_setups(COARSE_SPACE)[:50]
    a = counted(grid)
    b = counted(np.concatenate([grid[:10], grid[:10]]))
    assert counted.n_rfc == 50 and sum(calls) == 50
    np.testing.assert_array_equal(a[:10], b[:10])
    np.testing.assert_array_equal(a, base(grid))


def test_lookup_reach_reproduces_the_reach_function_on_the_grid():
    reach = toy_reach()
    grid = S.uniform_setups(COARSE_SPACE)
    look = S.lookup_reach(grid, reach(grid))
    pick = grid[::7]
    np.testing.assert_array_equal(look(pick), reach(pick))
    with pytest.raises(KeyError):
        look(np.array([[0.123, 0.456, 0.789]]))
    fallback = S.lookup_reach(grid, reach(grid), fallback=reach)
    off = np.array([[0.123, 0.456, 0.789]])
    np.testing.assert_array_equal(fallback(off), reach(off))


@pytest.mark.parametrize("variant", S.GD_VARIANTS)
def test_gradient_descent_never_decreases_and_conservative_keeps_the_seed(variant):
    reach = S.CountingReach(toy_reach(n=80, seed=3))
    rng = np.random.default_rng(1)
    grid = S.uniform_setups(SPACE)
    for j in rng.choice(len(grid), 12, replace=False):
        seed_cover = reach(grid[j][None])[0]
        g = S.gradient_descent(reach, grid[j], variant, SPACE, SAMP)
        assert np.all(np.diff(g.path_scores) > 0)
        assert g.covered.sum() >= seed_cover.sum()
        np.testing.assert_array_equal(g.covered, reach(g.setup[None])[0])
        # round 1 is conservative in every variant: its end covers the seed's patches
        end1 = reach(g.round_ends[0][None])[0]
        assert np.all(end1[seed_cover])
        if variant.startswith("C_"):
            assert np.all(g.covered[seed_cover])


def test_absolute_round_reaches_a_local_maximum():
    reach = S.CountingReach(toy_reach(n=80, seed=5))
    g = S.gradient_descent(reach, np.array([0.0, 1.0, 0.0]), "CA_XY", SPACE, SAMP)
    nb = S.neighbours(g.setup, (0, 1), S.gd_step(SAMP), SPACE)
    assert reach(nb).sum(axis=1).max() <= g.covered.sum()


def test_neighbours_wrap_alpha_and_stay_in_range():
    step = S.gd_step(SAMP)
    nb = S.neighbours(np.array([0.0, 1.0, 0.0]), (0, 1, 2), step, SPACE)
    assert len(nb) == 4  # x-1 and y+1 are outside [0, 1]
    assert np.all((nb[:, :2] >= 0) & (nb[:, :2] <= 1))
    assert np.isclose(nb[:, 2].max(), 2 * math.pi - step[2])


def test_uniform_sampling_counts_one_call_per_setup_and_removes_dominated():
    res = S.uniform_sampling(toy_reach(), COARSE_SPACE)
    grid = S.uniform_setups(COARSE_SPACE)
    assert res.n_rfc == len(grid)
    nd = res.nondominated_cover
    for i in range(len(nd)):
        for j in range(len(nd)):
            if i != j:
                assert not np.all(nd[j] <= nd[i])
    np.testing.assert_array_equal(nd.any(axis=0), res.cover.any(axis=0))


@pytest.mark.parametrize("variant", ["none", "CA_XY", "C_XYa"])
def test_hierarchical_sampling_covers_target_and_is_deterministic(variant):
    reach = toy_reach(n=60, seed=2)
    target = S.uniform_sampling(reach, COARSE_SPACE).cover.any(axis=0)
    a = S.hierarchical_sampling(reach, SPACE, SAMP, variant=variant, target=target)
    b = S.hierarchical_sampling(reach, SPACE, SAMP, variant=variant, target=target)
    assert a.covers_target == np.all(a.cover.any(axis=0)[target])
    np.testing.assert_array_equal(a.setups, b.setups)
    assert a.n_rfc == b.n_rfc and a.level == b.level
    if variant == "none":
        assert a.n_rfc == a.samples
        level1 = len(S.uniform_setups(SPACE, S.hierarchy_resolution(S.coarse_resolution(SPACE, SAMP), 1)))
        assert a.level > 1 or a.n_rfc == level1


@pytest.mark.parametrize("variant", ["none", "CA_XY"])
def test_random_sampling_covers_target_deterministically(variant):
    reach = toy_reach(n=60, seed=4)
    grid = S.uniform_setups(SPACE)
    look = S.lookup_reach(grid, reach(grid))
    target = look(grid).any(axis=0)
    a = S.random_sampling(look, SPACE, SAMP, variant=variant, seed=7, target=target)
    b = S.random_sampling(look, SPACE, SAMP, variant=variant, seed=7, target=target)
    c = S.random_sampling(look, SPACE, SAMP, variant=variant, seed=8, target=target)
    assert a.covers_target
    np.testing.assert_array_equal(a.setups, b.setups)
    assert a.n_rfc == b.n_rfc
    assert not np.array_equal(a.seeds, c.seeds)
    # the last seed completed the cover
    assert a.n_rfc >= a.samples


def test_random_sampling_off_grid():
    reach = toy_reach(n=40, seed=6)
    samp = dataclasses.replace(SAMP, random_on_grid=False, max_random_samples=500)
    res = S.random_sampling(reach, SPACE, samp, variant="C_XY", seed=1)
    assert res.samples <= 500
    assert res.covers_target == bool(res.cover.any(axis=0).all())


def test_alpha_steps_wrap_onto_the_grid_start():
    # 300 + 60 deg lands on 0 deg exactly (a float just under 360 deg would be a setup off the grid)
    space = dataclasses.replace(SPACE, res_alpha=math.radians(60))
    grid = S.uniform_setups(space)
    keys = set(S.setup_keys(grid))
    last = grid[np.isclose(grid[:, 2], math.radians(300))][0]
    nb = S.neighbours(last, (2,), np.array([0.25, 0.25, math.radians(60)]), space)
    assert all(k in keys for k in S.setup_keys(nb))


# ---------------------------------------------------------------- end-point map


def _reference_descents(grid, cover, space, samp, variant, seeds):
    """gradient_descent from each of ``seeds`` (grid rows) on a grid lookup: end rows, end
    setups, round-end rows and the rows each descent reach-tests (its own CountingReach, seed
    included)."""
    look = S.lookup_reach(grid, cover)
    row = {k: j for j, k in enumerate(S.setup_keys(grid))}
    ends, setups, round_ends, tested = [], [], [], []
    for j in seeds:
        reach = S.CountingReach(look)
        g = S.gradient_descent(reach, grid[j], variant, space, samp, seed_cover=reach(grid[j][None])[0])
        ends.append(row[S.setup_keys(g.setup[None])[0]])
        setups.append(g.setup)
        round_ends.append([row[k] for k in S.setup_keys(g.round_ends)])
        tested.append(sorted(row[k] for k in reach._memo))
        assert reach.n_rfc == len(tested[-1])
    return np.array(ends), np.array(setups), round_ends, tested


def _assert_map_is_gradient_descent(emap, grid, cover, space, samp, every=1):
    seeds = range(0, len(grid), every)
    ends, setups, round_ends, tested = _reference_descents(grid, cover, space, samp, emap.variant, seeds)
    np.testing.assert_array_equal(emap.end[seeds], ends)
    np.testing.assert_array_equal(emap.end_setup[seeds], setups)  # bit for bit, not only the same key
    assert emap.round_ends[seeds].tolist() == round_ends
    for j, t in zip(seeds, tested):
        assert emap.tested[emap.tested_ptr[j]:emap.tested_ptr[j + 1]].tolist() == t


def _assert_same_runs(emap, grid, cover, space, samp, seeds, target):
    """random_sampling_on_map gives random_sampling's result on the grid lookup."""
    exhausted = 0
    for seed in seeds:
        ref = S.random_sampling(S.lookup_reach(grid, cover), space, samp, variant=emap.variant, seed=seed,
                                target=target)
        fast = S.random_sampling_on_map(emap, seed=seed, target=target)
        for name in ("setups", "cover", "nondominated", "seeds"):
            np.testing.assert_array_equal(getattr(fast, name), getattr(ref, name), err_msg=name)
        assert (fast.n_rfc, fast.samples, fast.covers_target, fast.level) == \
            (ref.n_rfc, ref.samples, ref.covers_target, ref.level)
        exhausted += not ref.covers_target
    return exhausted


def _random_cover(m, n, seed, p=0.5):
    return np.random.default_rng(seed).random((m, n)) < p


# a small grid (5 x 5 x 6 = 150), a half-circle alpha range that does not wrap, and a grid with
# unequal x and y steps whose upper y bound is off the grid (a step from y = 1 m leaves the range)
SMALL_SPACE = dataclasses.replace(SPACE, res_x=0.25, res_y=0.25, res_alpha=math.radians(60))
HALF_SPACE = dataclasses.replace(SPACE, alpha_max=math.pi, res_x=0.5, res_y=0.5, res_alpha=math.radians(30))
ODD_SPACE = dataclasses.replace(SPACE, x_max=0.9, y_max=1.1, res_x=0.3, res_y=0.25, res_alpha=math.radians(60))
GRID_CASES = {
    "toy landscape": (SMALL_SPACE, lambda grid: toy_reach(n=70, seed=3)(grid)),
    "random covers": (SMALL_SPACE, lambda grid: _random_cover(len(grid), 10, 1)),
    "sparse random covers": (SMALL_SPACE, lambda grid: _random_cover(len(grid), 40, 2, p=0.1)),
    "half circle": (HALF_SPACE, lambda grid: toy_reach(n=50, seed=4)(grid)),
    "odd bounds": (ODD_SPACE, lambda grid: _random_cover(len(grid), 16, 5, p=0.3)),
}


def _steps_of(space):
    return dataclasses.replace(SAMP, gd_step_x=space.res_x, gd_step_y=space.res_y, gd_step_alpha=space.res_alpha)


@pytest.mark.parametrize("case", GRID_CASES)
def test_endpoint_map_is_gradient_descent_seed_by_seed(case):
    space, make_cover = GRID_CASES[case]
    samp, grid = _steps_of(space), S.uniform_setups(space)
    cover = make_cover(grid)
    maps = S.endpoint_maps(grid, cover, space, samp)
    assert list(maps) == list(S.VARIANTS)
    for variant, emap in maps.items():
        _assert_map_is_gradient_descent(emap, grid, cover, space, samp)
        _assert_same_runs(emap, grid, cover, space, samp, seeds=range(2), target=cover.any(axis=0))


def test_endpoint_map_on_a_real_reach_grid():
    from mavac.experiments import kabir_setups as K
    from mavac.params import ReachParams

    res = K.GRID_RESOLUTION["fast"]
    space = dataclasses.replace(SPACE, res_x=res[0], res_y=res[1], res_alpha=res[2])
    b = K.placed_baselines(("sine",), space, ReachParams(), wide_resolution=K.WIDE_RESOLUTIONS["fast"],
                           n_jobs=1)[0]["sine"]
    samp = _steps_of(b.space)
    exhausted = 0
    for emap in S.endpoint_maps(b.setups, b.cover, b.space, samp).values():
        # every third seed here; the runs below draw nearly every seed's end
        _assert_map_is_gradient_descent(emap, b.setups, b.cover, b.space, samp, every=3)
        exhausted += _assert_same_runs(emap, b.setups, b.cover, b.space, samp, seeds=(0,), target=b.coverable)
    assert exhausted == 3  # each CA variant walks away from a patch and draws the whole grid


def test_random_sampling_on_map_exhausts_the_grid_like_random_sampling():
    # patch 0 is reached only at x = 0, with patch 1; x = 0.25 reaches 1-3, x >= 0.5 reaches
    # 1-5: the absolute round walks away from patch 0, the conservative one keeps it
    grid = S.uniform_setups(SMALL_SPACE)
    cover = np.zeros((len(grid), 6), dtype=bool)
    for j, x in enumerate(grid[:, 0]):
        cover[j, [0, 1] if x < 0.1 else [1, 2, 3] if x < 0.4 else [1, 2, 3, 4, 5]] = True
    samp = _steps_of(SMALL_SPACE)
    maps = S.endpoint_maps(grid, cover, SMALL_SPACE, samp, ("C_XY", "CA_XY"))
    assert _assert_same_runs(maps["CA_XY"], grid, cover, SMALL_SPACE, samp, range(3), None) == 3
    assert S.random_sampling_on_map(maps["CA_XY"], seed=0).samples == len(grid)
    assert _assert_same_runs(maps["C_XY"], grid, cover, SMALL_SPACE, samp, range(3), None) == 0
    # an empty target is covered by the first seed
    assert S.random_sampling_on_map(maps["CA_XY"], seed=0, target=np.zeros(6, bool)).samples == 1


def test_endpoint_map_looks_up_candidates_whose_key_is_not_the_tables(monkeypatch):
    # a path's rounding could move a candidate's key off the table's: every slot is looked up
    space, make_cover = GRID_CASES["toy landscape"]
    samp, grid = _steps_of(space), S.uniform_setups(space)
    cover = make_cover(grid)
    want = S.endpoint_maps(grid, cover, space, samp)
    table = S._table

    def shifted(g, setups, axes):
        t = table(g, setups, axes)
        return dataclasses.replace(t, keys=t.keys + 1, grows=~t.grows)

    monkeypatch.setattr(S, "_table", shifted)
    for variant, emap in S.endpoint_maps(grid, cover, space, samp).items():
        for name in ("end", "end_setup", "round_ends", "tested_ptr", "tested"):
            np.testing.assert_array_equal(getattr(emap, name), getattr(want[variant], name), err_msg=name)


def test_endpoint_map_refuses_steps_off_the_grid_and_bad_variants():
    grid = S.uniform_setups(SMALL_SPACE)
    cover = toy_reach(n=20)(grid)
    off = dataclasses.replace(_steps_of(SMALL_SPACE), gd_step_x=0.2)
    with pytest.raises(KeyError):
        S.random_sampling(S.lookup_reach(grid, cover), SMALL_SPACE, off, variant="C_XY")
    with pytest.raises(KeyError, match="leaves the grid"):
        S.endpoint_maps(grid, cover, SMALL_SPACE, off, ("C_XY",))
    with pytest.raises(ValueError, match="variant"):
        S.endpoint_maps(grid, cover, SMALL_SPACE, SAMP, ("XY",))
    with pytest.raises(ValueError, match="one row per setup"):
        S.endpoint_maps(grid, cover[1:], SMALL_SPACE, SAMP)


def test_random_runs_give_the_rows_of_random_sampling():
    from mavac.experiments import kabir_setups as K

    grid = S.uniform_setups(SMALL_SPACE)
    cover = toy_reach(n=30, seed=8)(grid)
    b = K.Baseline("toy", SMALL_SPACE, grid, cover, np.ones(30), np.ones(30, dtype=int))
    samp = _steps_of(SMALL_SPACE)
    runs = K.random_runs({"toy": b}, samp, variants=("C_XY", "CA_XYa"), repetitions=3, chunk=2, n_jobs=1)
    best = K.min_cover_size(cover[S.nondominated(cover)])
    ref = []
    for v in ("C_XY", "CA_XYa"):
        for seed in range(3):
            res = S.random_sampling(S.lookup_reach(grid, cover), SMALL_SPACE, samp, variant=v, seed=seed,
                                    target=b.coverable)
            size = K.min_cover_size(res.nondominated_cover)
            ref.append(dict(object="toy", variant=v, seed=seed, n_rfc=res.n_rfc, samples=res.samples,
                            candidates=len(res.setups), nondominated=len(res.nondominated),
                            covers_target=res.covers_target, setups=size, optimal_setups=best,
                            optimal=res.covers_target and size == best))
    pd.testing.assert_frame_equal(runs, pd.DataFrame(ref))
    shuffled = dataclasses.replace(b, setups=grid[::-1].copy(), cover=cover[::-1].copy())
    with pytest.raises(ValueError, match="uniform_setups"):
        K.random_runs({"toy": shuffled}, samp, repetitions=1)

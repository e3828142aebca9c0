"""Setup planner (Kabir Sec. V): DFBnB (Algorithms 1-5) against brute force and the MILP certificate."""

import dataclasses
import math
import time
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mavac.params import SetupPlannerParams
from mavac.planning import setcover
from mavac.planning.iess import n_repeat_recommended
from mavac.planning.setcover import (
    brute_force_setup_cover,
    cleaning_rate,
    dfbnb_setup_cover,
    execution_order,
    execution_time_area_passes,
    milp_remaining_cover,
    milp_setup_cover,
    setup_costs_from_times,
    solve_setup_cover,
)

P = SetupPlannerParams(t_max=None, max_nodes=None)  # no bound: the property tests compare optima


@st.composite
def instances(draw, max_m=12, max_n=20):
    """Random covers with <= max_m setups, <= max_n patches, random positive costs and areas."""
    m = draw(st.integers(1, max_m))
    n = draw(st.integers(0, max_n))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    cover = rng.random((m, n)) < rng.uniform(0.1, 0.7)
    costs = rng.uniform(0.5, 20.0, m)
    area = rng.uniform(0.1, 2.0, n)
    return cover, costs, area


def is_cover(cover, chosen):
    target = cover.any(axis=0)
    got = cover[np.asarray(chosen, int)].any(axis=0) if len(chosen) else np.zeros_like(target)
    return np.array_equal(got, target)


def min_cardinality(cover):
    return len(brute_force_setup_cover(cover, np.ones(cover.shape[0]))[0])


@settings(max_examples=80, deadline=None)
@given(instances())
def test_dfbnb_equals_brute_force_and_milp(inst):
    cover, costs, area = inst
    _, bf = brute_force_setup_cover(cover, costs)
    mi = milp_setup_cover(cover, costs)
    assert mi.optimal and mi.cost == pytest.approx(bf, rel=1e-9, abs=1e-12)
    assert is_cover(cover, mi.setups)
    for guiding in (True, False):
        res = dfbnb_setup_cover(cover, costs, patch_area=area, params=dataclasses.replace(P, guiding=guiding))
        assert not res.timed_out
        assert res.cost == pytest.approx(bf, rel=1e-9, abs=1e-12)
        assert is_cover(cover, res.setups)
        assert len(set(res.setups.tolist())) == len(res.setups)


@settings(max_examples=40, deadline=None)
@given(instances(max_m=7, max_n=12))
def test_without_pruning_same_optimum_more_nodes(inst):
    cover, costs, area = inst
    _, bf = brute_force_setup_cover(cover, costs)
    for guiding in (True, False):
        on = dfbnb_setup_cover(cover, costs, patch_area=area, params=dataclasses.replace(P, guiding=guiding))
        off = dfbnb_setup_cover(cover, costs, patch_area=area,
                                params=dataclasses.replace(P, guiding=guiding, pruning=False))
        assert off.cost == pytest.approx(bf, rel=1e-9, abs=1e-12)
        # Pruning only cuts subtrees of the same depth-first tree.
        assert off.node_expansions >= on.node_expansions


def test_pruning_off_expands_more_nodes():
    rng = np.random.default_rng(5)
    cover = rng.random((7, 16)) < 0.5
    cover[:, ~cover.any(0)] = True
    costs = rng.uniform(1, 5, 7)
    on = dfbnb_setup_cover(cover, costs, params=P)
    off = dfbnb_setup_cover(cover, costs, params=dataclasses.replace(P, pruning=False))
    assert off.node_expansions > on.node_expansions
    assert off.cost == pytest.approx(on.cost)


@settings(max_examples=40, deadline=None)
@given(instances(max_m=10, max_n=16))
def test_algorithm4_lb_finds_cheapest_minimum_size_cover(inst):
    """With N_repeat large, IESS = minimum cover size q; Alg. 4 + eq. 2 is then exact over
    covers of at most q setups (Sec. V-B1: it guarantees the minimum setup size)."""
    cover, costs, area = inst
    m = cover.shape[0]
    q = min_cardinality(cover)
    # Eq. 5 for the worst q: Algorithm 5 misses the minimum with probability < 1e-9.
    n_repeat = n_repeat_recommended(m, 1 - 1e-9)
    params = dataclasses.replace(P, algorithm=4, bound="lb", n_repeat=n_repeat)
    res = dfbnb_setup_cover(cover, costs, patch_area=area, params=params)
    assert res.iess == q
    assert len(res.setups) == q and is_cover(cover, res.setups)
    _, best_q = brute_force_setup_cover(cover, costs, max_size=q)
    assert res.cost == pytest.approx(best_q, rel=1e-9, abs=1e-12)
    assert res.cost >= brute_force_setup_cover(cover, costs)[1] - 1e-9
    assert res.n_repeat == n_repeat


@settings(max_examples=40, deadline=None)
@given(instances(max_m=10, max_n=16), st.sampled_from([0.0, 5.0]), st.sampled_from([0.0, 0.1]))
def test_algorithm4_eq7_is_a_valid_cover_no_better_than_optimum(inst, t_decay, rate):
    cover, costs, area = inst
    _, bf = brute_force_setup_cover(cover, costs)
    params = dataclasses.replace(P, algorithm=4, bound="b", n_repeat=200, t_decay=t_decay,
                                 t_decay_rate=rate)
    res = dfbnb_setup_cover(cover, costs, patch_area=area, params=params)
    assert is_cover(cover, res.setups)
    assert res.cost >= bf - 1e-9
    assert len(res.setups) <= res.iess


def test_t_decay_prunes_more():
    rng = np.random.default_rng(11)
    cover = rng.random((9, 18)) < 0.45
    cover[:, ~cover.any(0)] = True
    costs = rng.uniform(1, 5, 9)
    base = dataclasses.replace(P, algorithm=4, bound="lb", n_repeat=5000)
    plain = dfbnb_setup_cover(cover, costs, params=base)
    decayed = dfbnb_setup_cover(cover, costs, params=dataclasses.replace(base, t_decay=1.0,
                                                                            t_decay_rate=0.01))
    assert decayed.node_expansions <= plain.node_expansions
    assert decayed.cost >= plain.cost - 1e-12


def test_private_patches_force_a_single_chain():
    """Step 5: a patch covered by one unused setup forces that branch only."""
    cover = np.eye(5, dtype=bool)
    res = dfbnb_setup_cover(cover, np.arange(1.0, 6.0), params=P)
    assert sorted(res.setups.tolist()) == [0, 1, 2, 3, 4]
    assert res.node_expansions == 6  # root + one forced child per level


def hard_instance():
    """Dense cover without private patches: the unpruned tree has ~e * 14! nodes."""
    rng = np.random.default_rng(0)
    cover = rng.random((14, 60)) < 0.5
    return cover, rng.uniform(1.0, 2.0, 14)


def test_t_max_abort_is_honoured():
    cover, costs = hard_instance()
    t_max = 0.5
    params = dataclasses.replace(P, pruning=False, t_max=t_max)
    t0 = time.perf_counter()
    res = dfbnb_setup_cover(cover, costs, params=params)
    wall = time.perf_counter() - t0
    assert res.timed_out
    # Correctness of the abort (clock read at every node), with slack for a loaded machine.
    assert res.seconds <= 1.1 * t_max + 0.3
    assert wall <= 1.1 * t_max + 0.5
    assert is_cover(cover, res.setups)  # the guided first dive gave an incumbent


def test_t_max_bounds_algorithm3_including_algorithm5():
    cover, costs = hard_instance()
    params = dataclasses.replace(P, algorithm=4, pruning=False, t_max=0.3, n_repeat=10**9)
    res = dfbnb_setup_cover(cover, costs, params=params)
    assert res.timed_out and res.seconds <= 1.1 * 0.3 + 0.3
    assert 1 <= res.iess <= 14


def test_auto_n_repeat_refused_when_astronomical_without_t_max():
    cover = np.eye(40, dtype=bool)
    with pytest.raises(ValueError, match="n_repeat"):
        dfbnb_setup_cover(cover, np.ones(40), params=dataclasses.replace(P, algorithm=4))


def test_auto_n_repeat_follows_section_ixb():
    rng = np.random.default_rng(2)
    cover = rng.random((8, 10)) < 0.4
    cover[:, ~cover.any(0)] = True
    res = dfbnb_setup_cover(cover, np.ones(8), params=dataclasses.replace(P, algorithm=4))
    assert res.n_repeat == n_repeat_recommended(8, 0.9)


@pytest.mark.parametrize("method", ["milp", "dfbnb", "both"])
def test_empty_stain_gives_empty_plan(method):
    for cover in (np.zeros((3, 0), bool), np.zeros((0, 0), bool)):
        res = solve_setup_cover(cover, np.ones(cover.shape[0]), method=method)
        assert res.setups.size == 0 and res.cost == 0.0 and res.status == "empty"
        assert res.uncoverable.size == 0


@pytest.mark.parametrize("method", ["milp", "dfbnb", "both"])
def test_uncoverable_patches_are_listed(method):
    cover = np.array([[1, 0, 1, 0, 0], [0, 0, 1, 1, 0], [1, 0, 0, 1, 0]], bool)
    res = solve_setup_cover(cover, np.array([1.0, 1.0, 3.0]), method=method)
    np.testing.assert_array_equal(res.uncoverable, [1, 4])
    assert sorted(res.setups.tolist()) == [0, 1] and res.cost == pytest.approx(2.0)
    all_out = solve_setup_cover(np.zeros((2, 3), bool), np.ones(2), method=method)
    np.testing.assert_array_equal(all_out.uncoverable, [0, 1, 2])
    # patches remain and nothing reaches them: no plan, no cost, not "empty"
    assert all_out.setups.size == 0 and all_out.status == "no_solution" and all_out.cost == math.inf
    assert all_out.certificate_cost is None


@pytest.mark.parametrize("method", ["milp", "dfbnb", "both"])
def test_zero_setups_is_no_solution_listing_every_patch(method):
    res = solve_setup_cover(np.zeros((0, 3), bool), np.ones(0), method=method)
    assert res.status == "no_solution" and res.cost == math.inf
    np.testing.assert_array_equal(res.uncoverable, [0, 1, 2])


@settings(max_examples=30, deadline=None)
@given(instances())
def test_solve_both_certifies_dfbnb(inst):
    cover, costs, area = inst
    res = solve_setup_cover(cover, costs, patch_area=area, params=P, method="both", setup_time=0.25)
    if cover.shape[1] and not cover.any():
        assert res.status == "no_solution"
        return
    assert res.status in ("optimal", "empty")
    assert res.certificate_gap == pytest.approx(0.0, abs=1e-9)
    assert is_cover(cover, res.setups)
    assert res.cost == pytest.approx(res.step_costs.sum())
    assert res.setup_time_total + res.execution_time_total == pytest.approx(res.cost)
    assert res.setup_time_total == pytest.approx(0.25 * len(res.setups))
    # Greedy execution order: rates of the steps never increase.
    rates = res.step_area / res.step_costs
    assert np.all(np.diff(rates) <= 1e-12)
    assert res.step_area.sum() == pytest.approx(area[cover.any(0)].sum())


def test_execution_order_is_greedy_by_rate():
    cover = np.array([[1, 1, 0, 0], [0, 1, 1, 1], [1, 0, 0, 1]], bool)
    costs = np.array([1.0, 1.0, 1.0])
    np.testing.assert_array_equal(execution_order(cover, costs, [0, 1, 2]), [1, 0, 2])
    rem = np.array([True, False, False, False])
    np.testing.assert_allclose(cleaning_rate(cover, costs, remaining=rem), [1.0, 0.0, 1.0])


def test_cost_model_helpers():
    cover = np.array([[1, 1, 0], [0, 1, 1]], bool)
    area = np.array([0.01, 0.02, 0.03])
    passes = np.array([1, 2, 3])
    te = execution_time_area_passes(cover, area, passes, rate=0.01)
    np.testing.assert_allclose(te, [(0.01 + 0.04) / 0.01, (0.04 + 0.09) / 0.01])
    np.testing.assert_allclose(setup_costs_from_times(te, 60.0), te + 60.0)
    np.testing.assert_allclose(setup_costs_from_times(te, [1.0, 2.0]), te + [1.0, 2.0])


@pytest.mark.parametrize("kwargs,name", [
    (dict(n_repeat=0), "n_repeat"),
    (dict(t_max=0.0), "t_max"),
    (dict(t_max=-1.0), "t_max"),
    (dict(setup_time=-1.0), "setup_time"),
    (dict(algorithm=3), "algorithm"),
    (dict(bound="ub"), "bound"),
    (dict(t_decay=-1.0), "t_decay"),
    (dict(t_decay=1.0), "t_decay"),  # Algorithm 2 has no T_decay
    (dict(algorithm=4, t_decay_rate=-0.1), "t_decay_rate"),
    (dict(iess_prob=1.0), "iess_prob"),
    (dict(guiding=1), "guiding"),
])
def test_bad_params(kwargs, name):
    with pytest.raises(ValueError, match=name):
        SetupPlannerParams(**kwargs)


def test_bad_inputs():
    cover = np.eye(3, dtype=bool)
    with pytest.raises(ValueError, match="setup_time"):
        setup_costs_from_times([1.0, 2.0, 3.0], -5.0)
    with pytest.raises(ValueError, match="setup_costs"):
        solve_setup_cover(cover, [1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match="setup_costs"):
        solve_setup_cover(cover, [1.0, 1.0])
    with pytest.raises(ValueError, match="setup_time"):
        solve_setup_cover(cover, np.ones(3), setup_time=-1.0)
    with pytest.raises(ValueError, match="method"):
        solve_setup_cover(cover, np.ones(3), method="greedy")
    with pytest.raises(ValueError, match="patch_area"):
        solve_setup_cover(cover, np.ones(3), patch_area=[1.0, 1.0])
    with pytest.raises(ValueError, match="cover"):
        solve_setup_cover(np.ones(3, bool), np.ones(3))
    with pytest.raises(ValueError, match="passes"):
        execution_time_area_passes(cover, np.ones(3), [0, 1, 1], 1.0)
    with pytest.raises(ValueError, match="rate"):
        execution_time_area_passes(cover, np.ones(3), [1, 1, 1], 0.0)
    with pytest.raises(ValueError, match="cover"):
        brute_force_setup_cover(np.eye(21, dtype=bool), np.ones(21))


def test_milp_time_limit_and_status():
    rng = np.random.default_rng(1)
    cover = rng.random((30, 50)) < 0.2
    cover[:, ~cover.any(0)] = True
    costs = rng.uniform(1, 3, 30)
    res = milp_setup_cover(cover, costs, time_limit=30.0)
    assert res.optimal and res.status == "optimal" and is_cover(cover, res.setups)
    assert res.cost == pytest.approx(costs[res.setups].sum())
    with pytest.raises(ValueError, match="time_limit"):
        milp_setup_cover(cover, costs, time_limit=0.0)


def test_timed_out_solution_status():
    cover, costs = hard_instance()
    res = solve_setup_cover(cover, costs, params=dataclasses.replace(P, pruning=False, t_max=0.2),
                            method="both")
    assert res.timed_out and res.status == "timed_out"
    assert res.certificate_gap >= -1e-12 and math.isfinite(res.cost)


def test_heuristic_configurations_report_converged():
    rng = np.random.default_rng(4)
    cover = rng.random((8, 15)) < 0.4
    cover[:, ~cover.any(0)] = True
    costs = rng.uniform(1, 3, 8)
    for kw in (dict(algorithm=4, n_repeat=500), dict(bound="b")):
        res = solve_setup_cover(cover, costs, params=dataclasses.replace(P, **kw), method="both")
        assert res.status == "converged" and res.certificate_gap >= -1e-12
    exact = solve_setup_cover(cover, costs, params=P, method="dfbnb")
    assert exact.status == "optimal" and exact.node_expansions > 0


# ---- issue 12 (Table V/VI) and issue 14 (reliability) -----------------------------------------


def test_node_limit_stops_deterministically_and_says_so():
    cover, costs = hard_instance()
    params = dataclasses.replace(P, pruning=False, max_nodes=5000)
    a = dfbnb_setup_cover(cover, costs, params=params)
    b = dfbnb_setup_cover(cover, costs, params=params)
    assert a.node_limited and not a.timed_out and not a.finished
    assert a.node_expansions == b.node_expansions == 5000
    assert a.cost == b.cost and a.setups.tolist() == b.setups.tolist()
    res = solve_setup_cover(cover, costs, params=params, method="dfbnb")
    assert res.status == "node_limited" and res.node_limited and not res.timed_out
    done = dfbnb_setup_cover(cover[:4, :10], costs[:4], params=P)
    assert done.finished


def test_defaults_are_bounded():
    d = SetupPlannerParams()
    assert d.t_max is not None and d.t_max > 0 and d.max_nodes is not None


def test_large_instance_warns_and_recommends_the_proven_optimum():
    rng = np.random.default_rng(3)
    cover = rng.random((60, 40)) < 0.3
    params = dataclasses.replace(SetupPlannerParams(), max_nodes=2000)
    with pytest.warns(UserWarning, match="method='auto'"):
        res = solve_setup_cover(cover, rng.uniform(1, 2, 60), params=params, method="both")
    assert res.node_expansions <= 2000 and any("method='auto'" in w for w in res.warnings)


def _paper_algorithm2_nodes(cover, costs):
    """Algorithm 2 transcribed literally (no pruning, no guiding): node count of its tree."""
    m = cover.shape[0]
    count = 0

    def add_setup(p_r, s_u):
        nonlocal count
        count += 1
        if not p_r:
            return
        single = [i for i in sorted(p_r) if sum(cover[j, i] for j in s_u) == 1]
        if single:
            s = next(j for j in s_u if cover[j, single[0]])
            add_setup(p_r - set(np.flatnonzero(cover[s])), [j for j in s_u if j != s])
            return
        for s in s_u:  # "For every s in S_u", including setups that reach nothing of P_r
            add_setup(p_r - set(np.flatnonzero(cover[s])), [j for j in s_u if j != s])

    add_setup(set(np.flatnonzero(cover.any(axis=0))), list(range(m)))
    return count


@settings(max_examples=30, deadline=None)
@given(instances(max_m=6, max_n=8))
def test_branching_follows_algorithm2_every_unused_setup(inst):
    cover, costs, _ = inst
    res = dfbnb_setup_cover(cover, costs, params=dataclasses.replace(P, pruning=False, guiding=False))
    assert res.node_expansions == _paper_algorithm2_nodes(cover, costs)


def _remaining_brute_force(cover, ts, times):
    best = math.inf
    target = cover.any(axis=0)
    for mask in range(1, 1 << cover.shape[0]):
        chosen = [j for j in range(cover.shape[0]) if mask >> j & 1]
        if np.array_equal(cover[chosen].any(axis=0), target):
            best = min(best, ts * len(chosen) + times[target].sum())
    return best if target.any() else 0.0


@settings(max_examples=40, deadline=None)
@given(instances(max_m=7, max_n=12), st.sampled_from([0.0, 0.3, 5.0]))
def test_remaining_cost_model_dfbnb_equals_milp_and_brute_force(inst, ts):
    cover, _, area = inst
    times = area * 2.0
    costs = setup_costs_from_times(cover.astype(float) @ times, ts) + 1e-9
    params = dataclasses.replace(P, cost_model="remaining")
    d = dfbnb_setup_cover(cover, costs, patch_area=area, params=params, setup_time=ts, patch_time=times)
    m = milp_remaining_cover(cover, ts, times)
    bf = _remaining_brute_force(cover, ts, times)
    assert d.finished and m.optimal
    assert d.cost == pytest.approx(bf, abs=1e-9) and m.cost == pytest.approx(bf, abs=1e-9)
    res = solve_setup_cover(cover, costs, patch_area=area, params=params, method="both", setup_time=ts,
                            patch_time=times)
    if cover.any():
        assert res.step_costs.sum() == pytest.approx(res.cost) and res.certificate_gap == pytest.approx(0.0, abs=1e-9)


def test_remaining_cost_model_needs_times():
    with pytest.raises(ValueError, match="patch_time"):
        dfbnb_setup_cover(np.eye(3, dtype=bool), np.ones(3), params=dataclasses.replace(P, cost_model="remaining"))
    with pytest.raises(ValueError, match="cost_model"):
        SetupPlannerParams(cost_model="order")


def test_unproven_certificate_is_no_certificate(monkeypatch):
    """The proof stopped at its node budget with 62 where the plan costs 60: status and bound, no
    certificate."""
    cover, costs = hard_instance()
    fake = SimpleNamespace(setups=np.array([0, 1, 2]), cost=62.0, status="node_limited", optimal=False, seconds=0.01,
                           reduced=SimpleNamespace(uncoverable=np.zeros(0, np.int64)), dual_bound=55.0, proof="none")
    monkeypatch.setattr(setcover, "certified_cover", lambda *a, **k: fake)
    res = solve_setup_cover(cover, costs, params=dataclasses.replace(P, max_nodes=3000), method="both")
    assert res.certificate_cost is None and res.certificate_gap is None
    assert res.certificate_status == "node_limited" and res.certificate_bound == 55.0


def test_seconds_and_t_max_cover_the_whole_call(monkeypatch):
    cover, costs = hard_instance()
    real = setcover.certified_cover

    def slow_certificate(*args, **kwargs):
        time.sleep(0.4)
        return real(*args, **kwargs)

    monkeypatch.setattr(setcover, "certified_cover", slow_certificate)
    t0 = time.perf_counter()
    res = solve_setup_cover(cover, costs, params=dataclasses.replace(P, pruning=False, t_max=0.6), method="both")
    wall = time.perf_counter() - t0
    assert res.seconds >= 0.4 and res.seconds >= wall - 0.1  # the whole call, the MILP's time in it
    assert res.timed_out and wall <= 0.6 + 0.25  # the search got only what the MILP left


def test_auto_is_the_proven_optimum_where_dfbnb_stops_above_it():
    rng = np.random.default_rng(3)
    cover = rng.random((60, 40)) < 0.3
    costs = rng.uniform(1, 2, 60)
    params = dataclasses.replace(SetupPlannerParams(), max_nodes=50, t_max=None)
    with pytest.warns(UserWarning):
        both = solve_setup_cover(cover, costs, params=params, method="both")
    auto = solve_setup_cover(cover, costs, params=params)
    assert both.status == "node_limited" and both.certificate_gap > 0
    assert auto.status == "optimal" and auto.cost == pytest.approx(both.certificate_cost) and auto.cost < both.cost
    assert auto.certificate_gap == 0 and auto.certificate_proof in ("enumeration", "milp")
    assert np.array_equal(cover[auto.setups].any(axis=0), cover.any(axis=0))


@pytest.mark.parametrize("reduce", [True, False], ids=["reduced", "paper's search"])
@pytest.mark.parametrize("method", ["auto", "milp", "dfbnb", "both"])
def test_every_method_agrees_with_brute_force_on_small_instances(method, reduce):
    rng = np.random.default_rng(21)
    for _ in range(25):
        m, n = int(rng.integers(2, 10)), int(rng.integers(2, 20))
        cover = rng.random((m, n)) < 0.35
        if not cover.any():
            continue
        costs = rng.uniform(1.0, 5.0, m)
        res = solve_setup_cover(cover, costs, method=method, params=dataclasses.replace(P, t_max=None, reduce=reduce))
        assert res.status == "optimal"
        assert res.cost == pytest.approx(brute_force_setup_cover(cover, costs)[1])

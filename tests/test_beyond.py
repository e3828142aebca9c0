"""Notebook 12's experiments: exact cover counts and IESS law, the node budget of DFBnB, Algorithm
4 sweeps (and the same sweep on a dask cluster), and the HPR plan re-evaluated by ray casting."""

import itertools
import math

import joblib
import numpy as np
import pytest

from mavac.experiments import beyond as B
from mavac.experiments import mavac_offline as mo
from mavac.params import SetupPlannerParams
from mavac.planning.iess import initial_estimate_of_setup_size, n_repeat_recommended, p_find_min_cover
from mavac.planning.setcover import dfbnb_setup_cover


def _random_cover(m=7, n=12, seed=3, p=0.35):
    rng = np.random.default_rng(seed)
    return rng.random((m, n)) < p


def _instance(cover, costs, name="toy", setup_time=60.0):
    from mavac.planning.setcover import milp_setup_cover

    milp = milp_setup_cover(cover, costs)
    return B.IessInstance(name, cover, np.asarray(costs, float), np.ones(cover.shape[1]), setup_time,
                          milp.cost, len(milp.setups), B.covers_by_size(cover))


# A unique minimum cover {0, 1} (q = 2) among m = 6 setups; setups 2-5 each cover one third.
UNIQUE = np.array([[1, 1, 1, 0, 0, 0],
                   [0, 0, 0, 1, 1, 1],
                   [1, 1, 0, 0, 0, 0],
                   [0, 0, 1, 1, 0, 0],
                   [0, 0, 0, 0, 1, 1],
                   [1, 0, 0, 0, 0, 1]], dtype=bool)


def test_covers_by_size_matches_enumeration():
    cover = _random_cover()
    coverable = cover.any(axis=0)
    expected = np.zeros(cover.shape[0] + 1, dtype=np.int64)
    for k in range(cover.shape[0] + 1):
        for subset in itertools.combinations(range(cover.shape[0]), k):
            expected[k] += bool(k) and bool(cover[list(subset)].any(axis=0)[coverable].all())
    assert B.covers_by_size(cover).tolist() == expected.tolist()
    assert B.covers_by_size(cover)[-1] == 1


def test_covers_by_size_refuses_large_m():
    with pytest.raises(ValueError, match="m <= 20"):
        B.covers_by_size(np.ones((21, 3), dtype=bool))


def test_iess_law_is_eq5_for_a_unique_cover_and_a_distribution():
    counts = B.covers_by_size(UNIQUE)
    assert counts[2] == 1 and counts[1] == 0
    for n in (1, 3, 40):
        law = B.iess_probabilities(counts, n)
        assert law.sum() == pytest.approx(1.0)
        assert law[2] == pytest.approx(p_find_min_cover(2, 6, n))
        assert law[:2].sum() == 0.0


def test_iess_law_matches_algorithm_5():
    cover = _random_cover(m=6, n=10, seed=5, p=0.45)
    law = B.iess_probabilities(B.covers_by_size(cover), 2)
    draws = np.array([initial_estimate_of_setup_size(cover, 2, seed=s) for s in range(3000)])
    freq = np.bincount(draws, minlength=len(law)) / len(draws)
    assert np.abs(freq - law).max() < 0.035  # > 4 standard errors of a 3000-draw frequency


def test_node_budget_stops_the_search_deterministically():
    cover = _random_cover(m=10, n=20, seed=1, p=0.3)
    costs = np.linspace(1.0, 2.0, 10)
    free = dfbnb_setup_cover(cover, costs, params=SetupPlannerParams(pruning=False))
    assert not free.node_limited and free.node_expansions > 50
    capped = dfbnb_setup_cover(cover, costs, params=SetupPlannerParams(pruning=False, max_nodes=50))
    assert capped.node_limited and capped.node_expansions == 50
    again = dfbnb_setup_cover(cover, costs, params=SetupPlannerParams(pruning=False, max_nodes=50))
    assert again.cost == capped.cost and again.setups.tolist() == capped.setups.tolist()
    with pytest.raises(ValueError, match="max_nodes"):
        SetupPlannerParams(max_nodes=0)


def _toy_runs(**kw):
    costs = np.array([5.0, 5.0, 4.0, 4.0, 4.0, 4.0])
    inst = _instance(UNIQUE, costs)
    return inst, B.alg4_runs([inst], seeds=range(6), progress=False, **kw)


def test_alg4_runs_summary_and_outcome_by_estimate():
    inst, runs = _toy_runs(grid=(1, 50), bounds=("b", "lb"))
    assert set(runs.n_repeat) == {1, 50, n_repeat_recommended(6)}
    assert (runs.iess >= inst.q).all() and not runs.node_limited.any()
    lb = runs[runs.bound == "lb"]
    # eq. 2 with a depth cap at or above the optimum's size is exact: every run is optimal
    assert inst.optimum_size == 2 and lb.optimal.all()
    by = B.outcome_by_iess(runs)
    assert set(by.columns) >= {"object", "setup_time", "bound", "iess", "optimal", "runs"}
    s = B.alg4_summary(runs, [inst])
    assert ((s.ci_low <= s.p_optimal) & (s.p_optimal <= s.ci_high)).all()
    assert (s.eq5 <= s.p_iess_q_exact + 1e-12).all()  # a unique minimum cover: equal
    assert np.allclose(s.eq5, s.p_iess_q_exact)
    table = B.optimality_table(s)
    assert len(table) == 2 and table.N_IX_B.iloc[0] == n_repeat_recommended(6)


def test_alg4_runs_are_reproducible():
    _, a = _toy_runs(grid=(2,))
    _, b = _toy_runs(grid=(2,))
    assert a.equals(b)


def test_two_trial_sweep_on_a_dask_cluster_equals_the_local_backend():
    distributed = pytest.importorskip("distributed", reason="install the dask extra: pip install -e '.[dask]'")
    inst = _instance(UNIQUE, np.array([5.0, 5.0, 4.0, 4.0, 4.0, 4.0]))
    kw = dict(seeds=range(4), grid=(3,), bounds=("b",), chunk=4, progress=False)  # 2 tasks: N = 3 and IX-B's
    local = B.alg4_runs([inst], n_jobs=1, **kw)
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        with distributed.get_task_stream(client) as stream, joblib.parallel_backend("dask"):
            remote = B.alg4_runs([inst], n_jobs=2, **kw)
        assert len(stream.data) >= 2  # the trials ran on the cluster's workers
    assert client.status == "closed" and cluster.status.name == "closed"
    assert local.equals(remote)


def test_visibility_rows_reevaluate_the_plan_with_ray_casting():
    plans = B.visibility_plans(machines=("test_bench",), seeds=(0,), params=mo.fast_params(), progress=False)
    assert set(plans.visibility) == {"hpr", "raycast"}
    ray = plans[plans.visibility == "raycast"].iloc[0]
    assert ray.C_raycast == pytest.approx(ray.C) and ray.false_visible == 0.0 and ray.missed == 0.0
    for row in plans.itertuples():  # seen = counted - counted but unseen + seen but uncounted
        assert row.C_raycast == pytest.approx(row.C - row.false_visible + row.missed)
    summary = B.visibility_summary(plans)
    assert summary.seeds.tolist() == [1, 1] and math.isnan(summary.C_sd.iloc[0])
    assert plans.rrt_timeouts.dtype.kind == "i" and (plans.rrt_timeouts >= 0).all()

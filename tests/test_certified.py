"""certified_cover: proven optima against brute force, both proofs, budgets and the OR-Library."""

from pathlib import Path

import numpy as np
import pytest

from mavac.params import CertifyParams
from mavac.planning.certified import certified_cover
from mavac.planning.instances import read_scp
from mavac.planning.setcover import brute_force_setup_cover

ORLIB = Path(__file__).resolve().parent.parent / "data" / "orlib"
#: Proven optima of scp41-48 (Caprara, Fischetti and Toth 1999), as data/orlib/README.md lists them.
ORLIB_OPTIMA = {"scp41": 429, "scp42": 512, "scp43": 516, "scp44": 494, "scp45": 512, "scp46": 560,
                "scp47": 430, "scp48": 492}
ENUMERATE_ONLY = CertifyParams(max_enumerated_size=1000, enumeration_nodes=10**7)
MILP_ONLY = CertifyParams(max_enumerated_size=1)


def _instances(seed: int, count: int):
    rng = np.random.default_rng(seed)
    for t in range(count):
        m, n = int(rng.integers(2, 15)), int(rng.integers(2, 30))
        cover = rng.random((m, n)) < rng.uniform(0.15, 0.5)
        if cover.any():
            yield cover, (np.ones(m) if t % 2 else rng.uniform(1.0, 10.0, m))


@pytest.mark.parametrize("params", [CertifyParams(), ENUMERATE_ONLY, MILP_ONLY], ids=["default", "enumeration", "milp"])
def test_proven_optimum_equals_brute_force(params):
    for cover, costs in _instances(3, 60):
        res = certified_cover(cover, costs, params=params)
        assert res.optimal and res.dual_bound == pytest.approx(res.cost)
        assert res.cost == pytest.approx(brute_force_setup_cover(cover, costs)[1])
        assert res.cost == pytest.approx(costs[res.setups].sum())
        assert np.array_equal(cover[res.setups].any(axis=0), cover.any(axis=0))


def test_each_proof_is_used_where_it_applies():
    proofs = set()
    for params in (ENUMERATE_ONLY, MILP_ONLY):
        proofs |= {certified_cover(c, w, params=params).proof for c, w in _instances(4, 80)}
    assert {"reduction", "enumeration", "milp"} <= proofs


def test_size_bound_follows_from_the_incumbent_and_the_cheapest_setups():
    # greedy takes s2 then s3 (21); the two cheapest setups already cost 10 + 11 = 21, so only a
    # single setup could beat the incumbent, and none covers alone
    cover = np.array([[1, 1, 0, 0], [0, 0, 1, 1], [1, 0, 1, 0], [0, 1, 0, 1]], dtype=bool)
    res = certified_cover(cover, np.array([12.0, 13.0, 10.0, 11.0]))
    assert res.incumbent_cost == 21.0 and res.size_bound == 1
    assert res.optimal and res.cost == 21.0 and res.setups.tolist() == [2, 3]


def test_shallow_covers_are_searched_even_when_the_greedy_size_bound_is_too_large():
    # greedy 11 bounds the size at 3 > max_enumerated_size 2; the two-setup pass finds 10, whose
    # bound (2) the enumeration then reaches: proven without the integer program
    cover = np.array([[1, 0, 1, 0], [0, 0, 1, 1], [1, 1, 0, 1], [0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 0],
                      [0, 0, 0, 1]], dtype=bool)
    costs = np.array([6.0, 1.0, 9.0, 7.0, 3.0, 2.0, 2.0])
    res = certified_cover(cover, costs, params=CertifyParams(max_enumerated_size=2))
    assert res.incumbent_cost == 11.0 and res.size_bound == 3
    assert res.optimal and res.cost == 10.0 and res.proof == "enumeration" and res.milp_nodes == 0


def test_budget_exhausted_reports_a_bound_not_a_proof():
    rng = np.random.default_rng(3)
    cover = rng.random((60, 40)) < 0.12
    tight = certified_cover(cover, np.ones(60), params=CertifyParams(max_enumerated_size=1, milp_nodes=1))
    full = certified_cover(cover, np.ones(60))
    assert tight.status == "node_limited" and not tight.optimal and tight.proof == "none"
    assert tight.dual_bound <= full.cost <= tight.cost
    assert full.optimal


def test_remaining_model_zero_setup_times_cost_nothing():
    cover = np.array([[1, 0], [0, 1], [1, 1]], dtype=bool)
    res = certified_cover(cover, np.zeros(3))
    assert res.optimal and res.cost == 0.0 and np.array_equal(cover[res.setups].any(axis=0), [True, True])


def test_nothing_coverable_is_an_empty_optimal_plan():
    res = certified_cover(np.zeros((3, 4), dtype=bool), np.ones(3))
    assert res.optimal and res.setups.size == 0 and res.reduced.uncoverable.tolist() == [0, 1, 2, 3]


@pytest.mark.parametrize("name", sorted(ORLIB_OPTIMA))
def test_orlib_scp4_instances_are_proven_optimal(name):
    cover, costs = read_scp(ORLIB / f"{name}.txt")
    assert cover.shape == (1000, 200)
    res = certified_cover(cover, costs)
    assert res.optimal and res.cost == ORLIB_OPTIMA[name]
    assert cover[res.setups].any(axis=0).all()
    # 200 rows of unit-ish costs: the size bound is far above the enumeration's, so the LP proves
    assert res.proof in ("lp", "milp") and res.lp_bound <= res.cost and res.fixed_setups > 0


def test_read_scp_refuses_a_file_that_is_not_one(tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("2 3\n1 1 1\n2 1 4\n")
    with pytest.raises(ValueError, match="outside 1..3"):
        read_scp(bad)
    bad.write_text("hello")
    with pytest.raises(ValueError, match="not an OR-Library scp file"):
        read_scp(bad)
    bad.write_text("2 3\n1 1 1\n1 1\n")
    with pytest.raises(ValueError, match="ends before row 2"):
        read_scp(bad)


def test_instance_files_round_trip_byte_for_byte(tmp_path):
    from mavac.planning.instances import read_instance, write_instance

    rng = np.random.default_rng(1)
    cover, costs = rng.random((7, 19)) < 0.4, rng.uniform(1, 9, 7)
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    write_instance(a, cover, costs, setups=np.zeros((7, 3)))
    write_instance(b, cover, costs, setups=np.zeros((7, 3)))
    assert a.read_bytes() == b.read_bytes()
    back = read_instance(a)
    assert np.array_equal(back["cover"], cover) and np.array_equal(back["costs"], costs)
    assert back["setups"].shape == (7, 3)
    (tmp_path / "c.npz").write_text("not a zip")
    with pytest.raises(ValueError, match="not a set-cover instance file"):
        read_instance(tmp_path / "c.npz")


@pytest.mark.parametrize("name", ["sine", "schwefel", "concave_bowl", "hyperboloid"])
def test_committed_table2_instances_are_readable_and_coverable(name):
    """The instances notebook 06 writes (data/instances/) load with consistent shapes."""
    from mavac.planning.instances import read_instance

    data = read_instance(Path(__file__).resolve().parent.parent / "data" / "instances" / f"kabir_table2_{name}.npz")
    cover, costs = data["cover"], data["costs"]
    assert cover.shape[0] == len(costs) == len(data["setups"]) and cover.shape[1] == len(data["patch_area"])
    assert np.all(costs > float(data["setup_time"])) and cover.any(axis=1).all()


@pytest.mark.parametrize("cover, costs, message", [
    (np.ones((2, 3), dtype=bool), np.ones(3), r"costs must have shape \(2,\)"),
    (np.ones((2, 3), dtype=bool), np.array([1.0, np.nan]), "costs must be finite and >= 0"),
    (np.ones((2, 3), dtype=bool), np.array([1.0, -1.0]), "costs must be finite and >= 0"),
    (np.ones(3, dtype=bool), np.ones(3), "cover must be a 2-D"),
])
def test_bad_instances_are_refused_with_the_parameter_named(cover, costs, message):
    with pytest.raises(ValueError, match=message):
        certified_cover(cover, costs)
    with pytest.raises(TypeError, match="CertifyParams"):
        certified_cover(np.ones((1, 1), dtype=bool), np.ones(1), params={"milp_nodes": 3})


def test_three_setup_optimum_is_proven_by_enumeration_without_the_integer_program():
    """The Table II Schwefel instance: greedy costs 635 s (size bound 6), the optimum is 3 setups;
    the depth-3 probe finds it and proves it, with no integer-program node needed."""
    from mavac.planning.instances import read_instance

    inst = read_instance(ORLIB.parent / "instances" / "kabir_table2_schwefel.npz")
    r = certified_cover(inst["cover"], inst["costs"], params=CertifyParams(milp_nodes=1))
    assert r.status == "optimal" and r.proof == "enumeration" and len(r.setups) == 3
    assert r.incumbent_cost > r.cost and r.milp_nodes == 0
    assert np.all(inst["cover"][r.setups].any(axis=0) >= inst["cover"].any(axis=0))

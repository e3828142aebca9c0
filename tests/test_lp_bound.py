"""lp_bound: column generation against the full LP, the Lagrangian bound, reduced-cost fixing."""

import numpy as np
import pytest
from scipy.optimize import linprog

from mavac.planning.lp_bound import fixable, lp_bound, reduced_costs
from mavac.planning.setcover import brute_force_setup_cover


def _instances(seed: int, count: int, m_max: int = 14):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        m, n = int(rng.integers(3, m_max)), int(rng.integers(3, 40))
        cover = rng.random((m, n)) < rng.uniform(0.15, 0.5)
        cover = cover[:, cover.any(axis=0)]
        if cover.shape[1]:
            yield cover, rng.uniform(1.0, 10.0, m)


def _full_lp(cover, costs) -> float:
    res = linprog(costs, A_ub=-cover.T.astype(float), b_ub=-np.ones(cover.shape[1]), bounds=(0, None),
                  method="highs")
    return res.fun


def test_column_generation_reaches_the_full_lp_optimum():
    for cover, costs in _instances(5, 40, m_max=80):
        lp = lp_bound(cover, costs)
        assert lp.converged
        assert lp.bound == pytest.approx(_full_lp(cover, costs), rel=1e-7)
        assert np.all(lp.duals >= 0.0)
        assert np.allclose(lp.reduced_costs, costs - cover.astype(float) @ lp.duals)


def test_master_starts_small_and_grows_only_as_pricing_asks():
    rng = np.random.default_rng(8)
    cover = rng.random((400, 60)) < 0.2
    costs = rng.uniform(1.0, 10.0, 400)
    lp = lp_bound(cover, costs)
    assert lp.converged and 1 < lp.rounds and len(lp.master) < 400


def test_a_round_budget_leaves_a_valid_bound_that_is_not_claimed_converged():
    rng = np.random.default_rng(8)
    cover = rng.random((400, 60)) < 0.2
    costs = rng.uniform(1.0, 10.0, 400)
    one = lp_bound(cover, costs, max_rounds=1)
    assert not one.converged and one.rounds == 1
    assert one.bound <= _full_lp(cover, costs) + 1e-9


def test_bound_never_exceeds_the_optimum_and_fixing_keeps_every_cheaper_cover():
    fixed_any = False
    for cover, costs in _instances(6, 60):
        rows, opt = brute_force_setup_cover(cover, costs)
        lp = lp_bound(cover, costs)
        assert lp.bound <= opt + 1e-9
        # with a 1 % worse incumbent, the optimum is a cheaper cover: none of its setups may go
        drop = fixable(lp, 1.01 * opt, 1e-6)
        assert not drop[rows].any()
        fixed_any |= bool(drop.any())
    assert fixed_any


def test_reduced_costs_in_blocks_equal_one_product():
    rng = np.random.default_rng(2)
    cover = rng.random((1300, 20)) < 0.3
    costs, duals = rng.uniform(1, 5, 1300), rng.uniform(0, 1, 20)
    assert np.allclose(reduced_costs(cover, costs, duals), costs - cover.astype(float) @ duals)

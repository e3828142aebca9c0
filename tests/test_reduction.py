"""reduce_instance: exact set-cover reductions, checked against brute force."""

import numpy as np
import pytest

from mavac.planning.reduction import reduce_instance
from mavac.planning.setcover import brute_force_setup_cover


def _random_instance(rng, unit: bool):
    m, n = int(rng.integers(1, 13)), int(rng.integers(1, 25))
    cover = rng.random((m, n)) < rng.uniform(0.1, 0.6)
    costs = np.ones(m) if unit else rng.uniform(1.0, 10.0, m)
    return cover, costs


def _optimum(cover, costs):
    if not cover.any():
        return 0.0
    return brute_force_setup_cover(cover, costs)[1]


@pytest.mark.parametrize("unit", [True, False], ids=["unit costs", "weighted costs"])
def test_reduction_keeps_the_optimum_and_lifts_to_a_cover(unit):
    rng = np.random.default_rng(11 if unit else 12)
    for _ in range(80):
        cover, costs = _random_instance(rng, unit)
        red = reduce_instance(cover, costs)
        rest = _optimum(red.cover, red.costs) if red.cover.shape[1] else 0.0
        assert red.forced_cost + rest == pytest.approx(_optimum(cover, costs))
        if red.cover.shape[1]:
            chosen = red.lift(brute_force_setup_cover(red.cover, red.costs)[0])
        else:
            chosen = red.lift([])
        assert np.array_equal(cover[chosen].any(axis=0), cover.any(axis=0))  # the lifted plan covers


def test_remaining_cost_model_reduces_on_setup_times():
    """Under the "remaining" model a plan costs sum t_s + a constant: reducing on t_s keeps the optimum."""
    rng = np.random.default_rng(5)
    for _ in range(60):
        cover, ts = _random_instance(rng, unit=False)
        red = reduce_instance(cover, ts)
        rest = _optimum(red.cover, red.costs) if red.cover.shape[1] else 0.0
        assert red.forced_cost + rest == pytest.approx(_optimum(cover, ts))


def test_each_rule_on_a_small_instance():
    cover = np.array([
        # p0  p1  p2  p3  p4
        [1, 0, 0, 0, 0],  # s0: alone on p0 -> forced
        [0, 1, 1, 0, 0],  # s1: subset of s2 at the same cost -> dropped
        [0, 1, 1, 1, 0],  # s2: then alone on p1 -> forced, and p3 is covered
        [0, 0, 0, 1, 0],  # s3: nothing left to cover -> dropped
        [0, 0, 0, 0, 0],  # s4: reaches nothing
        [0, 1, 1, 1, 0],  # s5: identical to s2, dearer -> dropped
    ], dtype=bool)
    costs = np.array([1.0, 2.0, 2.0, 1.0, 1.0, 3.0])
    red = reduce_instance(cover, costs)
    assert red.uncoverable.tolist() == [4]
    assert red.forced.tolist() == [0, 2] and red.forced_cost == 3.0
    assert red.cover.shape == (0, 0) and red.lift([]).tolist() == [0, 2]
    assert red.summary() == "6 x 5 -> 0 x 0 (2 forced, 1 uncoverable patches)"


def test_implied_and_identical_patches_are_dropped():
    cover = np.array([
        # p0  p1  p2  p3
        [1, 1, 1, 0],
        [1, 0, 1, 1],
        [0, 1, 0, 1],
    ], dtype=bool)
    red = reduce_instance(cover, np.array([1.0, 1.0, 1.0]))
    # p2 = {s0, s1} is identical to p0 (dropped, higher index); p1 = {s0, s2}, p3 = {s1, s2}
    assert red.patches.tolist() == [0, 1, 3] and red.forced.size == 0


def test_a_column_every_setup_reaches_is_implied_by_any_other():
    cover = np.array([[1, 1, 0], [1, 0, 1]], dtype=bool)
    red = reduce_instance(cover, np.array([1.0, 1.0]))
    assert 0 not in red.patches.tolist()
    red = reduce_instance(np.ones((2, 1), dtype=bool), np.array([2.0, 1.0]))
    assert red.forced.tolist() == [1] and red.cover.shape[1] == 0  # the dearer row is dominated


def test_identical_rows_at_equal_cost_keep_the_lowest_index():
    cover = np.array([[1, 1, 0], [1, 1, 0], [0, 1, 1], [1, 0, 1]], dtype=bool)
    red = reduce_instance(cover, np.ones(4))
    assert red.setups.tolist() == [0, 2, 3]


def test_a_cheaper_subset_is_not_dominated():
    cover = np.array([[1, 1, 1, 0], [1, 1, 0, 1], [0, 0, 1, 1]], dtype=bool)
    red = reduce_instance(cover, np.array([10.0, 1.0, 1.0]))
    assert red.setups.tolist() == [0, 1, 2]
    red = reduce_instance(cover, np.array([1.0, 1.0, 1.0]))
    assert red.setups.tolist() == [0, 1, 2]  # no row is a subset of another

"""Algorithm 5 (initial estimate of setup size) and its theorem, eq. 5-6 (Kabir Sec. V-B1, IX-B)."""

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest

from mavac.planning.iess import (
    initial_estimate_of_setup_size,
    n_repeat_for,
    n_repeat_for_all_q,
    n_repeat_recommended,
    p_find_min_cover,
    p_single_trial,
)


def exact_eq5(q, m, n):
    p = Fraction(math.factorial(q) * math.factorial(m - q), math.factorial(m))  # eq. 6
    return 1 - (1 - p) ** n


@pytest.mark.parametrize("q,m,n", [(1, 2, 1), (3, 6, 10), (6, 13, 3951), (2, 9, 40), (5, 5, 1)])
def test_eq5_matches_exact_rational(q, m, n):
    assert p_find_min_cover(q, m, n) == pytest.approx(float(exact_eq5(q, m, n)), rel=1e-12, abs=1e-15)


def test_eq6_is_one_over_binomial():
    for m in range(1, 15):
        for q in range(1, m + 1):
            assert p_single_trial(q, m) == pytest.approx(1 / math.comb(m, q), rel=1e-15)


def test_large_m_is_robust():
    # C(2000, 1000) overflows a float: p underflows to 0 and eq. 5 to 0, no exception.
    assert p_find_min_cover(1000, 2000, 10**6) == 0.0
    assert 0.0 < p_find_min_cover(30, 60, 10**18) < 1.0


@pytest.mark.parametrize("m", [4, 7, 12, 13, 20])
def test_n_repeat_is_the_smallest_reaching_prob(m):
    for q in range(1, m):
        n = n_repeat_for(m, q, 0.9)
        assert p_find_min_cover(q, m, n) >= 0.9
        if n > 1:
            assert p_find_min_cover(q, m, n - 1) < 0.9


def test_n_repeat_closed_form():
    # N = ceil(log(1 - prob) / log(1 - p)) away from float ties.
    for m, q in [(13, 6), (12, 6), (20, 10), (7, 2)]:
        p = 1 / math.comb(m, q)
        assert n_repeat_for(m, q, 0.9) == math.ceil(math.log(0.1) / math.log(1 - p))


@pytest.mark.parametrize("m", [6, 11, 12, 20])
def test_fig9_bell_curve(m):
    qs, ns = n_repeat_for_all_q(m, 0.9)
    np.testing.assert_array_equal(qs, np.arange(1, m))
    np.testing.assert_array_equal(ns, ns[::-1])  # C(m, q) = C(m, m - q)
    peak = int(np.argmax(ns))
    assert qs[peak] in (m // 2, math.ceil(m / 2))
    assert np.all(np.diff(ns[: peak + 1]) >= 0) and np.all(np.diff(ns[peak:]) <= 0)
    assert n_repeat_recommended(m, 0.9) == ns.max()


def test_q_equal_m_needs_one_trial():
    assert p_find_min_cover(5, 5, 1) == 1.0
    assert n_repeat_for(5, 5) == 1
    assert n_repeat_recommended(1) == 1


@pytest.mark.parametrize("kwargs,name", [
    (dict(q=0, m=5, n_repeat=1), "q"),
    (dict(q=6, m=5, n_repeat=1), "q"),
    (dict(q=2, m=5, n_repeat=0), "n_repeat"),
    (dict(q=2, m=0, n_repeat=1), "m"),
])
def test_bad_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        p_find_min_cover(**kwargs)


@pytest.mark.parametrize("prob", [0.0, 1.0, 1.5])
def test_bad_prob(prob):
    with pytest.raises(ValueError, match="prob"):
        n_repeat_for(10, 5, prob)


# Unique minimum cover {A, B, C} (q = 3) among m = 6 setups: the singletons cannot be part of
# any 3-cover, so no other cover of size 3 exists.
UNIQUE = np.array([
    [1, 1, 0, 0, 0, 0],  # A
    [0, 0, 1, 1, 0, 0],  # B
    [0, 0, 0, 0, 1, 1],  # C
    [1, 0, 0, 0, 0, 0],
    [0, 0, 1, 0, 0, 0],
    [0, 0, 0, 0, 1, 0],
], bool)


def test_unique_instance_is_unique():
    covers = [s for s in itertools.combinations(range(6), 3) if UNIQUE[list(s)].any(0).all()]
    assert covers == [(0, 1, 2)]


def test_algorithm5_frequency_matches_eq5():
    """Monte Carlo: fraction of runs of Algorithm 5 returning q equals eq. 5 (seeded, fixed N)."""
    rng = np.random.default_rng(12345)
    n_repeat, runs = 10, 3000
    hits = sum(initial_estimate_of_setup_size(UNIQUE, n_repeat, seed=rng) == 3 for _ in range(runs))
    expected = p_find_min_cover(3, 6, n_repeat)  # 1 - (19/20)^10 ~ 0.40
    sigma = math.sqrt(expected * (1 - expected) / runs)
    assert abs(hits / runs - expected) < 5 * sigma


def test_algorithm5_single_trial_frequency():
    rng = np.random.default_rng(7)
    runs = 4000
    hits = sum(initial_estimate_of_setup_size(UNIQUE, 1, seed=rng) == 3 for _ in range(runs))
    p = 1 / 20
    assert abs(hits / runs - p) < 5 * math.sqrt(p * (1 - p) / runs)


def test_algorithm5_never_below_minimum_and_seeded():
    rng = np.random.default_rng(1)
    for _ in range(30):
        cover = rng.random((7, 12)) < 0.35
        est = initial_estimate_of_setup_size(cover, 50, seed=4)
        assert est == initial_estimate_of_setup_size(cover, 50, seed=4)
        target = cover.any(0)
        sizes = [k for k in range(0, 8) for s in itertools.combinations(range(7), k)
                 if np.array_equal(cover[list(s)].any(0) if s else np.zeros(12, bool), target)]
        assert est >= min(sizes)
        # Enough trials find the minimum (eq. 5 with q = ceil(7/2) gives >= 1 - 1e-9).
        assert initial_estimate_of_setup_size(cover, n_repeat_for(7, 4, 1 - 1e-9), seed=0) == min(sizes)


def test_algorithm5_trivial_cases():
    assert initial_estimate_of_setup_size(np.zeros((3, 4), bool), 5) == 0
    assert initial_estimate_of_setup_size(np.zeros((3, 0), bool), 5) == 0
    assert initial_estimate_of_setup_size(np.eye(4, dtype=bool), 3) == 4
    with pytest.raises(ValueError, match="n_repeat"):
        initial_estimate_of_setup_size(np.eye(3, dtype=bool), 0)

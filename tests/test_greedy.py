"""Greedy selection (MAVAC spots and guards) against a direct transcription of the paper's steps."""

import itertools

import numpy as np
import pytest

from mavac.planning.greedy import greedy_scores, greedy_select


def paper_greedy(sets, P, weights=None, k1=1.0, k2=1.0, n=None):
    """The paper's three steps, literally, on Python sets (reference implementation)."""
    n = n if n is not None else max((max(s) for s in sets if s), default=-1) + 1
    w = [1.0] * len(sets) if weights is None else list(weights)
    remaining = [set(s) for s in sets]

    def score(i):
        if not remaining[i]:
            return 0.0
        return w[i] ** k1 * (len(remaining[i]) / n) ** k2

    chosen, threshold = [], None
    while True:
        scores = [score(i) for i in range(len(sets))]
        best = max(range(len(sets)), key=lambda i: (scores[i], -i)) if sets else None
        if best is None or scores[best] <= 0:
            break
        if threshold is None:
            threshold = P * scores[best]
        elif scores[best] < threshold * (1.0 - 1e-12):
            break
        chosen.append(best)
        taken = set(remaining[best])
        for r in remaining:
            r -= taken
    return chosen


def _instance(rng, m, n, density):
    return rng.random((m, n)) < density


@pytest.mark.parametrize("seed", range(40))
def test_greedy_matches_paper_steps(seed):
    rng = np.random.default_rng(seed)
    m, n = int(rng.integers(1, 9)), int(rng.integers(1, 15))
    access = _instance(rng, m, n, rng.uniform(0.1, 0.7))
    P = float(rng.choice([0.0, 0.02, 0.15, 0.3, 0.7, 1.0]))
    weights = rng.uniform(0, 1, m) if seed % 2 else None
    k1, k2 = float(rng.choice([0.0, 0.5, 1.0])), float(rng.choice([0.0, 0.5, 1.0]))
    ref = paper_greedy([set(np.flatnonzero(r)) for r in access], P, weights, k1, k2, n)
    got = greedy_select(access, P, weights=weights, k1=k1, k2=k2)
    assert got.selected.tolist() == ref
    assert np.array_equal(got.covered, access[got.selected].any(axis=0) if len(ref) else np.zeros(n, bool))


def test_P_zero_covers_everything_coverable():
    rng = np.random.default_rng(3)
    access = _instance(rng, 12, 40, 0.15)
    got = greedy_select(access, 0.0)
    assert np.array_equal(got.covered, access.any(axis=0))
    # every selected candidate added something new
    assert np.all(got.gains > 0)


def test_greedy_is_optimal_on_disjoint_sets_and_threshold_semantics():
    # disjoint sets of sizes 5, 3, 1: threshold P x 5
    access = np.zeros((3, 9), dtype=bool)
    access[0, :5] = access[1, 5:8] = access[2, 8] = True
    assert greedy_select(access, 0.6).selected.tolist() == [0, 1]  # 3 >= 0.6*5
    assert greedy_select(access, 0.61).selected.tolist() == [0]  # 3 < 3.05
    assert greedy_select(access, 0.2).selected.tolist() == [0, 1, 2]


def test_greedy_never_worse_than_brute_force_bound_on_tiny_instances():
    # with P = 0, greedy reaches full coverage; its size is within the ln(n)+1 set-cover bound
    rng = np.random.default_rng(7)
    for _ in range(20):
        access = _instance(rng, 6, 8, 0.35)
        target = access.any(axis=0)
        best = None
        for r in range(1, 7):
            for combo in itertools.combinations(range(6), r):
                if np.array_equal(access[list(combo)].any(axis=0), target):
                    best = r
                    break
            if best:
                break
        got = greedy_select(access, 0.0)
        if best is not None:
            assert best <= len(got.selected) <= best * (np.log(8) + 1)


def test_covered_elements_are_not_new():
    access = np.array([[1, 1, 1, 0], [0, 0, 0, 1]], dtype=bool)
    got = greedy_select(access, 0.0, covered=np.array([1, 1, 0, 0], dtype=bool))
    assert got.selected.tolist() == [0, 1]
    assert got.gains.tolist() == [1, 1]


def test_score_is_equation_3():
    s = greedy_scores([2, 0, 4], 8, weights=[0.5, 1.0, 0.25], k1=1.0, k2=0.5)
    assert s == pytest.approx([0.5 * (2 / 8) ** 0.5, 0.0, 0.25 * (4 / 8) ** 0.5])


def test_empty_inputs():
    assert greedy_select(np.zeros((0, 5), bool), 0.1).selected.size == 0
    assert greedy_select(np.zeros((3, 5), bool), 0.1).selected.size == 0


@pytest.mark.parametrize("name,kwargs", [("P", dict(P=1.5)), ("P", dict(P=-0.1)), ("k1", dict(P=0.1, k1=2.0)),
                                         ("k2", dict(P=0.1, k2=-1.0))])
def test_bad_parameters(name, kwargs):
    with pytest.raises(ValueError, match=name):
        greedy_select(np.ones((2, 2), bool), **kwargs)


def test_bad_shapes():
    with pytest.raises(ValueError, match="access"):
        greedy_select(np.ones(3, bool), 0.1)
    with pytest.raises(ValueError, match="weights"):
        greedy_select(np.ones((2, 2), bool), 0.1, weights=[0.5])
    with pytest.raises(ValueError, match="weights"):
        greedy_select(np.ones((2, 2), bool), 0.1, weights=[0.5, 1.5])
    with pytest.raises(ValueError, match="covered"):
        greedy_select(np.ones((2, 2), bool), 0.1, covered=[True])


@pytest.mark.parametrize("seed", range(25))
def test_lazy_evaluation_gives_the_eager_result(seed):
    rng = np.random.default_rng(100 + seed)
    m, n = int(rng.integers(1, 30)), int(rng.integers(1, 60))
    bound = rng.random((m, n)) < rng.uniform(0.1, 0.6)
    exact = bound & (rng.random((m, n)) < rng.uniform(0.3, 1.0))
    weights = rng.uniform(0, 1, m)
    P = float(rng.choice([0.0, 0.05, 0.15, 0.5]))
    calls = []

    def evaluate(idx):
        calls.append(len(idx))
        return exact[idx]

    eager = greedy_select(exact, P, weights=weights)
    lazy = greedy_select(bound, P, weights=weights, evaluate=evaluate, batch=3)
    assert lazy.selected.tolist() == eager.selected.tolist()
    assert np.array_equal(lazy.covered, eager.covered)
    assert lazy.scores == pytest.approx(eager.scores)
    assert sum(calls) <= m

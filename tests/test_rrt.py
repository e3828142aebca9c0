import numpy as np
import pytest

from mavac.planning.rrt import PlanResult, plan_rrt_connect

CENTRE, RADIUS = np.array([0.5, 0.5]), 0.3
LOWER, UPPER = np.zeros(2), np.ones(2)
START, GOAL = np.array([0.1, 0.5]), np.array([0.9, 0.5])  # the disc blocks the straight line


def outside_disc(q):
    return bool(np.linalg.norm(q - CENTRE) > RADIUS)


def test_path_goes_around_the_disc():
    res = plan_rrt_connect(outside_disc, START, GOAL, LOWER, UPPER, seed=3, resolution=0.005)
    assert isinstance(res, PlanResult) and res.solved and res.reason == "solved"
    assert res.seconds > 0
    path = res.path
    assert path.ndim == 2 and path.shape[1] == 2
    np.testing.assert_array_equal(path[0], START)
    np.testing.assert_array_equal(path[-1], GOAL)
    assert all(outside_disc(q) for q in path)
    assert np.all((path >= LOWER) & (path <= UPPER))
    # Interpolated at the motion-checking resolution (fraction of the box diagonal).
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert steps.max() <= 0.005 * np.sqrt(2) * (1 + 1e-6)
    # Around, not through: longer than the blocked straight line.
    assert steps.sum() > np.linalg.norm(GOAL - START)


def test_same_seed_same_path():
    a = plan_rrt_connect(outside_disc, START, GOAL, LOWER, UPPER, seed=7)
    b = plan_rrt_connect(outside_disc, START, GOAL, LOWER, UPPER, seed=7)
    assert a.solved and b.solved
    np.testing.assert_array_equal(a.path, b.path)


def test_free_space_path_is_simplified_to_a_straight_line():
    lower, upper = -np.pi * np.ones(6), np.pi * np.ones(6)
    q0, q1 = np.full(6, -1.0), np.linspace(-0.5, 1.5, 6)
    seen = []

    def always_valid(q):
        seen.append(q.shape)
        return True

    res = plan_rrt_connect(always_valid, q0, q1, lower, upper, seed=1)
    assert res.solved
    assert set(seen) == {(6,)}  # the checker receives (nq,) arrays
    direction = (q1 - q0) / np.linalg.norm(q1 - q0)
    offsets = res.path - q0
    off_line = offsets - np.outer(offsets @ direction, direction)
    np.testing.assert_allclose(off_line, 0.0, atol=1e-9)


def test_iteration_budget_gives_the_same_path_as_an_unbounded_search():
    # The budget only decides when to stop: a budget large enough to solve gives the same
    # path as a (practically) unbounded one, and repeated calls agree bit for bit.
    unbounded = plan_rrt_connect(outside_disc, START, GOAL, LOWER, UPPER, seed=7, time_limit=60.0,
                                 max_iterations=10**9)
    budget = next(k for k in (2**i for i in range(20))
                  if plan_rrt_connect(outside_disc, START, GOAL, LOWER, UPPER, seed=7, time_limit=60.0,
                                      max_iterations=k).solved)
    a = plan_rrt_connect(outside_disc, START, GOAL, LOWER, UPPER, seed=7, time_limit=60.0, max_iterations=budget)
    b = plan_rrt_connect(outside_disc, START, GOAL, LOWER, UPPER, seed=7, time_limit=60.0, max_iterations=budget)
    assert unbounded.solved and a.solved and b.solved
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.path, unbounded.path)


def test_exhausted_iteration_budget_is_unsolved_with_a_reason():
    def ring_free(q):  # the centre is enclosed by an invalid ring: never solvable
        return not (0.2 < np.linalg.norm(q - CENTRE) < 0.3)

    calls = []

    def counting(q):
        calls.append(1)
        return ring_free(q)

    # A generous time cap: the iteration budget, not the clock, stops the search.
    res = plan_rrt_connect(counting, CENTRE, [0.95, 0.5], LOWER, UPPER, time_limit=600.0, max_iterations=200)
    assert (res.solved, res.path, res.reason) == (False, None, "iteration budget exhausted")
    n_checks = len(calls)
    calls.clear()
    again = plan_rrt_connect(counting, CENTRE, [0.95, 0.5], LOWER, UPPER, time_limit=600.0, max_iterations=200)
    assert again.reason == "iteration budget exhausted"
    assert len(calls) == n_checks  # the same search, state for state


def test_invalid_start_or_goal_is_reported_not_raised():
    inside = CENTRE.copy()
    res = plan_rrt_connect(outside_disc, inside, GOAL, LOWER, UPPER)
    assert (res.solved, res.path, res.reason) == (False, None, "invalid start")
    res = plan_rrt_connect(outside_disc, START, inside, LOWER, UPPER)
    assert (res.solved, res.path, res.reason) == (False, None, "invalid goal")


def test_unreachable_goal_is_unsolved():
    def ring_free(q):  # the centre is enclosed by an invalid ring
        return not (0.2 < np.linalg.norm(q - CENTRE) < 0.3)

    res = plan_rrt_connect(ring_free, CENTRE, [0.95, 0.5], LOWER, UPPER, max_iterations=300)
    assert not res.solved and res.path is None and res.reason != "solved"


def test_validity_exception_propagates():
    def broken(q):
        if q[0] > 0.3:
            raise RuntimeError("checker failed")
        return True

    with pytest.raises(RuntimeError, match="checker failed"):
        plan_rrt_connect(broken, START, GOAL, LOWER, UPPER)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(time_limit=0.0), "time_limit"),
        (dict(time_limit=-1.0), "time_limit"),
        (dict(resolution=0.0), "resolution"),
        (dict(resolution=1.5), "resolution"),
        (dict(seed=-1), "seed"),
        (dict(max_iterations=0), "max_iterations"),
        (dict(max_iterations=2.5), "max_iterations"),
        (dict(q_start=[0.1, 0.5, 0.0]), "q_start"),
        (dict(q_start=[1.5, 0.5]), "q_start"),
        (dict(q_goal=[np.nan, 0.5]), "q_goal"),
        (dict(lower=[0.0, 2.0]), "lower"),
        (dict(lower=[0.0], upper=[1.0]), "q_start"),
        (dict(is_valid=None), "is_valid"),
    ],
)
def test_bad_parameters_raise(kwargs, name):
    args = dict(
        is_valid=outside_disc, q_start=START, q_goal=GOAL, lower=LOWER, upper=UPPER
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        plan_rrt_connect(**args)


class _Clock:
    """``time.perf_counter`` running ``rate`` times as fast as the real one."""

    def __init__(self, real, rate: float):
        self.real, self.rate, self.origin = real, rate, real()

    def __call__(self) -> float:
        return self.origin + self.rate * (self.real() - self.origin)


def _slit(q):  # a wall at x = 0.5 with a 2 % slit: RRT-Connect needs hundreds of iterations
    return not (0.45 < q[0] < 0.55 and abs(q[1] - 0.5) > 0.01)


def _plans(seeds, **kwargs):
    out = []
    for s in seeds:
        r = plan_rrt_connect(_slit, [0.1, 0.1], [0.9, 0.9], LOWER, UPPER, seed=s, max_iterations=3000, **kwargs)
        out.append((r.solved, r.reason, None if r.path is None else r.path.tobytes()))
    return out


def test_results_do_not_depend_on_the_clock(monkeypatch):
    # Same seeds, same budget: a clock 300x too slow or a huge cap change nothing, and a clock
    # 300x too fast (a loaded machine) or a tiny cap either changes nothing or raises
    # PlanningTimeout; it never turns a solved plan into a quiet failure.
    import time

    from mavac.planning.rrt import PlanningTimeout

    seeds = range(6)
    reference = _plans(seeds)
    assert any(solved for solved, _, _ in reference)
    assert _plans(seeds, time_limit=1e6) == reference
    real, raised = time.perf_counter, 0
    for rate, cap in ((1 / 300, 600.0), (300.0, 1.0), (1.0, 1e-4)):
        monkeypatch.setattr(time, "perf_counter", _Clock(real, rate))
        for s, expected in zip(seeds, reference):
            try:
                got = _plans([s], time_limit=cap)[0]
            except PlanningTimeout as exc:
                assert "time_limit" in str(exc) and "max_iterations=3000" in str(exc)
                raised += 1
                continue
            assert got == expected, f"seed {s}, clock x{rate:g}, cap {cap} s"
        monkeypatch.setattr(time, "perf_counter", real)
    assert raised > 0  # the fast clock and the tiny cap did fire

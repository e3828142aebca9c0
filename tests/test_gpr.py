"""GPR operation-parameter learning (Kabir, Sec. VIII) on a cheap analytic black box."""

import dataclasses

import numpy as np
import pytest

from mavac.params import GPRParams
from mavac.scrubbing.gpr import (coarse_grid, dense_optimum, experiments_to_reach, learn_parameters,
                              objective, random_search)

FAST = GPRParams(Cp_th=0.7, P_th=0.3, max_experiments=80, n_candidates=512, patience=30)


class Analytic:
    """C_p = 0.9 - 0.5 v_n + 0.4 f_n_n - 0.3 |z - z*|^2, capped at 0.95 (linear-normalised v,
    f_n; log-normalised z = (kappa, f_x, A_x)). With C_p^th = 0.7 the feasible optimum of the
    objective 0.5 v_n + 0.5 (1 - f_n_n) is v_n = 0.4, f_n_n = 0, z = z*: J* = 0.7."""

    def __init__(self, params, noise=0.01):
        self.p, self.noise = params, noise
        self.lo, self.hi = np.array(params.lower), np.array(params.upper)

    def mean(self, X):
        X = np.atleast_2d(X)
        lin = (X - self.lo) / (self.hi - self.lo)
        logu = np.log(X / self.lo) / np.log(self.hi / self.lo)
        z = logu[:, 2:] - np.array([0.6, 0.4, 0.5])
        return np.minimum(0.9 - 0.5 * lin[:, 0] + 0.4 * lin[:, 1] - 0.3 * (z**2).sum(axis=1), 0.95)

    def __call__(self, x, rng):
        return float(self.mean(x)[0] + rng.normal(0.0, self.noise))


def test_dense_optimum_of_analytic_model():
    opt = dense_optimum(Analytic(FAST).mean, FAST)
    assert opt.feasible and opt.objective == pytest.approx(0.7, abs=0.01)
    assert opt.C_p >= FAST.Cp_th
    assert opt.chosen["f_n"] < 3.0  # at the lower bound, up to the (log-spaced) grid cell


def test_gpr_reaches_known_optimum_within_budget():
    black_box = Analytic(FAST)
    opt = dense_optimum(black_box.mean, FAST)
    result = learn_parameters(black_box, FAST, rng=np.random.default_rng(0))
    assert result.experiments <= FAST.max_experiments
    reach = experiments_to_reach(result.history, opt, tol=0.05)
    assert reach is not None and reach <= FAST.max_experiments
    assert result.feasible
    x = np.array([[result.chosen[n] for n in ("v", "f_n", "kappa", "f_x", "A_x")]])
    assert objective(x, FAST)[0] >= opt.objective - 0.05
    assert black_box.mean(x)[0] >= FAST.Cp_th - 0.05
    assert {"explore", "exploit"} <= set(result.history["phase"]) <= {"explore", "exploit", "search"}
    assert len(coarse_grid(FAST)) == (result.history["phase"] == "explore").sum()


def test_unreachable_threshold_is_infeasible_within_budget():
    params = dataclasses.replace(FAST, Cp_th=0.99, max_experiments=45)
    result = learn_parameters(Analytic(params), params, rng=np.random.default_rng(1))
    assert not result.feasible and result.chosen is None
    assert result.experiments <= params.max_experiments
    assert experiments_to_reach(result.history, dense_optimum(Analytic(params).mean, params)) is None


def test_a_known_constraint_is_part_of_the_feasibility_rule():
    """The cell's path-deviation cap (here 4 mm, below the analytic optimum's ~6 mm swing):
    no point outside it is run or chosen; without the rule the learner runs such points."""
    from mavac.scrubbing.lissajous import vector_excursions

    params = dataclasses.replace(FAST, max_experiments=40)
    names = ["v", "f_n", "kappa", "f_x", "A_x"]
    free = learn_parameters(Analytic(params), params, rng=np.random.default_rng(5))
    assert (vector_excursions(free.history[names].to_numpy()) > 0.004).any()
    capped = learn_parameters(Analytic(params), params, rng=np.random.default_rng(5),
                              admissible=lambda X: vector_excursions(X) <= 0.004)
    assert np.all(vector_excursions(capped.history[names].to_numpy()) <= 0.004)
    assert capped.feasible and vector_excursions(np.array([[capped.chosen[n] for n in names]]))[0] <= 0.004
    with pytest.raises(ValueError, match="admissible"):
        learn_parameters(Analytic(params), params, admissible=lambda X: np.zeros(len(X), bool))


def test_same_seed_same_result():
    params = dataclasses.replace(FAST, max_experiments=36)
    a = learn_parameters(Analytic(params), params, rng=np.random.default_rng(3))
    b = learn_parameters(Analytic(params), params, rng=np.random.default_rng(3))
    assert a.history.equals(b.history) and a.chosen == b.chosen
    r1 = random_search(Analytic(params), params, budget=20, rng=np.random.default_rng(4))
    r2 = random_search(Analytic(params), params, budget=20, rng=np.random.default_rng(4))
    assert r1.history.equals(r2.history) and r1.experiments == 20


def test_random_search_stays_in_bounds():
    r = random_search(Analytic(FAST), FAST, budget=50, rng=np.random.default_rng(0))
    X = r.history[["v", "f_n", "kappa", "f_x", "A_x"]].to_numpy()
    assert np.all(X >= np.array(FAST.lower)) and np.all(X <= np.array(FAST.upper))


def test_objective_prefers_speed_and_low_force():
    X = np.array([[0.05, 40.0, 5000, 6, 30], [0.6, 2.0, 5000, 6, 30], [0.3, 20.0, 1000, 1, 5]])
    J = objective(X, FAST)
    assert J[0] == pytest.approx(0.0) and J[1] == pytest.approx(1.0) and 0 < J[2] < 1


@pytest.mark.parametrize("field,value", [("v_bounds", (0.5, 0.1)), ("f_n_bounds", (10.0, 2.0)),
                                         ("kappa_bounds", (1e4, 1e3)), ("f_x_bounds", (5.0, 5.0)),
                                         ("A_x_bounds", (60.0, 5.0)), ("A_x_bounds", (0.0, 5.0)),
                                         ("v_bounds", (0.1, 1.5)), ("Cp_th", 1.5), ("P_th", 0.0),
                                         ("P_th", 1.0), ("grid_points", 1), ("max_experiments", 0),
                                         ("speed_weight", 2.0), ("patience", 0)])
def test_bad_params(field, value):
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(GPRParams(), **{field: value})


def test_bad_call_arguments():
    with pytest.raises(ValueError, match="budget"):
        random_search(Analytic(FAST), FAST, budget=0)
    with pytest.raises(ValueError, match="points_per_axis"):
        dense_optimum(Analytic(FAST).mean, FAST, points_per_axis=(5, 5, 5))
    with pytest.raises(ValueError, match="X"):
        objective(np.ones((3, 4)), FAST)

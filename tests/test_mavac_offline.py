"""The MAVAC offline studies behind notebooks 02-04: Table 1 both ways, the HPR calibration at
spot distances, and how much C moves with k1."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from mavac.experiments import mavac_offline as mo
from mavac.params import InspectionParams, SpotParams, Visibility


def test_spot_hpr_radius_is_calibrated_at_spot_distances():
    """Visibility.spot_radius_factor is the factor that misclassifies the fewest (viewpoint,
    element) pairs against exact ray casting at the spot viewpoints of the three machines
    (half the candidate spots, to keep the test short); the guards' factor, calibrated at
    L_d = 0.5 m, is not."""
    params = dataclasses.replace(InspectionParams(), spot=SpotParams(ring_spacing=0.5))
    sweep = mo.spot_hpr_radius_sweep(params=params)
    assert set(sweep["machine"]) == {"test_bench", "sanding_machine", "milling_machine"}
    best = mo.best_radius_factor(sweep)
    assert best == Visibility().spot_radius_factor
    assert best != Visibility().radius_factor
    # misclassification is worse on both sides of the optimum: a real minimum, not an edge
    factors = sorted(sweep["radius_factor"].unique())
    assert factors[0] < best < factors[-1]


def test_best_radius_factor_counts_pairs_over_machines():
    sweep = pd.DataFrame(dict(machine=["a", "a", "b", "b"], radius_factor=[10.0, 30.0, 10.0, 30.0],
                              agreement=[0.9, 0.8, 0.5, 0.7], pairs=[100, 100, 1000, 1000]))
    assert mo.best_radius_factor(sweep) == 30.0  # 10 + 300 wrong pairs against 20 + 500


@pytest.fixture(scope="module")
def k1_table():
    return mo.k1_effect(params=mo.fast_params().with_visibility("hpr"), k1_values=(0.0, 0.5, 1.0))


def test_k1_effect_measures_how_much_C_moves(k1_table):
    """The paper says k1 "does not affect C or O". Eq. 3 with a constant I_m is blind to k1; with
    k1 = 0 every variant is that constant; the table reports how far C moves otherwise."""
    t = k1_table.set_index(["maneuverability", "k1"])
    const = t.loc["constant (I_m = 1)"]
    assert const["C_guards"].nunique() == 1 and const["guards"].nunique() == 1
    for name in mo.IM_VARIANTS:
        assert t.loc[(name, 0.0), "C_guards"] == const.loc[0.0, "C_guards"]
    summary = mo.k1_summary(k1_table).set_index("maneuverability")
    default = summary.loc["I_m (k = 50, default)"]
    assert default["C_moves"] == pytest.approx(default["C_guards_k1=1"] - default["C_guards_k1=0"])
    assert summary.loc["constant (I_m = 1)", "C_moves"] == 0.0
    # on our bench the default I_m does move C: the paper's claim does not hold for us
    assert abs(default["C_moves"]) > 0.01, summary
    assert (k1_table["visibility"] == "hpr").all()


def test_k1_effect_rejects_unknown_variants():
    with pytest.raises(ValueError, match="variants"):
        mo.k1_effect(variants=("I_m squared",))
    with pytest.raises(ValueError, match="k1"):
        mo.k1_effect(k1_values=(2.0,))


def test_table1_reports_both_methods_and_both_readings_of_O():
    trials = mo.table1_trials(trials=1, P_s_values=(0.02, 0.3), params=mo.fast_params())
    assert set(trials["visibility"]) == {"hpr", "raycast"}
    assert np.all(trials["O"] >= trials["O_pairwise"] - 1e-12)
    summary = mo.table1_summary(trials)
    side = mo.table1_vs_paper(summary)
    for col in ("spots_paper", "C_hpr", "C_raycast", "O_eq2_paper", "O_eq2_hpr", "O_pairwise_raycast"):
        assert col in side
    fit = mo.overlap_reading_fit(summary)
    assert list(fit["reading"]) == ["eq2", "pairwise"] and np.all(fit["mean_abs_difference"] >= 0)
    with pytest.raises(ValueError, match="visibility"):
        mo.table1_trials(trials=1, visibility=("exact",))

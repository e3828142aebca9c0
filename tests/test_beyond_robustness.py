"""Notebook 12, Part 2: the sweep points are the units declared, the unperturbed trials are
Part 1's, and the summary and breaking points follow from the runs."""

import dataclasses

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from mavac.experiments import beyond_online as BO
from mavac.experiments import beyond_robustness as BR
from mavac.params import DustParams, OnlineParams, PerturbationParams


def test_each_sweep_point_sets_one_field_and_the_unperturbed_trial_is_part_1s():
    items = BR.robustness_items(seeds=(1, 2), fast=True)
    n_points = 1 + sum(len(v[3]) for v in BR.SWEEPS.values())
    assert len(items) == 2 * n_points and len(set(items)) == len(items)
    assert items[0] == BO.comparison_items(scenes=("test_bench",), densities=(1.0,), seeds=(1,), fast=True)[0]
    for unit in items:
        sweep, value = BR.sweep_of(unit)
        assert BR.sweep_unit("test_bench", unit[-2], sweep, value, fast=True) == unit
        changed = [f.name for f in dataclasses.fields(PerturbationParams)
                   if getattr(unit[4], f.name) != getattr(PerturbationParams(), f.name)]
        assert len(changed) + (unit[5] != 1.0) == (sweep != "none")
    assert BR.sweep_of(BR.sweep_unit("a", 1, "suction_radius", 0.5)) == ("suction_radius", 0.5)
    assert BO.unit_params(BR.sweep_unit("a", 1, "suction_radius", 0.5, fast=True)).vacuum.suction_radius == \
        pytest.approx(0.5 * OnlineParams().vacuum.suction_radius)
    largest = BR.robustness_items(seeds=(1,), largest_only=True)
    assert [BR.sweep_of(u) for u in largest[1:]] == [(s, float(v[3][-1])) for s, v in BR.SWEEPS.items()]


@pytest.fixture
def on_the_box(monkeypatch, box_plan):
    machine, plan = box_plan
    monkeypatch.setattr(BO, "load_machine", lambda scene: machine)
    monkeypatch.setattr(BO, "offline_plan", lambda scene, reading, *, offline, fast: plan)
    monkeypatch.setattr(BO, "online_params", lambda reading, *, fast: OnlineParams(dust=DustParams(spacing=0.1)))


def test_a_run_of_decoys_counts_false_detections_and_shares_the_unperturbed_trial(on_the_box):
    items = BR.robustness_items(sweeps=("decoys",), scene="box", seeds=(2,), fast=True, largest_only=True)
    outcomes = BO.run_units(items + items[:1])
    assert len(outcomes) == 2
    runs = BR.robustness_runs(items, outcomes=outcomes)
    assert list(runs.columns) == BR.RUN_COLUMNS and runs.sweep.tolist() == ["none", "decoys"]
    none, decoys = runs.iloc[0], runs.iloc[1]
    assert none.precision == 1.0 and decoys.precision < 1.0 and decoys.value == 30.0


def _runs() -> pd.DataFrame:
    """Synthetic runs: unperturbed 90 +- 1; machine shift 85 at 0.05 m and 60 at 0.2 m; suction
    radius 50 at x0.5 and 92 at x1.5."""
    rows = []
    for sweep, value, mean in (("none", 0.0, 90.0), ("machine_shift", 0.05, 85.0), ("machine_shift", 0.2, 60.0),
                               ("suction_radius", 0.5, 50.0), ("suction_radius", 1.5, 92.0)):
        for seed, noise in zip((1, 2, 3), (-1.0, 0.0, 1.0)):
            rows.append(dict(sweep=sweep, value=value, scene="s", seed=seed, heaps=100, cleaned=int(mean + noise),
                             cleaning_pct=mean + noise, sim_time_s=400.0, guards=10, guards_unreachable=0,
                             spots_blocked=0, poses_skipped=0, detected=100, precision=1.0,
                             transit_contacts=seed, transit_peak_force=100.0 * seed))
    return pd.DataFrame(rows, columns=BR.RUN_COLUMNS)


def test_summary_starts_each_sweep_at_the_shared_unperturbed_trials():
    s = BR.robustness_summary(_runs())
    shift = s[s.sweep == "machine_shift"]
    assert shift.value.tolist() == [0.0, 0.05, 0.2] and shift.trials.tolist() == [3, 3, 3]
    assert shift.share_of_unperturbed.tolist() == pytest.approx([1.0, 85 / 90, 60 / 90], abs=1e-4)
    suction = s[s.sweep == "suction_radius"]
    assert suction.value.tolist() == [0.5, 1.0, 1.5]  # sorted, the nominal radius in the middle
    half = stats.t.ppf(0.975, 2) * 1.0 / np.sqrt(3)  # sd 1 over three seeds
    assert shift.cleaning_pct_high.iloc[0] - shift.cleaning_pct.iloc[0] == pytest.approx(half, abs=1e-3)
    # two trials in three pressed past the UR10's limit (peaks 100, 200 and 300 N)
    assert shift.over_force_limit.iloc[0] == pytest.approx(2 / 3, abs=1e-4)


def test_breaking_point_is_the_smallest_perturbation_below_80_percent_or_none():
    b = BR.breaking_points(BR.robustness_summary(_runs())).set_index("sweep")
    assert b.loc["machine_shift", "broke"] and b.loc["machine_shift", "breaking_point"] == 0.2
    assert b.loc["suction_radius", "breaking_point"] == 0.5 and b.loc["suction_radius", "largest_swept"] in (0.5, 1.5)
    held = _runs()
    held.loc[held.sweep == "machine_shift", "cleaning_pct"] = 89.0
    b = BR.breaking_points(BR.robustness_summary(held)).set_index("sweep")
    assert not b.loc["machine_shift", "broke"] and np.isnan(b.loc["machine_shift", "breaking_point"])
    assert b.loc["machine_shift", "largest_swept"] == 0.2


def test_the_plot_has_one_panel_per_sweep_with_the_breaking_line():
    fig = BR.plot_robustness(BR.robustness_summary(_runs()))
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == 2
    assert all(any(line.get_linestyle() == "--" for line in ax.lines) for ax in visible)

"""Notebook 05's tables: per-trial rows, the paper-style mean, scenes and regions, paper beside
ours, miss causes per region."""

import numpy as np
import pandas as pd
import pytest

from mavac.cleaning.trial import TrialResult
from mavac.experiments import mavac_online as mon


def _run(scene, reading, trial, cleaned, n=10, enclosed=2, offline="hpr"):
    causes = np.array([""] * cleaned + ["no approach found"] * (n - cleaned))
    result = TrialResult(scene, trial, np.zeros((n, 3)), np.arange(n) < cleaned, causes, detected=12,
                         true_positives=12, recalled=n - 1)
    result.times.arm_s = 60.0
    regions = np.array(["open"] * (n - enclosed) + ["enclosed"] * enclosed)  # misses fall in the last heaps
    unseen = np.arange(n) == n - 1  # the last heap (enclosed) lies where no camera looks
    return dict(scene=scene, reading=reading, offline=offline, trial=trial, result=result, regions=regions,
                unseen=unseen)


def _runs():
    spec = [("test_bench", "paper", 1, 8), ("test_bench", "paper", 2, 9), ("sanding_milling", "paper", 1, 7),
            ("sanding_milling", "paper", 2, 5), ("test_bench", "authors", 1, 4), ("sanding_milling", "authors", 1, 2)]
    raycast = [("test_bench", "paper", 1, 10), ("sanding_milling", "paper", 1, 6)]
    return [_run(*s) for s in spec] + [_run(*s, offline="raycast") for s in raycast]


def test_trials_table_has_region_counts_and_no_wall_time():
    trials = mon.trials_table(_runs())
    assert list(trials.columns[:len(mon.TRIAL_COLUMNS)]) == mon.TRIAL_COLUMNS
    assert "wall_s" not in trials.columns
    first = trials.iloc[0]
    assert (first.open_heaps, first.open_cleaned, first.enclosed_heaps, first.enclosed_cleaned) == (8, 8, 2, 0)


def test_paper_style_mean_averages_every_trial_of_both_scenes():
    summary = mon.table2(mon.trials_table(_runs()))
    paper = summary[(summary.reading == "paper") & (summary.offline == "hpr")
                    & (summary.statistic == "paper-style mean")].iloc[0]
    assert paper.cleaning_pct == pytest.approx((80 + 90 + 70 + 50) / 4)
    assert (paper.cleaning_pct_min, paper.cleaning_pct_max, paper.trials) == (50.0, 90.0, 4)
    bench = summary[(summary.reading == "paper") & (summary.offline == "hpr") & (summary.scene == "test_bench")
                    & (summary.region == "all")]
    assert bench.cleaning_pct.iloc[0] == pytest.approx(85.0)


def test_regions_pool_heaps_over_trials():
    summary = mon.table2(mon.trials_table(_runs()))
    pooled = summary[(summary.reading == "paper") & (summary.offline == "hpr") & (summary.scene == "both")
                     & (summary.statistic == "pooled heaps")]
    by_region = dict(zip(pooled.region, pooled.cleaning_pct))
    assert by_region["open"] == pytest.approx(100.0 * (8 + 8 + 7 + 5) / 32)
    assert by_region["enclosed"] == pytest.approx(100.0 * 1 / 8)  # bench trial 2 cleans heap 8


def test_paper_beside_ours_reads_paper_values_for_both_readings():
    comparison = mon.table2_vs_paper(mon.table2(mon.trials_table(_runs())))
    head = comparison.iloc[0]
    assert head.paper_cleaning_pct == 84.0  # the paper's Results, from data/paper_values.csv
    assert head.ours_paper_hpr == pytest.approx(72.5) and head.ours_authors_hpr == pytest.approx(30.0)
    assert head.ours_paper_raycast == pytest.approx(80.0)  # the third variant: its own column
    bench = comparison[comparison.row == "test bench"].iloc[0]
    assert bench.paper_cleaning_pct == 87.8  # mean of the paper's five test-bench trials
    assert np.isnan(comparison[comparison.row == "enclosed heaps, both"].paper_cleaning_pct.iloc[0])


def test_miss_causes_are_split_by_region():
    misses = mon.miss_causes_table(_runs())
    row = misses[(misses.reading == "paper") & (misses.offline == "hpr") & (misses.scene == "test_bench")
                 & (misses.region == "enclosed")].iloc[0]
    assert row["no approach found"] == 3  # trial 1 misses 2 enclosed heaps, trial 2 one
    assert isinstance(mon.times_table(_runs()), pd.DataFrame)


def test_miss_shares_sum_to_one_hundred_per_row():
    shares = mon.miss_shares(mon.miss_causes_table(_runs()))
    assert (shares["uncleaned"] > 0).all()
    assert np.allclose(shares[list(mon.CAUSES)].sum(axis=1), 100.0)


def test_top_causes_name_the_largest_counts_per_variant_and_scene():
    top = mon.top_causes(mon.miss_causes_table(_runs()))
    row = top[(top.reading == "paper") & (top.offline == "hpr") & (top.scene == "sanding_milling")].iloc[0]
    assert (row.cause_1, row.count_1) == ("no approach found", 3 + 5) and row.count_2 == 0 and row.cause_2 == ""


def test_unseen_heaps_are_counted_per_region_from_the_plans_visibility():
    trials = mon.trials_table(_runs())
    assert (trials.enclosed_unseen == 1).all() and (trials.open_unseen == 0).all()
    table = mon.unseen_table(trials)
    assert len(table) == 6 and (table.unseen == 1.0).all()


def test_unseen_heaps_take_the_nearest_surface_element():
    from types import SimpleNamespace

    plan = SimpleNamespace(points=np.array([[0.0, 0, 0], [1.0, 0, 0]]),
                           pose_set=SimpleNamespace(visible=np.array([[True, False], [False, False]])))
    assert mon.unseen_heaps(plan, [[0.1, 0, 0], [0.9, 0, 0]]).tolist() == [False, True]


def test_sensitivity_points_change_one_dimension_at_a_time():
    from mavac.geometry.machines import StandIn

    points = mon.sensitivity_points()
    assert len(points) == 2 + 2 + 1  # three values each (the shelf has two), the nominal left out
    nominal = StandIn()
    for dimension, value, stand_in in points:
        changed = [f for f in ("mill_bench_height", "mill_sill", "sander_shelf") if getattr(stand_in, f) != getattr(nominal, f)]
        assert changed == [dimension] and getattr(stand_in, dimension) == value
    assert [p[:2] for p in mon.sensitivity_points(fast=True)] == [("mill_bench_height", 0.65)]


def test_sensitivity_table_puts_the_nominal_first_and_pools_seeds():
    from mavac.geometry.machines import StandIn

    nominal = [r for r in _runs() if r["scene"] == "sanding_milling"]
    lifted = [_run("sanding_milling", "paper", t, c) | dict(dimension="mill_sill", value=0.07, stand_in=StandIn(mill_sill=0.07))
              for t, c in ((1, 3), (2, 4))]
    table = mon.sensitivity_table(nominal, lifted)
    assert table.dimension.tolist() == ["nominal", "mill_sill"]
    assert table.cleaning_pct.tolist() == [pytest.approx(60.0), pytest.approx(35.0)]
    assert table.seeds.tolist() == ["1 2", "1 2"] and table.mill_sill.tolist() == [0.0, 0.07]


def test_trials_of_makes_each_plan_once_then_runs_every_item_in_order(monkeypatch):
    made = []
    monkeypatch.setattr(mon, "offline_plan", lambda scene, reading, *, offline, fast, stand_in:
                        made.append((scene, reading, offline, stand_in)))
    monkeypatch.setattr(mon, "_trial", lambda item: (item[0], item[2]))
    items = [("test_bench", ("paper", "hpr"), seed, True, None) for seed in (1, 2)]
    items.append(("sanding_milling", ("paper", "raycast"), 1, True, None))
    assert mon.trials_of(items, n_jobs=1) == [("test_bench", 1), ("test_bench", 2), ("sanding_milling", 1)]
    assert made == [("test_bench", "paper", "hpr", None), ("sanding_milling", "paper", "raycast", None)]


def test_run_sensitivity_maps_every_point_and_seed_at_once_and_labels_each_run(monkeypatch):
    maps = []

    def trials_of(items, *, n_jobs):
        maps.append(items)
        return [dict(trial=item[2], ran_on=item[4]) for item in items]

    monkeypatch.setattr(mon, "trials_of", trials_of)
    runs = mon.run_sensitivity(seeds=(1, 2))
    points = mon.sensitivity_points()
    assert len(maps) == 1 and len(runs) == 2 * len(points)
    for k, run in enumerate(runs):
        dimension, value, stand_in = points[k // 2]
        assert (run["dimension"], run["value"], run["stand_in"], run["ran_on"], run["trial"]) == \
            (dimension, value, stand_in, stand_in, (1, 2)[k % 2])


def _drawn_tick_labels(axis):
    """The tick labels a draw placed (reading them through ``get_ticklabels`` would move them back)."""
    lo, hi = sorted(axis.get_view_interval())
    locs = axis.get_majorticklocs()
    return [t.label1 for t in axis.majorTicks[:len(locs)] if lo - 1e-9 <= t.get_loc() <= hi + 1e-9]


def test_fig8_tick_labels_do_not_overlap():
    import matplotlib.pyplot as plt

    from mavac.geometry.machines import load_machine

    runs = []
    for scene, n in (("test_bench", 146), ("sanding_milling", 156)):  # the paper-scale trial 1 heaps
        lo, hi = load_machine(scene).mesh.bounds
        result = TrialResult(scene, 1, np.random.default_rng(0).uniform(lo, hi, (n, 3)), np.arange(n) < 0.8 * n,
                             np.array([""] * n), detected=n, true_positives=n, recalled=n)
        runs.append(dict(scene=scene, reading="paper", offline="hpr", trial=1, result=result))
    fig = mon.plot_fig8(runs)
    try:
        fig.set_dpi(120)  # as plots.save writes 05_fig8.png
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        for ax in fig.axes:
            labels = [lb for axis in (ax.xaxis, ax.yaxis, ax.zaxis) for lb in _drawn_tick_labels(axis)]
            boxes = [lb.get_window_extent(renderer) for lb in labels if lb.get_visible() and lb.get_text()]
            assert len(boxes) >= 6  # still two or more ticks per axis
            clashes = [(labels[i].get_text(), labels[j].get_text()) for i in range(len(boxes))
                       for j in range(i + 1, len(boxes)) if boxes[i].overlaps(boxes[j])]
            assert not clashes, (ax.get_title(), clashes)
    finally:
        plt.close(fig)

"""Notebook 05's tables: per-trial rows, the paper-style mean, scenes and regions, paper beside
ours, miss causes per region."""

import numpy as np
import pandas as pd
import pytest

from mavac.cleaning.trial import TrialResult
from mavac.experiments import mavac_online as mon


def _run(scene, reading, trial, cleaned, n=10, enclosed=2):
    causes = np.array([""] * cleaned + ["no approach found"] * (n - cleaned))
    result = TrialResult(scene, trial, np.zeros((n, 3)), np.arange(n) < cleaned, causes, detected=12,
                         true_positives=12, recalled=n - 1)
    result.times.arm_s = 60.0
    regions = np.array(["open"] * (n - enclosed) + ["enclosed"] * enclosed)  # misses fall in the last heaps
    return dict(scene=scene, reading=reading, trial=trial, result=result, regions=regions)


def _runs():
    spec = [("test_bench", "paper", 1, 8), ("test_bench", "paper", 2, 9), ("sanding_milling", "paper", 1, 7),
            ("sanding_milling", "paper", 2, 5), ("test_bench", "authors", 1, 4), ("sanding_milling", "authors", 1, 2)]
    return [_run(*s) for s in spec]


def test_trials_table_has_region_counts_and_no_wall_time():
    trials = mon.trials_table(_runs())
    assert list(trials.columns[:len(mon.TRIAL_COLUMNS)]) == mon.TRIAL_COLUMNS
    assert "wall_s" not in trials.columns
    first = trials.iloc[0]
    assert (first.open_heaps, first.open_cleaned, first.enclosed_heaps, first.enclosed_cleaned) == (8, 8, 2, 0)


def test_paper_style_mean_averages_every_trial_of_both_scenes():
    summary = mon.table2(mon.trials_table(_runs()))
    paper = summary[(summary.reading == "paper") & (summary.statistic == "paper-style mean")].iloc[0]
    assert paper.cleaning_pct == pytest.approx((80 + 90 + 70 + 50) / 4)
    assert (paper.cleaning_pct_min, paper.cleaning_pct_max, paper.trials) == (50.0, 90.0, 4)
    bench = summary[(summary.reading == "paper") & (summary.scene == "test_bench") & (summary.region == "all")]
    assert bench.cleaning_pct.iloc[0] == pytest.approx(85.0)


def test_regions_pool_heaps_over_trials():
    summary = mon.table2(mon.trials_table(_runs()))
    pooled = summary[(summary.reading == "paper") & (summary.scene == "both") & (summary.statistic == "pooled heaps")]
    by_region = dict(zip(pooled.region, pooled.cleaning_pct))
    assert by_region["open"] == pytest.approx(100.0 * (8 + 8 + 7 + 5) / 32)
    assert by_region["enclosed"] == pytest.approx(100.0 * 1 / 8)  # bench trial 2 cleans heap 8


def test_paper_beside_ours_reads_paper_values_for_both_readings():
    comparison = mon.table2_vs_paper(mon.table2(mon.trials_table(_runs())))
    head = comparison.iloc[0]
    assert head.paper_cleaning_pct == 84.0  # the paper's Results, from data/paper_values.csv
    assert head.ours_paper == pytest.approx(72.5) and head.ours_authors == pytest.approx(30.0)
    bench = comparison[comparison.row == "test bench"].iloc[0]
    assert bench.paper_cleaning_pct == 87.8  # mean of the paper's five test-bench trials
    assert np.isnan(comparison[comparison.row == "enclosed heaps, both scenes"].paper_cleaning_pct.iloc[0])


def test_miss_causes_are_split_by_region():
    misses = mon.miss_causes_table(_runs())
    row = misses[(misses.reading == "paper") & (misses.scene == "test_bench") & (misses.region == "enclosed")].iloc[0]
    assert row["no approach found"] == 3  # trial 1 misses 2 enclosed heaps, trial 2 one
    assert isinstance(mon.times_table(_runs()), pd.DataFrame)


def test_miss_shares_sum_to_one_hundred_per_row():
    shares = mon.miss_shares(mon.miss_causes_table(_runs()))
    assert (shares["uncleaned"] > 0).all()
    assert np.allclose(shares[list(mon.CAUSES)].sum(axis=1), 100.0)

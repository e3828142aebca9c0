"""Notebook 05's tables: Table 2 rows, the sanding+milling sum, paper beside ours, miss causes."""

import numpy as np
import pandas as pd

from mavac.cleaning.trial import TrialResult
from mavac.experiments import mavac_online as mon


def _result(machine, seed, cleaned, n=10, detected=12, tp=12):
    causes = np.array([""] * cleaned + ["hidden"] * (n - cleaned))
    r = TrialResult(machine, seed, np.zeros((n, 3)), np.arange(n) < cleaned, causes, detected=detected,
                    true_positives=tp, recalled=n - 1)
    r.times.arm_s, r.wall_s = 10.0, 1.0
    return r


def _runs():
    return [dict(machine=m, trial=t, result=_result(m, t, c)) for m, t, c in
            [("test_bench", 1, 8), ("test_bench", 2, 9), ("sanding_machine", 1, 7), ("milling_machine", 1, 5)]]


def test_table2_has_the_issue_columns_and_sums_sanding_and_milling():
    table = mon.table2(_runs())
    assert list(table.columns) == mon.TABLE2_COLUMNS
    combined = table[table.machine == mon.COMBINED].iloc[0]
    assert combined.heaps == 20 and combined.cleaned == 12 and combined.uncleaned == 8
    assert combined.cleaning_pct == 60.0 and combined.recall == 0.9
    assert table[table.machine == "test_bench"].cleaning_pct.tolist() == [80.0, 90.0]


def test_paper_beside_ours_reads_paper_values():
    comparison = mon.table2_vs_paper(mon.table2(_runs()))
    bench = comparison[comparison.machine == "test_bench"].iloc[0]
    assert bench.paper_cleaning_pct == 87.8  # mean of the paper's five test-bench trials
    assert bench.ours_cleaning_pct_simulated == 85.0
    overall = comparison.iloc[-1]
    assert overall.paper_cleaning_pct == 84.0


def test_miss_causes_are_summed_per_machine():
    misses = mon.miss_causes_table(_runs())
    bench = misses[misses.machine == "test_bench"].iloc[0]
    assert bench["hidden"] == 3 and bench["never in view"] == 0
    assert isinstance(mon.times_table(_runs()), pd.DataFrame)

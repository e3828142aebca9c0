"""Notebook 11's tables (mavac.experiments.kabir_bimanual) from the cell's per-pass logs."""

from types import SimpleNamespace

import numpy as np
import pytest

from mavac.experiments.kabir_bimanual import EXECUTION_COLUMNS, execution_table, summary_table
from mavac.scrubbing.run import PartRun


def _row(commanded, contact, error_all, rms_all, error_contact, rms_contact, **other):
    row = {c: 0 for c in EXECUTION_COLUMNS if c not in ("part", "parameters", "pass")}
    row.update(setup="round 0 setup 1", pass_=1, commanded_steps=commanded, contact_steps=contact,
               duty=contact / commanded, force_error_all=error_all, force_rms_all=rms_all,
               force_error_contact=error_contact, force_rms_contact=rms_contact, failed=False,
               wear_depth_max_mm=1.0, residue_fraction=0.1)
    row.update(other)
    return row


def _run(rows):
    execution = SimpleNamespace(rows=rows, setup_times=[10.0], setups=[{}])
    state = SimpleNamespace(images=[dict(residue_fraction=0.1)])
    return PartRun("hull", [], execution, state, 0, 0.9, 0, SimpleNamespace(f_n=10.0), 1.0)


def test_summary_weights_every_commanded_step_and_keeps_the_worst_pass():
    good = _row(900, 900, 0.0, 0.1, 0.0, 0.1)
    bad = _row(100, 40, -0.6, 0.8, 0.0, 0.1, nonpad_part_steps=3, integral_saturated_steps=10, failed=True)
    runs = {("hull", "learned"): _run([good, bad]), ("hull", "paper"): _run([good])}
    ex = execution_table(runs)
    assert list(ex.columns) == EXECUTION_COLUMNS and len(ex) == 3
    s = summary_table(runs).set_index("parameters")
    assert s.loc["learned", "duty_min"] == pytest.approx(0.4)
    assert s.loc["learned", "duty"] == pytest.approx(940 / 1000)
    assert s.loc["learned", "force_error_all"] == pytest.approx(-0.06)  # over all 1000 commanded steps
    assert s.loc["learned", "force_rms_all"] == pytest.approx(np.sqrt((900 * 0.01 + 100 * 0.64) / 1000))
    assert s.loc["learned", "integral_saturated_share"] == pytest.approx(0.01)
    assert s.loc["learned", "nonpad_part_steps"] == 3 and s.loc["learned", "failed_passes"] == 1
    assert s.loc["paper", "duty_min"] == 1.0 and s.loc["paper", "failed_passes"] == 0

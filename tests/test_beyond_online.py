"""Notebook 12's adaptive-against-systematic comparison: its runs, the intervals over seeds and
the time ratio."""

import dataclasses
import warnings

import numpy as np
import pandas as pd
import pytest
import trimesh
from scipy import stats

from mavac.experiments import beyond_online as BO
from mavac.experiments.mavac_offline import fast_params
from mavac.geometry.machines import machine_from_mesh
from mavac.inspection.inspection_plan import plan_inspection
from mavac.experiments.mavac_online import paper_scene_means
from mavac.paper import paper_values
from mavac.params import DustParams, OnlineParams


@pytest.fixture(scope="module")
def box_scene():
    """A 0.8 x 0.5 x 0.6 m box, its fast-mode plan cut to three poses, and coarse dust."""
    machine = machine_from_mesh(trimesh.creation.box(bounds=[[-0.4, -0.25, 0.0], [0.4, 0.25, 0.6]]), name="box")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_inspection(machine, params=fast_params())
    return machine, dataclasses.replace(plan, pose_set=plan.pose_set.head(3))


@pytest.fixture
def on_the_box(box_scene, monkeypatch):
    machine, plan = box_scene
    monkeypatch.setattr(BO, "load_machine", lambda scene: machine)
    monkeypatch.setattr(BO, "offline_plan", lambda scene, reading, *, offline, fast: plan)
    monkeypatch.setattr(BO, "online_params", lambda reading, *, fast: OnlineParams(dust=DustParams(spacing=0.1)))
    return machine, plan


def test_items_run_adaptive_per_density_and_systematic_once_for_all():
    items = BO.comparison_items(scenes=("a", "b"), densities=(1.0, 0.1), seeds=(1, 2, 3), fast=True)
    assert len(items) == 2 * 2 * 3 + 2 * 3 and {i[0] for i in items} == set(BO.METHODS)
    assert items[0] == BO.adaptive_unit("a", 1, density=1.0, fast=True)
    assert items[0] == ("adaptive", "a", "hpr", 1.0, BO.PerturbationParams(), 1.0, 1, True)
    assert items[-1] == ("systematic", "b", (1.0, 0.1), 3, True)
    with pytest.raises(ValueError, match=r"densities must be in \(0, 1\]"):
        BO.comparison_items(densities=(0.0,))


def test_a_systematic_run_scores_each_density_on_the_subset_its_own_run_would_have(on_the_box):
    from mavac.cleaning.systematic import run_systematic

    machine, plan = on_the_box
    unit = BO.systematic_unit("box", (1.0, 0.5), 4, fast=True)
    full, sparse = BO.comparison_rows(unit, BO.unit_run(unit))
    assert sparse["heaps"] == round(0.5 * full["heaps"]) and 0 <= sparse["cleaned"] <= sparse["heaps"]
    for column in ("sim_time_s", "tool_path_m", "joint_travel_rad"):
        assert sparse[column] == full[column] > 0
    assert full["time_per_cleaned_heap_s"] == pytest.approx(full["sim_time_s"] / full["cleaned"], rel=1e-3)
    # the run at density 0.5 itself: same motion, and the same heaps cleaned
    own = run_systematic(machine, plan, params=OnlineParams(dust=DustParams(spacing=0.1, density=0.5)), seed=4)
    assert own.n_cleaned == sparse["cleaned"] and round(own.times.sim_time_s, 3) == sparse["sim_time_s"]


def test_adaptive_runs_the_online_trial_and_measures_its_motion(on_the_box):
    from mavac.cleaning.trial import run_trial

    machine, plan = on_the_box
    unit = BO.adaptive_unit("box", 4, fast=True)
    (row,) = BO.comparison_rows(unit, BO.unit_run(unit))
    trial = run_trial(machine, plan, params=OnlineParams(dust=DustParams(spacing=0.1)), seed=4)
    assert row["cleaned"] == trial.n_cleaned and row["sim_time_s"] == round(trial.times.sim_time_s, 3)
    assert row["tool_path_m"] > 0 and row["joint_travel_rad"] > 0
    runs = BO.comparison_runs([BO.systematic_unit("box", (0.5, 1.0), 4, fast=True), unit])
    assert list(runs.columns) == BO.RUN_COLUMNS
    assert runs[["method", "density"]].values.tolist() == [["adaptive", 1.0], ["systematic", 1.0], ["systematic", 0.5]]


def _runs() -> pd.DataFrame:
    rows = []
    for method, base in (("adaptive", 100.0), ("systematic", 300.0)):
        for density in (1.0, 0.1):
            for seed, noise in enumerate((-1.0, 0.0, 1.0)):
                time = base * (density if method == "adaptive" else 1.0) + noise
                rows.append(dict(method=method, scene="s", density=density, seed=seed, heaps=10, cleaned=5,
                                 cleaning_pct=50.0 + noise, sim_time_s=time, base_s=0.0, arm_s=time, vacuum_s=0.0,
                                 tool_path_m=1.0, joint_travel_rad=2.0, time_per_cleaned_heap_s=time / 5))
    return pd.DataFrame(rows, columns=BO.RUN_COLUMNS)


def test_summary_gives_the_mean_and_its_student_t_interval():
    s = BO.comparison_summary(_runs())
    row = s[(s.method == "adaptive") & (s.density == 1.0)].iloc[0]
    half = stats.t.ppf(0.975, 2) * 1.0 / np.sqrt(3)  # the standard error of (-1, 0, 1) + 100 is 1 / sqrt(3)
    assert row.runs == 3 and row.sim_time_s == pytest.approx(100.0)
    assert row.sim_time_s_low == pytest.approx(100.0 - half, abs=1e-3)
    assert row.sim_time_s_high == pytest.approx(100.0 + half, abs=1e-3)
    assert row.tool_path_m_low == row.tool_path_m == row.tool_path_m_high == 1.0  # no spread


def test_time_ratio_is_adaptive_over_systematic_per_scene_and_over_both():
    r = BO.time_ratios(BO.comparison_summary(_runs()))
    one = r[(r.scene == "s") & (r.density == 1.0)].iloc[0]
    assert one.time_ratio == pytest.approx(100.0 / 300.0, abs=1e-3)
    sparse = r[(r.scene == "both") & (r.density == 0.1)].iloc[0]
    assert sparse.time_ratio == pytest.approx(10.0 / 300.0, abs=1e-3)


def test_the_plot_has_time_and_cleaning_panels_per_scene():
    fig = BO.plot_comparison(BO.comparison_summary(_runs()))
    assert len(fig.axes) == 2 and fig.axes[0].get_ylabel() == "simulated time (s)"


def test_paper_beside_ours_reads_table_2_for_each_scene():
    runs = _runs().assign(scene="test_bench")
    table = BO.comparison_vs_paper(BO.comparison_summary(runs))
    row = table.iloc[0]
    assert row.scene == "test_bench" and row.ours_adaptive_sim_time_s == pytest.approx(100.0)
    assert row.ours_systematic_cleaning_pct == pytest.approx(50.0)
    assert row.paper_cleaning_pct == paper_scene_means()["test_bench"]
    timed = paper_values("mavac", "Table 2", "time")
    minutes = timed[timed.condition.str.contains("machine=test bench")]["value"]
    assert row.paper_time_s == pytest.approx(60.0 * minutes.mean()) and len(minutes) > 0


@pytest.fixture(scope="module")
def box_plans(box_scene):
    """The box's fast plans with HPR and with ray casting, cut to three poses."""
    machine, _ = box_scene
    plans = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for method in ("hpr", "raycast"):
            plan = plan_inspection(machine, params=fast_params().with_visibility(method))
            plans[method] = dataclasses.replace(plan, pose_set=plan.pose_set.head(3))
    return machine, plans


def test_visibility_items_pair_each_seed_with_both_plans():
    items = BO.visibility_items(scenes=("a",), seeds=(1, 2), fast=True)
    assert items == [BO.adaptive_unit("a", seed, offline=offline, fast=True) for offline in ("hpr", "raycast")
                     for seed in (1, 2)]


def test_false_visible_heaps_are_counted_but_unseen_and_none_on_a_ray_cast_plan(box_plans, monkeypatch):
    machine, plans = box_plans
    monkeypatch.setattr(BO, "load_machine", lambda scene: machine)
    monkeypatch.setattr(BO, "offline_plan", lambda scene, reading, *, offline, fast: plans[offline])
    monkeypatch.setattr(BO, "online_params", lambda reading, *, fast: OnlineParams(dust=DustParams(spacing=0.1)))
    runs = BO.visibility_runs(BO.visibility_items(scenes=("box",), seeds=(3,), fast=True))
    assert list(runs.columns) == BO.VISIBILITY_COLUMNS and len(runs) == 2
    for row in runs.itertuples():
        assert 0 <= row.false_visible_undetected <= row.heaps_false_visible <= row.heaps_counted <= row.heaps
        assert row.false_visible_cleaned <= row.heaps_false_visible and row.guards > 0
    ray = runs[runs.offline == "raycast"].iloc[0]
    assert ray.C_raycast == pytest.approx(ray.C) and ray.heaps_false_visible == 0
    hpr = runs[runs.offline == "hpr"].iloc[0]
    on = BO.heaps_on_elements(plans["hpr"], plans["hpr"].points[:5], BO.VisibilityScene(machine.mesh))
    assert on["C"] == pytest.approx(hpr.C, abs=1e-4) and on["counted"].tolist() == plans["hpr"].observed[:5].tolist()
    s = BO.visibility_summary(runs)
    assert s.trials.tolist() == [1, 1] and s.offline.tolist() == ["hpr", "raycast"]


def test_an_online_sweep_point_on_a_dask_cluster_equals_the_local_backend(on_the_box):
    distributed = pytest.importorskip("distributed", reason="install the dask extra: pip install -e '.[dask]'")
    import joblib

    items = [BO.adaptive_unit("box", 4, density=0.5, fast=True), BO.systematic_unit("box", (1.0, 0.5), 4, fast=True)]
    local = BO.comparison_runs(items, n_jobs=1)
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        with distributed.get_task_stream(client) as stream, joblib.parallel_backend("dask"):
            remote = BO.comparison_runs(items, n_jobs=2)
        assert len(stream.data) >= 2  # the runs went to the cluster's workers
    assert local.equals(remote) and len(local) == 3

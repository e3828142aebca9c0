"""The two readings of MAVAC (paper's text, authors' code): valid parameters that differ where
the code differs from the text, and a clear error for an unknown reading."""

import dataclasses
import math

import pytest

import mavac.params as mp
from mavac.params import OnlineParams
from mavac.cleaning.readings import READINGS, check_reading, inspection_params, online_params


def test_readings_are_spelled_once():
    assert READINGS == ("paper", "authors")


def test_paper_reading_is_the_package_default_with_the_authors_alpha_and_delta():
    """The paper gives no alpha or delta (eq. 5): the paper reading takes the authors' (20 deg,
    doosan.py:417; 5 cm, online.py:182-184 at 4a4038c); the package defaults stay ours."""
    paper = online_params("paper")
    assert paper.approach.alpha == pytest.approx(math.radians(20.0)) and paper.approach.delta == 0.05
    assert OnlineParams().approach.alpha == pytest.approx(math.radians(15.0)) and OnlineParams().approach.delta == 0.10
    default = OnlineParams()
    assert dataclasses.replace(paper, approach=default.approach) == default
    assert online_params() == paper


def test_authors_reading_differs_where_the_code_does():
    paper, authors = online_params("paper"), online_params("authors")
    # 4a4038c: online.py:191 (0.7 m), dust.py:138-141 (eps 0.13, noise kept), doosan.py:417 (20 deg)
    assert paper.detection.max_tip_distance is None and authors.detection.max_tip_distance == 0.7
    assert (authors.approach.cluster_eps, authors.approach.cluster_min_samples) == (0.13, 1)
    assert authors.approach.delta == 0.05 and authors.approach.alpha == pytest.approx(math.radians(20.0))
    assert authors.approach.area_order == "tsp" and paper.approach.area_order == "detection"
    assert paper.vacuum.pattern == "linear" and authors.vacuum.pattern == "spiral"
    assert (authors.vacuum.spiral_radius, authors.vacuum.spiral_turns, authors.vacuum.spiral_time) == (0.01, 2.0, 5.0)
    assert (authors.vacuum.stiffness, authors.vacuum.rotational_stiffness, authors.vacuum.speed) == (100.0, 20.0, 0.02)
    # the same in both: the sensor's depth range, the reach filter, no duplicate filter, TSP inside areas
    for field in ("min_depth", "max_depth", "reach", "duplicate"):
        assert getattr(paper.detection, field) == getattr(authors.detection, field)
    assert paper.detection.max_depth == 2.88 and paper.approach.node_order == authors.approach.node_order == "tsp"


@pytest.mark.parametrize("reading", READINGS)
def test_readings_give_valid_params_also_in_fast_mode(reading):
    params = online_params(reading, fast=True)
    assert params.dust.spacing == 0.2
    assert dataclasses.replace(params) == params  # re-validates every field


@pytest.mark.parametrize("bad", ["Paper", "code", ""])
def test_unknown_reading_is_a_value_error_naming_the_legal_values(bad):
    for fn in (online_params, check_reading, inspection_params):
        with pytest.raises(ValueError, match=r"reading must be one of \('paper', 'authors'\)"):
            fn(bad)


def test_non_string_reading_is_a_type_error():
    with pytest.raises(TypeError, match="reading"):
        online_params(1)


def test_offline_reading_is_hpr_and_ray_casting_stays_the_package_default():
    assert mp.InspectionParams().visibility.method == "raycast"
    assert inspection_params("paper") == mp.InspectionParams().with_visibility("hpr")
    assert inspection_params("paper", offline="raycast") == mp.InspectionParams()
    assert inspection_params("authors", offline="raycast").visibility.method == "raycast"
    with pytest.raises(ValueError, match="offline must be one of"):
        inspection_params("paper", offline="HPR")


def test_variants_are_each_reading_with_hpr_and_the_paper_with_ray_casting():
    from mavac.cleaning.readings import VARIANTS

    assert VARIANTS == (("paper", "hpr"), ("paper", "raycast"), ("authors", "hpr"))


def test_authors_offline_reading():
    paper, authors = inspection_params("paper"), inspection_params("authors")
    assert authors.camera.theta_a == pytest.approx(math.radians(45)) and authors.camera.theta_b == pytest.approx(math.radians(35))
    assert authors.camera.L_d == 0.7 and authors.guard.standoff == 0.4
    assert authors.visibility == mp.Visibility("hpr", radius=10.0)
    assert authors != paper


def test_fast_mode_scales_the_authors_dbscan_radius_with_the_heap_spacing():
    assert online_params("authors", fast=True).approach.cluster_eps == pytest.approx(0.26)
    assert online_params("paper", fast=True).approach == online_params("paper").approach


def test_authors_reading_runs_a_trial_with_tip_filter_and_spiral():
    """One short pybullet trial (3 poses of a small box): the authors' reading end to end."""
    import warnings

    import trimesh

    from mavac.cleaning.trial import run_trial
    from mavac.experiments.mavac_offline import fast_params
    from mavac.geometry.machines import machine_from_mesh
    from mavac.inspection.inspection_plan import plan_inspection

    machine = machine_from_mesh(trimesh.creation.box(bounds=[[-0.5, -0.3, 0.0], [0.5, 0.3, 0.6]]), name="box")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_inspection(machine, params=fast_params())
    plan = dataclasses.replace(plan, pose_set=plan.pose_set.head(3))
    r = run_trial(machine, plan, params=online_params("authors", fast=True), seed=3)
    assert set(r.filtered) == {"depth", "reach", "tip", "duplicate"} and r.filtered["duplicate"] == 0
    assert r.detected > 0 and r.areas > 0
    assert r.times.vacuum_s >= 5.0 * r.areas_cleaned  # each vacuumed area ends with a 5 s spiral


def test_differences_lists_exactly_the_fields_that_differ():
    from mavac.cleaning.readings import differences

    table = differences()
    online = table[table.stage == "online"].set_index("parameter")
    assert online.loc["detection.max_tip_distance", "authors"] == 0.7
    assert "approach.delta" not in online.index and "approach.alpha" not in online.index  # both the authors'
    assert "time_step" not in online.index  # equal in both readings: not listed
    offline = table[table.stage == "offline"].set_index("parameter")
    assert offline.loc["guard.standoff", "authors"] == 0.4

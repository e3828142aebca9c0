"""Tests run in fast mode so nothing they write lands in data/results or figures."""

import os

os.environ["MAVAC_FAST"] = "1"

import pytest  # noqa: E402 (the environment above is set before anything imports mavac)


@pytest.fixture
def count_checker_builds(monkeypatch):
    """``count(module) -> list``: replace ``module.CollisionChecker`` by a subclass that appends
    to the returned list each time one is built."""
    def count(module):
        built = []

        class Counting(module.CollisionChecker):
            def __init__(self, *args, **kwargs):
                built.append(1)
                super().__init__(*args, **kwargs)

        monkeypatch.setattr(module, "CollisionChecker", Counting)
        return built

    return count


@pytest.fixture
def box_plan():
    """A 0.8 x 0.5 x 0.6 m box machine and its fast-mode plan's first three poses (online tests
    that need a real plan, fast)."""
    import dataclasses
    import warnings

    import trimesh

    from mavac.experiments.mavac_offline import fast_params
    from mavac.geometry.machines import machine_from_mesh
    from mavac.inspection.inspection_plan import plan_inspection

    machine = machine_from_mesh(trimesh.creation.box(bounds=[[-0.4, -0.25, 0.0], [0.4, 0.25, 0.6]]), name="box")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_inspection(machine, params=fast_params())
    return machine, dataclasses.replace(plan, pose_set=plan.pose_set.head(3))

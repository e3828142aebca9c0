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

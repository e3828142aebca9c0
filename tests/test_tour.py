"""The short open tour (mavac.planning.tour)."""

import numpy as np
import pytest

from mavac.planning.tour import short_open_path


def test_short_open_path():
    x = np.array([0.0, 5.0, 1.0, 3.0, 2.0, 4.0])
    d = np.abs(x[:, None] - x[None])
    order = short_open_path(d, 0)
    assert x[order].tolist() == sorted(x.tolist())
    rng = np.random.default_rng(0)
    pts = rng.uniform(0, 1, (9, 2))
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    order = short_open_path(d, 3)
    assert order[0] == 3 and sorted(order.tolist()) == list(range(9))
    assert short_open_path(np.zeros((0, 0))).size == 0


def test_bad_input():
    with pytest.raises(ValueError, match="start"):
        short_open_path(np.zeros((2, 2)), 5)
    with pytest.raises(ValueError, match="dist"):
        short_open_path(np.zeros((2, 3)))

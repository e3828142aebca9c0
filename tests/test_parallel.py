import pytest

from mavac.parallel import map_trials


def _square(x):
    return x * x


def test_results_in_item_order_serial_and_processes():
    items = list(range(7))
    assert map_trials(_square, items, progress=False) == [x * x for x in items]
    assert map_trials(_square, items, n_jobs=2, progress=False) == [x * x for x in items]


def test_zero_jobs_is_an_error():
    with pytest.raises(ValueError, match="n_jobs"):
        map_trials(_square, [1], n_jobs=0)

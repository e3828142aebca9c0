"""The disk cache checks each entry against its checksum before loading it."""

import numpy as np
import pytest
from joblib import Memory

from mavac.cache import CHECKSUM_FILE, verified_cache

CALLS = []


def _ramp(n: int) -> np.ndarray:
    CALLS.append(n)
    return np.arange(n, dtype=np.float64)


def _flip_middle(path, n_bytes=4096):
    data = bytearray(path.read_bytes())
    mid = len(data) // 2
    data[mid:mid + n_bytes] = bytes(b ^ 0xFF for b in data[mid:mid + n_bytes])
    path.write_bytes(bytes(data))


@pytest.fixture
def cached(tmp_path):
    CALLS.clear()
    return verified_cache(_ramp, location=Memory(tmp_path, verbose=0))


def test_second_call_loads_the_stored_output(cached):
    a = cached(100_000)
    b = cached(100_000)
    assert np.array_equal(a, b) and CALLS == [100_000]


def test_flipped_bytes_are_detected_and_recomputed(cached, tmp_path):
    expected = cached(100_000)
    output = next(tmp_path.rglob("output.pkl"))
    assert (output.parent / CHECKSUM_FILE).is_file()
    _flip_middle(output)
    # the flip keeps the file size and still unpickles: joblib alone would return garbage
    assert not np.array_equal(cached.memorized(100_000), expected)
    with pytest.warns(RuntimeWarning, match="differs from its checksum"):
        again = cached(100_000)
    assert np.array_equal(again, expected) and CALLS == [100_000, 100_000]
    assert np.array_equal(cached(100_000), expected) and len(CALLS) == 2  # stored again, intact


def test_entry_without_checksum_is_recomputed(cached, tmp_path):
    cached(1000)
    output = next(tmp_path.rglob("output.pkl"))
    (output.parent / CHECKSUM_FILE).unlink()
    with pytest.warns(RuntimeWarning, match="has no checksum"):
        assert np.array_equal(cached(1000), np.arange(1000.0))
    assert CALLS == [1000, 1000]


def test_reachability_map_entry_flipped(tmp_path, monkeypatch):
    """The issue's case: 4 KB flipped in the middle of a reachability map's pickle."""
    from mavac import cache
    from mavac.inspection import reachability as R
    from mavac.params import ReachabilityMapParams
    from mavac.robots.models import ur10_mobile

    monkeypatch.setattr(cache, "memory", lambda: Memory(tmp_path, verbose=0))
    robot = ur10_mobile()
    tiny = ReachabilityMapParams(voxel_size=0.1, n_directions=8, n_samples=2000, n_rotations=8, seed=5)
    first = R.reachability_map(robot, tiny)
    output = next(tmp_path.rglob("output.pkl"))
    assert output.stat().st_size > 3 * 4096
    _flip_middle(output)
    with pytest.warns(RuntimeWarning, match="differs from its checksum"):
        second = R.reachability_map(robot, tiny)
    assert np.array_equal(first.reachable, second.reachable)

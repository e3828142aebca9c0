import pandas as pd
import pytest

from mavac.io import atomic_path, write_csv, write_json


def test_write_csv_round_trip(tmp_path):
    df = pd.DataFrame({"a": [1, 2], "b": [0.5, 0.25]})
    path = write_csv(df, tmp_path / "sub" / "t.csv")
    pd.testing.assert_frame_equal(pd.read_csv(path), df)


def test_interrupted_write_leaves_no_file(tmp_path):
    target = tmp_path / "t.csv"
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise KeyboardInterrupt
    assert not target.exists()
    assert list(tmp_path.iterdir()) == []


def test_interrupted_write_keeps_previous_version(tmp_path):
    target = write_json({"v": 1}, tmp_path / "p.json")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("{broken")
            raise RuntimeError
    assert target.read_text() == '{\n  "v": 1\n}'


def test_written_files_get_normal_permissions(tmp_path):
    path = write_json({"v": 1}, tmp_path / "p.json")
    assert path.stat().st_mode & 0o644 == 0o644


@pytest.mark.parametrize("sig", ["SIGKILL", "SIGTERM"])
def test_killed_writer_leaves_its_temporary_in_the_temp_folder_until_the_next_write(tmp_path, sig):
    import signal

    from _children import HALF_WRITTEN_CSV, end, start, wait_line
    from mavac.io import TEMP_DIR

    target = tmp_path / "t.csv"
    proc = start(HALF_WRITTEN_CSV, target)
    wait_line(proc, "writing")
    proc.send_signal(getattr(signal, sig))
    assert proc.wait(timeout=30) == -getattr(signal, sig)
    end(proc)
    # nothing half-written at the target or hidden beside it: one temporary, in the temp folder
    assert [p.name for p in tmp_path.iterdir()] == [TEMP_DIR]
    assert len(list((tmp_path / TEMP_DIR).iterdir())) == 1
    df = pd.DataFrame({"a": [1], "b": [2]})
    write_csv(df, target)
    pd.testing.assert_frame_equal(pd.read_csv(target), df)
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]  # stale temporary and folder gone


def test_a_live_writers_temporary_is_not_cleaned(tmp_path):
    from _children import HALF_WRITTEN_CSV, end, start, wait_line
    from mavac.io import TEMP_DIR

    proc = start(HALF_WRITTEN_CSV, tmp_path / "slow.csv")
    try:
        wait_line(proc, "writing")
        write_csv(pd.DataFrame({"a": [1]}), tmp_path / "other.csv")
        assert len(list((tmp_path / TEMP_DIR).iterdir())) == 1  # still being written
    finally:
        end(proc)
    assert not (tmp_path / "slow.csv").exists()


def test_write_json_refuses_infinity_and_nan(tmp_path):
    import math

    for value in (math.inf, math.nan):
        with pytest.raises(ValueError, match="JSON"):
            write_json({"cost": value}, tmp_path / "x.json")
    assert not list(tmp_path.iterdir())

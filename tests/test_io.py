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

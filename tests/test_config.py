from mavac import config


def test_fast_mode_writes_under_build(monkeypatch, tmp_path):
    monkeypatch.setenv("MAVAC_FAST", "1")
    assert config.is_fast()
    assert config.results_dir() == config.BUILD_DIR / "results"
    assert config.figures_dir() == config.BUILD_DIR / "figures"
    assert config.fast_or_full(3, 12) == 3


def test_full_mode_writes_committed_dirs(monkeypatch):
    monkeypatch.setenv("MAVAC_FAST", "0")
    assert not config.is_fast()
    assert config.results_dir() == config.DATA_DIR / "results"
    assert config.figures_dir() == config.ROOT / "figures"
    assert config.fast_or_full(3, 12) == 12


def test_cache_dir_override(monkeypatch, tmp_path):
    monkeypatch.setenv("MAVAC_CACHE", str(tmp_path / "c"))
    assert config.cache_dir() == tmp_path / "c" and (tmp_path / "c").is_dir()

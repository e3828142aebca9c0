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


def test_mavac_out_redirects_results_and_figures(monkeypatch, tmp_path):
    monkeypatch.setenv("MAVAC_OUT", str(tmp_path / "out"))
    monkeypatch.setenv("MAVAC_FAST", "0")
    assert config.results_dir() == tmp_path / "out" / "data" / "results"
    assert config.figures_dir() == tmp_path / "out" / "figures"
    monkeypatch.setenv("MAVAC_FAST", "1")
    assert config.results_dir() == tmp_path / "out" / "build" / "results"
    assert config.user_output_dir() == tmp_path / "out"


def test_installed_package_writes_to_the_current_directory(monkeypatch, tmp_path):
    # an installed package (not a checkout) never writes beside itself
    monkeypatch.delenv("MAVAC_OUT", raising=False)
    monkeypatch.delenv("MAVAC_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(config, "in_checkout", lambda: False)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MAVAC_FAST", "0")
    assert config.results_dir() == tmp_path / "data" / "results"
    assert config.figures_dir() == tmp_path / "figures"
    assert config.cache_dir() == tmp_path / "xdg" / "mavac"
    assert config.user_output_dir() == tmp_path


def test_checkout_defaults_to_the_repository(monkeypatch):
    monkeypatch.delenv("MAVAC_OUT", raising=False)
    assert config.in_checkout()
    assert config.output_root() == config.ROOT

"""Paths and the fast-mode flag. No side effects at import: everything is read at call time.

Fast mode (``MAVAC_FAST=1``) shrinks sample counts and trial numbers and redirects every
artifact under ``build/`` so a CI run never overwrites the committed paper-scale results.

Where outputs go: ``MAVAC_OUT`` when set; otherwise the repository root when ``mavac`` runs
from a source checkout (so the notebooks write the committed ``data/results`` and
``figures``); otherwise the current directory. An installed package never writes next to
itself.
"""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA_DIR = ROOT / "data"
BUILD_DIR = ROOT / "build"


def is_fast() -> bool:
    """True when ``MAVAC_FAST`` is set to a true value (1, true, yes)."""
    return os.environ.get("MAVAC_FAST", "0").strip().lower() in {"1", "true", "yes", "on"}


def fast_or_full(fast, full):
    """Return ``fast`` in fast mode and ``full`` otherwise (same code path, smaller sizes)."""
    return fast if is_fast() else full


def in_checkout() -> bool:
    """True when the package runs from a source checkout (editable install or ``PYTHONPATH``)."""
    return (ROOT / "pyproject.toml").is_file() and (ROOT / "notebooks").is_dir()


def env_folder(name: str) -> Path | None:
    """The folder an environment variable names (None when unset); ValueError when it names a file."""
    value = os.environ.get(name, "").strip()
    if not value:
        return None
    path = Path(value).expanduser()
    if path.exists() and not path.is_dir():
        raise ValueError(f"{name}={value} is a file, not a folder; point it at a folder or unset it")
    return path


def user_output_dir() -> Path:
    """Folder the user chose for outputs: ``MAVAC_OUT``, else the current directory."""
    return env_folder("MAVAC_OUT") or Path.cwd()


def output_root() -> Path:
    """Root of the notebooks' outputs: ``MAVAC_OUT``, else the checkout, else the current directory."""
    if os.environ.get("MAVAC_OUT", "").strip() or not in_checkout():
        return user_output_dir()
    return ROOT


def results_dir() -> Path:
    """Where result CSVs go: ``data/results`` at paper scale, ``build/results`` in fast mode,
    under :func:`output_root`."""
    root = output_root()
    path = root / "build" / "results" if is_fast() else root / "data" / "results"
    path.mkdir(parents=True, exist_ok=True)
    return path


def figures_dir() -> Path:
    """Where figures go: ``figures`` at paper scale, ``build/figures`` in fast mode, under
    :func:`output_root`."""
    root = output_root()
    path = root / "build" / "figures" if is_fast() else root / "figures"
    path.mkdir(parents=True, exist_ok=True)
    return path


def instances_dir() -> Path:
    """Where planner instances go: ``data/instances`` at paper scale, ``build/instances`` in fast
    mode, under :func:`output_root`."""
    root = output_root()
    path = root / "build" / "instances" if is_fast() else root / "data" / "instances"
    path.mkdir(parents=True, exist_ok=True)
    return path


def cache_dir() -> Path:
    """On-disk cache for expensive stages: ``MAVAC_CACHE``, else ``build/cache`` in a checkout,
    else the user's cache folder (``$XDG_CACHE_HOME/mavac`` or ``~/.cache/mavac``)."""
    path = env_folder("MAVAC_CACHE")
    if path is None:
        path = BUILD_DIR / "cache" if in_checkout() else \
            Path(os.environ.get("XDG_CACHE_HOME", "") or Path.home() / ".cache") / "mavac"
    path.mkdir(parents=True, exist_ok=True)
    return path

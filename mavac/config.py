"""Paths and the fast-mode flag. No side effects at import: everything is read at call time.

Fast mode (``MAVAC_FAST=1``) shrinks sample counts and trial numbers and redirects every
artifact under ``build/`` so a CI run never overwrites the committed paper-scale results.
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


def results_dir() -> Path:
    """Where result CSVs go: ``data/results`` at paper scale, ``build/results`` in fast mode."""
    path = BUILD_DIR / "results" if is_fast() else DATA_DIR / "results"
    path.mkdir(parents=True, exist_ok=True)
    return path


def figures_dir() -> Path:
    """Where figures go: ``figures`` at paper scale, ``build/figures`` in fast mode."""
    path = BUILD_DIR / "figures" if is_fast() else ROOT / "figures"
    path.mkdir(parents=True, exist_ok=True)
    return path


def cache_dir() -> Path:
    """On-disk cache for expensive stages (``MAVAC_CACHE`` overrides)."""
    path = Path(os.environ.get("MAVAC_CACHE", BUILD_DIR / "cache"))
    path.mkdir(parents=True, exist_ok=True)
    return path

"""Input checks shared by the whole package: every refusal is a ValueError naming the
parameter and its valid range, raised before any dependency sees the bad value."""

from __future__ import annotations

import math

import numpy as np


def check_range(name: str, value, lo=-math.inf, hi=math.inf, *, lo_open=False, hi_open=False):
    """Raise ``ValueError`` unless ``lo <= value <= hi`` (open ends if asked); return value."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    low_ok = v > lo if lo_open else v >= lo
    high_ok = v < hi if hi_open else v <= hi
    if not (math.isfinite(v) or (v == hi == math.inf)) or not (low_ok and high_ok):
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        raise ValueError(f"{name} must be in {lb}{lo}, {hi}{rb}, got {value!r}")
    return value


def check_unit(name: str, value):
    """``value`` in [0, 1]."""
    return check_range(name, value, 0.0, 1.0)


def check_positive(name: str, value):
    """``value`` > 0."""
    return check_range(name, value, 0.0, math.inf, lo_open=True)


def check_nonnegative(name: str, value):
    """``value`` >= 0."""
    return check_range(name, value, 0.0, math.inf)


def check_int(name: str, value, lo: int = 0, hi: int | None = None) -> int:
    """An integer in [lo, hi]."""
    if isinstance(value, bool) or not float(value).is_integer():
        raise ValueError(f"{name} must be an integer, got {value!r}")
    check_range(name, value, lo, math.inf if hi is None else hi)
    return int(value)


def check_points(name: str, array, dim: int = 3) -> np.ndarray:
    """A finite ``(n, dim)`` float array (a single ``(dim,)`` row is promoted)."""
    a = np.asarray(array, dtype=float)
    if a.ndim == 1 and a.shape[0] == dim:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != dim:
        raise ValueError(f"{name} must have shape (n, {dim}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def check_cover(cover) -> np.ndarray:
    """A 2-D ``(m, n)`` boolean cover matrix (``cover[j, i]``: setup j reaches patch i);
    0/1 integers are accepted and converted."""
    c = np.asarray(cover)
    if c.ndim != 2:
        raise ValueError(f"cover must be a 2-D (m, n) boolean array, got shape {c.shape}")
    if c.dtype != bool:
        if not np.all((c == 0) | (c == 1)):
            raise ValueError("cover must be boolean (or 0/1)")
        c = c.astype(bool)
    return c


def check_bounds(name: str, lower, upper):
    """Elementwise ``lower <= upper`` for parameter boxes; returns float arrays."""
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    if lo.shape != hi.shape:
        raise ValueError(f"{name}: lower and upper bounds have different shapes {lo.shape} vs {hi.shape}")
    if np.any(lo > hi):
        bad = np.flatnonzero(np.atleast_1d(lo > hi)).tolist()
        raise ValueError(f"{name}: lower bound > upper bound at index {bad}")
    return lo, hi

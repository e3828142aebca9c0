"""Input checks shared by the whole package, raised before any dependency sees the bad value.

Every refusal names the parameter and what is valid: a ``TypeError`` (a
:class:`ParameterTypeError`, also a ``ValueError``) when the value has the wrong type (a
string, a boolean or ``None`` where a number is meant, floats where indices are meant), a
``ValueError`` when the type is right but the value is not (NaN, infinity, out of range, wrong
shape, ragged). Parameter dataclasses check every field in one place, :func:`check_fields`:
its type and finiteness from the annotation, its legal values (range, choices, tuple length)
from the declaration :func:`ranged`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
import os
import types
import typing
from pathlib import Path

import numpy as np


class ParameterTypeError(TypeError, ValueError):
    """A parameter of the wrong type. A ``TypeError``, and a ``ValueError`` too, so code that
    catches ``ValueError`` for every bad parameter (the package's rule before types were
    checked apart) still catches it."""


def _type_name(value) -> str:
    return type(value).__name__


def check_real(name: str, value) -> float:
    """A real number (int, float or a numpy scalar of either, not bool, str or None); returns
    it as a float, which may be NaN or infinite (:func:`check_range` refuses those)."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ParameterTypeError(f"{name} must be a real number, got {value!r} ({_type_name(value)})")
    return float(value)


def check_range(name: str, value, lo=-math.inf, hi=math.inf, *, lo_open=False, hi_open=False):
    """Raise unless ``value`` is a finite real number with ``lo <= value <= hi`` (open ends if
    asked): ``TypeError`` for a non-number, ``ValueError`` otherwise. Returns ``value``."""
    v = check_real(name, value)
    low_ok = v > lo if lo_open else v >= lo
    high_ok = v < hi if hi_open else v <= hi
    if not math.isfinite(v) or not (low_ok and high_ok):
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        finite = "" if math.isfinite(v) else " (and finite)"
        raise ValueError(f"{name} must be in {lb}{lo}, {hi}{rb}{finite}, got {value!r}")
    return value


def check_unit(name: str, value):
    """``value`` in [0, 1]."""
    return check_range(name, value, 0.0, 1.0)


def check_positive(name: str, value):
    """``value`` > 0 (and finite)."""
    return check_range(name, value, 0.0, math.inf, lo_open=True)


def check_nonnegative(name: str, value):
    """``value`` >= 0 (and finite)."""
    return check_range(name, value, 0.0, math.inf)


def check_int(name: str, value, lo: int = 0, hi: int | None = None) -> int:
    """An integer in [lo, hi]; a float of integral value (``2.0``) is taken as that integer."""
    v = check_real(name, value)
    if not v.is_integer():
        raise ValueError(f"{name} must be an integer, got {value!r}")
    check_range(name, value, lo, math.inf if hi is None else hi)
    return int(v)


def check_array(name: str, value, dtype=None) -> np.ndarray:
    """``np.asarray(value, dtype)`` of numbers, with numpy's refusals (ragged nesting) turned
    into errors naming the parameter, and text or ``None`` refused rather than parsed."""
    if value is None:
        raise ParameterTypeError(f"{name} must be an array, got None")
    try:
        a = np.asarray(value)
        if a.dtype.kind == "O" and dtype is not None:  # e.g. a list mixing numpy scalars and ints
            a = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a rectangular array of numbers ({exc})") from None
    if a.dtype.kind in "OUSV":
        raise ParameterTypeError(f"{name} must be an array of numbers, got dtype {a.dtype}")
    return a if dtype is None else a.astype(dtype, copy=False)


def check_points(name: str, array, dim: int = 3) -> np.ndarray:
    """A finite ``(n, dim)`` float array (a single ``(dim,)`` row is promoted)."""
    a = check_array(name, array, float)
    if a.ndim == 1 and a.shape[0] == dim:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != dim:
        raise ValueError(f"{name} must have shape (n, {dim}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def check_bool_array(name: str, value) -> np.ndarray:
    """A boolean array; 0/1 numbers are accepted and converted, anything else (NaN, 0.5, 2) is
    refused rather than cast to True."""
    a = check_array(name, value)
    if a.dtype != bool:
        if not np.all((a == 0) | (a == 1)):
            raise ValueError(f"{name} must be boolean (or 0/1)")
        a = a.astype(bool)
    return a


def check_cover(cover) -> np.ndarray:
    """A 2-D ``(m, n)`` boolean cover matrix (``cover[j, i]``: setup j reaches patch i);
    0/1 integers are accepted and converted."""
    c = check_bool_array("cover", cover)
    if c.ndim != 2:
        raise ValueError(f"cover must be a 2-D (m, n) boolean array, got shape {c.shape}")
    return c


def check_indices(name: str, ids, n: int) -> np.ndarray:
    """Indices into ``n`` items: ``(k,)`` integers in ``[0, n)`` or an ``(n,)`` boolean mask.

    Floats are refused, not truncated (``0.7`` is no index). Returns ``(k,)`` int64.
    """
    a = check_array(name, ids)
    if a.dtype == bool:
        if a.shape != (n,):
            raise ValueError(f"{name} as a boolean mask must have shape ({n},), got {a.shape}")
        return np.flatnonzero(a)
    if a.size == 0:
        return np.zeros(0, dtype=np.int64)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.dtype.kind not in "iu":
        raise ParameterTypeError(f"{name} must be integer indices (or a boolean mask), got dtype {a.dtype}")
    if a.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of indices, got shape {a.shape}")
    if a.min() < 0 or a.max() >= n:
        raise ValueError(f"{name} must index [0, {n - 1}], got values in [{a.min()}, {a.max()}]")
    return a.astype(np.int64)


def check_instance(name: str, value, cls):
    """``value`` is a ``cls`` (e.g. a parameter dataclass handed to a function)."""
    if not isinstance(value, cls):
        raise ParameterTypeError(f"{name} must be a {cls.__name__}, got {value!r} ({_type_name(value)})")
    return value


def check_bool(name: str, value) -> bool:
    """``value`` is a bool (``numpy.bool_`` too), not a string or a number standing for one."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterTypeError(f"{name} must be True or False, got {value!r} ({_type_name(value)})")
    return bool(value)


def check_sequence(name: str, value) -> list:
    """``value`` is a list, tuple or other iterable of items (not a string, whose characters
    would be taken for items); returned as a list."""
    if isinstance(value, (str, bytes)) or not isinstance(value, typing.Iterable):
        raise ParameterTypeError(f"{name} must be a sequence such as a list or tuple, got {value!r} "
                                 f"({_type_name(value)})")
    return list(value)


def check_callable(name: str, value, signature: str):
    """``value`` is callable; ``signature`` says what it is called with, for the message."""
    if not callable(value):
        raise ParameterTypeError(f"{name} must be a callable {signature}, got {_type_name(value)}")
    return value


def check_path(name: str, path) -> Path:
    """A file path (``str`` or ``os.PathLike``), returned as a ``Path``."""
    if not isinstance(path, (str, os.PathLike)):
        raise ParameterTypeError(f"{name} must be a file path (str or os.PathLike), got {path!r} "
                                 f"({_type_name(path)})")
    return Path(path)


def check_bounds(name: str, lower, upper):
    """Elementwise ``lower <= upper`` for parameter boxes; returns float arrays."""
    lo = check_array(name, lower, float)
    hi = check_array(name, upper, float)
    if lo.shape != hi.shape:
        raise ValueError(f"{name}: lower and upper bounds have different shapes {lo.shape} vs {hi.shape}")
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise ValueError(f"{name}: bounds must be finite")
    if np.any(lo > hi):
        bad = np.flatnonzero(np.atleast_1d(lo > hi)).tolist()
        raise ValueError(f"{name}: lower bound > upper bound at index {bad}")
    return lo, hi


def check_size(name: str, value, count: float, limit: float, what: str) -> None:
    """Refuse a parameter value that sets the size of the work beyond ``limit``: a tiny step or
    a huge count would otherwise run for hours or exhaust memory instead of failing. ``count``
    is the number of ``what`` (e.g. "waypoints") that ``name = value`` would make; each caller
    states why its ``limit`` is far above any real use."""
    if not count <= limit:
        raise ValueError(f"{name} = {value!r} would make about {count:.3g} {what}, more than the "
                         f"{limit:.3g} this step allows; change {name}")


# ---- parameter dataclasses: one check of every field, from its annotation and declaration ----


@dataclasses.dataclass(frozen=True)
class _Legal:
    """The legal values of one field, declared with :func:`ranged`: a closed or open interval
    (for a tuple field, of each element), or a set of choices; a tuple's length."""

    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple | None = None
    length: int | None = None
    nonempty: bool = False

    def check(self, name: str, value) -> None:
        """Raise ``ValueError`` naming the field unless ``value`` is legal."""
        if self.choices is not None:
            if value not in self.choices:
                raise ValueError(f"{name} must be one of {self.choices}, got {value!r}")
            return
        if isinstance(value, tuple):
            if self.length is not None and len(value) != self.length:
                raise ValueError(f"{name} must hold {self.length} values, got {value!r}")
            if self.nonempty and not value:
                raise ValueError(f"{name} must hold at least one value")
        for v in value if isinstance(value, tuple) else (value,):
            check_range(name, v, self.lo, self.hi, lo_open=self.lo_open, hi_open=self.hi_open)


_LEGAL = "mavac.legal"  # the metadata key of a field's _Legal


def ranged(default, *, ge=None, gt=None, le=None, lt=None, choices: tuple | None = None,
           length: int | None = None, nonempty: bool = False) -> dataclasses.Field:
    """A parameter dataclass field with its default and its legal values, which
    :func:`check_fields` enforces after the type.

    Parameters
    ----------
    default : object
        The field's default (immutable: a number, a string, a tuple or ``None``).
    ge, gt : float, optional
        Lower bound, closed (``value >= ge``) or open (``value > gt``); at most one of them.
    le, lt : float, optional
        Upper bound, closed (``value <= le``) or open (``value < lt``); at most one of them.
        For a tuple field the bounds hold for each element; ``None`` is legal for an
        ``X | None`` field whatever the bounds.
    choices : tuple, optional
        The legal values (strings or integers), instead of bounds.
    length : int, optional
        For a tuple field, the exact number of elements.
    nonempty : bool
        For a tuple field, whether at least one element is needed.

    Returns
    -------
    dataclasses.Field
        ``dataclasses.field(default=default)`` carrying the declaration in its metadata.

    Examples
    --------
    >>> @dataclasses.dataclass(frozen=True)
    ... class Camera(CheckedFields):
    ...     L_d: float = ranged(0.5, gt=0.0)
    >>> Camera(L_d=0.0)
    Traceback (most recent call last):
    ...
    ValueError: L_d must be in (0.0, inf], got 0.0
    """
    if (ge is not None and gt is not None) or (le is not None and lt is not None):
        raise TypeError("ranged: give at most one of ge and gt, and one of le and lt")
    if choices is not None and not all(b is None for b in (ge, gt, le, lt)):
        raise TypeError("ranged: give choices or bounds, not both")
    legal = _Legal(lo=next((b for b in (ge, gt) if b is not None), -math.inf),
                   hi=next((b for b in (le, lt) if b is not None), math.inf),
                   lo_open=gt is not None, hi_open=lt is not None,
                   choices=None if choices is None else tuple(choices), length=length, nonempty=nonempty)
    return dataclasses.field(default=default, metadata={_LEGAL: legal})


@functools.lru_cache(maxsize=None)
def _field_types(cls) -> tuple:
    hints = typing.get_type_hints(cls)
    return tuple((f.name, hints[f.name], f.metadata.get(_LEGAL)) for f in dataclasses.fields(cls))


def _check_field(owner: str, name: str, value, kind):
    """Type (``TypeError``) and finiteness (``ValueError``) of one field value; returns the
    value to store (a list given for a tuple field becomes a tuple)."""
    label = f"{name} ({owner})"
    options = typing.get_args(kind) if isinstance(kind, types.UnionType) else (kind,)
    if value is None and type(None) in options:
        return None
    kind = next(k for k in options if k is not type(None))
    if kind is bool:
        if not isinstance(value, (bool, np.bool_)):
            raise ParameterTypeError(f"{label} must be True or False, got {value!r} ({_type_name(value)})")
        return bool(value)
    if kind is int:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
            raise ParameterTypeError(f"{label} must be an integer, got {value!r} ({_type_name(value)})")
        return value
    if kind is float:
        if not math.isfinite(check_real(label, value)):
            raise ValueError(f"{label} must be finite, got {value!r}")
        return value
    if kind is str:
        if not isinstance(value, str):
            raise ParameterTypeError(f"{label} must be a string, got {value!r} ({_type_name(value)})")
        return value
    if kind is tuple:
        if not isinstance(value, (tuple, list)):
            raise ParameterTypeError(f"{label} must be a tuple of numbers, got {value!r} ({_type_name(value)})")
        for v in value:
            if not math.isfinite(check_real(label, v)):
                raise ValueError(f"{label} must hold finite numbers, got {tuple(value)!r}")
        return tuple(value)
    return check_instance(label, value, kind)  # a nested parameter dataclass


def check_fields(params) -> None:
    """Check every field of a parameter dataclass: first the type and finiteness of each, from
    its annotation (``float``, ``int``, ``bool``, ``str``, ``tuple`` of numbers, ``X | None``, a
    nested dataclass), then the legal values declared with :func:`ranged`. Every dataclass of
    :mod:`mavac.params` runs it first (:class:`CheckedFields`); checks that relate two fields
    follow in its own ``__post_init__``.

    Raises ``TypeError`` for a wrong type (a string or a boolean where a number is meant, a
    float where an integer is meant) and ``ValueError`` for NaN, infinity or a value outside
    the declared ones, naming the field. All types are checked before any value, so a wrong
    type is a ``TypeError`` whatever else is wrong.
    """
    owner = type(params).__name__
    fields = _field_types(type(params))
    for name, kind, _ in fields:
        value = getattr(params, name)
        checked = _check_field(owner, name, value, kind)
        if checked is not value:
            object.__setattr__(params, name, checked)  # frozen: store the normalised value
    for name, _, legal in fields:
        value = getattr(params, name)
        if legal is not None and value is not None:
            legal.check(name, value)


class CheckedFields:
    """Base of the parameter dataclasses: ``__post_init__`` runs :func:`check_fields`. A
    subclass with checks across fields overrides it and calls ``super().__post_init__()``
    first."""

    def __post_init__(self):
        check_fields(self)

    @classmethod
    def from_dict(cls, values: dict):
        """The parameters ``dataclasses.asdict`` gave, e.g. read back from a JSON file: nested
        parameter dataclasses are rebuilt from their dicts and every field is checked as usual;
        a key that is not a field is a ``ValueError`` naming it, a missing one takes its default."""
        if not isinstance(values, dict):
            raise ParameterTypeError(f"{cls.__name__} values must be a dict, got {_type_name(values)}")
        kinds = {name: kind for name, kind, _ in _field_types(cls)}
        unknown = sorted(set(values) - set(kinds))
        if unknown:
            raise ValueError(f"{cls.__name__} has no parameter {', '.join(map(repr, unknown))}; "
                             f"its parameters are {', '.join(kinds)}")
        return cls(**{name: (kinds[name].from_dict(value) if isinstance(value, dict)
                             and isinstance(kinds[name], type) and issubclass(kinds[name], CheckedFields)
                             else value) for name, value in values.items()})

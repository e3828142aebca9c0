import dataclasses
import math

import numpy as np
import pytest

from mavac.validate import (CheckedFields, check_bounds, check_int, check_points, check_positive, check_range,
                            check_unit, ranged)


def test_check_unit_names_parameter_and_range():
    assert check_unit("P_s", 0.5) == 0.5
    with pytest.raises(ValueError, match=r"P_s must be in \[0.0, 1.0\], got 1.5"):
        check_unit("P_s", 1.5)
    with pytest.raises(ValueError, match="P_g"):
        check_unit("P_g", float("nan"))


def test_open_intervals_and_types():
    with pytest.raises(ValueError, match=r"L_d must be in \(0.0, inf\]"):
        check_positive("L_d", 0.0)
    with pytest.raises(ValueError, match="theta_a"):
        check_range("theta_a", math.pi / 2, 0, math.pi / 2, lo_open=True, hi_open=True)
    with pytest.raises(TypeError, match="x must be a real number, got 'abc'"):
        check_range("x", "abc")
    with pytest.raises(TypeError, match="x must be a real number, got True"):
        check_range("x", True)
    with pytest.raises(ValueError, match=r"L_d must be in \(0.0, inf\] \(and finite\), got inf"):
        check_positive("L_d", float("inf"))
    with pytest.raises(ValueError, match="N_repeat must be an integer"):
        check_int("N_repeat", 2.5)
    with pytest.raises(ValueError, match="N_repeat"):
        check_int("N_repeat", 0, lo=1)


def test_points_and_bounds():
    assert check_points("p", [1, 2, 3]).shape == (1, 3)
    with pytest.raises(ValueError, match=r"points must have shape \(n, 3\)"):
        check_points("points", np.zeros((4, 2)))
    with pytest.raises(ValueError, match="NaN"):
        check_points("points", [[0, np.nan, 0]])
    with pytest.raises(ValueError, match=r"bounds: lower bound > upper bound at index \[1\]"):
        check_bounds("bounds", [0, 2], [1, 1])


@dataclasses.dataclass(frozen=True)
class _Declared(CheckedFields):
    closed: float = ranged(0.5, ge=0.0, le=1.0)
    open_: float = ranged(0.5, gt=0.0, lt=1.0)
    count: int = ranged(2, ge=1)
    maybe: float | None = ranged(None, gt=0.0)
    mode: str = ranged("a", choices=("a", "b"))
    pair: tuple = ranged((0.1, 0.2), gt=0.0, length=2)
    some: tuple = ranged((1.0,), ge=-1.0, le=1.0, nonempty=True)


def test_ranged_closed_and_open_ends():
    assert _Declared(closed=0.0).closed == 0.0 and _Declared(closed=1.0).closed == 1.0
    with pytest.raises(ValueError, match=r"closed must be in \[0.0, 1.0\], got 1.5"):
        _Declared(closed=1.5)
    for end in (0.0, 1.0):
        with pytest.raises(ValueError, match=r"open_ must be in \(0.0, 1.0\), got"):
            _Declared(open_=end)
    with pytest.raises(ValueError, match=r"count must be in \[1, inf\], got 0"):
        _Declared(count=0)


def test_ranged_none_choices_and_tuple_elements():
    assert _Declared(maybe=None).maybe is None
    with pytest.raises(ValueError, match=r"maybe must be in \(0.0, inf\], got -1.0"):
        _Declared(maybe=-1.0)
    assert _Declared(mode="b").mode == "b"
    with pytest.raises(ValueError, match=r"mode must be one of \('a', 'b'\), got 'c'"):
        _Declared(mode="c")
    assert _Declared(pair=[0.3, 0.4]).pair == (0.3, 0.4)  # a list is stored as a tuple
    with pytest.raises(ValueError, match=r"pair must be in \(0.0, inf\], got 0.0"):
        _Declared(pair=(0.1, 0.0))
    with pytest.raises(ValueError, match=r"pair must hold 2 values, got \(0.1,\)"):
        _Declared(pair=(0.1,))
    with pytest.raises(ValueError, match="some must hold at least one value"):
        _Declared(some=())
    with pytest.raises(ValueError, match=r"some must be in \[-1.0, 1.0\], got 2.0"):
        _Declared(some=(0.0, 2.0))


def test_types_are_checked_before_ranges():
    # A wrong type anywhere is a TypeError even when an earlier field is out of range.
    with pytest.raises(TypeError, match="mode"):
        _Declared(closed=1.5, mode=3)
    with pytest.raises(TypeError, match="pair"):
        _Declared(count=0, pair=("a", 0.1))


def test_ranged_refuses_contradictory_declarations():
    with pytest.raises(TypeError, match="ge and gt"):
        ranged(1.0, ge=0.0, gt=0.0)
    with pytest.raises(TypeError, match="le and lt"):
        ranged(1.0, le=2.0, lt=2.0)
    with pytest.raises(TypeError, match="choices or bounds"):
        ranged("a", choices=("a",), ge=0.0)


def test_ranged_default_stays_the_class_attribute():
    assert _Declared.closed == 0.5 and _Declared.mode == "a"


def test_every_parameter_dataclass_reads_back_from_its_json():
    import json

    import mavac.params as P

    classes = [c for c in vars(P).values() if isinstance(c, type) and issubclass(c, CheckedFields)
               and dataclasses.is_dataclass(c) and c.__module__ == P.__name__]
    assert len(classes) > 10
    for cls in classes:
        default = cls()
        assert cls.from_dict(json.loads(json.dumps(dataclasses.asdict(default)))) == default, cls.__name__
    changed = P.InspectionParams().with_visibility("hpr")
    assert P.InspectionParams.from_dict(json.loads(json.dumps(dataclasses.asdict(changed)))) == changed
    with pytest.raises(ValueError, match=r"SpotParams has no parameter 'P_x'; its parameters are P_s, "):
        P.InspectionParams.from_dict({"spot": {"P_x": 1.0}})
    with pytest.raises(ValueError, match=r"P_s must be in \[0.0, 1.0\], got 2"):
        P.InspectionParams.from_dict({"spot": {"P_s": 2}})
    with pytest.raises(TypeError, match="InspectionParams values must be a dict, got list"):
        P.InspectionParams.from_dict([])

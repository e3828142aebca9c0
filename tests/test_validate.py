import math

import numpy as np
import pytest

from mavac.validate import check_bounds, check_int, check_points, check_positive, check_range, check_unit


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

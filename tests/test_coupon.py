"""The GPR learner's coupon in the cell and the Preston constant calibrated on it
(mavac.scrubbing.coupon)."""

import numpy as np
import pytest

from mavac.experiments.kabir_bimanual import PARTS, paper_operation, paper_thresholds
from mavac.params import PRESTON, BimanualCellParams, ScrubModel
from mavac.scrubbing.coupon import CouponCell, calibrated_preston


@pytest.fixture(scope="module")
def coupon():
    with CouponCell(BimanualCellParams()) as c:
        yield c


def test_the_preston_constant_is_the_calibrated_one(coupon):
    """The typed constant is what its calibration gives on today's cell (within its rounding),
    and the cell and the analytic model share it."""
    calibrated = {p: calibrated_preston(coupon, paper_operation(p), paper_thresholds(p)[0]) for p in PARTS}
    assert max(calibrated.values()) == pytest.approx(PRESTON, rel=0.03)
    assert BimanualCellParams().preston == ScrubModel().preston == PRESTON
    # at the constant, each part's paper point meets its paper threshold on the coupon
    for p in PARTS:
        assert coupon.c_p_at(paper_operation(p), PRESTON) >= paper_thresholds(p)[0]


def test_c_p_grows_with_the_constant_from_one_simulated_stroke(coupon):
    x = paper_operation("hull")
    c_p = [coupon.c_p_at(x, k) for k in (1e-6, 1e-5, 1e-4, 1e-3)]
    assert np.all(np.diff(c_p) >= 0) and c_p[0] < 0.1 < 0.9 < c_p[-1]
    assert coupon(x) == coupon.c_p_at(x, coupon.params.preston)
    assert sum(key == tuple(x) for key in coupon.strokes) == 1  # the stroke ran once


def test_calibration_refuses_what_it_cannot_reach(coupon, monkeypatch):
    x = paper_operation("hull")
    with pytest.raises(ValueError, match="c_p_target"):
        calibrated_preston(coupon, x, 1.0)
    with pytest.raises(ValueError, match="bounds"):
        calibrated_preston(coupon, x, 0.5, bounds=(1e-3, 1e-4))
    with pytest.raises(ValueError, match="C_p stays below it"):
        calibrated_preston(coupon, x, 0.5, bounds=(1e-9, 1e-8))
    with pytest.raises(ValueError, match="preston"):
        coupon.c_p_at(x, 0.0)
    monkeypatch.setattr(CouponCell, "held_contact", lambda self, row: False)
    with pytest.raises(ValueError, match="did not hold contact"):
        calibrated_preston(coupon, x, 0.5)

"""Lissajous force oscillation (Kabir, Sec. VIII)."""

import dataclasses
import math

import numpy as np
import pytest

from mavac.params import LissajousParams
from mavac.scrubbing.lissajous import lissajous_force, lissajous_offset, overlay_path


def _spectrum_peak(signal, fs):
    spec = np.fft.rfft(signal)
    freqs = np.fft.rfftfreq(len(signal), 1 / fs)
    k = int(np.argmax(np.abs(spec[1:]))) + 1
    return freqs[k], spec[k]


def test_frequencies_and_phase_from_fft():
    p = LissajousParams()
    fs = 1000.0
    t = np.arange(0, 5.0, 1 / fs)  # 30 x-periods and 12 y-periods: no leakage
    force = lissajous_force(t, p)
    fx, X = _spectrum_peak(force[:, 0], fs)
    fy, Y = _spectrum_peak(force[:, 1], fs)
    assert fx == pytest.approx(p.f_x)
    assert fy == pytest.approx(p.f_y_ratio * p.f_x)
    # sin(w t + phase) has FFT phase (phase - pi/2); y has -pi/2: the difference is the phase.
    dphi = np.angle(X) - np.angle(Y)
    assert math.remainder(dphi - p.phase, 2 * math.pi) == pytest.approx(0.0, abs=1e-6)
    assert np.abs(force[:, 0]).max() == pytest.approx(p.A_x, rel=1e-3)
    assert np.abs(force[:, 1]).max() == pytest.approx(p.A_y, rel=1e-3)


def test_offset_is_force_over_stiffness():
    p = dataclasses.replace(LissajousParams(), kappa_x=2000.0, kappa_y=8000.0)
    t = np.linspace(0, 1, 101)
    np.testing.assert_allclose(lissajous_offset(t, p) * [2000.0, 8000.0], lissajous_force(t, p))


def test_overlay_path_frames_and_forces():
    p = LissajousParams()
    n = 50
    path = np.column_stack([np.linspace(0, 0.2, n), np.zeros(n), np.zeros(n)])
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    out = overlay_path(path, normals, p)
    duration = 0.2 / p.tool_speed
    assert out.t[-1] == pytest.approx(duration)
    # Normal force pushes into the surface (tool z = -normal), oscillation stays in the plane.
    np.testing.assert_allclose(out.forces[:, 2], -p.f_n)
    np.testing.assert_allclose(out.positions[:, 2], 0.0, atol=1e-12)
    # Tool x is the direction of travel: x deviation = F_x / kappa_x about the nominal path.
    nominal_x = out.t * p.tool_speed
    np.testing.assert_allclose(out.positions[:, 0] - nominal_x, out.forces[:, 0] / p.kappa_x, atol=1e-12)
    # Same result from explicit tool frames.
    R = np.tile(np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]]), (n, 1, 1))
    out2 = overlay_path(path, R, p)
    np.testing.assert_allclose(out2.positions, out.positions, atol=1e-12)
    np.testing.assert_allclose(out2.forces, out.forces, atol=1e-12)


def test_speed_argument_sets_duration():
    path = np.array([[0.0, 0, 0], [0.1, 0, 0]])
    out = overlay_path(path, np.array([[0, 0, 1.0]] * 2), speed=0.05)
    assert out.t[-1] == pytest.approx(2.0)


@pytest.mark.parametrize("field,value", [("f_x", 0.0), ("kappa_x", 0.0), ("kappa_y", -5.0),
                                         ("A_x", -1.0), ("v", 0.0), ("v", 1.5), ("f_n", -1.0),
                                         ("tool_speed_at_vmax", 0.0), ("f_y_ratio", 0.0)])
def test_bad_params(field, value):
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(LissajousParams(), **{field: value})


def test_bad_overlay_inputs():
    path = np.array([[0.0, 0, 0], [0.1, 0, 0]])
    normals = np.array([[0, 0, 1.0]] * 2)
    with pytest.raises(ValueError, match="speed"):
        overlay_path(path, normals, speed=-0.1)
    with pytest.raises(ValueError, match="dt"):
        overlay_path(path, normals, dt=0.0)
    with pytest.raises(ValueError, match="path"):
        overlay_path(path[:1], normals[:1])
    with pytest.raises(ValueError, match="frames"):
        overlay_path(path, np.ones((3, 3)))
    with pytest.raises(ValueError, match="zero length"):
        overlay_path(np.zeros((2, 3)), normals)
    with pytest.raises(ValueError, match="t must"):
        lissajous_force(np.array([0.0, np.nan]))


@pytest.mark.parametrize("phase", [math.pi / 2, 0.0, -math.pi / 2])
def test_overlay_runs_past_the_path_ends_by_at_most_A_over_kappa(phase):
    # Kabir Sec. VIII: the oscillation is overlaid on the nominal path; on a straight path the
    # deviation along the travel direction is at most A_x / kappa_x (6 mm for Fig. 3's 30 N, 5000 N/m)
    from mavac.scrubbing.lissajous import end_overshoot

    p = dataclasses.replace(LissajousParams(), phase=phase)
    path = np.column_stack([np.linspace(0, 0.06, 30), np.zeros(30), np.zeros(30)])
    over = overlay_path(path, np.tile([0.0, 0.0, 1.0], (30, 1)), p)
    before, past = end_overshoot(path, over.positions)
    limit = p.A_x / p.kappa_x
    assert before <= limit + 1e-9 and past <= limit + 1e-9
    assert max(before, past) > 0  # and it does run past an end: the pattern is not clipped


def test_overshoot_of_a_turning_path_stays_within_the_combined_swing():
    from mavac.scrubbing.lissajous import end_overshoot

    p = LissajousParams()
    angle = np.linspace(0, np.pi / 2, 60)  # a quarter circle of 4 cm radius: the end direction turns
    path = np.column_stack([0.04 * np.sin(angle), 0.04 * (1 - np.cos(angle)), np.zeros(60)])
    over = overlay_path(path, np.tile([0.0, 0.0, 1.0], (60, 1)), p)
    before, past = end_overshoot(path, over.positions)
    assert max(before, past) <= np.hypot(p.A_x / p.kappa_x, p.A_y / p.kappa_y) + 1e-9

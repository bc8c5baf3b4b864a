import math

import numpy as np
import pytest

from ballaststudy.metrics import force_propagation_angle, x90

W = 0.34                      # container width [m] (thesis 4.1: 34 cm)
SEG = W / 20
XC = -W / 2 + SEG * (np.arange(20) + 0.5)   # plate middle at x = 0
WIDTH = np.full(20, SEG)


def test_uniform_force():
    out = force_propagation_angle(np.full(20, 100.0), XC, WIDTH, 0.0, 0.20, 0.02)   # depth 0.18
    x = 0.9 * W / 2
    assert out["x90_left"] == pytest.approx(x, rel=1e-9), f"x90_left measured {out['x90_left']}, expected {x}"
    assert out["x90_right"] == pytest.approx(x, rel=1e-9), f"x90_right measured {out['x90_right']}, expected {x}"
    fa = math.degrees(math.atan2(0.18, x))   # from the horizontal: 49.64 deg
    for k in ("fpa_left", "fpa_right", "fpa"):
        assert out[k] == pytest.approx(fa, abs=1e-9), f"{k} measured {out[k]}, expected {fa}"
    assert out["depth"] == pytest.approx(0.18)


def test_asymmetric_force():
    f = np.zeros(20)
    f[10] = 500.0            # right: all in the segment next to the middle
    f[0] = 80.0              # left: all in the outermost segment
    xl, xr = x90(f, XC, WIDTH, 0.0)
    assert xr == pytest.approx(0.9 * SEG), f"x90_right measured {xr}, expected {0.9 * SEG}"
    exp_l = W / 2 - SEG + 0.9 * SEG
    assert xl == pytest.approx(exp_l), f"x90_left measured {xl}, expected {exp_l}"
    out = force_propagation_angle(f, XC, WIDTH, 0.0, 0.15, 0.0)
    fl, fr = math.degrees(math.atan2(0.15, exp_l)), math.degrees(math.atan2(0.15, 0.9 * SEG))
    assert out["fpa_left"] == pytest.approx(fl) and out["fpa_right"] == pytest.approx(fr)
    assert out["fpa"] == pytest.approx((fl + fr) / 2)
    assert out["fpa_right"] > out["fpa_left"], "concentrated force must give the steeper angle"


def test_interpolation_within_segment():
    f = np.zeros(20)
    f[10], f[11] = 3.0, 1.0          # total 4, 90 % = 3.6: 3 in seg 1, then 0.6 of seg 2
    _, xr = x90(f, XC, WIDTH, 0.0)
    assert xr == pytest.approx(1.6 * SEG), f"measured {xr}, expected {1.6 * SEG}"


def test_segment_crossing_the_middle_is_split_by_length():
    # two segments [0,1], [1,2]; middle at 0.5: segment 0 gives half its force to each side
    xl, xr = x90([2.0, 0.0], [0.5, 1.5], [1.0, 1.0], 0.5)
    assert xl == pytest.approx(0.45) and xr == pytest.approx(0.45), f"measured {xl}, {xr}, expected 0.45"
    # middle at 0.25: left gets 1/4 of seg 0 on [0, 0.25], right 3/4 on [0, 0.75] + seg 1
    xl, xr = x90([4.0, 1.0], [0.5, 1.5], [1.0, 1.0], 0.25)
    assert xl == pytest.approx(0.225), f"left measured {xl}, expected 0.225"
    # right: 3 N on [0, 0.75], 1 N on [0.75, 1.75]; 90 % of 4 = 3.6 -> 0.75 + 0.6
    assert xr == pytest.approx(1.35), f"right measured {xr}, expected 1.35"


def test_no_force_is_nan_and_bad_depth_raises():
    out = force_propagation_angle(np.zeros(20), XC, WIDTH, 0.0, 0.18, 0.0)
    assert math.isnan(out["fpa_left"]) and math.isnan(out["x90_right"])
    with pytest.raises(ValueError):
        force_propagation_angle(np.ones(20), XC, WIDTH, 0.0, -0.01, 0.0)

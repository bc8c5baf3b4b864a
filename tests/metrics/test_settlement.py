import numpy as np
import pytest

from ballaststudy.metrics import loading_branch_crossing, settlement

N = 38                      # samples per cycle: t = 0.5 (peak) on the grid, t = 0.25 not


def cycle(sink, b=1e-3):
    """Force 15 -> 45 -> 15 kN: F = 30 - 15 cos(2 pi t) [kN]; it crosses 30 kN upward at
    t = 0.25 exactly. The ball sinks by ``sink`` plus b*t within the cycle (y linear in t)."""
    t = np.arange(N) / N
    f = 30e3 - 15e3 * np.cos(2 * np.pi * t)
    y = 0.2 - sink - b * t
    return y, f


def test_crossing_on_loading_branch_sinusoid():
    y, f = cycle(0.0)
    y_c, y_pk, f_pk = loading_branch_crossing(y, f, 30e3)
    expected = 0.2 - 1e-3 * 0.25
    assert y_c == pytest.approx(expected, abs=1e-8), f"y at 30 kN measured {y_c}, expected {expected}"
    assert y_pk == pytest.approx(0.2 - 1e-3 * 0.5, abs=1e-12), f"y at peak measured {y_pk}"
    assert f_pk == pytest.approx(45e3)


def test_settlement_relative_to_cycle0_positive_down():
    sinks = [0.0, 1e-3, 2.5e-3, 4e-3]
    ys, fs = zip(*(cycle(s) for s in sinks))
    out = settlement(ys, fs, 30e3)
    assert np.allclose(out["settlement"], sinks, atol=1e-8), f"measured {out['settlement']}, expected {sinks}"
    expected_peak = np.array(sinks) + 1e-3 * 0.25   # peak at t=0.5, reference at t=0.25
    assert np.allclose(out["displacement_at_peak"], expected_peak, atol=1e-8), \
        f"measured {out['displacement_at_peak']}, expected {expected_peak}"


def test_unloading_branch_is_ignored():
    y, f = cycle(0.0)
    y = y.copy()
    y[N // 2 + 1:] -= 0.05            # a jump after the peak must not change the reading
    y_c, _, _ = loading_branch_crossing(y, f, 30e3)
    assert y_c == pytest.approx(0.2 - 0.25e-3, abs=1e-8), f"measured {y_c}"


def test_no_crossing_gives_nan():
    y, f = cycle(0.0)
    assert np.isnan(loading_branch_crossing(y, f + 20e3, 30e3)[0])
    # starts above 30 kN, peaks, falls to 20 kN and rises to 32 kN after the peak: that
    # late crossing is not on the loading branch
    f = np.array([35e3, 40e3, 45e3, 30e3, 20e3, 32e3])
    got = loading_branch_crossing(np.linspace(0, -1e-3, 6), f, 30e3)[0]
    assert np.isnan(got), f"measured {got}, expected NaN (no crossing before the peak)"

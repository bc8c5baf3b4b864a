import numpy as np
import pytest

from ballaststudy.metrics import breakage_rate
from ballaststudy.metrics.breakage import broken_mass_share

STEPS = np.array([50, 150, 150, 250, 299, 300])
MODES = np.array([1, 1, 2, 1, 2, 1])          # 1 tension, 2 shear
BOUNDS = [100, 200, 300]                     # cycle 0: [100, 200), cycle 1: [200, 300)


def test_counts_and_rates_equal_the_records():
    out = breakage_rate(MODES, STEPS, 200, BOUNDS)
    assert list(out["breakages_per_cycle"]) == [2, 2], f"measured {out['breakages_per_cycle']}"
    assert list(out["broken_tension"]) == [2, 3], f"measured {out['broken_tension']}"
    assert list(out["broken_shear"]) == [1, 2], f"measured {out['broken_shear']}"
    assert np.allclose(out["breakage_rate_tension"], [2 / 200, 3 / 200]), out["breakage_rate_tension"]
    assert np.allclose(out["breakage_rate_shear"], [1 / 200, 2 / 200]), out["breakage_rate_shear"]
    assert np.allclose(out["breakage_rate"], [3 / 200, 5 / 200]), out["breakage_rate"]


def test_string_modes_and_elements_per_bond():
    names = np.where(MODES == 1, "tension", "shear")
    a = breakage_rate(names, STEPS, 200, BOUNDS, n_elements_per_bond=2)
    assert np.allclose(a["breakage_rate"], [3 / 400, 5 / 400]), f"measured {a['breakage_rate']}"


def test_bad_mode_rejected():
    with pytest.raises(ValueError, match="tension"):
        breakage_rate(["crush"], [1], 10, [0, 5])


def test_broken_mass_share_is_the_mass_outside_each_stones_largest_piece():
    """Three stones: one whole, one split into pieces of mass 3, 1 and a deleted ball of
    1 (fines), one of mass 9 split 5 / 4; non-stone balls (-1) count nowhere."""
    r = np.array([2.0, 2.0, 3.0, 1.0, 1.0, 5.0, 4.0, 7.0])
    units = np.array([0, 0, 1, 1, 1, 2, 2, -1])
    labels = np.array([0, 0, 1, 2, -1, 3, 4, 5])
    total, kept = 4.0 + 5.0 + 9.0, 4.0 + 3.0 + 5.0
    assert broken_mass_share(units, labels, r) == pytest.approx(1.0 - kept / total, rel=1e-12)
    assert broken_mass_share(units, np.array([0, 0, 1, 1, 1, 2, 2, 3]), r) == 0.0
    assert broken_mass_share(units, np.full(8, -1), r) == 1.0          # all gone
    m = np.random.default_rng(1).random(4000)                           # whole stones: 0 exactly,
    whole = np.repeat(np.arange(100), 40)                               # not to round-off
    assert broken_mass_share(whole, 3 * whole + 7, m) == 0.0
    with pytest.raises(ValueError, match="no stone balls"):
        broken_mass_share(np.full(8, -1), labels, r)

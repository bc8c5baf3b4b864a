import numpy as np
import pytest

from ballaststudy.metrics import breakage_rate

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

"""Sobol indices from a small design on planted outputs with known indices: for
y = a x1 + b x2 on a uniform box, S_i = a_i^2 var(x_i) / sum (no interaction: S1 = ST);
an output that ignores a parameter gives it ~0 (negative control)."""
import numpy as np
import pytest

from ballaststudy.calibration.bayes import initial_design as design
from ballaststudy.calibration.sensitivity import sobol_indices

LOWER, UPPER = np.array([2.0, 0.5]), np.array([5.0, 0.8])
NAMES = ["F_str_co", "mu"]


def test_linear_output_gives_the_analytic_indices():
    thetas = design(LOWER, UPPER, 10, seed=4)
    a, b = 0.001, -0.02                     # per unit: ranges 3 and 0.3 -> variances 9/12, 0.09/12
    y = 0.01 + a * thetas[:, 0] + b * thetas[:, 1]
    v1, v2 = a ** 2 * 9 / 12, b ** 2 * 0.09 / 12
    si = sobol_indices(thetas, y, LOWER, UPPER, NAMES)
    assert si["F_str_co"]["S1"] == pytest.approx(v1 / (v1 + v2), abs=0.06)
    assert si["mu"]["S1"] == pytest.approx(v2 / (v1 + v2), abs=0.06)
    for s in si.values():
        assert s["ST"] == pytest.approx(s["S1"], abs=0.06)


def test_an_ignored_parameter_has_no_index():
    thetas = design(LOWER, UPPER, 10, seed=5)
    rng = np.random.default_rng(0)
    y = 0.004 * np.exp(-(thetas[:, 0] - 2.0)) + rng.normal(0, 1e-5, len(thetas))
    si = sobol_indices(thetas, y, LOWER, UPPER, NAMES)
    assert si["F_str_co"]["S1"] > 0.9 and si["mu"]["ST"] < 0.05

"""The calibration's per-test summary: RMSE under Table 4.2, calibrated on all tests, and
with the test left out."""
import numpy as np

from ballaststudy.calibration.bayes import HeldOut
from ballaststudy.calibration.cli import held_out_rmse
from ballaststudy.calibration.report import _held_out_table


def test_held_out_rmse_is_per_test():
    """Two tests: each test's RMSE under Table 4.2, calibrated and held out, from its own
    points only; summary.md carries them as a table."""
    y = np.array([1.0, 2.0, 3.0, 10.0, 20.0])
    point_test = np.array([0, 0, 0, 1, 1])
    held = HeldOut(np.zeros(2), y + np.array([0.0, 0.0, 0.0, 3.0, -3.0]), np.zeros((2, 1)))
    out = held_out_rmse(held, y + 1.0, y + np.array([2.0, 2.0, 2.0, 0.0, 0.0]), y, point_test, ["a", "b"])
    assert out == {"a": {"rmse_before": 1.0, "rmse_after": 2.0, "rmse_held_out": 0.0},
                   "b": {"rmse_before": 1.0, "rmse_after": 0.0, "rmse_held_out": 3.0}}
    table = _held_out_table(out)
    assert "| b | 1 | 0 | 3 |" in table and _held_out_table(None) == ""

"""The calibration's per-test summary: RMSE under Table 4.2, calibrated on all tests, and
with the test left out."""
import numpy as np

from ballaststudy.calibration.bayes import HeldOut, posterior
from ballaststudy.calibration.cli import held_out_rmse
from ballaststudy.calibration.report import _held_out_table, summary_markdown


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


def test_summary_warns_of_few_specimens_for_several_tests(tmp_path):
    """Several targets with K < 6 specimens: summary.md says the intervals are too narrow."""
    class Flat:
        def predict(self, thetas):
            return np.zeros((len(thetas), 2)), np.zeros((len(thetas), 2))
    post = posterior(Flat(), np.zeros(2), np.ones(2), [0.0], [1.0], 64)
    summary = dict(quantity="axial_strain", points=2, cycles=5, method="m", table_4_2={"mu": 0.7},
                   prior_coverage={"mu": 0.9}, correlation={}, rmse_before=1.0, rmse_after=0.5, dem_cases=12,
                   targets=["a", "b"],
                   sets=2, failed_cases=0,
                   held_out={t: {"rmse_before": 1.0, "rmse_after": 0.5, "rmse_held_out": 0.7} for t in "ab"})
    for cases, warned in ((3, True), (6, False)):
        summary_markdown(tmp_path / "s.md", "a, b", ["mu"], post, {**summary, "cases": cases})
        text = (tmp_path / "s.md").read_text()
        assert ("read the intervals as too narrow" in text) == warned
        assert "DEM cases run: 12 (2 parameter sets x 2 tests x" in text

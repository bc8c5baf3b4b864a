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


def _flat_summary(points, **extra):
    """A posterior of a flat surrogate over ``points`` measured points, and a summary of it."""
    class Flat:
        def predict(self, thetas):
            return np.zeros((len(thetas), points)), np.zeros((len(thetas), points))
    post = posterior(Flat(), np.zeros(points), np.ones(points), [0.0], [1.0], 64)
    return post, dict(quantity="axial_strain", points=points, cycles=5, method="m", table_4_2={"mu": 0.7},
                      prior_coverage={"mu": 0.9}, correlation={}, rmse_before=1.0, rmse_after=0.5,
                      failed_cases=0, **extra)


def test_summary_warns_of_few_specimens_for_several_tests(tmp_path):
    """Several targets with K < 6 specimens: summary.md says the intervals are too narrow."""
    post, summary = _flat_summary(2, dem_cases=12, targets=["a", "b"], sets=2, held_out={
        t: {"rmse_before": 1.0, "rmse_after": 0.5, "rmse_held_out": 0.7} for t in "ab"})
    for cases, warned in ((3, True), (6, False)):
        summary_markdown(tmp_path / "s.md", "a, b", ["mu"], post, {**summary, "cases": cases})
        text = (tmp_path / "s.md").read_text()
        assert ("read the intervals as too narrow" in text) == warned
        assert "DEM cases run: 12 (2 parameter sets x 2 tests x" in text


def test_summary_names_the_stress_mapping(tmp_path):
    """summary.md says which stress mapping the tests ran under (scenario/mapping.py)."""
    post, summary = _flat_summary(1, dem_cases=3, targets=["a"], sets=1, cases=3)
    summary_markdown(tmp_path / "s.md", "a", ["mu"], post, summary)
    assert "Stress mapping: **none**" in (tmp_path / "s.md").read_text()
    record = {"stress_mapping": "strength_ratio", "stress_mapping_ratio": 0.5,
              "stress_mapping_confining_pressure_kPa": 30.0, "stress_mapping_lab_q_peak_kPa": 400.0,
              "stress_mapping_model_q_peak_kPa": 200.0, "stress_mapping_model_peak_share": 1.0,
              "stress_mapping_lab_deviator_min_kPa": 15.0,
              "stress_mapping_lab_deviator_max_kPa": 230.0, "stress_mapping_deviator_min_kPa": 7.5,
              "stress_mapping_deviator_max_kPa": 115.0, "stress_mapping_lab_envelope_citation": "planted",
              "stress_mapping_model_envelope_file": "env.nc"}
    summary_markdown(tmp_path / "s.md", "a", ["mu"], post, {**summary, "stress_mapping_tests": {"src/a": record}})
    text = (tmp_path / "s.md").read_text()
    assert "Stress mapping: **strength_ratio**" in text
    assert "| src/a | 30 | 400 | 200 (100 %) | 0.5000 | 15-230 | 7.5-115 |" in text

